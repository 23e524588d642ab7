// Runs a command-line program of build/bin for the app tests: exit code, stdout and stderr.
#pragma once

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace cdp::test {

struct CommandResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

inline CommandResult run_shell(const std::string& command);

// `args` is passed to /bin/sh after the program path; quote what needs quoting.
inline CommandResult run_app(const std::string& program, const std::string& args) {
  return run_shell(std::string(CDP_BIN_DIR) + "/" + program + " " + args);
}

// A fresh temporary folder, removed when the object goes.
struct TempDir {
  std::filesystem::path path;
  explicit TempDir(const std::string& name) {
    path = std::filesystem::temp_directory_path() / ("cdp_" + name + "_" + std::to_string(getpid()));
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~TempDir() { std::filesystem::remove_all(path); }
  std::filesystem::path write(const std::string& file, const std::string& text) const {
    std::ofstream(path / file) << text;
    return path / file;
  }
};

}  // namespace cdp::test

namespace cdp::test {

// Runs a whole shell command line (run_app, and what it cannot say: a `ulimit` before the
// program): exit code, stdout, and stderr through a temporary file.
inline CommandResult run_shell(const std::string& command) {
  static int counter = 0;
  const auto err_path = std::filesystem::temp_directory_path() /
                        ("cdp_shell_stderr_" + std::to_string(getpid()) + "_" + std::to_string(counter++));
  CommandResult r;
  FILE* pipe = popen(("(" + command + ") 2>" + err_path.string()).c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf{};
  std::size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) r.out.append(buf.data(), n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(err_path);
  std::stringstream ss;
  ss << in.rdbuf();
  r.err = ss.str();
  std::filesystem::remove(err_path);
  return r;
}

// The program path for a build/bin program.
inline std::string bin(const std::string& program) { return std::string(CDP_BIN_DIR) + "/" + program; }

}  // namespace cdp::test
