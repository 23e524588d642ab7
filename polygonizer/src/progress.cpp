#include <polygonizer/progress.h>

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace cdp {

ProgressBar::ProgressBar(std::string label, double delay_seconds)
    : label_(std::move(label)), enabled_(isatty(STDERR_FILENO) != 0), delay_(delay_seconds),
      start_(std::chrono::steady_clock::now()) {}

ProgressBar::~ProgressBar() {
  if (drawn_) std::fprintf(stderr, "\r\033[K");
}

void ProgressBar::update(double fraction) {
  if (!enabled_) return;
  const int permille = static_cast<int>(std::clamp(fraction, 0.0, 1.0) * 1000);
  if (permille == last_permille_) return;
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  if (elapsed < delay_) return;
  last_permille_ = permille;
  constexpr int width = 30;
  const int filled = permille * width / 1000;
  std::fprintf(stderr, "\r%s [%.*s%*s] %5.1f%% %6.1fs", label_.c_str(), filled, "##############################",
               width - filled, "", permille / 10.0, elapsed);
  std::fflush(stderr);
  drawn_ = true;
}

}  // namespace cdp
