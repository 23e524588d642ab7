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
//                    regions over the surface, each sample's code from RegionCodes), on one code
//   mesh_crease_patches  one tracker per group, its fronts the group's cycles (the groups on all
//                    threads), then one mesh in group order
#pragma once

#include "tracker.h"

#include <cdp/core/crease_curves.h>
#include <cdp/core/errors.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <map>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace cdp::adaptive {

// Fewest edges of a patch's fixed boundary when it is resampled (a crease here, a block's seam
// in blocks.cpp): two between corners (two curves joining the same two corners bound a patch of
// at least four vertices), three for a loop.
inline constexpr std::size_t kMinOpenEdges = 2, kMinLoopEdges = 3;

// The creases cannot be laid out as patch boundaries (a crease that ends without a corner, a
// corner where a piece's boundary cannot be followed, a sample that Newton cannot put on its
// crease). The caller meshes the surface without crease handling instead.
class CreaseLayoutError : public NoSurfaceError {
 public:
  using NoSurfaceError::NoSurfaceError;
};
// resample_curve's: a vertex projected onto its crease landed more than half an edge from where
// it was placed along the traced polyline.
class CreaseVertexError : public CreaseLayoutError {
 public:
  using CreaseLayoutError::CreaseLayoutError;
};

struct CreaseMesh {
  Mesh mesh;  // closed where every patch closed; its first `crease_vertices` vertices lie on creases
  // Per vertex, as the tracker keeps them (Tracker::vertex_edge_length, vertex_mac, vertex_shape_index).
  std::vector<double> target, mac, shape_index;
  std::size_t crease_vertices = 0, pieces = 0;
  // Where each group's triangles end in mesh.triangles (the groups' parts in group order, each
  // holding its triangles together): the repair repairs the groups side by side (repair_mesh).
  std::vector<std::size_t> group_ends;
  std::size_t steps = 0, splits = 0, merges = 0;
  // Stuck fronts the patches' trackers closed ear by ear (Tracker::forced_closures).
  std::size_t forced_closures = 0;
  // Bridges, closures and placements the patch tests refused (Tracker::patch_refusals).
  std::size_t patch_refusals = 0;
  // The tightest bend the patches' trackers met (Tracker::tightest_bend), for the run's: the
  // reruns that lower min_edge for a bend read it (lowered_min_edge, min_edge_for_tolerance).
  std::pair<double, Vec3> tightest{std::numeric_limits<double>::infinity(), Vec3::Zero()};
  // Patch vertices moved onto the field's surface after their patch was meshed: a patch's piece
  // fixes the branches of its creases everywhere, and where the field's value does not depend on
  // one of them as its values choose it (a pawn's head, a ball smoothly united with a capped cone:
  // over the ball the blend's clamp hides which of the cone's faces is taken, but with the
  // branch of its side fixed the clamp no longer saturates), the piece is another function. The
  // tracker placed its vertices on the piece, up to 0.012 off the surface, and nothing said so.
  std::size_t landed = 0;
};

// A mesh whose first vertices are `shared` (on creases, or on the blocks' seams), to be joined by
// the parts meshed from loops of them (add_part): no normal yet, an infinite target, no curvature.
CreaseMesh start_shared(const std::vector<Vec3>& shared);
// Adds `part`, meshed by a tracker from loops of shared vertices, to `out`: the part's vertex
// loop_ids[l][k] is out's shared vertex shared_ids[l][k], whose normal sums the parts' (the mean
// once finish_shared normalizes it; per-side normals at a crease are the mesh's corners'
// business), whose target is the smallest and whose curvature the largest of them; the part's
// other vertices are appended with their target, mac and shape index (the tracker's), then its
// triangles.
void add_part(CreaseMesh& out, const Mesh& part, const std::vector<std::vector<int>>& loop_ids,
              const std::vector<std::vector<int>>& shared_ids, std::span<const double> target,
              std::span<const double> mac, std::span<const double> shape_index);
// Normalizes the first `shared` vertices' summed normals.
// \throw CreaseLayoutError "adaptive: <unreached> near <point>" for one no part reached.
void finish_shared(CreaseMesh& out, std::size_t shared, const std::string& unreached);

// A point's code as the region growth of crease-aware meshing compares them (grouping the
// patches' boundary cycles by the smooth region they bound): its branches as the values take
// them, with the choices that change nothing there free (Field::pieces). Which choices those are
// follows from the branches taken (a min or max that discards an argument, a clamp that
// saturates to an exact constant), so the code found at one point serves every later point
// that takes the same branches: one evaluation (Field::branch_record) instead of one for each
// branch point. Found afresh, and not kept, where a branch point's switch lies within
// kFreshCode of `step` (a region growth step): there a product may be small rather than zero.
class RegionCodes {
 public:
  static constexpr double kFreshCode = 1e-3;
  RegionCodes(const Field& field, double step) : field_(field), step_(step) {}
  // The code at p (empty for a model without branch points).
  // \throw as Field::pieces.
  std::vector<std::uint8_t> at(const Vec3& p);
  // The codes found afresh (Field::pieces_first_order) so far.
  std::size_t fresh() const { return fresh_; }

 private:
  const Field& field_;
  double step_;
  // Ordered element by element (std::less on byte vectors compares them with memcmp, where GCC 12
  // warns of a bound it cannot see).
  struct ByElement {
    bool operator()(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b) const {
      return std::lexicographical_compare(a.begin(), a.end(), b.begin(), b.end(),
                                          [](std::uint8_t x, std::uint8_t y) { return x < y; });
    }
  };
  std::map<std::vector<std::uint8_t>, std::vector<std::uint8_t>, ByElement> known_;
  std::size_t fresh_ = 0;
};

// Lays out `creases` (from trace_creases on `field`) and meshes every patch they bound, its
// fronts looking ahead with `look_ahead_gradation` (Settings::look_ahead_gradation;
// kPatchLookAheadGradations, stage_creases.h). The groups' trackers run on `threads` threads
// (AdaptiveOptions::threads: 0 all cores) for a thread-safe field, each group's mesh joined in
// group order: the mesh is the same on any number. Throws CreaseLayoutError as above, and
// whatever a tracker throws (StalledFrontError, LimitExceededError; the first group's in group
// order).
CreaseMesh mesh_crease_patches(const Field& field, const CreaseTracingResult& creases, const Settings& settings,
                               double estimated_area, double look_ahead_gradation, int threads = 1);

}  // namespace cdp::adaptive
