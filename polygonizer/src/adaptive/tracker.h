// The state of one adaptive polygonization: the mesh being built, its fronts, the spatial
// hashes and the counters. The operations of Figure 6 of the paper are member functions,
// each defined in the file named after it:
//   tracker.cpp         vertices, front bookkeeping, seed hexagon, the polygonization cycle
//   front_angle.cpp     front angles and visibility sectors in the tangent plane
//   collision.cpp       Self-Intersection / Front-Collision tests (which front point is hit)
//   expand_point.cpp    expand (minimal-angle point -> n triangles and new front points)
//   split_front.cpp     split-front (a front that runs into itself becomes two)
//   merge_fronts.cpp    unify-front (two fronts that meet become one)
//   rollback.cpp        undo a region gone wrong and mesh it again (Settings::rollback)
#pragma once

#include "edge_length.h"
#include "front.h"
#include "missed_necks.h"
#include "spatial_hash.h"

#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/curvature.h>
#include <cdp/core/errors.h>
#include <cdp/core/newton_projection.h>

#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <span>
#include <tuple>
#include <utility>
#include <vector>

namespace cdp::adaptive {

// A ball where edges are at most `edge` long, whatever the curvature asks.
struct FinerZone {
  Vec3 center;
  double radius, edge;
};

// The shortest edge a front tries: a quarter of min_edge. A front that cannot advance even
// there is stalled (StalledFrontError). The loops that halve a placement's length from its
// target stop below kShortestEdgeLoop of min_edge instead, a little under the quarter, so that
// a length halved down to a quarter of min_edge is still tried whatever its last bits.
inline constexpr double kShortestEdge = 0.25;
inline constexpr double kShortestEdgeLoop = 0.24;

// The bound on the cost of the neighbour searches: points looked at per front step, averaged
// over windows of kSearchWindow steps (the default of AdaptiveOptions::max_search_visits).
// Surfaces the method meshes take 40-130 over a whole run (bunny VIS-800, torus, tanglecube,
// Chmutov, 50 blobs at factors 1 and 3); a window far above it has edges much shorter than the
// hash cells somewhere (the vertex hash splits crowded cells, four levels deep; the front hash
// does not) or a front running over finished mesh, and would go on for hours; it is stopped
// with an error naming the place instead. A window rather than the whole run, so that a run
// that degenerates late is stopped soon after. Past this default bound the error is a
// StalledFrontError, which the polygonizer meets as a stall, by meshing again with rollbacks;
// past a caller's own bound (AdaptiveOptions::max_search_visits) it is not.
inline constexpr std::uint64_t kSearchVisitsPerStep = 5000;
inline constexpr std::uint64_t kSearchWindow = 4096;

// Options with every default resolved.
// Settings::look_ahead: the edge length may grow by this share of the distance from a front
// point's target (with edges of about the target, 1.4 times an edge's length an edge). The
// grading's kGrowth binds first where sizes drop: with it at 1.5, 0.25 here gave the same
// meshes on the bunny VIS-800, the Igea and bunny MPU models and Chmutov's sextic.
inline constexpr double kLookAheadGradation = 0.4;

struct Settings {
  Sizing sizing;
  TriangleCountRule rule = TriangleCountRule::Hartmann;
  double collision_factor = 1.3;
  std::size_t max_triangles = 0;
  std::size_t max_steps = 0;
  // Whether a vertex placed on a kink of a black box (a bend tighter than Field::derivative_step,
  // or between two vertices a turn of a few degrees within that step: kink_between)
  // ends the run at once (BlackBoxKinkError): CreaseHandling::Follow, whose promise no mesh of
  // such a field keeps, unless its caller promises it smooth (resolve_settings).
  bool stop_at_kink = false;
  std::uint64_t search_visits_per_step = kSearchVisitsPerStep;  // AdaptiveOptions::max_search_visits
  bool callers_search_bound = false;  // search_visits_per_step is the caller's, not the default
  bool curvature_properties = false;
  // Variant::Improved's additions inside the tracker (Variant::Paper turns them off): the
  // grading of new points' targets, and points along an expansion's first and last new front
  // edges where those would be far longer than the new ones (add_side_points).
  bool grading = true;
  bool side_points = true;
  double diagonal = 1;
  // Whether regions where the tracker goes wrong are undone and meshed again (rollback.cpp).
  // polygonize_adaptive turns it on only to mesh a surface again after a StalledFrontError, and
  // in the careful run after any failure (anticipate), so that every surface meshed without it
  // comes out as before.
  bool rollback = false;
  // Whether an expansion whose new point asks for edges far shorter than it was placed at
  // places it again closer (expand_point.cpp), and rollbacks mesh their holes with shorter
  // edges (rollback.cpp). polygonize_adaptive turns both on, with the rollbacks, only to mesh
  // a surface again after a run that failed (a front that crossed a neck narrower than its
  // edges: the fifty blobs at factors 1 and 2), so that every surface meshed without it comes
  // out as before.
  bool anticipate = false;
  // Balls the careful run meshes with shorter edges from the start: around the necks and tunnels
  // the first run stepped over (missed_necks.h), which its fronts reached with edges too long to
  // see them.
  std::vector<FinerZone> finer_zones;
  // Whether an expansion's edge length also looks at the front points around it (within a few
  // edges, on any front): no longer than their targets plus kLookAheadGradation times their
  // distance. On for the fronts of crease patches, whose loops prescribe short edges that fronts
  // coming from elsewhere must grade down to before they meet them (a box face's front from its
  // outer edges met the round hole's rim, edges 0.07 apart, with edges of 0.47: 8-degree
  // triangles at factor 10).
  bool look_ahead = false;
  // The look-ahead's share of the distance (kLookAheadGradation; the crease patches' own,
  // kPatchLookAheadGradations in stage_creases.h).
  double look_ahead_gradation = kLookAheadGradation;
  // Cell size of the spatial hashes: about a typical edge, so that a query visits a few cells
  // holding a few points each whatever the density.
  double hash_cell = 1;
  CancelToken cancel;  // AdaptiveOptions::cancel
};

// The error of a front that cannot advance even at a quarter of min_edge, or whose searches
// pass the default bound on their cost (kSearchVisitsPerStep): both where a front has gone
// wrong, which a run with rollbacks undoes early.
class StalledFrontError : public LimitExceededError {
 public:
  using LimitExceededError::LimitExceededError;
};

// With Settings::stop_at_kink: a vertex placed where a black box's normal turns within the step
// of its central differences, or a step whose normal turns, beyond what its ends' curvature
// explains, by more than a few degrees within that step (kink_between),
// met a crease or corner of the function, which the field does not describe and so no mesh of it
// follows. Meshing on would not end it: the fronts that cannot cross such a crease crowd along it
// with edges of min_edge until a bound of the searches stops them (a Menger sponge as a numpy
// function, 486 triangles as an expression: 152,000 triangles and 80 s, then an error), and of 17
// such runs (box, hexagonal prism, capped cylinder, Menger sponge, fogleman's README model and the
// gyroid ball, each at factors 1, 3 and 6) three meshed, with up to 200 times the triangles an
// expression of the same function needs, in up to 17 s. The run's error names the kink
// (explain_failure in failure_message.h) and what meshes it.
class BlackBoxKinkError : public LimitExceededError {
 public:
  using LimitExceededError::LimitExceededError;
};

// How an error that names an acute crease a front stalled at ends: the way such a crease is
// meshed (polygonize_adaptive adds its own advice to other errors of a run across creases).
inline constexpr const char* kAlongCreaseAdvice = "a crease this sharp is meshed only along it (creases: follow, the default)";

// How many times the grid's measure of the area the mesh may cover before the run is stopped
// as a runaway (Crofton's estimate from the grid's crossed edges is within about 2x on surfaces
// the grid resolves). Over 343 runs (the topology sweep's 40 fields and experiments/fields at
// factors 1-5 and three tolerances, 421 tracker runs) the largest measure was 2.04, a front that
// then stalled, and the one run past it went on to the bound: blobs33 at factor 1, whose front
// ran over finished mesh with triangles 30 times smaller than the surface's and took 11 s to
// reach 8 (4.8 million steps), then the careful run meshed it in 0.03 s. 4 keeps a margin of 2
// over what meshing runs measure and stops such a runaway in less than half the time.
inline constexpr double kAreaBound = 4;
// When the area bound stops a run, the other sheet is looked for along the normal within this
// many of the last triangle's longest edge either way, sampled this many times a side and
// halved this many times (sheets_closer_than_edges). The grid's cells at most this many times
// the sheets' distance see both (a sphere's shell 0.01 thick meshed with cells of 0.034).
inline constexpr double kOtherSheetReach = 2;
inline constexpr int kOtherSheetSamples = 32;
inline constexpr int kOtherSheetHalvings = 8;
inline constexpr double kSheetGridCells = 3;

// The distance from surface point p to another sheet of the surface along its normal, either
// way, when it is under `edge` (the edges of a mesh whose fronts took one sheet for the other).
std::optional<double> sheets_apart(const Field& field, const Vec3& p, double edge);
// What an error says of two sheets `gap` apart where the edges are `edge` long: the max_edge, and
// the seed_resolution (kSheetGridCells), that keep each front on its own sheet.
std::string sheets_advice(const Field& field, double gap, double edge, double min_edge);

// Normals whose angle is below arccos of this belong to one side of the surface (see same_side).
inline constexpr double kSameSideCosine = 0;

// A placement whose normal turned more than 75 degrees from its origin's is refused above
// min_edge, so that the expansion retries at half the length (a walk over a crease is exempt:
// from the crease point on, the turn is half the crease's angle, which is right). Such a turn is beyond what the sizing plans (one radian
// of turn per edge at factor 1, less at higher factors) and means one of two things: Newton
// jumped across a gap narrower than the step onto another sheet, whose normal near the gap is
// at about 90 degrees (two spheres 1e-3 apart at factor 1 came out as triangles with corners
// on both spheres), or the curvature grows between the two points (a neck between blobs) and
// the tangent-plane tests, which see the new point foreshortened to cos 75 = 0.26, fold the
// mesh over. At factor 2 and above the torus and the bunny never turn that much. Bridges obey
// the same bound (can_bridge).
inline constexpr double kMaxTurnCosine = 0.2588;

// Points in the tracker's error messages (and the crease layout's): "(x, y, z)", six decimals.
inline std::string format_point(const Vec3& p) {
  // Appended in place: GCC 12 warns falsely (-Wstringop-overflow) on "literal" + std::string&&
  // once <string> comes from the precompiled header.
  std::string s = "(";
  s += std::to_string(p.x());
  s += ", ";
  s += std::to_string(p.y());
  s += ", ";
  s += std::to_string(p.z());
  s += ")";
  return s;
}

class Tracker {
 public:
  // A surface point with its curvature (one gradient_hessian evaluation), ready to become a vertex.
  struct Placed {
    Vec3 point;
    Curvature curvature;
    // The Newton step toward grad F = 0 from the point, where the Hessian is regular
    // (missed_necks.h): vertices close to a critical point start the search for necks the
    // fronts stepped over.
    std::optional<Vec3> to_critical = std::nullopt;
    // The target edge length the C1 seams near the point ask for (seam_edge_length;
    // Settings::grading only): infinite where there is none.
    double seam_target = std::numeric_limits<double>::infinity();
  };

