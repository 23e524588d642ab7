#include <cdp/raytrace/mesh_quality.h>

#include <cdp/core/errors.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace cdp {

MeshQuality compute_mesh_quality(const Mesh& mesh, const MeshQualityOptions& options) {
  MeshQuality q;
  q.triangles = mesh.num_triangles();
  q.vertices = mesh.num_vertices();
  q.near_equilateral_ratio = options.near_equilateral_ratio;
  q.histogram_edges = options.histogram_edges;
  if (q.histogram_edges.empty())
    for (int i = 0; i <= 20; ++i) q.histogram_edges.push_back(1.0 + 0.1 * i);
  if (q.histogram_edges.size() < 2 || !std::is_sorted(q.histogram_edges.begin(), q.histogram_edges.end()))
    throw InvalidInputError("mesh quality: histogram_edges must be at least two increasing numbers");
  q.histogram_counts.assign(q.histogram_edges.size() - 1, 0);
  const auto nv = static_cast<long long>(mesh.positions.size());
  for (const auto& t : mesh.triangles)
    for (int i : t)
      if (i < 0 || i >= nv) throw InvalidInputError("mesh quality: a triangle index is out of range");

  std::vector<double> ratios, min_angles, radius_ratios, lengths;
  std::size_t near_equilateral = 0;
  for (const auto& t : mesh.triangles) {
    const Vec3 &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
    const double la = (c - b).norm(), lb = (a - c).norm(), lc = (b - a).norm();  // opposite a, b, c
    const double area = 0.5 * (b - a).cross(c - a).norm();
    const double shortest = std::min({la, lb, lc}), longest = std::max({la, lb, lc});
    if (!(shortest > 0.0) || !(area > 0.0)) {
      ++q.degenerate;
      continue;
    }
    lengths.insert(lengths.end(), {la, lb, lc});
    const double ratio = longest / shortest;
    ratios.push_back(ratio);
    if (ratio <= options.near_equilateral_ratio) ++near_equilateral;
    const auto bin = std::upper_bound(q.histogram_edges.begin(), q.histogram_edges.end(), ratio);
    if (bin == q.histogram_edges.end()) ++q.histogram_overflow;
    else if (bin != q.histogram_edges.begin()) ++q.histogram_counts[static_cast<std::size_t>(bin - q.histogram_edges.begin() - 1)];
    // Corner angles from atan2(|cross|, dot): accurate for slivers too.
    auto angle = [](const Vec3& u, const Vec3& v) { return std::atan2(u.cross(v).norm(), u.dot(v)); };
    const double min_angle = std::min({angle(b - a, c - a), angle(c - b, a - b), angle(a - c, b - c)});
    min_angles.push_back(min_angle * 180.0 / std::numbers::pi);
    // 2 r_in / r_circ = 16 A^2 / (perimeter * la * lb * lc).
    radius_ratios.push_back(16.0 * area * area / ((la + lb + lc) * la * lb * lc));
  }
  q.share_thresholds = options.share_thresholds;
  for (const double t : q.share_thresholds) {
    const auto n = std::count_if(ratios.begin(), ratios.end(), [t](double r) { return r <= t; });
    q.shares_at_most.push_back(ratios.empty() ? 0.0 : static_cast<double>(n) / static_cast<double>(ratios.size()));
  }
  q.edge_ratio = sample_stats(ratios);
  q.near_equilateral_fraction = ratios.empty() ? 0.0 : static_cast<double>(near_equilateral) / static_cast<double>(ratios.size());
  q.min_angle_deg = sample_stats(min_angles);
  q.angles = angle_statistics(mesh);
  q.radius_ratio = sample_stats(radius_ratios);
  q.edge_length = sample_stats(lengths);
  q.topology = analyze_topology(mesh);
  return q;
}

}  // namespace cdp
