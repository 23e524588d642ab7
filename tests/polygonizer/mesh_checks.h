// Independent checks of polygonizer output used by the polygonizer tests: a reference topology
// from a simple marching-tetrahedra polygonization, a hashed triangle-triangle intersection
// test, distances to the surface and triangle shape statistics.
#pragma once

#include <polygonizer/field.h>
#include <polygonizer/mesh.h>
#include <polygonizer/mesh_topology.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
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

// Whether segment [p, q] passes through the interior of triangle (a, b, c), with margins so
// that touching at shared points does not count.
inline bool segment_hits_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 d = q - p, e1 = b - a, e2 = c - a;
  const Vec3 s = d.cross(e2);
  const double det = e1.dot(s);
  const double scale = e1.norm() * e2.norm() * d.norm();
  if (std::abs(det) <= 1e-12 * scale) return false;  // parallel or degenerate: not counted
  const Vec3 o = p - a;
  const double u = o.dot(s) / det;
  const Vec3 r = o.cross(e1);
  const double v = d.dot(r) / det;
  const double t = e2.dot(r) / det;
  constexpr double eps = 1e-7;
  return t > eps && t < 1 - eps && u > eps && v > eps && u + v < 1 - eps;
}

// Pairs of triangles that cross each other (not counting neighbours sharing an edge), found
// through a hash grid of triangle bounding boxes.
inline std::size_t count_self_intersections(const Mesh& mesh) {
  const auto& P = mesh.positions;
  double mean_edge = 0;
  for (const auto& t : mesh.triangles) mean_edge += (P[t[0]] - P[t[1]]).norm();
  mean_edge /= std::max<std::size_t>(1, mesh.triangles.size());
  const double cell = std::max(mean_edge, 1e-12);
  std::map<std::array<long, 3>, std::vector<int>> grid;
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const auto& t = mesh.triangles[f];
    Vec3 lo = P[t[0]].cwiseMin(P[t[1]]).cwiseMin(P[t[2]]), hi = P[t[0]].cwiseMax(P[t[1]]).cwiseMax(P[t[2]]);
    for (long k = std::floor(lo.z() / cell); k <= std::floor(hi.z() / cell); ++k)
      for (long j = std::floor(lo.y() / cell); j <= std::floor(hi.y() / cell); ++j)
        for (long i = std::floor(lo.x() / cell); i <= std::floor(hi.x() / cell); ++i)
          grid[{i, j, k}].push_back(static_cast<int>(f));
  }
  std::set<std::pair<int, int>> hits;
  for (const auto& [key, faces] : grid)
    for (std::size_t x = 0; x < faces.size(); ++x)
      for (std::size_t y = x + 1; y < faces.size(); ++y) {
        const int f = std::min(faces[x], faces[y]), g = std::max(faces[x], faces[y]);
        const auto& A = mesh.triangles[f];
        const auto& B = mesh.triangles[g];
        int shared = 0;
        for (int a : A)
          for (int b : B) shared += a == b;
        if (shared >= 2) continue;
        bool hit = false;
        for (int e = 0; e < 3 && !hit; ++e) {
          const int a0 = A[e], a1 = A[(e + 1) % 3], b0 = B[e], b1 = B[(e + 1) % 3];
          const bool a_touches = std::count(B.begin(), B.end(), a0) || std::count(B.begin(), B.end(), a1);
          const bool b_touches = std::count(A.begin(), A.end(), b0) || std::count(A.begin(), A.end(), b1);
          if (!a_touches && segment_hits_triangle(P[a0], P[a1], P[B[0]], P[B[1]], P[B[2]])) hit = true;
          if (!b_touches && segment_hits_triangle(P[b0], P[b1], P[A[0]], P[A[1]], P[A[2]])) hit = true;
        }
        if (hit) hits.insert({f, g});
      }
  return hits.size();
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

}  // namespace cdp::test
