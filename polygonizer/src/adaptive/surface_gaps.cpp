#include "surface_gaps.h"

#include "spatial_hash.h"
#include "union_find.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <utility>

namespace cdp::adaptive {

namespace {

// Grid cells between the two ends of a facing pair in joined_by_surface. Two walls of a shell
// whose facing pair runs at a slant of up to 60 degrees to their normals are then at least four
// cells apart, which leaves cells without a sign change between their bands of crossed cells
// (each about a cell thick), so 26-neighbour filling cannot pass; the wall of a cut neck is one
// band from cap to cap. The pairs of a cut neck run along it, nearly tangent to the caps' rims
// (their ends' normals within 3-15 degrees of square to the segment on the fifty blobs at
// --tolerance 3e-2 and random blob field blobs19 at --factor 1).
constexpr double kJoinCellsPerGap = 8;
// Facing pairs tested for each two components. Shell walls face each other everywhere; a cut
// neck at a few places (the fifty blobs at --tolerance 3e-2: the first pair found is on it), and
// each grid test samples about 15,600 values (25^3 nodes).
constexpr int kJoinTestsPerComponentPair = 4;
// Cells along each axis of a test's grid: the box is at most three pair lengths wide, so 24 and
// rounding; the bound keeps the grid's size fixed whatever the arithmetic.
constexpr int kMaxJoinCells = 3 * static_cast<int>(kJoinCellsPerGap) + 1;

// A cap closing a front across a neck spans the neck's section: its centroid lies deep in the
// solid, 0.19-0.51 of its longest edge at the cuts found (the fifty blobs at --tolerance 3e-2,
// blobs19 of the topology sweep at factors 1 and 2). A triangle that follows the surface lies
// within about a sixth of its edge even at factor 1 (a chord as long as the radius of curvature):
// 0.07 beside the facing walls of a shell 0.05 thick, 0.11 between two spheres 1e-3 apart, whose
// grids (cells an eighth of the pair's length) cannot tell the walls apart.
constexpr double kCapDepth = 0.15;

// Samples of F along a facing pair's segment, and how far (a share of its deepest value) F may
// wiggle against the valley's slope before the segment counts as dipping twice (noise of a
// data-driven model's field is far below it).
constexpr int kSegmentSamples = 16;
constexpr double kValleySlack = 0.05;

}  // namespace

std::vector<FacingPair> facing_across_solid(const Field& field, const Mesh& mesh, int per_component_pair) {
  const std::size_t nv = mesh.positions.size();
  UnionFind sets(nv);
  std::vector<double> longest(nv, 0.0);  // each vertex's longest edge
  double cell = 0;
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      sets.unite(a, b);
      const double l = (mesh.positions[a] - mesh.positions[b]).norm();
      longest[a] = std::max(longest[a], l);
      longest[b] = std::max(longest[b], l);
      cell = std::max(cell, l);
    }
  std::vector<FacingPair> found;
  if (!(cell > 0) || per_component_pair <= 0) return found;
  SpatialHash hash(2 * cell);
  for (std::size_t v = 0; v < nv; ++v)
    if (longest[v] > 0) hash.insert(static_cast<int>(v), mesh.positions[v]);
  std::map<std::pair<int, int>, int> per_pair;  // (smaller root, larger root) -> pairs found
  for (std::size_t a = 0; a < nv; ++a) {
    if (!(longest[a] > 0)) continue;
    const Vec3& pa = mesh.positions[a];
    const double reach = 2 * longest[a];
    const int ra = sets.find(static_cast<int>(a));
    hash.for_each_near(pa, reach, [&](int b) {
      // The test is symmetric in a and b: each pair once.
      if (b <= static_cast<int>(a)) return;
      const int rb = sets.find(b);
      if (rb == ra) return;
      const std::pair<int, int> key{std::min(ra, rb), std::max(ra, rb)};
      if (const auto it = per_pair.find(key); it != per_pair.end() && it->second >= per_component_pair) return;
      const Vec3 d = mesh.positions[b] - pa;
      if (d.norm() > std::min(reach, 2 * longest[b]) || !(mesh.normals[a].dot(d) < 0) ||
          !(mesh.normals[b].dot(-d) < 0))
        return;
      // Inside all along, in one valley: F falls from one end and rises to the other. Two separate
      // solids have outside between them, or, closer than the samples, a ridge of F rising to
      // the gap (two spheres 1e-3 apart: a segment from one to the other dips twice).
      std::array<double, kSegmentSamples + 1> f{};
      for (int k = 1; k < kSegmentSamples; ++k) {
        f[k] = field.value(pa + (double(k) / kSegmentSamples) * d);
        if (!(f[k] < 0)) return;
      }
      const int low = static_cast<int>(std::min_element(f.begin() + 1, f.end() - 1) - f.begin());
      const double slack = kValleySlack * -f[low];
      for (int k = 1; k < low; ++k)
        if (f[k + 1] > f[k] + slack) return;
      for (int k = low; k + 1 < kSegmentSamples; ++k)
        if (f[k + 1] < f[k] - slack) return;
      ++per_pair[key];
      found.push_back({static_cast<int>(a), b});
    });
  }
  return found;
}

