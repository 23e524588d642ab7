// What polygonize_adaptive reports beside its mesh (PolygonizeStats::adaptive): one typed struct
// per stage of a run (polygonizer/README.md, "How a run goes") and one for the runs made again.
// STATS.json writes it (cdp/io/polygonize_stats_json.h) under the keys docs/stats.md lists.
#pragma once

#include <cdp/core/adaptive_modes.h>
#include <cdp/core/field.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace cdp {

// The options as the run resolved them.
struct AdaptiveSettingsReport {
  Variant variant = Variant::Improved;
  SizingMode sizing = SizingMode::Factor;
  double factor = 0;     // SizingMode::Factor only (STATS "factor")
  double tolerance = 0;  // the tolerance asked for (its default resolved); not with SizingMode::Factor
  double min_edge = 0, max_edge = 0;  // the edge clamps after their defaults (STATS "edge_length")
  TriangleCountRule triangle_count = TriangleCountRule::Hartmann;
  int seed_resolution = 0;
  bool grading = false;               // new points' targets graded (Variant::Improved)
  bool quality_repair = false;        // the repair stage ran (Variant::Improved)
  bool tolerance_refinement = false;  // triangles measured and split to the tolerance
};

// The seeding guarantee's counts (polygonizer/src/adaptive/seeding.h).
struct SeedingReport {
  std::size_t sign_changes = 0;      // grid edges and refined-cell segments where F changes sign
  std::size_t seeds = 0;             // components started
  std::size_t failed_seeds = 0;      // surface points where not even a hexagon fitted
  std::size_t covered_nearby = 0;    // sign changes no triangle crosses, but a triangle of the sheet is near
  std::size_t below_resolution = 0;  // sign changes on meshed components, in detail finer than min_edge
  std::size_t thin_bridges = 0;      // surface points that walk to one component and run onto another (seeding.cpp, kTipFacing)
  std::size_t seeds_first = 0;       // seeds started before the grid's: bridges an earlier attempt found (seeding.h)
  std::size_t refined_cells = 0;     // cells split by the small-component search
  std::size_t unresolved_cells = 0;  // cells at min_edge that may still hold surface (thinner than min_edge)
  std::size_t unsearched_cells = 0;  // cells the search's budget left unsplit, which may hold surface (seeding.cpp)
  Vec3 first_unsearched = Vec3::Zero();  // the centre of the first of them
  std::size_t probes = 0;            // Newton probes: local minima of |F| (no bound), the band's curls
  std::size_t probes_outside = 0;    // of them, those that landed outside the box: not seeds (seeding.cpp)
  std::size_t band_cells = 0;        // grid cells of the band around the surface scanned at min_edge (sampled volumes)
  std::size_t band_components = 0;   // connected sets of sign changes found there, one of each visited
  std::size_t uncovered = 0;         // sign changes not meshed after the run: 0 on success (STATS "uncovered_crossings")
  Vec3 first_uncovered = Vec3::Zero();
  std::size_t non_finite_samples = 0;  // seed-grid samples where F was NaN or infinite
  // Where two solids touch, F is zero on their common face and of one sign on either side: no
  // surface passes there. Seed-grid samples on such a face counted as inside (SeedGrid::touching),
  // and sign changes whose surface point lay on one, not seeded (seeding.cpp, kTouchingDepth).
  std::size_t touching_samples = 0;
  std::size_t touching_crossings = 0;
};

// The fronts' counters over the tracking stage of the run kept.
struct TrackerReport {
  std::size_t steps = 0;
  std::uint64_t search_visits = 0;  // points the neighbour searches looked at
  std::size_t deferrals = 0, anticipations = 0, side_points = 0;
  std::size_t forced_closures = 0;  // the crease patches' included
  std::size_t rollbacks = 0, rollbacks_failed = 0;
  std::size_t crease_points = 0;
  std::size_t over_mesh_rejections = 0;
  // Placements refused for landing on another sheet than their origin's (Tracker::jumped).
  std::size_t sheet_jumps = 0;
  double curvature_seconds = 0, hessian_seconds = 0;
  // The smallest radius of curvature the fronts met; negative when none was finite (STATS
  // "curvature.min_radius"). For a kink of a black box found between two vertices, the length
  // within which its normal turns (under the differences' step).
  double min_curvature_radius = -1;
};

