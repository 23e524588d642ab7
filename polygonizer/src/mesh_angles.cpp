#include <cdp/core/mesh_angles.h>
#include <cdp/core/polygonize_stats.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace cdp {
namespace {

// The smallest corner angle of triangle (a, b, c) in degrees, each from atan2(|cross|, dot):
// accurate for slivers too.
double smallest_angle_degrees(const Vec3& a, const Vec3& b, const Vec3& c) {
  const auto angle = [](const Vec3& u, const Vec3& v) { return std::atan2(u.cross(v).norm(), u.dot(v)); };
  return std::min({angle(b - a, c - a), angle(c - b, a - b), angle(a - c, b - c)}) * 180 / std::numbers::pi;
}

}  // namespace

AngleStatistics angle_statistics(const Mesh& mesh) {
  constexpr int kBins = 60;
  AngleStatistics s;
  std::vector<long long> per_degree(kBins, 0);
  double min_deg = 180, sum_min = 0, sum_ratio = 0;
  std::size_t under[3] = {0, 0, 0};
  for (const auto& t : mesh.triangles) {
    const Vec3 &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
    const double la = (b - c).norm(), lb = (c - a).norm(), lc = (a - b).norm();
    const double shortest = std::min({la, lb, lc});
    const double area2 = (b - a).cross(c - a).norm();
    if (!(shortest > 0) || !(area2 > 0)) {
      ++s.degenerate;
      continue;
    }
    const double m = smallest_angle_degrees(a, b, c);
    ++s.triangles;
    min_deg = std::min(min_deg, m);
    sum_min += m;
    sum_ratio += std::max({la, lb, lc}) / shortest;
    if (m < 10) ++under[0];
    if (m < 20) ++under[1];
    if (m < 30) ++under[2];
    ++per_degree[std::clamp(static_cast<int>(std::floor(m)), 0, kBins - 1)];
  }
  s.below.assign(kBins, 0);
  long long running = 0;
  for (int k = 0; k < kBins; ++k) s.below[k] = running += per_degree[k];
  if (s.triangles == 0) return s;
  const double n = static_cast<double>(s.triangles);
  s.min_degrees = min_deg;
  s.mean_min_degrees = sum_min / n;
  s.mean_edge_ratio = sum_ratio / n;
  s.share_under_10 = under[0] / n;
  s.share_under_20 = under[1] / n;
  s.share_under_30 = under[2] / n;
  return s;
}

CreaseAngles crease_angles(const Field& field, const Mesh& mesh, double near) {
  if (!(near > 0)) near = 1e-6 * field.bounds().diagonal();
  CreaseAngles r;
  std::vector<char> on_crease(mesh.positions.size(), 0);
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    on_crease[v] = field.pieces(mesh.positions[v], near).size() > 1;
    r.crease_vertices += static_cast<std::size_t>(on_crease[v]);
  }
  for (const auto& t : mesh.triangles) {
    const Vec3 &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
    const double m = smallest_angle_degrees(a, b, c);
    if (on_crease[t[0]] || on_crease[t[1]] || on_crease[t[2]]) {
      ++r.triangles_at_creases;
      r.min_degrees_at_creases = std::min(r.min_degrees_at_creases, m);
    } else {
      ++r.triangles_away;
      if (m < r.min_degrees_away) r.min_degrees_away = m, r.worst_away = (a + b + c) / 3;
    }
  }
  return r;
}

void add_angle_statistics(const Mesh& mesh, PolygonizeStats& stats) { stats.angles = angle_statistics(mesh); }

void add_mesh_summary(const Mesh& mesh, PolygonizeStats& stats) {
  add_angle_statistics(mesh, stats);
  stats.topology = analyze_topology(mesh);
}

}  // namespace cdp