  Tracker(const Field& field, const Settings& settings, Mesh& mesh);
  // For a cancelled run: hands the tracker's memory (its hashes' cells, the fronts, the
  // per-vertex arrays; no callback) to a thread of its own (background_release.h), leaving the
  // tracker empty. Only its destructor may follow.
  void release_in_background() noexcept;
  // Frees the per-vertex arrays, the hashes and the fronts once the run asks nothing of them (after
  // the repair and the curvature properties): their counters stay (report, splits, merges, area,
  // the tightest bend, the critical starts). At 1.85M triangles, 45 MB that the final checks,
  // the run's peak, no longer hold. Only the counters may be asked for after it.
  void release_bulk();
  // AdaptiveOptions::cancel, for the stages that work beside the tracker (the seeding's checks).
  const CancelToken& cancel_token() const { return s_.cancel; }

  // Meshes the component through `seed` (a point on the surface). Returns false when not even
  // the first hexagon could be placed there (the caller tries another seed).
  bool mesh_from_seed(const Vec3& seed);
  // Meshes the region bounded by `loops`, each a closed polygon of new vertices (at least three)
  // with the unmeshed region on its left seen from outside (front.h): the loops become the
  // fronts, and their edges stay as they are, each getting one triangle. Returns the vertex ids
  // given to the loops' points. Crease-aware meshing starts each piece's patches this way.
  std::vector<std::vector<int>> mesh_from_loops(std::span<const std::vector<Placed>> loops);
  // Takes the vertices and triangles already in the mesh (meshed elsewhere, with these
  // per-vertex targets and curvature properties) as finished surface: the fronts treat them as
  // they treat their own finished mesh, and the area bound counts them.
  void adopt_finished(std::span<const double> target, std::span<const double> mac, std::span<const double> shape_index);
  // The same, taking the arrays rather than copying them.
  void adopt_finished(std::vector<double>&& target, std::vector<double>&& mac, std::vector<double>&& shape_index);
  // For a tracker meshing one piece's patches (crease_patches.h): whether a straight edge between
  // two points of the loops runs inside the patches rather than across a region the piece does
  // not cover (two loops of the piece pass close by each other there). Bridges between two loop
  // vertices must pass it.
  using PatchTest = std::function<bool(const Vec3&, const Vec3&)>;
  void set_patch_test(PatchTest test) { patch_test_ = std::move(test); }
  // And whether a new point (placed with step d) lies in the patches: a front that crosses its
  // boundary (through a neck narrower than its edges) would go on over the piece's surface
  // beyond the patch, where the CSG field takes another piece. Such placements are refused.
  using PointTest = std::function<bool(const Vec3&, double)>;
  void set_point_test(PointTest test) { point_test_ = std::move(test); }
  // Whether an edge between vertices u and w would leave the patches (both loop vertices, and
  // the patch test fails; counted). Bridges are refused then, and closures expand instead.
  bool leaves_patch(int u, int w) const;

