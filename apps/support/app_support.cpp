#include "support/app_support.h"

#include <cdp/core/errors.h>
#include <cdp/io/atomic_write.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>

#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <sys/wait.h>
#include <unistd.h>

namespace cdp::app {

namespace {

// Children passed signals on to: experiment runs at most one child per job thread, so a small
// fixed table (lock-free atomics, which a signal handler may touch) is enough.
constexpr int kMaxChildren = 256;
std::atomic<pid_t> g_children[kMaxChildren];

// How long an interrupted parent waits for its children to clean up before killing them: our
// programs remove their temporaries in microseconds; the bound keeps a stuck child from
// keeping the parent alive.
constexpr int kChildWaitRounds = 50;
constexpr long kChildWaitNanoseconds = 100'000'000;  // 50 x 0.1 s = 5 s

// The signal being handled, so that a child registered while the handler runs (in another
// thread, between its start and its registration) is passed the signal too.
std::atomic<int> g_interrupted{0};

// The run token (run_token), whether a CancellableRun is alive, and the signal that cancelled it.
const CancelToken g_run_token;
std::atomic<bool> g_run_armed{false};
std::atomic<int> g_cancelled_by{0};

void end_by(int sig);

void on_signal(int sig) {
  if (g_run_armed.load()) {
    int none = 0;
    if (g_cancelled_by.compare_exchange_strong(none, sig)) {
      g_run_token.cancel();  // the run ends at its next poll, then the program by end_if_interrupted
      return;
    }
  }
  end_by(sig);
}

void end_by(int sig) {
  g_interrupted.store(sig);
  remove_pending_temporary_file();
  bool any = false;
  for (auto& c : g_children) {
    const pid_t pid = c.load();
    if (pid > 0) {
      kill(pid, sig);
      any = true;
    }
  }
  for (int round = 0; any && round < kChildWaitRounds; ++round) {
    any = false;
    for (auto& c : g_children) {
      const pid_t pid = c.load();
      if (pid <= 0) continue;
      const pid_t r = waitpid(pid, nullptr, WNOHANG);
      if (r == pid || (r < 0 && errno == ECHILD)) c.store(0);
      else any = true;
    }
    if (any) {
      const timespec ts{0, kChildWaitNanoseconds};
      nanosleep(&ts, nullptr);
    }
  }
  for (auto& c : g_children)
    if (const pid_t pid = c.load(); pid > 0) kill(pid, SIGKILL);
  // End by the same signal, so that the caller sees how the program ended.
  signal(sig, SIG_DFL);
  raise(sig);
}

}  // namespace

const CancelToken& run_token() { return g_run_token; }

CancellableRun::CancellableRun() { g_run_armed.store(true); }

// A signal that came after the run's last poll (the run finished all the same) ends the program
// here, before anything is written.
CancellableRun::~CancellableRun() {
  g_run_armed.store(false);
  end_if_interrupted();
}

void end_if_interrupted() {
  if (const int sig = g_cancelled_by.load(); sig != 0) end_by(sig);
}

void install_signal_handling() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&sa.sa_mask, sig);
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) sigaction(sig, &sa, nullptr);
  signal(SIGXFSZ, SIG_IGN);
}

void keep_freed_memory() {
#ifdef __GLIBC__
  // A user's own settings (glibc's environment variables) win.
  for (const char* name : {"GLIBC_TUNABLES", "MALLOC_TRIM_THRESHOLD_", "MALLOC_MMAP_THRESHOLD_"})
    if (std::getenv(name) != nullptr) return;
  // Blocks up to glibc's largest mmap threshold (32 MiB on 64-bit) come from the heap, whose
  // freed blocks are reused, and the heap's top is never trimmed. The mmap threshold first: where
  // it is refused (32-bit glibc caps it at 512 KiB) both stay at their defaults (setting the trim
  // threshold alone would also freeze the mmap threshold at 128 KiB).
  constexpr int kTrimThreshold = 1 << 30, kMmapThreshold = 32 << 20;
  if (mallopt(M_MMAP_THRESHOLD, kMmapThreshold) == 1) mallopt(M_TRIM_THRESHOLD, kTrimThreshold);
#endif
}

void register_child(pid_t pid) {
  for (auto& c : g_children) {
    pid_t empty = 0;
    if (c.compare_exchange_strong(empty, pid)) break;
  }
  if (const int sig = g_interrupted.load(); sig != 0) kill(pid, sig);
}

void unregister_child(pid_t pid) {
  for (auto& c : g_children) {
    pid_t expected = pid;
    if (c.compare_exchange_strong(expected, 0)) return;
  }
}

