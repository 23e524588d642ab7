#include "stage_seed_grid.h"

#include <cdp/core/curvature.h>
#include <cdp/core/errors.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace cdp::adaptive {

namespace {

double area_of_crossings(std::size_t crossings, double h) {
  return crossings >= kMeasuredCrossings ? static_cast<double>(crossings) * h * h / kMeanCrossings : 0.0;
}

}  // namespace

double measured_area(const SeedGrid& grid) {
  std::size_t n = 0;
  grid.for_each_sign_change([&](const std::array<int, 3>&, const std::array<int, 3>&) { ++n; });
  return area_of_crossings(n, grid.h);
}

SeedGridStage sample_seed_grid_stage(const Field& field, const AdaptiveOptions& options, const Settings& settings) {
  SeedOptions seed_options;
  seed_options.resolution = options.seed_resolution;
  seed_options.threads = options.threads;
  SeedGridStage out{sample_seed_grid(field, seed_options)};
  const SeedGrid& grid = out.grid;
  std::vector<Vec3> points;
  grid.for_each_sign_change([&](const std::array<int, 3>& a, const std::array<int, 3>& b) {
    const double fa = grid.value(a[0], a[1], a[2]), fb = grid.value(b[0], b[1], b[2]);
    const Vec3 pa = grid.point(a[0], a[1], a[2]);
    points.push_back(pa + fa / (fa - fb) * (grid.point(b[0], b[1], b[2]) - pa));
  });
  out.crossings = points.size();
  out.estimated_area = area_of_crossings(out.crossings, grid.h);
  std::vector<double> lengths;
  const std::size_t stride = std::max<std::size_t>(1, points.size() / 64);
  for (std::size_t i = 0; i < points.size(); i += stride) {
    try {
      lengths.push_back(edge_length(settings.sizing, curvature_at(field, points[i]).min_radius));
    } catch (const NoSurfaceError&) {
    }
  }
  out.hash_cell = settings.hash_cell;
  if (!lengths.empty() && out.estimated_area > 0) {
    // Triangles of side e cover sqrt(3)/4 e^2 each: the area times the mean of one over that.
    // The meshes of the experiments' fields have 1.05-2.2 times as many (the sample misses some
    // of the finest regions: the Igea VIS-4004 at factor 3 has 2.2 times, the torus at factor 40
    // 1.07); the median edge's estimate, 1.07-7.7 times.
    double inverse_area = 0;
    for (const double e : lengths) inverse_area += 1 / (0.25 * std::sqrt(3.0) * e * e);
    out.estimated_triangles = out.estimated_area * inverse_area / static_cast<double>(lengths.size());
  }
  if (!lengths.empty()) {
    std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
    out.hash_cell = 2 * lengths[lengths.size() / 2];
  }
  return out;
}

}  // namespace cdp::adaptive