  void set_progress(ProgressCallback cb) { progress_ = std::move(cb); }
  // The surface's area as the seed grid measures it (0: unknown). Progress is reported against
  // it, and a mesh whose area passes kAreaBound times it has a front running over finished mesh.
  void set_estimated_area(double area) { estimated_area_ = area; }
  // The area of the triangles made so far (with those adopted from the crease patches).
  double area() const { return area_; }

  std::size_t steps() const { return steps_; }
  // Points looked at by the spatial searches (front and vertex hashes).
  std::uint64_t search_visits() const {
    return released_visits_ ? *released_visits_ : front_hash_.visits() + vertex_hash_.visits();
  }
  // Throws LimitExceededError, naming the place of `node`, when the searches have cost more than
  // Settings::search_visits_per_step a step.
  void check_search_budget(int node);
  std::size_t splits() const { return splits_; }
  std::size_t merges() const { return merges_; }
  std::size_t deferrals() const { return deferrals_; }
  // The vertex where the surface bends most tightly (smallest radius of curvature) so far, and
  // that radius (infinity before the first vertex): where it is below min_edge the sizing was
  // clamped there, and an error names the place.
  std::pair<double, Vec3> tightest_bend() const { return tightest_; }
  // Placements made again at half the length because the new point asked for far shorter edges.
  std::size_t anticipations() const { return anticipations_; }
  std::size_t side_points() const { return side_points_; }  // add_side_points' points in expansions made
  // The vertices placed within kCriticalReach edges of a critical point of F (missed_necks.h).
  const std::vector<CriticalStart>& critical_starts() const { return critical_starts_; }
  // The distance between the two sheets sheets_closer_than_edges found where this tracker stopped
  // (polygonize_adaptive meshes them again with max_edge twice it: kRuns' thin_sheets).
  std::optional<double> sheets_gap() const { return sheets_gap_; }
  // Small stuck fronts closed ear by ear without the expansion's tests.
  std::size_t forced_closures() const { return forced_closures_; }
  // Points placed on a crease, with the mean normal of its two sides.
  std::size_t crease_points() const { return crease_points_; }
  // Placements refused because they landed on finished mesh.
  std::size_t over_mesh() const { return over_mesh_; }
  // Placements refused because Newton took them onto another sheet (jumped).
  std::size_t sheet_jumps() const { return sheet_jumps_; }
  // Wall-clock time spent in curvature_at (Hessian evaluation and eigen-decomposition).
  // Time in curvature: the Hessian evaluations and the eigen-decomposition together, and the
  // evaluations alone.
  double curvature_seconds() const { return curvature_seconds_; }
  double hessian_seconds() const { return hessian_seconds_; }
  // Stuck regions undone and re-meshed (see rollback.cpp).
  std::size_t rollbacks() const { return rollbacks_; }
  // Rollbacks given up because the hole's boundary could not be traced into fronts.
  std::size_t failed_rollbacks() const { return failed_rollbacks_; }
  // Bridges refused because they would leave the patches (set_patch_test).
  std::size_t patch_refusals() const { return patch_refusals_; }
  // The counters above as the run's report holds them (min_curvature_radius left at -1: the run
  // reports the tightest bend of all its trackers, Tracking::tightest).
  TrackerReport report() const;
  // Drops the vertices rollbacks left without a triangle, renumbering the rest (a no-op when
  // there was no rollback). Call once, after the last seed.
  void compact();
  const std::vector<double>& vertex_mac() const { return mac_; }
  const std::vector<double>& vertex_shape_index() const { return shape_index_; }
  const std::vector<double>& vertex_edge_length() const { return target_; }