bool joined_by_surface(const Field& field, const Vec3& a, const Vec3& b) {
  const double distance = (b - a).norm();
  if (!(distance > 0)) return false;
  const double h = distance / kJoinCellsPerGap;
  const Box box = field.bounds();
  const Vec3 lo = (a.cwiseMin(b) - Vec3::Constant(distance)).cwiseMax(box.min);
  const Vec3 hi = (a.cwiseMax(b) + Vec3::Constant(distance)).cwiseMin(box.max);
  std::array<int, 3> n{};
  for (int k = 0; k < 3; ++k) {
    const double cells = std::ceil((hi[k] - lo[k]) / h);
    n[k] = std::clamp(static_cast<int>(std::isfinite(cells) ? cells : 1), 1, kMaxJoinCells);
  }
  const auto node = [&](int i, int j, int k) { return (static_cast<std::size_t>(k) * (n[1] + 1) + j) * (n[0] + 1) + i; };
  std::vector<Vec3> points;
  points.reserve(static_cast<std::size_t>(n[0] + 1) * (n[1] + 1) * (n[2] + 1));
  for (int k = 0; k <= n[2]; ++k)
    for (int j = 0; j <= n[1]; ++j)
      for (int i = 0; i <= n[0]; ++i) points.push_back(lo + h * Vec3(i, j, k));
  std::vector<double> values(points.size());
  field.values(points.data(), values.data(), points.size());
  const auto cell = [&](int i, int j, int k) { return (static_cast<std::size_t>(k) * n[1] + j) * n[0] + i; };
  std::vector<char> crossed(static_cast<std::size_t>(n[0]) * n[1] * n[2], 0);
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        int inside = 0;
        for (int c = 0; c < 8; ++c) inside += values[node(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2))] < 0;
        crossed[cell(i, j, k)] = inside > 0 && inside < 8;
      }
  const auto cell_of = [&](const Vec3& p) {
    std::array<int, 3> c{};
    for (int k = 0; k < 3; ++k) c[k] = std::clamp(static_cast<int>(std::floor((p[k] - lo[k]) / h)), 0, n[k] - 1);
    return c;
  };
  // Reached from a's cell; b's cell is the goal.
  std::vector<char> state(crossed.size(), 0);
  std::vector<std::array<int, 3>> stack;
  const auto around = [&](const std::array<int, 3>& c, auto&& fn) {
    for (int dk = -1; dk <= 1; ++dk)
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
          const std::array<int, 3> m{c[0] + di, c[1] + dj, c[2] + dk};
          if (m[0] < 0 || m[1] < 0 || m[2] < 0 || m[0] >= n[0] || m[1] >= n[1] || m[2] >= n[2]) continue;
          fn(m);
        }
  };
  const std::array<int, 3> ca = cell_of(a), cb = cell_of(b);
  const std::size_t goal = cell(cb[0], cb[1], cb[2]);
  if (crossed[cell(ca[0], ca[1], ca[2])]) {
    state[cell(ca[0], ca[1], ca[2])] = 1;
    stack.push_back(ca);
  }
  // The walk visits each cell once: bounded by the grid's size.
  while (!stack.empty()) {
    const std::array<int, 3> c = stack.back();
    stack.pop_back();
    if (cell(c[0], c[1], c[2]) == goal) return true;
    around(c, [&](const std::array<int, 3>& m) {
      const std::size_t id = cell(m[0], m[1], m[2]);
      if (crossed[id] && !state[id]) {
        state[id] = 1;
        stack.push_back(m);
      }
    });
  }
  return false;
}

double deepest_triangle_near(const Field& field, const Mesh& mesh, const Vec3& center, double radius) {
  double deepest = 0;
  for (const auto& t : mesh.triangles) {
    const Vec3 &p = mesh.positions[t[0]], &q = mesh.positions[t[1]], &r = mesh.positions[t[2]];
    const Vec3 c = (p + q + r) / 3;
    if ((c - center).norm() > radius) continue;
    Vec3 g;
    const double f = field.value_gradient(c, g);
    const double edge = std::max({(q - p).norm(), (r - q).norm(), (p - r).norm()});
    if (g.squaredNorm() > 0 && edge > 0) deepest = std::max(deepest, std::abs(f) / g.norm() / edge);
  }
  return deepest;
}

std::optional<Vec3> uncovered_between_components(const Field& field, const Mesh& mesh) {
  for (const FacingPair& p : facing_across_solid(field, mesh, kJoinTestsPerComponentPair)) {
    const Vec3 &a = mesh.positions[p.a], &b = mesh.positions[p.b];
    const Vec3 mid = 0.5 * (a + b);
    // The cap first: a few evaluations where the grid costs thousands, and a shell's facing walls
    // (the common pair) have none.
    if (deepest_triangle_near(field, mesh, mid, (b - a).norm()) > kCapDepth && joined_by_surface(field, a, b))
      return mid;
  }
  return std::nullopt;
}

}  // namespace cdp::adaptive
