// The machinery Marching Cubes and Marching Tetrahedra share: the lattice, the cached corner
// values, the two traversals, the welded edge vertices and the statistics. A method only says
// how one cube with given corner values is cut into triangles.
#pragma once

#include <cdp/baselines/marching_options.h>

#include <cdp/core/polygonize_result.h>

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace cdp::marching {

// A lattice edge seen from one cube: corners a and b (numbered as in cube_cases.h) with b's
// offset at least a's in every coordinate, so the edge has one name shared by all its cubes.
// With a == kCentre it stands instead for an extra vertex, private to the cube, at the centre of
// the polygon CubeMesh::centres[b].
struct LocalEdge {
  std::uint8_t a = 0, b = 0;
};
inline constexpr std::uint8_t kCentre = 255;
using CubeTriangle = std::array<LocalEdge, 3>;  // counter-clockwise seen from outside

// Corner c of the unit cube at its offset (c & 1, (c >> 1) & 1, (c >> 2) & 1), numbered as in
// cube_cases.h.
inline Vec3 corner_position(int c) { return Vec3(c & 1, (c >> 1) & 1, (c >> 2) & 1); }

struct CubeMesh {
  std::vector<CubeTriangle> triangles;
  std::vector<std::vector<LocalEdge>> centres;  // polygons whose centre is a vertex
  void clear() {
    triangles.clear();
    centres.clear();
  }
};

// Appends the triangles of one cube with corner values f (inside: f < 0) to `out`.
using CubeMesher = std::function<void(const std::array<double, 8>& f, CubeMesh& out)>;

// Runs the traversal of the options over the lattice, meshing each visited cube with `mesher`.
// `method` names the method in errors and statistics; `face_ambiguity` is Marching Cubes' rule
// for the report (empty for Marching Tetrahedra).
PolygonizeResult run_marching(const Field& field, const MarchingOptions& options, const char* method,
                              const CubeMesher& mesher, const std::string& face_ambiguity);

}  // namespace cdp::marching