 private:
  // What measure may take instead of evaluating a point: the gradient and Hessian already
  // evaluated there (BatchProjector::hessian); a null Hessian where none was.
  struct Known {
    const Vec3* gradient = nullptr;
    const Mat3* hessian = nullptr;
  };
  // One new point's walk along the surface (see place_points).
  struct Walk {
    Vec3 at, normal, heading;
    Vec3 start_gradient;  // where this leg's Newton started (ProjectionResult::start_gradient)
    double left = 0;
    std::optional<Placed> placed;
    bool walking = true, failed = false;
    std::size_t creases = 0;  // crease points it landed on, counted once it is known to be wanted
  };
  // The buffers of place_points, kept from expansion to expansion: allocating them for the one
  // or two points of each would cost a few percent of the run on a cheap field.
  struct PlacementBuffers {
    std::vector<Walk> walks;
    std::vector<std::size_t> legging;  // the walks taking the current leg
    std::vector<Vec3> starts, landed, crease_at, crease_n;
    std::vector<Known> known;
    std::vector<ProjectionOptions> options;
    std::vector<std::optional<Placed>> measured;
    std::vector<std::optional<Vec3>> creases;
    BatchProjector newton;
  };
  // measure's buffers of field derivatives.
  struct DerivativeBuffers {
    std::vector<double> values;
    std::vector<Vec3> points, gradients;
    std::vector<Mat3> hessians;
    std::vector<std::size_t> which;  // of the points, those evaluated here
  };
  struct ExpandOutcome {
    bool expanded = false;
    int obstacle = -1;  // when not expanded: a front node to bridge to, or -1
  };

