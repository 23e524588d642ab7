// A progress bar on standard error, drawn only when stderr is an interactive terminal and the
// run has lasted long enough to be worth one. Algorithms take a ProgressCallback in their
// options and call it with a fraction in [0, 1]; the apps connect it to a ProgressBar.
#pragma once

#include <chrono>
#include <functional>
#include <string>

namespace cdp {

using ProgressCallback = std::function<void(double fraction)>;

class ProgressBar {
 public:
  explicit ProgressBar(std::string label, double delay_seconds = 0.5);
  ~ProgressBar();  // clears the line if it drew anything
  void update(double fraction);
  ProgressCallback callback() {
    return [this](double f) { update(f); };
  }

 private:
  std::string label_;
  bool enabled_;
  bool drawn_ = false;
  int last_permille_ = -1;
  double delay_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace cdp
