// Independent checks of polygonizer output used by the polygonizer tests: a reference topology
// from a simple marching-tetrahedra polygonization, the self-intersection count of
// <cdp/raytrace/self_intersection.h>, distances to the surface, triangle shape statistics, and
// expect_sound (the checks every output mesh must pass); expect_phases_add_up (the adaptive
// method's stats "phases" against its totals).
#pragma once

#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/field.h>
#include <cdp/core/mesh.h>
#include <cdp/core/mesh_topology.h>
#include <cdp/raytrace/self_intersection.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

namespace cdp::test {

// Marching tetrahedra on an n-cell grid over the field's box (Freudenthal split of each cube
// into six tetrahedra around its main diagonal, so neighbouring cubes agree). Only the
// topology is used: components and genus of a sufficiently fine sampling of the surface.
inline Mesh marching_tetrahedra_reference(const Field& field, int n) {
  const Box box = field.bounds();
  const Vec3 h = box.size() / n;
  const int m = n + 1;
  std::vector<Vec3> pts;
  pts.reserve(static_cast<std::size_t>(m) * m * m);
  for (int k = 0; k < m; ++k)
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i) pts.push_back(box.min + Vec3(i * h.x(), j * h.y(), k * h.z()));
  std::vector<double> f(pts.size());
  field.values(pts.data(), f.data(), pts.size());
  const auto id = [&](int i, int j, int k) { return (static_cast<long>(k) * m + j) * m + i; };
  Mesh mesh;
  std::unordered_map<long long, int> edge_vertex;
  const auto crossing = [&](long a, long b) {
    if (a > b) std::swap(a, b);
    const long long key = a * static_cast<long long>(pts.size()) + b;
    auto it = edge_vertex.find(key);
    if (it != edge_vertex.end()) return it->second;
    const double t = f[a] / (f[a] - f[b]);
    mesh.positions.push_back(pts[a] + t * (pts[b] - pts[a]));
    edge_vertex.emplace(key, static_cast<int>(mesh.positions.size()) - 1);
    return static_cast<int>(mesh.positions.size()) - 1;
  };
  static const int tets[6][4] = {{0, 1, 3, 7}, {0, 3, 2, 7}, {0, 2, 6, 7}, {0, 6, 4, 7}, {0, 4, 5, 7}, {0, 5, 1, 7}};
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        long corner[8];
        for (int c = 0; c < 8; ++c) corner[c] = id(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
        for (const auto& tet : tets) {
          std::vector<long> in, out;
          for (int c : tet) (f[corner[c]] < 0 ? in : out).push_back(corner[c]);
          if (in.empty() || out.empty()) continue;
          Vec3 cin = Vec3::Zero(), cout = Vec3::Zero();
          for (long v : in) cin += pts[v] / in.size();
          for (long v : out) cout += pts[v] / out.size();
          // Orientation from edge midpoints, which never degenerate, outward = towards `out`.
          const auto emit = [&](std::array<std::pair<long, long>, 3> e) {
            Vec3 mid[3];
            int v[3];
            for (int q = 0; q < 3; ++q) {
              mid[q] = 0.5 * (pts[e[q].first] + pts[e[q].second]);
              v[q] = crossing(e[q].first, e[q].second);
            }
            if ((mid[1] - mid[0]).cross(mid[2] - mid[0]).dot(cout - cin) < 0) std::swap(v[1], v[2]);
            mesh.triangles.push_back({v[0], v[1], v[2]});
          };
          if (in.size() == 1) emit({{{in[0], out[0]}, {in[0], out[1]}, {in[0], out[2]}}});
          else if (in.size() == 3) emit({{{out[0], in[0]}, {out[0], in[1]}, {out[0], in[2]}}});
          else {
            emit({{{in[0], out[0]}, {in[0], out[1]}, {in[1], out[1]}}});
            emit({{{in[0], out[0]}, {in[1], out[1]}, {in[1], out[0]}}});
          }
        }
      }
  return mesh;
}

// Pairs of triangles that meet anywhere other than at the vertices or the edge they share
// (exact test, Embree broad phase: <cdp/raytrace/self_intersection.h>, whose rules apply).
inline std::size_t count_self_intersections(const Mesh& mesh) { return find_self_intersections(mesh).pairs; }

