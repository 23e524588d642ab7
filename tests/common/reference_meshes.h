// Meshes whose geometry is known in closed form, for tests, benchmarks and sanity checks of the
// metrics: an icosphere with exact normals and a regular tetrahedron.
#pragma once

#include <cdp/core/mesh.h>

namespace cdp {

// The icosahedron subdivided `subdivisions` times (20 * 4^s triangles), every vertex projected
// onto the sphere, normals exact (radial), triangles counter-clockwise seen from outside.
Mesh icosphere(int subdivisions, const Vec3& center = Vec3::Zero(), double radius = 1.0);

// Regular tetrahedron with unit edges centred at the origin, outward-oriented, face normals
// averaged at the vertices (radial).
Mesh regular_tetrahedron();

}  // namespace cdp
