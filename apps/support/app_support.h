// What every program shares and no library should have: signals, checks of the paths a command
// line names, and progress reports on the terminal or in a log (the command lines themselves:
// command_line.h). Programs only; the libraries stay free of terminal output and process control.
#pragma once

#include <cdp/core/cancel.h>
#include <cdp/core/progress.h>

#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace cdp::app {

// SIGINT, SIGTERM and SIGHUP remove the temporary file of a write in progress, pass the signal
// on to the child processes registered below, and end the program by that signal (status
// 128 + N in a shell). SIGXFSZ (a file size limit) is ignored, so that the write that exceeds
// the limit fails with EFBIG and is reported like a full disk rather than killing the program.
void install_signal_handling();

// The token of the program's run (AdaptiveOptions::cancel, MarchingOptions::cancel). While a
// CancellableRun is alive, the first of those signals cancels it instead of ending the program
// at once: the run stops at its next poll (cancel.h) with CancelledError, its memory freed and
// nothing written, and the program then ends by that signal (end_if_interrupted). A second
// signal, or one outside a CancellableRun, ends the program at once as above.
const CancelToken& run_token();
class CancellableRun {
 public:
  CancellableRun();
  ~CancellableRun();
  CancellableRun(const CancellableRun&) = delete;
  CancellableRun& operator=(const CancellableRun&) = delete;
};
// After a CancelledError: ends the program by the signal that cancelled its run, as an
// uncancellable one would have ended; returns where no signal did (a caller's own token).
void end_if_interrupted();

// Keeps the memory a program frees for its own reuse instead of handing it back to the system
// (glibc's trim and mmap thresholds raised): a run frees and allocates again large tables (the
// checks', the sizing's), and memory handed back is faulted in again a page at a time. On this
// project's virtual machines a fault costs about 10 us: polygonize on the torus at factor 20 in
// the paper variant (100k triangles) makes 6,812 page faults instead of 8,967, spends 0.059 s
// in the kernel instead of 0.078 and takes 0.90 of the time (medians of 10 pairs of runs); its
// peak grows by 2 MB. Programs only: a library must not change its host's allocator. Nothing
// changes where glibc's allocator settings are given in the environment, or without glibc.
void keep_freed_memory();

// A child process to pass signals on to, between its start and its end. Start children with
// signals blocked (BlockSignals) and register them before unblocking, so that no signal falls
// between the start and the registration.
void register_child(pid_t pid);
void unregister_child(pid_t pid);

class BlockSignals {
 public:
  BlockSignals();
  ~BlockSignals();
  BlockSignals(const BlockSignals&) = delete;
  BlockSignals& operator=(const BlockSignals&) = delete;

 private:
  unsigned char saved_[128];  // a sigset_t, kept opaque here
};

// Checks the files a command will write before any work starts: each output's folder exists
// and is writable, no output is a folder, no two outputs are the same file, and no output is one
// of the inputs. Throws InvalidInputError "PATH: problem". `outputs` pairs an option name
// ("-o", "--stats") with its path.
void check_output_paths(const std::vector<std::pair<std::string, std::filesystem::path>>& outputs,
                        const std::vector<std::filesystem::path>& inputs);

// Progress of a long run on standard error. Bar: a bar redrawn in place, only on an interactive
// terminal (the default). Lines: one line per phase and then one every few seconds, for logs and
// CI (`--progress`). None: silent (`--quiet`).
class ProgressReporter {
 public:
  enum class Mode { None, Bar, Lines };
  ProgressReporter(std::string program, std::string label, Mode mode);
  ~ProgressReporter();  // clears the bar if it drew one

  // Starts a named phase ("seeding", "meshing", "writing out.ply"); fractions restart at 0.
  void phase(const std::string& name);
  void update(double fraction);
  ProgressCallback callback() {
    return [this](double f) { update(f); };
  }
  PhaseCallback phase_callback() {
    return [this](const std::string& name) { phase(name); };
  }

 private:
  double elapsed() const;
  void clear_bar();

  std::string program_, label_, phase_;
  Mode mode_;
  bool drawn_ = false;
  int last_permille_ = -1;
  double last_line_ = -1;
  std::chrono::steady_clock::time_point start_;
};

// The mode from the flags: --quiet wins, then --progress, then a bar when stderr is a terminal.
ProgressReporter::Mode progress_mode(bool quiet, bool lines);

}  // namespace cdp::app
