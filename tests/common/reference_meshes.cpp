#include "common/reference_meshes.h"

#include <cdp/core/errors.h>

#include <cmath>
#include <map>
#include <utility>

namespace cdp {

Mesh icosphere(int subdivisions, const Vec3& center, double radius) {
  if (subdivisions < 0 || subdivisions > 10) throw InvalidInputError("icosphere: subdivisions must be in [0, 10]");
  if (!(radius > 0.0)) throw InvalidInputError("icosphere: radius must be positive");
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> unit = {{-1, g, 0}, {1, g, 0},  {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                            {0, -1, -g}, {0, 1, -g}, {g, 0, -1},  {g, 0, 1},  {-g, 0, -1}, {-g, 0, 1}};
  for (Vec3& p : unit) p.normalize();
  std::vector<std::array<int, 3>> tris = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                          {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                          {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                          {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> midpoints;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto [it, inserted] = midpoints.try_emplace(key, static_cast<int>(unit.size()));
      if (inserted) unit.push_back((unit[a] + unit[b]).normalized());
      return it->second;
    };
    std::vector<std::array<int, 3>> next;
    next.reserve(tris.size() * 4);
    for (const auto& t : tris) {
      const int ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]), ca = midpoint(t[2], t[0]);
      next.push_back({t[0], ab, ca});
      next.push_back({t[1], bc, ab});
      next.push_back({t[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    tris = std::move(next);
  }
  Mesh mesh;
  mesh.triangles = std::move(tris);
  mesh.normals = unit;
  mesh.positions.reserve(unit.size());
  for (const Vec3& n : unit) mesh.positions.push_back(center + radius * n);
  return mesh;
}

Mesh regular_tetrahedron() {
  // Alternate corners of a cube have equal pairwise distances 2 sqrt(2); scale to unit edges.
  const double s = 1.0 / (2.0 * std::sqrt(2.0));
  Mesh mesh;
  mesh.positions = {Vec3(1, 1, 1) * s, Vec3(1, -1, -1) * s, Vec3(-1, 1, -1) * s, Vec3(-1, -1, 1) * s};
  mesh.triangles = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
  for (const Vec3& p : mesh.positions) mesh.normals.push_back(p.normalized());
  return mesh;
}

}  // namespace cdp
