#include "triangle_count.h"

#include <cmath>
#include <numbers>

namespace cdp::adaptive {

int triangle_count(TriangleCountRule rule, double theta, double neighbour_distance, double delta) {
  const double x = 3.0 * theta / std::numbers::pi;
  if (rule == TriangleCountRule::PaperFloor) return static_cast<int>(std::floor(x));
  int n = static_cast<int>(x) + 1;
  const double per = theta / n;
  if (per < 0.8 && n > 1) --n;
  else if (n == 1 && per > 0.8 && neighbour_distance > 1.2 * delta) n = 2;
  return n;
}

}  // namespace cdp::adaptive
