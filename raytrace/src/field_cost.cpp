#include <cdp/raytrace/field_cost.h>

#include <algorithm>
#include <chrono>
#include <limits>
#include <vector>

namespace cdp {

namespace {

// The fastest of `repetitions` passes of `evaluate` over the points, per point.
template <class F>
double fastest_pass(const std::vector<Vec3>& points, int repetitions, F evaluate) {
  using Clock = std::chrono::steady_clock;
  double best = std::numeric_limits<double>::infinity();
  for (int r = 0; r < repetitions; ++r) {
    const auto start = Clock::now();
    for (const Vec3& p : points) {
      try {
        evaluate(p);
      } catch (const std::exception&) {
      }
    }
    best = std::min(best, std::chrono::duration<double>(Clock::now() - start).count());
  }
  return best / static_cast<double>(points.size());
}

}  // namespace

FieldCost measure_field_cost(const Field& field, const Mesh& mesh, const FieldCostOptions& options) {
  FieldCost cost;
  const std::size_t n = mesh.positions.size();
  if (n == 0 || options.max_points == 0) return cost;
  const std::size_t stride = (n + options.max_points - 1) / options.max_points;
  std::vector<Vec3> points;
  for (std::size_t i = 0; i < n; i += stride) points.push_back(mesh.positions[i]);
  const int reps = std::max(1, options.repetitions);
  // Results go to a volatile sink so that the calls are not optimized away.
  volatile double sink = 0;
  cost.value_seconds = fastest_pass(points, reps, [&](const Vec3& p) { sink = field.value(p); });
  cost.value_gradient_seconds = fastest_pass(points, reps, [&](const Vec3& p) {
    Vec3 g;
    sink = field.value_gradient(p, g);
  });
  cost.gradient_hessian_seconds = fastest_pass(points, reps, [&](const Vec3& p) {
    Vec3 g;
    Mat3 h;
    field.gradient_hessian(p, g, h);
    sink = h(0, 0);
  });
  (void)sink;
  cost.points = points.size();
  return cost;
}

}  // namespace cdp