// The crease stage (CreaseHandling::Follow).
struct CreaseReport {
  CreaseHandling handling = CreaseHandling::Ignore;  // Ignore whenever the variant is Paper
  bool followed = false;  // the mesh's edges run along the creases
  std::size_t curves = 0, corners = 0;  // traced
  std::size_t vertices = 0, pieces = 0, components = 0, steps = 0, patch_refusals = 0;  // of the patches
  // Patch vertices placed on their piece where the field is another function, moved onto the
  // field's surface (crease_patches.h, CreaseMesh::landed).
  std::size_t landed_vertices = 0;
  std::string fallback;   // why the creases are not followed, or empty
  int tracing_resolution = 0;  // of the last tracing; 0 when none was made
  // A black box (no pieces) meshed across a kink that held together (CreaseHandling::Ignore;
  // Follow stops at the first kink): cut across by chords.
  bool across_black_box = false;
};

// Block-parallel tracking (AdaptiveOptions::blocks; polygonizer/src/adaptive/blocks.h).
struct BlocksReport {
  bool requested = false;
  bool used = false;  // the mesh was made from blocks (else tracking alone: `fallback` says why)
  std::array<int, 3> blocks{1, 1, 1};  // along x, y, z
  std::array<std::vector<double>, 3> cuts;  // the cut planes' positions along each axis
  std::size_t meshed_blocks = 0, corners = 0, seams = 0, seam_vertices = 0, components = 0, steps = 0;
  // Layouts of cuts tried: more than 1 where the surface grazed a block's edge (its cuts moved).
  std::size_t layouts = 0;
  double estimated_triangles = 0;  // the surface's triangles as the seed grid estimates them
  unsigned threads = 1;  // that meshed the blocks (1 with a block runner: they ran elsewhere)
  // With AdaptiveOptions::block_runner: the bytes of the tasks handed to it and of the pieces it
  // returned for the run whose mesh was kept (what a cluster moves).
  std::size_t task_bytes = 0, piece_bytes = 0;
  // With a field whose calls cost more than their points (Field::costly_calls: a Python
  // function): the most faces or blocks traced and meshed in lockstep, each round's evaluations
  // of every kind gathered into one evaluation of the field (Field::evaluate_together, one call
  // of a Python function: polygonizer/src/adaptive/lockstep.h), and those rounds; 0 otherwise.
  std::size_t lockstep_tasks = 0;
  std::uint64_t lockstep_batches = 0;
  double layout_seconds = 0, seconds = 0;
  std::vector<double> block_seconds;  // each block's tracking, in block order
  // Each data-parallel pass the run made on its own thread besides the blocks (the seed grid, the
  // cut planes' samples, the seams' Hessians, the relaxation's targets, the band's repair in
  // parts, the final checks, ...): its wall time and the blocks of work it was cut into, which
  // `threads` threads share. With or without blocks; what the projected speedups on more threads
  // divide (BM_AdaptiveBlocks).
  std::vector<double> pass_seconds;
  std::vector<std::size_t> pass_blocks;
  std::string fallback;
  // The finished mesh's triangles that a cut plane passes through (the seams' neighbours), and
  // their quality: smallest angle, share under 30 degrees, mean longest / shortest edge.
  std::size_t wall_triangles = 0;
  double wall_min_angle_degrees = 0, wall_under_30_share = 0, wall_mean_edge_ratio = 0;
};

// The repair stage (polygonizer/src/adaptive/quality.h; STATS "quality.*").
struct QualityReport {
  double repair_below_degrees = 0;  // triangles whose smallest angle is under this are repaired
  std::size_t bad_before = 0;  // triangles under the angle bound before the pass
  std::size_t bad_after = 0;
  std::size_t flips = 0, moves = 0, collapses = 0;
  // Vertices the relaxation moved (moves kept, over its sweeps), and edges it flipped.
  std::size_t relaxed = 0;
  std::size_t relax_flips = 0;
  // Of `relaxed`, the moves of the search sweeps (QualityOptions::aim_mean_edge_ratio), and
  // how many such sweeps ran.
  std::size_t relax_searched = 0, relax_search_sweeps = 0;
  // Moves of the relaxation refused because the moved star would cross a triangle nearby.
  std::size_t relax_crossings = 0;
  // Vertices added: splits of edges for the tolerance, inserts in the quad around a cap's
  // longest edge for the angles.
  std::size_t splits = 0, inserts = 0;
  // Triangles the last resort split (measured beyond the tolerance after the refinement: an
  // edge halved down to min_edge / 2, or a vertex inside at the surface point nearest the
  // farthest sample); their vertices are counted in `splits` too.
  std::size_t last_resorts = 0;
  // Vertices found on a crease (never moved, their edges never flipped).
  std::size_t crease_vertices = 0;
  // Dense measurements (28 points, Newton's path length at each) of triangles left whose
  // estimate could not clear them, after the refinement and after each round of the last resort.
  std::size_t measured_densely = 0;
  // Triangles the refinement measured densely because their estimate was within the estimate's
  // margin below the tolerance, and of those the ones it left unsplit.
  std::size_t refine_measured = 0, refine_cleared = 0;
  // Of those, the triangles farther than the tolerance there (0 unless the refinement ran out
  // of rounds or could not split without breaking a check), the largest such distance and the
  // centroid of the triangle it was measured on.
  std::size_t over_tolerance = 0;
  double over_tolerance_worst = 0;
  Vec3 over_tolerance_near = Vec3::Zero();
};