  // Whether surface normals n and m (or vertex w's) belong to one side of the surface rather
  // than to two sheets facing each other across a thin gap or wall.
  static bool same_side(const Vec3& n, const Vec3& m) { return n.dot(m) > kSameSideCosine; }
  bool same_side(const Vec3& n, int w) const { return same_side(n, mesh_.normals[w]); }

  // --- tracker.cpp
  // Curvature at each point into out; nothing where the gradient vanishes. One gradients_hessians
  // batch, of the points without a Hessian in `known` (optional, one per point; see Known).
  void measure(std::span<const Vec3> points, std::vector<std::optional<Placed>>& out,
               std::span<const Known> known = {}) const;
  int add_vertex(const Placed& placed);
  // New surface points about distance d from vertex v, one in each tangent direction, as far
  // as they can be placed in order: the first direction where Newton fails or lands somewhere
  // implausible (another sheet, far away, finished mesh) ends the list. The directions' field
  // evaluations are batched (see place_points in tracker.cpp).
  std::vector<Placed> place_points(int v, std::span<const Vec3> dirs, double d) const;
  // Whether a point placed from vertex v along `heading` (unit, tangent) at distance d landed on
  // another sheet than v's (see tracker.cpp).
  bool jumped(int v, const Vec3& heading, double d, const Placed& landed) const;
  // Where a step of a black box from `a` (normal `na`) to `landed` crosses a kink of it (a crease
  // the differences resolve on both sides of), as the bend found there.
  std::optional<std::pair<double, Vec3>> kink_between(const Vec3& a, const Vec3& na, const Placed& landed) const;

