// The paper's curvature-dependent adaptive surface tracker (de Araujo & Jorge 2004, Figure 6).
//
// From a seed on the surface it grows a mesh by expanding, one at a time, the front point of
// smallest front angle into triangles whose edge length follows the local minimum radius of
// curvature. Fronts that run into themselves are split, fronts that run into other fronts are
// merged, so cracks are resolved on the fly and no re-meshing step follows. Beyond the paper:
// every component is meshed (seeds from a coarse sign-change grid), edge lengths can follow a
// tolerance instead of the heuristic factor, and every loop is bounded; by default
// (Variant::Improved) the few slivers the fronts leave are repaired locally and the tolerance is
// a bound on the distance between mesh and surface (Variant::Paper: the algorithm as printed).
// See polygonizer/README.md, section "Adaptive polygonizer".
#pragma once

#include <cdp/core/field.h>
#include <cdp/core/polygonize_result.h>
#include <cdp/core/cancel.h>
#include <cdp/core/progress.h>

#include <array>
#include <cstddef>
#include <string_view>

namespace cdp {

// How the target edge length follows the minimum radius of curvature r at a point.
enum class SizingMode {
  Factor,     // the paper: l = r / factor
  Tolerance,  // chord deviation: l = 2 sqrt(2 r eps - eps^2), so the chord sags at most eps
  // The sizing of Tolerance aimed at eps itself, without its bound: nothing is measured or
  // refined, so the mesh's distance to the surface is not bounded (a triangle sags about 4/3
  // of its edges' eps, more where the curvature changes along it); in Variant::Improved no edge
  // longer than min_edge turns the normal by more than a radian. In Variant::Paper it is the
  // tolerance, the same mesh. What it costs and gains against Tolerance and Factor:
  // bench/README.md, "Measurements behind the options".
  Chord,
};

// How many triangles the expansion of a front point with front angle theta produces.
enum class TriangleCountRule {
  // The paper's formula as printed, n = floor(3 theta / pi); n <= 1 closes the angle.
  PaperFloor,
  // Hartmann (1998): n = trunc(3 theta / pi) + 1; n - 1 when theta / n < 0.8 and n > 1; n = 2
  // when n = 1, theta > 0.8 and the two neighbours are farther apart than 1.2 delta.
  Hartmann,
};

// Which algorithm runs.
enum class Variant {
  // The paper's tracker with this project's additions for the triangles' shape and the
  // tolerance: the grading of new points' edge lengths, the local repair of triangles whose
  // smallest angle is under 30 degrees (edge flips, tangential vertex moves back onto the surface,
  // collapses of needles' short edges; src/adaptive/quality.h), and with SizingMode::Tolerance a
  // sizing margin plus splits of triangles sampled beyond the tolerance, so that it bounds the
  // distance between mesh and surface. A smooth surface's mesh that still misses the quality
  // bounds (a triangle under 20 degrees, more than 1% under 30, a mean longest/shortest edge
  // over 1.25, a triangle beyond the tolerance) is made once more with the fronts looking
  // ahead at the targets of front points nearby, and the mesh that misses fewer is kept (stats
  // "quality_rerun", "quality_rerun_kept", "look_ahead"; not when max_triangles or max_steps is set).
  Improved,
  // The algorithm as printed (Figure 6 with Hartmann's triangle count, see triangle_count),
  // none of the additions above: what the paper's method alone gives.
  Paper,
};

// What the adaptive method does with the creases and corners of a CSG field (one whose model
// reports its pieces: Field::pieces; other models are smooth and have none).
enum class CreaseHandling {
  // Trace the creases first and mesh each piece's patches from them (src/adaptive/
  // crease_patches.h): mesh edges run along the creases, and crease vertices lie on both pieces.
  // Where the creases cannot be laid out as patch boundaries, or a patch cannot be meshed, the
  // surface is meshed as if it were smooth (stats "creases.followed" says which).
  Follow,
  // Mesh across creases as across curvature (the paper's method; Variant::Paper always does).
  Ignore,
};

struct AdaptiveOptions {
  Variant variant = Variant::Improved;
  SizingMode sizing = SizingMode::Factor;
  // The paper's heuristic factor k: edge length = r_min / k. Used in SizingMode::Factor.
  double factor = 2.0;
  // Target distance eps, used in SizingMode::Tolerance and SizingMode::Chord. Non-positive:
  // 1e-3 of the bounding-box diagonal; not a number: InvalidInputError. Tolerance with
  // Variant::Improved: the largest distance between mesh and surface (sampled over every
  // triangle, see src/adaptive/quality.h) is at most eps where the refinement can split (the
  // rest is counted, stats "quality.over_tolerance"). Chord, and Variant::Paper: eps is the
  // sagitta of a chord at each point's smallest radius, which the mesh can exceed 2-4 times.
  double tolerance = 0;
  // Edge-length clamps. Non-positive: min_edge = 2e-3 and max_edge = 0.1 of the field's
  // bounding-box diagonal; not a number: InvalidInputError. With the default min_edge (and the
  // default max_triangles and max_steps, Variant::Improved), a surface that fails because it
  // bends with a radius of curvature below min_edge is meshed once more with min_edge a quarter
  // of that radius (not below 2e-4 of the diagonal, where a crease or singular point is more
  // likely than a bend); stats "min_edge_lowered" says so, and when that run fails too the
  // first error stands, with the second's appended. In tolerance mode a surface every such run
  // fails on is meshed once more with every edge turning the normal by at most a radian (stats
  // "turn_limited").
  double min_edge = 0;
  double max_edge = 0;
  // Hartmann's rule reproduces the paper's edge ratios (see README); the printed formula gives
  // flatter, longer-edged triangles.
  TriangleCountRule triangle_count = TriangleCountRule::Hartmann;
  // A front point q closer to the expanded point than collision_factor * edge length, visible
  // from it and on the same side of the surface, triggers a split or a merge instead of the
  // expansion. The paper uses 1; a little more also catches front edges passing close by.
  double collision_factor = 1.3;
  CreaseHandling creases = CreaseHandling::Follow;
  // Cells along the longest side of the box of the sign-change grid that finds the seeds and
  // checks that every component was meshed. Components smaller than about one cell can be
  // missed; raise this to catch them.
  int seed_resolution = 32;
  // Checks the finished mesh for intersecting triangles (self_intersecting_pairs: about 0.5 us
  // per triangle on one core) and throws NoSurfaceError naming the place when two intersect. On
  // by default: a mesh that is wrong without saying so is worse than a slower run.
  bool check_self_intersections = true;
  // Threads of the data-parallel passes (the seed grid of a thread-safe field, the relaxation's
  // targets, projections and intersection tests, the tolerance's estimates, the final checks):
  // 0 all cores this process may run on (its CPU affinity; at most 8), 1 the caller's only. The
  // tracker itself runs on the caller's thread; from two threads, a costly field's evaluations
  // there run half their sums on a second (a Vis from Vis::kSplitGradientHessianCentres
  // centres; stats "split_evaluations"). The mesh is the same, bit for bit, on any number.
  int threads = 0;
  // Adds vertex_scalars "mac" (maximum absolute curvature) and "shape_index" to the mesh.
  bool curvature_properties = false;
  // Bounds; hitting one throws LimitExceededError. 0: derived from the box and min_edge
  // (max_triangles = 20 box-surface areas in equilateral triangles of side min_edge, capped at
  // 5e7; max_steps = 4 max_triangles + 10^4).
  std::size_t max_triangles = 0;
  std::size_t max_steps = 0;
  // The neighbour searches' cost: points they look at per front step, averaged over windows of
  // 4096 steps. 0: 5000, a hundred times what meshing runs take (about 40-130); a window above it
  // has edges far shorter than the search cells somewhere or a front running over finished mesh.
  // Past the default bound the surface is meshed again with rollbacks, as after a stalled front,
  // before any error; past a bound set here the run ends with LimitExceededError.
  std::size_t max_search_visits = 0;
  // Called now and then with an estimate of the fraction of the meshing done.
  ProgressCallback progress;
  // Cancels the run from outside (cancel.h): polled in every phase's loops, it ends the run
  // with CancelledError.
  CancelToken cancel;
  // Called on entering each phase: "sampling the seed grid", "meshing along creases" (a field
  // with creases, CreaseHandling::Follow), "meshing", "repairing triangles", "checking the mesh".
  PhaseCallback phase;
};

// Meshes the zero set of `field` in its box with the paper's surface tracker: the runs and
// stages of polygonizer/README.md ("How a run goes").
// \pre field.bounds() is valid and holds the surface; F < 0 inside.
// \return a mesh closed, oriented, manifold and outward, one component per component of the
//         surface the seeding found, and (with check_self_intersections) free of
//         self-intersections, with its stats (below). The same field and options give the same
//         mesh bit for bit, on any number of threads.
// \throw NoSurfaceError when the field has no surface in its box (or it leaves the box), or when
//        no run made a mesh that passes the checks (the message names the place and the cause).
// \throw LimitExceededError when a bound is hit (max_triangles, max_steps, max_search_visits).
// \throw InvalidInputError for invalid options (a NaN, min_edge above max_edge, ...).
// \throw CancelledError when options.cancel is cancelled; the field is usable again.
// \throw whatever the field's evaluations throw (a Python function's error), unchanged.
// stats.extra holds "seeds" (seeds meshed from), "steps", "min_angle_degrees", "edge_length"
// ({"min", "max"} after clamping), "triangle_count_rule", "sizing", "variant", the additions in
// force ("grading", "quality_repair", "tolerance_refinement", "look_ahead": 0 or 1), the re-runs
// ("min_edge_lowered", "quality_rerun", "quality_rerun_kept") and the repair's counts
// ("quality.flips", "quality.moves", "quality.collapses", "quality.splits", ...), and the time
// and field calls of each phase of kAdaptivePhases over every run made ("phases.NAME.seconds",
// ".value", ".value_gradient", ".gradient_hessian"), whose calls add up to field_evaluations.
PolygonizeResult polygonize_adaptive(const Field& field, const AdaptiveOptions& options = {});

// The phases of stats "phases", in the order a run enters them: the seed grid (and the hash
// cell's curvature sample); the crease layout (its tracing and patches); the tracking (the
// seeding and the fronts); the quality (the repair, the relaxation, the tolerance's refinement,
// the curvature properties on request); the checks (topology, intersections, the gap and neck
// searches, wherever a run makes them). An error's crease tracing for its message counts in the
// phase that failed.
inline constexpr std::array<std::string_view, 5> kAdaptivePhases{"seed_grid", "creases", "tracking", "quality",
                                                                 "checks"};

const char* to_string(SizingMode mode);
const char* to_string(CreaseHandling creases);
const char* to_string(TriangleCountRule rule);
const char* to_string(Variant variant);

}  // namespace cdp
