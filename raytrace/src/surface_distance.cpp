#include <cdp/raytrace/surface_distance.h>

#include <cdp/core/errors.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace cdp {

namespace {
// A double in [0, 1) from the top 53 bits: the same on every platform, unlike the std distributions.
double unit(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }
}  // namespace

std::vector<Vec3> sample_mesh_surface(const Mesh& mesh, const SurfaceSamplingOptions& options) {
  std::vector<double> cdf;
  cdf.reserve(mesh.triangles.size());
  double total = 0.0;
  for (const auto& t : mesh.triangles) {
    const Vec3 &a = mesh.positions.at(t[0]), &b = mesh.positions.at(t[1]), &c = mesh.positions.at(t[2]);
    total += 0.5 * (b - a).cross(c - a).norm();
    cdf.push_back(total);
  }
  std::vector<Vec3> points;
  if (!(total > 0.0) || options.samples == 0) return points;
  points.reserve(options.samples);
  std::mt19937_64 rng(options.seed);
  for (std::size_t i = 0; i < options.samples; ++i) {
    const double x = unit(rng) * total;
    const auto it = std::upper_bound(cdf.begin(), cdf.end(), x);
    const std::size_t k = std::min<std::size_t>(static_cast<std::size_t>(it - cdf.begin()), cdf.size() - 1);
    const auto& t = mesh.triangles[k];
    // Uniform in the triangle: fold the unit square onto it.
    double r1 = unit(rng), r2 = unit(rng);
    if (r1 + r2 > 1.0) {
      r1 = 1.0 - r1;
      r2 = 1.0 - r2;
    }
    const Vec3& a = mesh.positions[t[0]];
    points.push_back(a + r1 * (mesh.positions[t[1]] - a) + r2 * (mesh.positions[t[2]] - a));
  }
  return points;
}

std::vector<double> first_order_distances(const Field& field, const std::vector<Vec3>& points) {
  std::vector<double> d(points.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 256), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      Vec3 g;
      const double f = field.value_gradient(points[i], g);
      const double n = g.norm();
      d[i] = n > 0.0 ? std::abs(f) / n : std::numeric_limits<double>::infinity();
    }
  });
  return d;
}

SampleStats vertex_distance(const Field& field, const Mesh& mesh) {
  return sample_stats(first_order_distances(field, mesh.positions));
}

SampleStats mesh_to_surface_distance(const Field& field, const Mesh& mesh, const SurfaceSamplingOptions& options) {
  return sample_stats(first_order_distances(field, sample_mesh_surface(mesh, options)));
}

SampleStats surface_to_mesh_distance(const GroundTruth& truth, const EmbreeScene& scene) {
  std::vector<Vec3> points;
  for (std::size_t i = 0; i < truth.hits.size(); ++i)
    if (truth.hits[i].hit()) points.push_back(truth.rays[i].origin + truth.hits[i].t * truth.rays[i].direction);
  std::vector<double> d;
  d.reserve(points.size());
  for (const ClosestPoint& c : scene.closest_points(points)) d.push_back(c.distance);
  return sample_stats(d);
}

}  // namespace cdp