 public:
  // The angle between the normal at pb and the normal at pa carried along the chord by the two
  // ends' curvature: the turn their curvature does not explain (a crease's angle across one).
  static double unexplained_turn(const Vec3& pa, const Curvature& ka, const Vec3& pb, const Curvature& kb);

 private:
  // For each point xs[i] whose gradient is ns[i]: the mean of the normals on both sides when it
  // lies on a crease, nothing elsewhere. Two value_gradient evaluations a point, in one batch.
  void crease_normals(std::span<const Vec3> xs, std::span<const Vec3> ns, std::vector<std::optional<Vec3>>& out) const;
  // Whether x (with its normal, placed at step d) lies on finished mesh (counted).
  bool over_finished_mesh(const Vec3& x, const Vec3& normal, double d) const;
  void emit_triangle(int a, int b, int c);
  // Why fronts run over finished mesh at p, where the failing triangle's edges are `edge` long:
  // another sheet of the surface nearer than that along the normal (a shell, a plate), and the
  // options that resolve it; empty when there is none.
  std::string sheets_closer_than_edges(const Vec3& p, double edge);
  std::optional<double> sheets_gap_;  // what sheets_closer_than_edges found
  int insert_node(int vertex, int front);
  // fs_.link, and the new front edge a -> b into the record of front edge lengths.
  void link(int a, int b);
  // The longest edge on any front now (edges that left the fronts are dropped lazily, and in
  // bulk by drop_stale_front_edges).
  double longest_front_edge() const;
  // Drops the stale entries of front_edges_ (see there).
  void drop_stale_front_edges();
  // Whether the front through node is a slit: narrower than min_edge, on one sheet (see step).
  bool is_slit(int node) const;
  void remove_node(int node);
  void refresh(int node);  // recompute the angle and requeue
  void relabel(int start, int front);
  void run_fronts();
  void step(int& front);
  void check_limits();
  bool zip_spike(int node);
  // For the error of a front that cannot advance: the closest pair (a vertex of node's front,
  // a mesh vertex) within `radius` whose normals face opposite ways, if any (within min_edge: a
  // feature thinner than min_edge).
  std::optional<std::pair<int, int>> thin_feature_at(int node, double radius) const;
  // For the same error: whether two such points lie on the two faces of a crease of the field
  // (Field::pieces) that passes near them, a wedge rather than a slab; its point and the angle
  // between its faces, seen from inside, in degrees.
  struct AcuteCrease {
    Vec3 point;
    double degrees;
  };
  std::optional<AcuteCrease> acute_crease_between(const Vec3& a, const Vec3& b) const;
  double local_edge_length(int node) const;

  // --- rollback.cpp
  // Removes the triangles around node (at_node) or around every point of its front f, with
  // every front touching them, and re-derives the hole's boundary as new fronts. Returns false
  // when the bounds are spent or the hole's boundary cannot be traced (nothing changed then).
  bool rollback(int f, int node, bool at_node);
  // The vertices of the component being meshed within `radius` of a stuck point, on its side.
  std::vector<char> rollback_region(const std::vector<int>& stuck, double radius) const;
  // Removes a traced hole: the `absorbed` fronts, the `removed` triangles (by index from the
  // component's first), the vertices `had` one of them and no other, and makes its `loops` fronts.
  void cut_hole(const std::vector<int>& absorbed, const std::vector<char>& removed, const std::vector<char>& had,
                const std::vector<std::vector<int>>& loops);

  // --- front_angle.cpp
  double front_angle(int node) const;
  // Angle of x around node's vertex, measured counter-clockwise from the direction of next in
  // the tangent plane, in [0, 2 pi).
  double sector_position(int node, const Vec3& x) const;
  bool in_sector(int node, const Vec3& x, double margin) const;

