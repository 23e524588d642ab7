// Marching Tetrahedra (Doi & Koide 1991), the paper's baseline: each lattice cube is split into
// the six tetrahedra around its main diagonal (Freudenthal / Kuhn), the same in every cube, so
// that neighbouring cubes cut their shared face along the same diagonal and no cracks appear.
// Same lattice, traversals, root search and statistics as Marching Cubes.
#pragma once

#include <cdp/baselines/marching_options.h>

#include <cdp/core/polygonize_result.h>

#include <array>

namespace cdp {

// The six tetrahedra as corners of the cube (numbered as in cube_cases.h): 0 and 7 and a
// monotone path between them, so every edge joins two corners whose offsets are ordered.
inline constexpr std::array<std::array<int, 4>, 6> kCubeTetrahedra = {{
    {0, 1, 3, 7}, {0, 3, 2, 7}, {0, 2, 6, 7}, {0, 6, 4, 7}, {0, 4, 5, 7}, {0, 5, 1, 7},
}};

// Marching Tetrahedra, the paper's baseline: each cube split into kCubeTetrahedra. stats.method =
// "mt"; otherwise as marching_cubes() (options.face_ambiguity is unused).
// \pre, \return and \throw as marching_cubes().
PolygonizeResult marching_tetrahedra(const Field& field, const MarchingOptions& options = {});

}  // namespace cdp
