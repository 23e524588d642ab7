// Crease-aware meshing of a CSG field (one whose model reports its pieces, Field::pieces): the
// creases are laid out first, as polylines of mesh vertices on both pieces (corners as their
// end points), and every piece's patches are then meshed by fronts that start from those
// polylines. The crease polylines are the patches' fixed boundaries: the fronts build triangles
// on them and never move or cut them, so mesh edges run along every crease and the two sides
// meet there exactly. Each piece is meshed on its own smooth function (the piece with its
// branches fixed), so the fronts never see a crease and never cross one.
//
// The steps, each in one place:
//   resample_curve   a traced crease as vertices spaced by the curvature of both sides and of
//                    the crease itself, each moved onto the crease by Newton (project_to_crease)
//   orient_darts     each crease as two directed boundaries, one per piece, with the piece's
//                    patch on the left seen from outside (the fronts' orientation, front.h)
//   trace_cycles     the boundary cycles of each piece's patches: at a corner a boundary goes on
//                    along the other crease of the same piece
//   group_cycles     the cycles of one smooth region together (by function, or where hidden
//                    choices code one region differently along its boundaries, by growing the
//                    regions over the surface), on one code
//   mesh_crease_patches  one tracker per group, its fronts the group's cycles, then one mesh
#pragma once

#include "tracker.h"

#include <cdp/core/crease_curves.h>
#include <cdp/core/errors.h>

#include <cstddef>
#include <vector>

namespace cdp::adaptive {

// The creases cannot be laid out as patch boundaries (a crease that ends without a corner, a
// corner where a piece's boundary cannot be followed, a sample that Newton cannot put on its
// crease). The caller meshes the surface without crease handling instead.
class CreaseLayoutError : public NoSurfaceError {
 public:
  using NoSurfaceError::NoSurfaceError;
};

struct CreaseMesh {
  Mesh mesh;  // closed where every patch closed; its first `crease_vertices` vertices lie on creases
  // Per vertex, as the tracker keeps them (Tracker::vertex_edge_length, vertex_mac, vertex_shape_index).
  std::vector<double> target, mac, shape_index;
  std::size_t crease_vertices = 0, pieces = 0;
  std::size_t steps = 0, splits = 0, merges = 0;
  // Stuck fronts the patches' trackers closed ear by ear (Tracker::forced_closures).
  std::size_t forced_closures = 0;
  // Bridges, closures and placements the patch tests refused (Tracker::patch_refusals).
  std::size_t patch_refusals = 0;
};

// Lays out `creases` (from trace_creases on `field`) and meshes every patch they bound, its
// fronts looking ahead with `look_ahead_gradation` (Settings::look_ahead_gradation;
// kPatchLookAheadGradations, stage_creases.h). Throws CreaseLayoutError as above, and whatever a
// tracker throws (StalledFrontError, LimitExceededError).
CreaseMesh mesh_crease_patches(const Field& field, const CreaseTracingResult& creases, const Settings& settings,
                               double estimated_area, double look_ahead_gradation);

}  // namespace cdp::adaptive