// The search for necks the fronts stepped over (polygonizer/src/adaptive/missed_necks.h).
struct NeckReport {
  std::size_t walks = 0;            // Newton walks started
  std::size_t critical_points = 0;  // distinct critical points they reached
  std::size_t tested = 0;           // thin enough to test against the mesh
  std::size_t reruns = 0;           // attempts made again with finer edges around a missed neck
  // Starts not walked once the walks reached their bound (a quarter of the mesh's vertices, at
  // least 4096): necks near them were not looked for. 0 on every run of the test suites.
  std::size_t unwalked = 0;
  // Triangles whose normal turns more than 60 degrees from a corner's (caps across a tube), looked
  // along for the core of a neck or tunnel with no saddle (a distance field's, on its medial axis).
  std::size_t caps = 0;
};

// The runs and recoveries behind the mesh kept (polygonizer/README.md, the tables kRuns and
// kRecoveries).
struct RecoveryReport {
  bool min_edge_lowered = false;         // run again with a lower min_edge
  bool turn_limited = false;             // run with every edge turning the normal at most a radian
  bool thin_sheets = false;              // run again with max_edge twice the distance of two sheets closer than its edges
  bool look_ahead = false;               // the fronts looked ahead (the run made for quality)
  bool quality_rerun = false;            // a second run was made for the quality bounds
  bool quality_rerun_kept = false;       // and its mesh was kept
  bool tolerance_rerun = false;          // a run again with min_edge lowered for triangles beyond the tolerance
  bool tolerance_rerun_kept = false;     // and its mesh was kept
  bool remeshed_with_rollbacks = false;  // meshed again with rollbacks after a stalled front
  bool remeshed_carefully = false;       // meshed again with limited turns (the careful recovery)
  double careful_max_turn = 0;           // the careful recovery's turn limit, 0 when it did not run
};

// The time and field evaluations of one phase (kAdaptivePhases), over every run made.
struct PhaseReport {
  double seconds = 0;
  EvaluationCounts evaluations;
};

// The phases of AdaptiveReport::phases, in the order a run enters them: the seed grid (and the
// hash cell's curvature sample); the crease layout (its tracing and patches); the tracking (the
// seeding and the fronts); the quality (the repair, the relaxation, the tolerance's refinement,
// the curvature properties on request); the checks (topology, intersections, the gap and neck
// searches, wherever a run makes them). An error's crease tracing for its message counts in the
// phase that failed.
inline constexpr std::array<std::string_view, 5> kAdaptivePhases{"seed_grid", "creases", "tracking", "quality",
                                                                 "checks"};

struct AdaptiveReport {
  AdaptiveSettingsReport settings;
  SeedingReport seeding;
  TrackerReport tracker;
  CreaseReport creases;
  BlocksReport blocks;
  QualityReport quality;
  NeckReport necks;
  RecoveryReport recoveries;
  // Summed over every run made, failed and discarded ones included: the evaluations add up to
  // PolygonizeStats::field_evaluations.
  std::array<PhaseReport, kAdaptivePhases.size()> phases{};
  // Evaluations split with a helper thread (a costly field tracked with two threads).
  std::uint64_t split_evaluations = 0;
  double seed_grid_seconds = 0;
  double min_angle_degrees = 0;  // the smallest angle of the mesh's triangles

  // The phase named `name` (one of kAdaptivePhases). \throw std::out_of_range for another name.
  const PhaseReport& phase(std::string_view name) const;
};

}  // namespace cdp