// The phases of an adaptive run (stats "phases", kAdaptivePhases): their field calls add up to
// the run's exactly, their seconds to at most its seconds and to nearly all of them (between
// runs only a discarded run's stats and the bounds a re-run is judged by are left out: far
// under kUncoveredShare of any run the tests make).
inline void expect_phases_add_up(const PolygonizeResult& r, const std::string& what) {
  constexpr double kUncoveredShare = 0.5;
  EvaluationCounts sum;
  double seconds = 0;
  for (const std::string_view name : kAdaptivePhases) {
    const PhaseReport& p = r.stats.adaptive->phase(name);
    sum += p.evaluations;
    seconds += p.seconds;
  }
  EXPECT_EQ(sum.value, r.stats.field_evaluations.value) << what;
  EXPECT_EQ(sum.value_gradient, r.stats.field_evaluations.value_gradient) << what;
  EXPECT_EQ(sum.gradient_hessian, r.stats.field_evaluations.gradient_hessian) << what;
  EXPECT_LE(seconds, r.stats.seconds) << what;
  EXPECT_GT(seconds, (1 - kUncoveredShare) * r.stats.seconds) << what;
}

// Largest first-order distance |F| / |grad F| of a mesh vertex to the surface.
inline double max_surface_distance(const Field& field, const Mesh& mesh) {
  double worst = 0;
  for (const Vec3& p : mesh.positions) {
    Vec3 g;
    const double v = field.value_gradient(p, g);
    worst = std::max(worst, std::abs(v) / g.norm());
  }
  return worst;
}

struct ShapeStats {
  double mean_ratio = 0;   // longest / shortest edge, averaged over triangles
  double std_ratio = 0;
  double min_angle_degrees = 180;
  double thin_fraction = 0;  // share of triangles with an angle under 10 degrees
};

inline ShapeStats shape_stats(const Mesh& mesh) {
  ShapeStats s;
  double sum = 0, sum2 = 0;
  std::size_t thin = 0;
  for (const auto& t : mesh.triangles) {
    double e[3];
    double smallest = 180;
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = mesh.positions[t[k]];
      const Vec3 u = mesh.positions[t[(k + 1) % 3]] - p, v = mesh.positions[t[(k + 2) % 3]] - p;
      e[k] = u.norm();
      smallest = std::min(smallest, std::atan2(u.cross(v).norm(), u.dot(v)) * 180 / M_PI);
    }
    s.min_angle_degrees = std::min(s.min_angle_degrees, smallest);
    if (smallest < 10) ++thin;
    const double r = *std::max_element(e, e + 3) / *std::min_element(e, e + 3);
    sum += r;
    sum2 += r * r;
  }
  const double n = std::max<std::size_t>(1, mesh.triangles.size());
  s.mean_ratio = sum / n;
  s.thin_fraction = thin / n;
  s.std_ratio = std::sqrt(std::max(0.0, sum2 / n - s.mean_ratio * s.mean_ratio));
  return s;
}

// Components and genus of a field's surface from marching tetrahedra at 56 and 72 cells, and
// whether the two grids agree (a reference is trusted only then); computed once per name.
struct MarchingReference {
  int components, genus;
  bool stable;
};
inline MarchingReference marching_reference(const std::string& name, const Field& field) {
  static std::map<std::string, MarchingReference> cache;
  if (const auto it = cache.find(name); it != cache.end()) return it->second;
  const MeshTopology a = analyze_topology(marching_tetrahedra_reference(field, 56));
  const MeshTopology b = analyze_topology(marching_tetrahedra_reference(field, 72));
  return cache[name] = {static_cast<int>(a.components), a.genus, a.components == b.components && a.genus == b.genus};
}

// A mesh a polygonizer may hand out: closed, edge- and vertex-manifold, oriented, outward
// (positive volume), free of self-intersections.
inline void expect_sound(const Mesh& mesh, const std::string& what) {
  const MeshTopology t = analyze_topology(mesh);
  EXPECT_TRUE(t.closed()) << what;
  EXPECT_TRUE(t.edge_manifold()) << what;
  EXPECT_TRUE(t.vertex_manifold()) << what;
  EXPECT_TRUE(t.oriented()) << what;
  EXPECT_GT(t.signed_volume, 0.0) << what;
  EXPECT_EQ(count_self_intersections(mesh), 0u) << what;
}

}  // namespace cdp::test