  // --- collision.cpp
  // A front node that the expansion of `node` with edge length delta would run into, or -1.
  int find_collision(int node, double delta) const;
  // The front node within radius that node bridges to best (the bridge leaving the largest
  // smallest angle, nearest first among good ones), or -1.
  int find_bridge(int node, double radius) const;
  // The triangle (prev, node, next) that closing node's angle adds.
  struct Ear {
    int node = -1, va = -1, vb = -1;  // the node, its prev's and its next's vertices
    double radius = 0;                // the longer of its two sides at node
    Vec3 inward = Vec3::Zero();       // normal at node x (b - a): into the triangle (a, p, b)
    double side_p = 0;                // inward . (p - a)
  };
  Ear ear(int node) const;
  // Whether the front point at vertex vq lies in the ear, as the paper's closing test sees it in
  // the tangent plane at node: nearer to node than the ear's longer side, facing the same way,
  // on node's side of the new edge (points right on it count) and inside node's sector.
  bool in_ear(const Ear& e, int vq) const;
  // The nearest front node in the ear (find_closing_obstacle), or -1.
  int find_closing_obstacle(int node) const;
  // Whether no other point of node's own front lies in the triangle (prev, node, next), seen in
  // node's tangent plane: the ear can be cut off without covering the rest of the front.
  bool ear_is_clear(int node) const;
  // The start node of a front edge that the segment from vertex vu to point w (vertex vw, or -1
  // for a point not yet in the mesh) crosses, seen in the tangent plane of frame_vertex; or -1.
  // With `near`, the front nodes come from the cells it gathered (the same answer).
  int crossed_front_edge(int vu, int vw, const Vec3& w, int frame_vertex,
                         const SpatialHash::Gathered* near = nullptr) const;
  // The box crossed_front_edge searches for the segment u-w, given longest_front_edge().
  std::pair<Vec3, Vec3> front_edge_search_box(const Vec3& u, const Vec3& w, double longest) const;
  // What to do when a new edge of node's expansion would cross the front edge starting at r:
  // the best bridge from node to a point at least as near as the far end of that edge, or -1.
  int bridge_around(int node, int r) const;
  // Whether node and q may be joined by a bridge edge.
  bool can_bridge(int node, int q) const;
  // The smallest of the four angles a bridge node-q leaves at its ends.
  double bridge_quality(int node, int q) const;

  // --- expand_point.cpp
  // Expands node with edge length delta into new triangles (Figure 6, expand), or reports the
  // front node in the way.
  ExpandOutcome expand(int node, double delta);
  // expand's steps. The fan's count - 1 new points at length delta, halved where they cannot be
  // placed (`placed_at` the length they were placed at); empty when none could be.
  std::vector<Placed> place_fan(const FrontNode& n, int count, double delta, double& placed_at);
  struct Fan {  // the fan's own first and last points and count, before any side points join them
    Vec3 first, last;
    std::size_t size;
  };
  // What to do instead of the expansion where its new points or edges meet the front, if anything.
  std::optional<ExpandOutcome> refuse_fan(int node, const std::vector<Placed>& placed, const Fan& fan, double delta);
  // The fan's triangles, and its points as front points in node's place.
  void emit_fan(int node, const std::vector<Placed>& placed, double delta);
  void close_angle(int node);
  bool folds_across(int vb, const std::vector<Placed>& placed, int va) const;
  // Adds to `placed` (the new points of expanding vertex v between its front neighbours vb
  // and va, placed at length d) points along its first and last new front edges where those
  // are longer than kSideEdgeRatio times d.
  void add_side_points(int v, int vb, int va, double d, std::vector<Placed>& placed);

  // --- split_front.cpp, merge_fronts.cpp
  void split_front(int p, int q);
  int merge_fronts(int p, int q);  // returns the surviving front

