// Generates the Marching Cubes table from the rule stated in cube_cases.h.
#include <cdp/baselines/cube_cases.h>

#include "lattice_mesher.h"

#include <cdp/core/field.h>

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

namespace cdp {

namespace {

using marching::corner_position;

Vec3 edge_midpoint(int e) { return 0.5 * (corner_position(kCubeEdges[e][0]) + corner_position(kCubeEdges[e][1])); }

Vec3 face_normal(int f) {
  Vec3 n = Vec3::Zero();
  n[f / 2] = f % 2 == 0 ? -1 : 1;
  return n;
}

bool is_inside(std::uint8_t inside, int corner) { return (inside >> corner) & 1; }

int edge_between(int a, int b) {
  for (int e = 0; e < 12; ++e)
    if ((kCubeEdges[e][0] == a && kCubeEdges[e][1] == b) || (kCubeEdges[e][0] == b && kCubeEdges[e][1] == a)) return e;
  return -1;
}

bool edge_on_face(int e, int f) {
  const auto& c = kCubeFaces[f];
  return std::count(c.begin(), c.end(), kCubeEdges[e][0]) && std::count(c.begin(), c.end(), kCubeEdges[e][1]);
}

// A diagonal joining two edges of a face lies in that face, where the cube across it could draw
// it too. Only the cube on the face's lower side (the face is its side-1 face) may draw it.
bool diagonal_allowed(int a, int b) {
  for (int f = 0; f < 6; ++f)
    if (edge_on_face(a, f) && edge_on_face(b, f)) return f % 2 == 1;
  return true;
}

// The face's edges in cyclic order around it: (0,1), (1,3), (3,2), (2,0) in face-local corners.
std::array<int, 4> face_cycle_edges(int f) {
  const auto& c = kCubeFaces[f];
  return {edge_between(c[0], c[1]), edge_between(c[1], c[3]), edge_between(c[3], c[2]), edge_between(c[2], c[0])};
}

// Triangulation of a polygon (cycle of edges) minimizing the total diagonal length among those
// whose diagonals are allowed; failing that, a fan around the polygon's centre vertex.
std::vector<std::array<int, 3>> triangulate(const std::vector<int>& poly, int centre) {
  const int n = static_cast<int>(poly.size());
  if (n == 3) return {{poly[0], poly[1], poly[2]}};
  constexpr double inf = std::numeric_limits<double>::infinity();
  // cost of chord (i, j): 0 for polygon sides, length for allowed diagonals, inf otherwise.
  const auto chord = [&](int i, int j) {
    if (j == i + 1 || (i == 0 && j == n - 1)) return 0.0;
    if (!diagonal_allowed(poly[i], poly[j])) return inf;
    return (edge_midpoint(poly[i]) - edge_midpoint(poly[j])).norm();
  };
  std::vector<std::vector<double>> best(n, std::vector<double>(n, inf));
  std::vector<std::vector<int>> split(n, std::vector<int>(n, -1));
  for (int i = 0; i + 1 < n; ++i) best[i][i + 1] = 0;
  for (int len = 2; len < n; ++len)
    for (int i = 0; i + len < n; ++i) {
      const int j = i + len;
      const double cij = chord(i, j);
      if (cij == inf) continue;
      for (int k = i + 1; k < j; ++k) {
        const double c = best[i][k] + best[k][j] + cij;
        if (c < best[i][j]) best[i][j] = c, split[i][j] = k;
      }
    }
  std::vector<std::array<int, 3>> tris;
  if (best[0][n - 1] == inf) {
    for (int i = 0; i < n; ++i) tris.push_back({poly[i], poly[(i + 1) % n], centre});
    return tris;
  }
  std::vector<std::pair<int, int>> stack{{0, n - 1}};
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    if (j - i < 2) continue;
    const int k = split[i][j];
    tris.push_back({poly[i], poly[k], poly[j]});  // cycle order, so orientation is kept
    stack.push_back({i, k});
    stack.push_back({k, j});
  }
  return tris;
}

CubeCase generate(std::uint8_t inside, std::uint8_t join) {
  const int case_id = inside * 64 + join;
  std::array<int, 12> next;
  next.fill(-1);
  for (int f = 0; f < 6; ++f) {
    const auto& c = kCubeFaces[f];
    const auto cyc = face_cycle_edges(f);
    std::vector<std::pair<int, int>> segments;
    if (face_is_ambiguous(inside, f)) {
      // Cut off the corners of the side that is not joined: each such corner's two face edges.
      const bool cut_inside = !((join >> f) & 1);
      for (int corner : c) {
        if (is_inside(inside, corner) != cut_inside) continue;
        std::vector<int> around;
        for (int e : cyc)
          if (kCubeEdges[e][0] == corner || kCubeEdges[e][1] == corner) around.push_back(e);
        segments.push_back({around[0], around[1]});
      }
    } else {
      std::vector<int> crossed;
      for (int e : cyc)
        if (is_inside(inside, kCubeEdges[e][0]) != is_inside(inside, kCubeEdges[e][1])) crossed.push_back(e);
      if (crossed.size() == 2) segments.push_back({crossed[0], crossed[1]});
      else if (!crossed.empty()) throw std::logic_error("cube case: odd crossing count on a face");
    }
    for (auto [a, b] : segments) {
      const int out_a = is_inside(inside, kCubeEdges[a][0]) ? kCubeEdges[a][1] : kCubeEdges[a][0];
      const Vec3 ma = edge_midpoint(a), mb = edge_midpoint(b);
      if (face_normal(f).cross(mb - ma).dot(corner_position(out_a) - ma) < 0) std::swap(a, b);
      if (next[a] != -1)
        throw std::logic_error("cube case " + std::to_string(case_id) + ": edge " + std::to_string(a) +
                               " leaves on two faces");
      next[a] = b;
    }
  }
  CubeCase out;
  std::array<bool, 12> used{};
  for (int start = 0; start < 12; ++start) {
    if (next[start] == -1 || used[start]) continue;
    std::vector<int> poly;
    for (int e = start; !used[e]; e = next[e]) {
      if (next[e] == -1) throw std::logic_error("cube case " + std::to_string(case_id) + ": open polygon");
      used[e] = true;
      poly.push_back(e);
    }
    if (poly.front() != start || next[poly.back()] != start)
      throw std::logic_error("cube case " + std::to_string(case_id) + ": polygons do not close");
    const int centre = kCubeCentreVertex + static_cast<int>(out.polygons.size());
    for (const auto& t : triangulate(poly, centre)) out.triangles.push_back(t);
    out.polygons.push_back(std::move(poly));
  }
  return out;
}

std::vector<CubeCase> generate_all() {
  std::vector<CubeCase> table(256 * 64);
  for (int inside = 0; inside < 256; ++inside) {
    for (int join = 0; join < 64; ++join) {
      std::uint8_t canonical = 0;  // decisions on unambiguous faces do not matter: share entries
      for (int f = 0; f < 6; ++f)
        if (face_is_ambiguous(inside, f)) canonical |= join & (1 << f);
      if (canonical != join) {
        table[inside * 64 + join] = table[inside * 64 + canonical];
        continue;
      }
      table[inside * 64 + join] = generate(static_cast<std::uint8_t>(inside), static_cast<std::uint8_t>(join));
    }
  }
  return table;
}

}  // namespace

bool face_is_ambiguous(std::uint8_t inside, int face) {
  const auto& c = kCubeFaces[face];
  const bool a = is_inside(inside, c[0]), b = is_inside(inside, c[1]);
  return a == is_inside(inside, c[3]) && b == is_inside(inside, c[2]) && a != b;
}

const CubeCase& cube_case(std::uint8_t inside, std::uint8_t join) {
  static const std::vector<CubeCase> table = generate_all();
  return table[inside * 64 + (join & 63)];
}

}  // namespace cdp