BlockSignals::BlockSignals() {
  static_assert(sizeof(sigset_t) <= sizeof(saved_), "room for a sigset_t");
  sigset_t block;
  sigemptyset(&block);
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&block, sig);
  pthread_sigmask(SIG_BLOCK, &block, reinterpret_cast<sigset_t*>(saved_));
}

BlockSignals::~BlockSignals() { pthread_sigmask(SIG_SETMASK, reinterpret_cast<sigset_t*>(saved_), nullptr); }

void check_output_paths(const std::vector<std::pair<std::string, std::filesystem::path>>& outputs,
                        const std::vector<std::filesystem::path>& inputs) {
  namespace fs = std::filesystem;
  // The same file, whether or not it exists yet: equal normalised absolute paths, or one inode.
  const auto same = [](const fs::path& a, const fs::path& b) {
    std::error_code ec;
    if (fs::exists(a, ec) && fs::exists(b, ec) && fs::equivalent(a, b, ec)) return true;
    return fs::weakly_canonical(fs::absolute(a, ec), ec) == fs::weakly_canonical(fs::absolute(b, ec), ec);
  };
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const auto& [flag, path] = outputs[i];
    std::error_code ec;
    if (fs::is_directory(path, ec)) throw InvalidInputError(path.string() + ": is a folder (" + flag + " needs a file name)");
    const fs::path dir = path.parent_path().empty() ? fs::path(".") : path.parent_path();
    if (!fs::is_directory(dir, ec)) throw InvalidInputError(path.string() + ": the folder " + dir.string() + " does not exist");
    if (access(dir.c_str(), W_OK) != 0)
      throw InvalidInputError(path.string() + ": cannot write in " + dir.string() + ": " + std::strerror(errno));
    for (std::size_t j = 0; j < i; ++j)
      if (same(path, outputs[j].second))
        throw InvalidInputError(path.string() + ": given both to " + outputs[j].first + " and to " + flag);
    for (const auto& in : inputs)
      if (same(path, in)) throw InvalidInputError(path.string() + ": " + flag + " would overwrite an input file");
  }
}

ProgressReporter::Mode progress_mode(bool quiet, bool lines) {
  if (quiet) return ProgressReporter::Mode::None;
  if (lines) return ProgressReporter::Mode::Lines;
  return isatty(STDERR_FILENO) ? ProgressReporter::Mode::Bar : ProgressReporter::Mode::None;
}

namespace {
// A bar appears only once a run has lasted this long: short runs stay silent.
constexpr double kBarDelaySeconds = 0.5;
// Lines mode: one line per phase, then at most one line this often, so that a log of a
// minutes-long run stays readable.
constexpr double kLinePeriodSeconds = 5.0;
}  // namespace

ProgressReporter::ProgressReporter(std::string program, std::string label, Mode mode)
    : program_(std::move(program)), label_(std::move(label)), mode_(mode), start_(std::chrono::steady_clock::now()) {}

ProgressReporter::~ProgressReporter() { clear_bar(); }

double ProgressReporter::elapsed() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void ProgressReporter::clear_bar() {
  if (drawn_) std::fprintf(stderr, "\r\033[K");
  drawn_ = false;
}

void ProgressReporter::phase(const std::string& name) {
  phase_ = name;
  last_permille_ = -1;
  if (mode_ == Mode::Lines) {
    std::fprintf(stderr, "%s: %s: %s (%.1f s)\n", program_.c_str(), label_.c_str(), name.c_str(), elapsed());
    std::fflush(stderr);
    last_line_ = elapsed();
  } else if (mode_ == Mode::Bar) {
    update(0);
  }
}

void ProgressReporter::update(double fraction) {
  if (mode_ == Mode::None) return;
  const int permille = static_cast<int>(std::clamp(fraction, 0.0, 1.0) * 1000);
  if (permille == last_permille_) return;
  const double t = elapsed();
  if (mode_ == Mode::Lines) {
    if (t - last_line_ < kLinePeriodSeconds) return;
    last_permille_ = permille;
    last_line_ = t;
    std::fprintf(stderr, "%s: %s: %s %.1f%% (%.1f s)\n", program_.c_str(), label_.c_str(), phase_.c_str(),
                 permille / 10.0, t);
    std::fflush(stderr);
    return;
  }
  if (t < kBarDelaySeconds) return;
  last_permille_ = permille;
  constexpr int width = 30;
  const int filled = permille * width / 1000;
  std::fprintf(stderr, "\r%s %s [%.*s%*s] %5.1f%% %6.1fs", label_.c_str(), phase_.c_str(), filled,
               "##############################", width - filled, "", permille / 10.0, t);
  std::fflush(stderr);
  drawn_ = true;
}

}  // namespace cdp::app
