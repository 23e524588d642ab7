// Helpers shared by the self-intersection tests of the core (hash broad phase) and of raytrace
// (Embree broad phase): the reference count without any broad phase, and joining meshes.
#pragma once

#include <cdp/core/mesh.h>
#include <cdp/core/triangle_intersection.h>

#include <utility>
#include <vector>

namespace cdp::test {

using Pairs = std::vector<std::pair<int, int>>;

// Every pair f < g decided by the exact test, without a broad phase.
inline Pairs brute_force_pairs(const Mesh& mesh) {
  Pairs out;
  const int n = static_cast<int>(mesh.triangles.size());
  for (int f = 0; f < n; ++f)
    for (int g = f + 1; g < n; ++g)
      if (triangles_intersect(mesh, f, g)) out.emplace_back(f, g);
  return out;
}

// Both meshes in one, b's vertices after a's.
inline Mesh merged(const Mesh& a, const Mesh& b) {
  Mesh m = a;
  const int offset = static_cast<int>(a.positions.size());
  m.positions.insert(m.positions.end(), b.positions.begin(), b.positions.end());
  for (auto t : b.triangles) m.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  return m;
}

}  // namespace cdp::test
