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

#include <cdp/core/adaptive_modes.h>
#include <cdp/core/adaptive_report.h>
#include <cdp/core/block_tasks.h>
#include <cdp/core/field.h>
#include <cdp/core/polygonize_result.h>
#include <cdp/core/cancel.h>
#include <cdp/core/progress.h>

#include <cstddef>
#include <optional>

namespace cdp {

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
  // tracker itself runs on the caller's thread (with `blocks`, the blocks' trackers on these; with
  // creases followed, the trackers and repairs of the groups of crease patches);
  // from two threads, a costly field's evaluations there run half their sums on a second (a Vis
  // from Vis::kSplitGradientHessianCentres centres; stats "split_evaluations"). The mesh is the same, bit for bit, on any number.
  int threads = 0;
  // Block-parallel tracking (Variant::Improved, a surface without followed creases): the box is
  // cut into blocks of about 2500 triangles by planes that depend only on the field and the
  // options, the curves where the surface crosses them are traced once (seams), and every block
  // is meshed from its seams by fronts of its own, on `threads` threads for a thread-safe field.
  // A field whose calls cost more than their points (Field::costly_calls: a Python function) is
  // cut into up to 64 blocks of at least 250 triangles, meshed in lockstep: one call of the field
  // makes the evaluations of all of them (stats blocks.lockstep_batches), their trackers fibers
  // on the calling thread between the calls.
  // The mesh is the same on any number of threads; it is another mesh than the one tracking alone
  // makes. A layout or a block that fails falls back to tracking alone (stats blocks.fallback),
  // except at a kink of a black box (creases: follow), which ends the run as tracking alone would.
  // Unset (the default): blocks, except for a run given max_steps or max_search_visits (bounds on
  // one tracker's work). A Python function too (since December 2026): on nine numpy models
  // (python/README.md) blocks in lockstep make 0.32 of its calls and take 0.53 of its time
  // (geometric means; 0.03-1.09 and 0.04-1.19); until its seams looked across themselves (blocks.cpp) a black box with C1
  // seams, a rounded box, took 3 to 7 times as long in blocks, and was tracked alone by default.
  std::optional<bool> blocks;
  // With `blocks`: the blocks' trackers run elsewhere (block_tasks.h; a Dask cluster from Python,
  // python/cdp/distributed.py) instead of on `threads` threads: the same mesh, bit for bit. Empty:
  // on this process's threads.
  BlockRunner block_runner;
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
  // Called now and then with an estimate of the fraction of the phase done (tracing creases, meshing).
  ProgressCallback progress;
  // Cancels the run from outside (cancel.h): polled in every phase's loops, it ends the run
  // with CancelledError.
  CancelToken cancel;
  // Called on entering each phase: "sampling the seed grid", "tracing creases" and "meshing
  // along creases" (a field with creases, CreaseHandling::Follow; "tracing creases again" on a
  // finer grid where the patches need it), "meshing", "repairing triangles", "checking the mesh".
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
// stats.adaptive holds the typed report of every stage (adaptive_report.h): the settings as
// resolved, the seeding, the tracker's counters, the creases, the repair, the neck search, the
// runs made again, and each phase's time and field calls over every run made.
PolygonizeResult polygonize_adaptive(const Field& field, const AdaptiveOptions& options = {});

}  // namespace cdp
