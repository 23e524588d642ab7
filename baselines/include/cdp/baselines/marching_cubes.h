// Marching Cubes (Lorensen & Cline 1987) on a cubic lattice over the field's box, with the case
// table generated from a stated rule (cube_cases.h), face ambiguities decided consistently
// between neighbouring cubes, crossings found by a root search on the field, and either
// Bloomenthal's continuation or a full grid traversal (marching_options.h).
#pragma once

#include <cdp/baselines/marching_options.h>

#include <cdp/core/polygonize_result.h>

namespace cdp {

// A welded, indexed mesh (one vertex per crossed lattice edge, less those merged away where
// edges under a hundredth of a cell are collapsed, so that no triangle degenerates) with normals
// from the field gradient; closed, oriented and edge-manifold when the surface lies inside the
// box. stats.method = "mc"; stats.lattice (lattice_report.h) holds the lattice, the cubes
// visited and crossed, the evaluations, the face-ambiguity rule, the short-edge collapse, and for
// the continuation its seeding (unreached_sign_changes is 0 unless the lattice is too coarse for
// some of the surface the seed grid sees).
// \pre field.bounds() is valid; F < 0 inside.
// \return the mesh and its stats (above).
// \throw InvalidInputError for invalid options (both cell_size and precision, a precision on a
//        field without constraint points, a lattice over the cell bound).
// \throw NoSurfaceError when no cube is crossed or the surface leaves the box (with
//        require_closed_in_box).
// \throw LimitExceededError at max_cubes or max_triangles.
// \throw CancelledError when options.cancel is cancelled; what the field's evaluations throw.
PolygonizeResult marching_cubes(const Field& field, const MarchingOptions& options = {});

}  // namespace cdp