  const Field& field_;
  Settings s_;
  Mesh& mesh_;
  std::vector<double> target_, mac_, shape_index_;
  std::vector<CriticalStart> critical_starts_;
  // Front edges by length (length, start node, end node), a max-heap with lazy deletion: an
  // entry is stale once its start node has left the fronts or links elsewhere, and the stale
  // entries are dropped each time the heap has doubled (drop_stale_front_edges). Kept with
  // std::push_heap and std::pop_heap (a priority_queue's order) so that it grows polled
  // (polled_growth.h): with every edge a front ever had, one doubling was a tenth of a second at
  // 2*10^6 triangles.
  mutable std::vector<std::tuple<double, int, int>> front_edges_;
  // Its stale entries are dropped when it reaches this size, which is then set to twice what is
  // left (drop_stale_front_edges).
  std::size_t drop_stale_at_ = kMinStaleDrop;
  static constexpr std::size_t kMinStaleDrop = std::size_t{1} << 16;
  FrontSet fs_;
  SpatialHash front_hash_;
  // Splits crowded cells (Crowding::split), which changes the order of its points: every query
  // on it marks, tests for any, or takes a minimum with ties broken by id. Read through
  // vertex_hash(), which first inserts the vertices [0, unhashed_) that adopt_finished or compact
  // left out of it: a mesh adopted from the blocks whose surface the seeding finds covered never
  // asks for them (the torus at 1.85M triangles: 0.14 s, one core, of a serial stretch).
  mutable SpatialHash vertex_hash_;
  mutable std::size_t unhashed_ = 0;
  SpatialHash& vertex_hash() const {
    if (unhashed_ > 0) hash_vertices();
    return vertex_hash_;
  }
  void hash_vertices() const;
  // Where the vertex hash's points are, for a crowded cell that splits (SpatialHash::insert).
  auto vertex_position() const {
    return [this](int v) -> const Vec3& { return mesh_.positions[static_cast<std::size_t>(v)]; };
  }
  std::vector<int> front_refs_;  // front nodes of each vertex: 0 once it is finished
  std::vector<int> stack_;
  // Rollbacks: vertices left without a triangle, the places rolled back (point, times), and
  // where the current component's vertices and triangles begin.
  std::vector<char> dead_;
  std::vector<std::pair<Vec3, int>> rollback_places_;
  // Balls where edges are shorter (Settings::finer_zones, and where a rollback meshes again).
  std::vector<FinerZone> finer_zones_;
  std::vector<double> rollback_place_targets_;  // per rollback place: its first longest target
  // Mutable: place_points records the kinks its steps cross (kink_between) here too.
  mutable std::pair<double, Vec3> tightest_{std::numeric_limits<double>::infinity(), Vec3::Zero()};
  // A placed point's target edge length: its curvature's, capped by a seam ahead and by the finer zones.
  double placed_target(const Placed& x) const {
    return zone_capped(x.point, std::min(edge_length(s_.sizing, x.curvature.min_radius), x.seam_target));
  }
  // The target edge length at p: `target`, capped by the finer zones p is in.
  double zone_capped(const Vec3& p, double target) const {
    for (const FinerZone& z : finer_zones_)
      if ((p - z.center).squaredNorm() < z.radius * z.radius) target = std::min(target, z.edge);
    return target;
  }
  std::size_t rollbacks_ = 0, failed_rollbacks_ = 0, first_vertex_ = 0, first_triangle_ = 0;
  std::uint64_t window_visits_ = 0;  // search_visits() at the start of the current window
  std::size_t steps_ = 0, splits_ = 0, merges_ = 0, deferrals_ = 0, forced_closures_ = 0, anticipations_ = 0;
  std::size_t side_points_ = 0;
  double area_ = 0, estimated_area_ = 0, last_progress_ = 0;
  // Field::derivative_step, 0 for a field with exact derivatives: a bend tighter than it is a
  // kink of a black box (Settings::stop_at_kink).
  double kink_radius_ = 0;
  mutable double curvature_seconds_ = 0, hessian_seconds_ = 0;
  mutable std::size_t crease_points_ = 0, over_mesh_ = 0, sheet_jumps_ = 0;
  mutable PlacementBuffers placement_;
  mutable DerivativeBuffers derivatives_;
  mutable SpatialHash::Gathered near_front_;  // expand's checks: the front cells around the expansion
  ProgressCallback progress_;
  PatchTest patch_test_;
  PointTest point_test_;
  std::vector<char> loop_vertex_;  // vertices given by mesh_from_loops
  mutable std::size_t patch_refusals_ = 0;
  std::optional<std::uint64_t> released_visits_;  // search_visits() when release_bulk freed the hashes
};

// Adds r's counters to sum's (min_curvature_radius left alone).
void add_tracker_counts(TrackerReport& sum, const TrackerReport& r);

}  // namespace cdp::adaptive
