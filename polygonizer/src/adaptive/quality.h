// Local repair of the few badly shaped triangles the fronts leave behind, a relaxation of the
// stretched ones (most vertices of a graded mesh), and the check that makes --tolerance a
// distance bound. None is a re-meshing: each starts from the triangles that fail its test
// (smallest angle under a bound; longest edge over 1.15 times the shortest; a sample farther
// from the surface than the tolerance) and changes only those triangles and their immediate
// neighbours (the stars of the vertices involved; the relaxation flips edges and moves vertices
// along the surface, and adds or removes none), with operations that keep the surface, the
// topology and the orientation: edge flips, tangential vertex moves projected back onto the
// surface by Newton, edge collapses and edge splits at surface points. Every operation is
// tested before it is applied (it must raise the smallest angle it touches, or for the
// relaxation lower the mean edge ratio of its star, or for its flips bring the valences nearer
// 6, without taking its smallest angle under 30 degrees; keep its triangles turned like the
// surface, keep the chord deviation and, with a tolerance, the distance bound, and intersect no
// triangle nearby), so the result is never worse than the input on any of these counts.
// Deterministic: triangles are visited in a fixed order (smallest angle, then index; the
// relaxation's vertices by index), and every loop is bounded (kQualityRounds rounds over a
// shrinking work list, kRelaxSweeps sweeps and at most kRelaxSearchSweeps more).
#pragma once

#include <cdp/core/adaptive_report.h>
#include <cdp/core/cancel.h>
#include <cdp/core/field.h>
#include <cdp/core/mesh.h>

#include <cstddef>
#include <vector>

namespace cdp::adaptive {

struct QualityOptions {
  // Triangles whose smallest angle is under this are repaired (radians).
  double improve_below = 0;
  // Positive: the largest distance from the mesh to the surface, sampled over every triangle,
  // must end at most this (triangles beyond it are split), and no operation may break it.
  double tolerance = 0;
  // The field's bounding-box diagonal (Newton's tolerance, crease probes).
  double diagonal = 1;
  // Shortest edge the splits may create.
  double min_edge = 0;
  // Shortest edge the last resort's splits may create (splits of triangles still farther than
  // the tolerance after the refinement); 0: min_edge.
  double last_resort_min_edge = 0;
  // With a tolerance: a triangle estimated over the estimate's margin below the tolerance but
  // not over it is measured densely before it is split, and left unsplit when it is within
  // kDenseClearShare of the tolerance there. Off for a mesh laid across creases as if smooth:
  // there the splits near a crease were what kept its angles (the two spheres at 2e-3: 19.8 ->
  // 10.9 degrees without them), and the tolerance does not hold across a crease either way.
  bool measure_near_bound = true;
  // With a tolerance, on a smooth field with exact derivatives (Field::smooth, not
  // Field::derivative_step), the distance estimates may predict edge midpoints from their ends'
  // derivatives where two predictions agree (repair_context.h, kPredictShare), and measure them
  // elsewhere: never, on a field that asks for it or whose calls are costly
  // (Field::predicts_from_hessians, Field::costly_calls), or on any such field (for tests and
  // measurements). The run decides it once for all its repairs (stage_repair.cpp).
  enum class Predict { Never, CostlyFields, Always };
  Predict predict_estimates = Predict::CostlyFields;
  // Positive: when the relaxation's sweeps leave the mesh's mean longest/shortest edge ratio
  // over this, it sweeps again with each move searched in the tangent plane (see relax), until
  // the mean is at or under it or a bounded number of sweeps has run. 0: no search. Not for a
  // mesh laid across creases as if smooth: its triangles across a crease stay stretched, and
  // the moves beside them may leave worse angles to the repair that follows.
  double aim_mean_edge_ratio = 0;
  // Threads of the independent passes: the relaxation's targets and the intersection tests of
  // its moves, and for a thread-safe field their projections and each refinement round's
  // tolerance estimates. 0 all cores (at most
  // 8), 1 the caller's only. The mesh and the evaluation counts are the same, bit for bit, on
  // any number.
  int threads = 0;
  CancelToken cancel;  // polled in every round and sweep (cancel.h)
  // An open mesh (a block's piece of surface, a band cut out of a mesh): the vertices on its
  // boundary edges stay where they are (never moved, removed or merged; renumbered only as
  // compact renumbers every vertex, see improve_mesh's `renumbered`),
  // and no boundary edge is flipped or split, so that the piece still fits what lies beyond it.
  bool keep_boundary = false;
  // With keep_boundary, whether over_tolerance counts the triangles beyond the tolerance that
  // touch a boundary vertex or a neighbour of one: false where the caller repairs that band
  // again and measures it there (the blocks, blocks.h).
  bool count_near_boundary = true;
};

// Repairs `mesh` in place (positions, normals, triangles; vertices and triangles that
// collapses remove are dropped, so indices change where anything was collapsed; vertices the
// splits add come last). `renumbered` (optional): each input vertex's index in the result, -1
// for one removed. `measured_again` (optional, one flag per input vertex; with keep_boundary and
// count_near_boundary): the boundary vertices whose neighbourhood the caller repairs and measures
// again, so that over_tolerance leaves out the triangles on or next to them (the parts of a band
// repaired side by side, stage_repair.h).
// \pre the mesh is oriented and manifold, with one unit normal per vertex, and closed unless
//      options.keep_boundary.
QualityReport improve_mesh(const Field& field, Mesh& mesh, const QualityOptions& options,
                           std::vector<int>* renumbered = nullptr,
                           const std::vector<char>* measured_again = nullptr);

// Adds the counts of one repair's report to `sum` (repairs of parts of one mesh: the blocks',
// the band's): counts summed, the search sweeps' most, the worst distance beyond the tolerance
// kept with where it was.
void add_repair_counts(QualityReport& sum, const QualityReport& r);

}  // namespace cdp::adaptive
