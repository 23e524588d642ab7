// polygonize_adaptive: resolves the options, finds seeds on every component, runs the tracker
// from each seed not yet covered, and fills in the common statistics.
#include "crease_patches.h"
#include "../helper_thread.h"
#include "../parallel.h"
#include "quality.h"
#include "seeding.h"
#include "spatial_hash.h"
#include "surface_gaps.h"
#include "tracker.h"

#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/crease_curves.h>
#include <cdp/core/curvature.h>
#include <cdp/core/errors.h>
#include <cdp/core/mesh_topology.h>
#include <cdp/core/surface_seeds.h>
#include <cdp/core/triangle_intersection.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

namespace cdp {

const char* to_string(SizingMode mode) {
  switch (mode) {
    case SizingMode::Factor: return "factor";
    case SizingMode::Tolerance: return "tolerance";
    case SizingMode::Chord: return "chord";
  }
  return "?";
}

const char* to_string(CreaseHandling creases) { return creases == CreaseHandling::Follow ? "follow" : "ignore"; }

const char* to_string(TriangleCountRule rule) {
  return rule == TriangleCountRule::PaperFloor ? "paper_floor" : "hartmann";
}

const char* to_string(Variant variant) { return variant == Variant::Paper ? "paper" : "improved"; }

namespace {

// Time and field evaluations by phase (kAdaptivePhases) of the runs polygonize_adaptive makes
// (stats "phases.*"), summed over every run it makes, failed and discarded ones included: the
// phases' evaluations add up to the run's field_evaluations exactly (nothing between runs
// evaluates), and their seconds to nearly all of its seconds (between runs: a discarded run's
// stats and destructors, the bounds a re-run is judged by, a fraction of a percent). A phase
// lasts from its entry to the next phase's or the run's end.
class PhaseLedger {
 public:
  explicit PhaseLedger(const Field& field) : field_(field) {}
  void enter(std::string_view name) {
    close();
    const auto it = std::find(kAdaptivePhases.begin(), kAdaptivePhases.end(), name);
    if (it == kAdaptivePhases.end()) throw std::logic_error("PhaseLedger: no phase " + std::string(name));
    current_ = static_cast<int>(it - kAdaptivePhases.begin());
    start_ = std::chrono::steady_clock::now();
    counts_ = field_.counts();
  }
  // Ends the current phase (a run's end, or its error).
  void close() {
    if (current_ < 0) return;
    Entry& e = entries_[current_];
    e.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    e.evaluations += field_.counts() - counts_;
    current_ = -1;
  }
  // Evaluations a run split with a helper thread (helper_thread.h; stats "split_evaluations").
  void add_split_evaluations(std::uint64_t n) { split_evaluations_ += n; }
  // Every phase, zero where no run entered it.
  void write(PolygonizeStats& st) const {
    st.extra["split_evaluations"] = split_evaluations_;
    for (std::size_t i = 0; i < kAdaptivePhases.size(); ++i) {
      const std::string key = "phases." + std::string(kAdaptivePhases[i]) + ".";
      st.extra[key + "seconds"] = entries_[i].seconds;
      st.extra[key + "value"] = entries_[i].evaluations.value;
      st.extra[key + "value_gradient"] = entries_[i].evaluations.value_gradient;
      st.extra[key + "gradient_hessian"] = entries_[i].evaluations.gradient_hessian;
    }
  }

 private:
  struct Entry {
    double seconds = 0;
    EvaluationCounts evaluations;
  };
  const Field& field_;
  std::array<Entry, kAdaptivePhases.size()> entries_{};
  std::uint64_t split_evaluations_ = 0;
  int current_ = -1;
  std::chrono::steady_clock::time_point start_{};
  EvaluationCounts counts_;
};

// Closes the ledger's phase when a run ends, by its return or its error.
struct PhaseCloser {
  PhaseLedger& ledger;
  ~PhaseCloser() { ledger.close(); }
};

// The sharpest crease of a traced layout, as the angle at which its two faces meet (180 degrees
// less the angle between the two pieces' outward normals, as Tracker::acute_crease_between
// measures it) at the traced point where it is smallest, and that point.
std::optional<std::pair<double, Vec3>> sharpest_crease(const Field& field, const CreaseTracingResult& traced) {
  std::optional<std::pair<double, Vec3>> best;
  for (const CreaseCurve& c : traced.curves)
    for (const Vec3& p : c.points) {
      const Vec3 na = field.piece(p, c.pieces[0]).gradient, nb = field.piece(p, c.pieces[1]).gradient;
      if (!(na.squaredNorm() > 0 && nb.squaredNorm() > 0)) continue;
      const double degrees = 180.0 - std::atan2(na.cross(nb).norm(), na.dot(nb)) * 180.0 / std::numbers::pi;
      if (!best || degrees < best->first) best = std::pair(degrees, p);
    }
  return best;
}

// Variant::Improved repairs triangles whose smallest angle is under 30 degrees: the quality
// bounds below ask for every triangle at 20 degrees or more and 99% at 30 or more, and aiming
// the repair at the higher bound leaves the lower one a margin.
constexpr double kRepairBelowDegrees = 30;

// The quality bounds on a smooth surface's mesh (see missed_bounds): a smallest angle of at least
// kBoundMinDegrees, at most kBoundShareUnder30 of the triangles with one under 30 degrees, a
// mean longest/shortest edge of at most kBoundMeanEdgeRatio. The last is also the repair's aim
// (QualityOptions::aim_mean_edge_ratio): its relaxation searches its moves where its plain
// sweeps leave the mean over it.
constexpr double kBoundMinDegrees = 20;
constexpr double kBoundShareUnder30 = 0.01;
constexpr double kBoundMeanEdgeRatio = 1.25;
// Where the distance bound needs it, the repair's last resort (quality.h) may halve edges down
// to this share of the default min_edge: an edge between one and two min_edge long on a bend a
// little tighter than min_edge follows (blobs37 of the topology sweep at 1e-3: radius of
// curvature 0.0062, edges of 0.009 where 0.0077 keeps the bound, min_edge 0.0063) cannot be
// split into halves of min_edge.
constexpr double kLastResortEdgeShare = 0.5;
// Creases are traced on the seed grid first and, when they cannot be laid out as patch boundaries
// (a corner whose boundary breaks off: a short crease between crossings of the grid was
// missed), once more on a grid twice as fine (eight times the values, on a field cheap enough
// to have min/max/abs branches: an expression).
constexpr int kCreaseTracings = 2;
// Variant::Improved with a tolerance sizes edges for a sagitta of this share of eps, and the
// refinement of quality.h splits what still exceeds eps. A triangle deviates more than its
// edges (an equilateral one with edges of sagitta s bulges 4/3 s at its centre: circumradius
// l / sqrt(3) against l / 2), so the full eps leaves many triangles to split, and splits make
// uneven triangles (each split leaves a vertex of valence 4, which the relaxation cannot make
// equilateral without breaking the bound the split just met); a small share makes triangles no
// split would have needed. Measured on the torus (R = 1, r = 0.35) at eps = 1e-3 before the
// relaxation: shares 0.5, 0.7, 1.0 give 25.9k, 19.6k, 19.8k triangles with 57, 534, 3488 splits
// and mean edge ratios 1.22, 1.25, 1.47. With it, shares 0.7 / 0.65 / 0.6: the unit sphere at
// 1e-4 83.3k / 78.7k / 77.6k triangles, 12.7k / 8.1k / 4.9k splits, ratios 1.289 / 1.237 / 1.199;
// the torus at 1e-3 19.5k / 20.5k / 21.9k, 1.168 / 1.157 / 1.145; the bunny VIS-800 at 3e-5
// 74.0k / 77.2k / 82.5k, 1.180 / 1.169 / 1.161. 0.65 is the largest share that keeps every
// measured case under the mean ratio of 1.25 (the quality bounds), at -6 % to +5 % triangles.
constexpr double kToleranceSizingShare = 0.65;
// SizingMode::Chord's edges turn the normal by at most this many radians (Sizing::max_turn): the
// paper's factor 1 where the chord sizing asks for longer edges. Without it blobs19 of the
// topology sweep at a chord deviation of 1e-3 of the diagonal kept a triangle of 10.5 degrees
// (2280 triangles; 28.2 degrees with it, and 23.0 / 26.4 with 0.7 / 0.5).
constexpr double kChordMaxTurn = 1;

adaptive::Settings resolve(const Field& field, const AdaptiveOptions& o) {
  const Box& box = field.bounds();
  if (!box.valid()) throw NoSurfaceError("adaptive: the field has no valid bounding box");
  const double diag = box.diagonal();
  const auto positive_or_default = [](double v, double fallback) { return v > 0 ? v : fallback; };
  adaptive::Settings s;
  s.diagonal = diag;
  s.sizing.mode = o.sizing;
  s.sizing.factor = o.factor;
  // A NaN would otherwise pass for "not given" below (positive_or_default).
  if (std::isnan(o.tolerance)) throw InvalidInputError("adaptive: the tolerance must be a number, not nan");
  if (std::isnan(o.min_edge)) throw InvalidInputError("adaptive: min_edge must be a number, not nan");
  if (std::isnan(o.max_edge)) throw InvalidInputError("adaptive: max_edge must be a number, not nan");
  s.sizing.tolerance = positive_or_default(o.tolerance, 1e-3 * diag);
  if (o.variant == Variant::Improved && o.sizing == SizingMode::Tolerance) s.sizing.tolerance *= kToleranceSizingShare;
  // The chord sizing asks for chords longer than the radius of curvature where eps exceeds r / 8;
  // Tolerance's refinement splits what that leaves beyond eps, and Chord, which measures
  // nothing, keeps its edges to the turn of the paper's factor 1 instead (kChordMaxTurn).
  if (o.variant == Variant::Improved && o.sizing == SizingMode::Chord) s.sizing.max_turn = kChordMaxTurn;
  s.grading = o.variant == Variant::Improved;
  s.side_points = o.variant == Variant::Improved && !field.has_pieces();
  // The default min_edge matches the default tolerance (1e-3 of the diagonal); a smaller
  // tolerance asks for edges shorter as its square root (the sagitta grows as the edge
  // squared), and Variant::Improved lowers the default with it so that the clamp does not
  // break the distance bound a tolerance promises, nor coarsen the sizing a chord asks for.
  double min_edge_default = 2e-3 * diag;
  if (o.variant == Variant::Improved && o.sizing != SizingMode::Factor && o.tolerance > 0 && o.tolerance < 1e-3 * diag)
    min_edge_default *= std::sqrt(o.tolerance / (1e-3 * diag));
  s.sizing.min_edge = positive_or_default(o.min_edge, min_edge_default);
  s.sizing.max_edge = positive_or_default(o.max_edge, 0.1 * diag);
  s.hash_cell = s.sizing.max_edge;  // refined from the seed crossings once they are known
  if (o.sizing == SizingMode::Factor && !(std::isfinite(o.factor) && o.factor > 0))
    throw InvalidInputError("adaptive: the factor must be a positive number, not " + std::to_string(o.factor));
  if (!std::isfinite(s.sizing.tolerance) || !std::isfinite(s.sizing.min_edge) || !std::isfinite(s.sizing.max_edge))
    throw InvalidInputError("adaptive: tolerance and edge lengths must be finite");
  if (s.sizing.min_edge > s.sizing.max_edge)
    throw InvalidInputError("adaptive: min_edge (" + std::to_string(s.sizing.min_edge) + ") exceeds max_edge (" +
                            std::to_string(s.sizing.max_edge) + ")");
  if (!(o.collision_factor >= 0.5 && o.collision_factor <= 3))
    throw InvalidInputError("adaptive: collision_factor must lie in [0.5, 3]");
  if (o.seed_resolution < 2) throw InvalidInputError("adaptive: seed_resolution must be at least 2");
  if (o.threads < 0) throw InvalidInputError("adaptive: threads must be 0 (all cores) or positive");
  s.rule = o.triangle_count;
  s.collision_factor = o.collision_factor;
  s.curvature_properties = o.curvature_properties;
  const Vec3 e = box.size();
  const double box_area = 2 * (e.x() * e.y() + e.y() * e.z() + e.z() * e.x());
  const double tri_area = std::sqrt(3.0) / 4 * s.sizing.min_edge * s.sizing.min_edge;
  const double derived = std::min(5e7, std::max(1e4, 20 * box_area / tri_area));
  s.max_triangles = o.max_triangles > 0 ? o.max_triangles : static_cast<std::size_t>(derived);
  s.max_steps = o.max_steps > 0 ? o.max_steps : 4 * s.max_triangles + 10000;
  s.search_visits_per_step = o.max_search_visits > 0 ? o.max_search_visits : adaptive::kSearchVisitsPerStep;
  s.callers_search_bound = o.max_search_visits > 0;
  s.cancel = o.cancel;
  return s;
}

// The tolerance the caller asked for (the sizing may use a share of it).
double positive_or_default_tolerance(const AdaptiveOptions& o, const adaptive::Settings& s) {
  return o.tolerance > 0 ? o.tolerance : 1e-3 * s.diagonal;
}

std::string format_point(const Vec3& p) {
  std::ostringstream s;
  s << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return s.str();
}

// The last line of defence against a wrong mesh with exit 0: the tracker's own output must be
// closed, oriented and manifold, each seed must have grown one component of its own (a front
// that merged across a gap into another sheet joins two), and (unless the caller opts out) no two
// triangles may intersect (fronts that crossed each other). Returns the components; throws
// NoSurfaceError naming the place otherwise. (A test of triangles against the vertex normals
// was tried and dropped: the MPU models' correct meshes have triangles whose face turns more
// than 120 degrees from a noisy vertex normal.)
std::size_t check_mesh(const Mesh& mesh, std::size_t seeds, bool check_intersections, int threads,
                       const CancelToken& cancel) {
  // With several threads the topology check runs on one of its own beside the intersection
  // check, whose blocks the other threads share: it is the serial part of the two (the paper
  // variant's torus at factor 5: about 8.5M instructions against the intersections' 31.5M).
  // Both are pure functions of the mesh, and their failures are reported in the order below
  // either way.
  const bool side_by_side = check_intersections && detail::worker_count(threads) > 1;
  MeshTopology t;
  std::vector<std::pair<int, int>> pairs;
  if (side_by_side) {
    std::exception_ptr error;
    std::thread topology([&] {
      try {
        t = analyze_topology(mesh);
      } catch (...) {
        error = std::current_exception();
      }
    });
    try {
      pairs = self_intersecting_pairs(mesh, 1, threads, &cancel);
    } catch (...) {
      topology.join();
      throw;
    }
    topology.join();
    if (error) std::rethrow_exception(error);
  } else {
    t = analyze_topology(mesh);
  }
  const auto fail = [](const std::string& what, const Vec3& where) {
    throw NoSurfaceError("adaptive: the mesh came out " + what + " near " + format_point(where) +
                         "; the surface may have a feature thinner than min_edge there");
  };
  if (!t.closed() || !t.edge_manifold() || !t.vertex_manifold() || !t.oriented())
    fail("with " + std::to_string(t.boundary_edges) + " boundary, " + std::to_string(t.nonmanifold_edges) +
             " non-manifold and " + std::to_string(t.misoriented_edges) + " misoriented edges, " +
             std::to_string(t.nonmanifold_vertices) + " non-manifold vertices",
         mesh.positions.empty() ? Vec3::Zero() : mesh.positions.front());
  if (t.components != seeds)
    fail("with " + std::to_string(t.components) + " components from " + std::to_string(seeds) + " seeds",
         mesh.positions.front());
  if (check_intersections) {
    if (!side_by_side) pairs = self_intersecting_pairs(mesh, 1, threads, &cancel);
    if (!pairs.empty())
      fail("intersecting itself (" + std::to_string(count_self_intersecting_pairs(mesh, threads)) + " pairs of triangles)",
           mesh.positions[mesh.triangles[pairs.front().first][0]]);
  }
  return t.components;
}

// A triangle's smallest angle is the one opposite its shortest edge: at that corner, the sine
// and cosine of the angle times the product of its sides (|u x v|, u . v), and the squared
// lengths of the shortest and the longest edge.
struct SmallestCorner {
  double sine, cosine, shortest2, longest2;
};

SmallestCorner smallest_corner(const Mesh& mesh, const std::array<int, 3>& t) {
  std::array<double, 3> l2;  // l2[c]: squared length of the edge opposite corner c
  for (int c = 0; c < 3; ++c) l2[c] = (mesh.positions[t[(c + 1) % 3]] - mesh.positions[t[(c + 2) % 3]]).squaredNorm();
  const int k = static_cast<int>(std::min_element(l2.begin(), l2.end()) - l2.begin());
  const Vec3& p = mesh.positions[t[k]];
  const Vec3 u = mesh.positions[t[(k + 1) % 3]] - p, v = mesh.positions[t[(k + 2) % 3]] - p;
  return {u.cross(v).norm(), u.dot(v), l2[k], *std::max_element(l2.begin(), l2.end())};
}

// One atan2 per triangle.
double min_angle_degrees(const Mesh& mesh) {
  double best = 180;
  for (const auto& t : mesh.triangles) {
    const SmallestCorner c = smallest_corner(mesh, t);
    best = std::min(best, std::atan2(c.sine, c.cosine) * 180 / std::numbers::pi);
  }
  return best;
}

// Whether a run may be made again after it failed or missed a bound: not after a run stopped
// by the caller's own bounds (max_triangles, max_steps, max_search_visits: a run made again with
// shorter edges would pass them sooner), nor in paper mode (the algorithm as printed, whatever it gives).
bool remeshing_allowed(const AdaptiveOptions& o) {
  return o.variant == Variant::Improved && o.max_triangles == 0 && o.max_steps == 0 && o.max_search_visits == 0;
}

// A run that fails having met a bend tighter than the step of a black box's central differences
// (Field::derivative_step) met a crease or corner of the function that the field does not
// describe: differences across it turn the normal within a step, a curvature no edge follows,
// and no branch data say where the two faces are. Meshing it again (carefully, with finer turns,
// with min_edge lowered) fails too, after several times as long (a gyroid clipped by a
// ball as a Python function: the first run failed at 3 s, the last at 17 s), so the run stops
// at the first failure and says so.
bool kink_in_black_box(const Field& field, const std::pair<double, Vec3>& bend) {
  const std::optional<double> step = field.derivative_step();
  return step && bend.first < *step;
}

// The surface meshed once with the options as given (polygonize_adaptive may call it more than
// once, see there). `bend` receives the tightest bend the runs met when they fail, for the
// caller's retry. `look_ahead`: Settings::look_ahead on every front (the run polygonize_adaptive
// makes again when a mesh misses the quality bounds). `max_turn` > 0: Sizing::max_turn from the
// start, the crease-aware patches included (polygonize_adaptive_once's last run in tolerance mode).
PolygonizeResult mesh_once(const Field& field, const AdaptiveOptions& options, PhaseLedger& phases,
                           std::pair<double, Vec3>& bend, bool look_ahead = false, double max_turn = 0) {
  const auto start = std::chrono::steady_clock::now();
  const EvaluationCounts before = field.counts();

  const PhaseCloser closer{phases};
  // `name`: the ledger's (kAdaptivePhases); `text`: what AdaptiveOptions::phase is told.
  const auto enter = [&](std::string_view name, const char* text) {
    options.cancel.check("adaptive");
    phases.enter(name);
    if (options.phase) options.phase(text);
  };
  enter("seed_grid", "sampling the seed grid");
  // Within the seed grid's phase: resolving asks has_pieces, whose first call samples a grid of
  // its own to classify the field's branch points (Field::branch_kinds, once per field).
  const adaptive::Settings s = resolve(field, options);
  SeedOptions seed_options;
  seed_options.resolution = options.seed_resolution;
  seed_options.threads = options.threads;
  const SeedGrid grid = sample_seed_grid(field, seed_options);

  // The hash cell follows the edge length the sizing asks for at up to 64 grid crossings (their
  // median), a deterministic sample spread over the surface.
  adaptive::Settings settings = s;
  settings.look_ahead = look_ahead;
  if (max_turn > 0) settings.sizing.max_turn = max_turn;
  std::size_t grid_crossings = 0;
  {
    std::vector<Vec3> points;
    grid.for_each_sign_change([&](const std::array<int, 3>& a, const std::array<int, 3>& b) {
      const double fa = grid.value(a[0], a[1], a[2]), fb = grid.value(b[0], b[1], b[2]);
      const Vec3 pa = grid.point(a[0], a[1], a[2]);
      points.push_back(pa + fa / (fa - fb) * (grid.point(b[0], b[1], b[2]) - pa));
    });
    grid_crossings = points.size();
    std::vector<double> lengths;
    const std::size_t stride = std::max<std::size_t>(1, points.size() / 64);
    for (std::size_t i = 0; i < points.size(); i += stride) {
      try {
        lengths.push_back(adaptive::edge_length(s.sizing, curvature_at(field, points[i]).min_radius));
      } catch (const NoSurfaceError&) {
      }
    }
    if (!lengths.empty()) {
      std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
      settings.hash_cell = 2 * lengths[lengths.size() / 2];
    }
  }

  // The seed grid and the hash cell's curvature sample: the fixed cost before any triangle.
  const double seed_grid_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  PolygonizeResult result;
  Mesh& mesh = result.mesh;
  std::optional<adaptive::Tracker> tracker;
  adaptive::SeedingReport seeding;
  // Crossed grid edges per unit area: (|nx| + |ny| + |nz|) / h^2 for a patch of normal n,
  // kMeanCrossings / h^2 on average over all orientations (Crofton); with fewer than
  // kMeasuredCrossings the surface is too small for the grid to measure.
  constexpr double kMeanCrossings = 1.5;
  constexpr std::size_t kMeasuredCrossings = 64;
  const double estimated_area =
      grid_crossings >= kMeasuredCrossings ? grid_crossings * grid.h * grid.h / kMeanCrossings : 0.0;

  // Creases first (CreaseHandling::Follow): the patches they bound are meshed from them, and the
  // seeding below meets that mesh as finished surface, so only components without creases are
  // left to it.
  std::optional<adaptive::CreaseMesh> creased;
  std::size_t crease_components = 0;
  std::string crease_fallback;
  CreaseTracingResult traced;
  int crease_tracing_resolution = 0;
  if (options.creases == CreaseHandling::Follow && options.variant == Variant::Improved) {
    options.cancel.check("adaptive");
    phases.enter("creases");  // the tracing too; AdaptiveOptions::phase hears of it where it finds creases
    CreaseTracingOptions co;
    co.resolution = options.seed_resolution;
    for (int attempt = 0; attempt < kCreaseTracings; ++attempt, co.resolution *= 2) {
      try {
        crease_tracing_resolution = co.resolution;
        traced = trace_creases(field, co);  // no work for a field without pieces
        if (!traced.curves.empty()) {
          if (attempt == 0 && options.phase) options.phase("meshing along creases");
          creased = adaptive::mesh_crease_patches(field, traced, settings, estimated_area);
          crease_components = analyze_topology(creased->mesh).components;
          crease_fallback.clear();
        }
        break;
      } catch (const adaptive::CreaseLayoutError& e) {
        crease_fallback = e.what();  // a crease the grid missed? A finer one may find it
      } catch (const NoSurfaceError& e) {
        crease_fallback = e.what();
        break;
      } catch (const LimitExceededError& e) {
        crease_fallback = e.what();
        break;
      }
    }
  }

  // The radius of curvature every run met at their tightest bend, and where: below min_edge the
  // surface has detail that edges of min_edge cannot follow (the perturbed Barth sextic's necks
  // bend with a radius of 0.0083, min_edge is 0.0145), and a failure is reported as such.
  std::pair<double, Vec3> tightest{std::numeric_limits<double>::infinity(), Vec3::Zero()};
  const auto note_tightest = [&] {
    if (tracker && tracker->tightest_bend().first < tightest.first) tightest = tracker->tightest_bend();
  };
  const auto mesh_surface = [&](bool rollback) {
    mesh = Mesh{};
    settings.rollback = rollback;
    note_tightest();  // of the run this one replaces
    tracker.emplace(field, settings, mesh);
    if (estimated_area > 0) tracker->set_estimated_area(estimated_area);
    if (options.progress) tracker->set_progress(options.progress);
    if (creased) {
      mesh.positions = creased->mesh.positions;
      mesh.normals = creased->mesh.normals;
      mesh.triangles = creased->mesh.triangles;
      tracker->adopt_finished(creased->target, creased->mac, creased->shape_index);
    }
    {
      // The tracker's field calls come one or two points at a time: a costly field may run half
      // of each on a second core, with the same bits (helper_thread.h). Lent for the tracking
      // only, which runs no parallel pass beside it.
      const detail::LendHelper helper(options.threads);
      struct Count {  // the splits of a run that throws count too, as its phases do
        PhaseLedger& phases;
        const detail::LendHelper& helper;
        ~Count() { phases.add_split_evaluations(helper.tasks_run()); }
      } count{phases, helper};
      seeding = adaptive::seed_every_component(field, grid, s.sizing.min_edge, settings.hash_cell, *tracker, mesh);
    }
    tracker->compact();
  };

  bool remeshed = false;
  bool no_crossing = false;  // the seeding found no sign change at all
  const auto mesh_everything = [&] {
    enter("tracking", "meshing");
    remeshed = false;
    try {
      mesh_surface(settings.anticipate);  // the careful run has the rollbacks on from the start
    } catch (const adaptive::StalledFrontError& stalled) {
      if (settings.anticipate) throw;
      // A stalled front is where a front that ran over finished mesh ends, thousands of steps
      // later (the MPU models at some factors): the surface is meshed again from the start with
      // the rollbacks on, which undo such places where they begin. Surfaces that mesh without
      // them are never meshed with them, so they come out exactly as before. When the second
      // run fails too, or its mesh fails the checks below (a rollback has been seen to leave a
      // non-manifold edge: the printed triangle count on the bunny VIS-800 at factor 1), the
      // first run's error stands.
      try {
        remeshed = true;
        mesh_surface(true);
        if (seeding.uncovered > 0) throw NoSurfaceError("uncovered sign changes");
        options.cancel.check("adaptive");
        phases.enter("checks");
        check_mesh(mesh, seeding.seeds + crease_components, options.check_self_intersections, options.threads, options.cancel);
      } catch (const CancelledError&) {
        throw;
      } catch (const std::exception&) {
        throw stalled;
      }
    }
    if (mesh.triangles.empty() && seeding.sign_changes == 0) {
      no_crossing = true;
      std::ostringstream msg;
      msg << "adaptive: no zero crossing of the field in its box " << format_point(field.bounds().min) << " - "
          << format_point(field.bounds().max) << " at seed resolution " << options.seed_resolution
          << " (F is " << (grid.values[0] < 0 ? "negative" : "positive") << " everywhere sampled)";
      throw NoSurfaceError(msg.str());
    }
    if (mesh.triangles.empty())
      throw NoSurfaceError("adaptive: the field changes sign but no seed could be meshed (vanishing gradient)");
    if (seeding.uncovered > 0)
      throw NoSurfaceError("adaptive: " + std::to_string(seeding.uncovered) +
                           " sign changes of the field are not covered by the mesh, the first near " +
                           format_point(seeding.first_uncovered) +
                           " (a singular point or a feature thinner than min_edge?)");
  };
  // A crease-aware mesh that fails on the way (a component left to the seeds that then stalls,
  // patches that intersect) is not the end: the surface is meshed again as a smooth one, and
  // the stats say why.
  const auto fall_back = [&](const std::exception& e) {
    if (!creased) return false;
    crease_fallback = e.what();
    creased.reset();
    crease_components = 0;
    mesh_everything();
    return true;
  };
  // An error of the smooth meshing says what the crease-aware one ran into first.
  const auto why = [&](const std::exception& e) {
    note_tightest();
    bend = tightest;
    std::string message = e.what();
    if (kink_in_black_box(field, tightest)) {
      // The cause first: the tracker's own advice (a smaller min_edge) does not help here.
      std::ostringstream kink;
      kink << "adaptive: the normal turns within " << tightest.first << " near " << format_point(tightest.second)
           << ", less than the step of the central differences that give this field's derivatives ("
           << *field.derivative_step() << "): a crease or corner of the function (a min, max, abs or branch in "
           << "it) that the field does not describe, which no mesh of it follows; a field that names its min, max "
           << "and abs (an expression, or from Python a cdp.sdf model or a numpy function cdp.trace can follow) is "
           << "meshed along its creases, and exact gradient and Hessian functions resolve a smooth bend this tight. "
           << "Where the run stopped: " << message;
      message = kink.str();
    } else if (tightest.first < s.sizing.min_edge) {
      std::ostringstream bend;
      bend << "; the surface bends with a radius of curvature of " << tightest.first << " near "
           << format_point(tightest.second) << ", below min_edge (" << s.sizing.min_edge
           << "), detail finer than the mesh's shortest edge";
      message += bend.str();
    }
    // Meshed across its creases by choice (CreaseHandling::Ignore, or the paper variant, which
    // has no crease handling): the fronts meet a crease as curvature without bound, and do not
    // always close across a sharp one (the box less a ball, the gyroid ball, the spheres on a
    // bar at factors 8 and 9 fail so, with errors that named a stuck front or the neighbour
    // searches' bound and advised another min_edge). The message says that the field has
    // creases, names the sharpest and the way that meshes them, unless the tracker has already
    // named the crease where its front stalled.
    const bool across_by_choice = options.creases == CreaseHandling::Ignore || options.variant == Variant::Paper;
    if (across_by_choice && field.has_pieces() && message.find(adaptive::kAlongCreaseAdvice) == std::string::npos) {
      try {
        CreaseTracingOptions co;
        co.resolution = options.seed_resolution;
        if (const auto sharpest = sharpest_crease(field, trace_creases(field, co))) {
          std::ostringstream crease;
          crease << "; the field has creases, which this run meshed across as if they were curvature (the sharpest: "
                 << "faces meeting at " << std::lround(sharpest->first) << " degrees near "
                 << format_point(sharpest->second) << "); the improved variant with creases: follow (the defaults) "
                 << "meshes along them";
          message += crease.str();
        }
      } catch (const CancelledError&) {
        throw;
      } catch (const std::exception&) {
        // no layout to name (a tracing bound or a field that fails there): the message as it is
      }
    }
    return crease_fallback.empty() ? message
                                   : message + " (meshed as smooth after crease-aware meshing failed: " + crease_fallback + ")";
  };
  adaptive::QualityReport quality;
  const bool repair = options.variant == Variant::Improved;
  const double tolerance = positive_or_default_tolerance(options, s);
  // The repair, the curvature properties and the final checks of a mesh made; returns its components.
  const auto repair_and_check = [&] {
    quality = {};
    // A mesh that covers more than kOverlapArea times the area the seed grid measures has a
    // front that ran over finished mesh: it is checked before the repair, which cannot take
    // doubled surface away and would spend its rounds on the triangles where the sheets cross
    // (blobs31 of the topology sweep at tolerance 3e-2: 45 s on a mesh of 469k triangles and
    // 112k intersecting pairs, area 1.83 times the estimate, that the checks then refused).
    // Each triangle is counted with its own crossing weight (|nx| + |ny| + |nz|, against the
    // estimate's mean kMeanCrossings), so that a cube's faces (weight 1) do not pass for doubled
    // surface. Meshes the checks pass measure 0.90-1.01 times the estimate on the topology
    // sweep's fields; the failed ones, 1.13-1.94. Not for the crease-aware meshes, whose
    // intersections are checked after the repair (it removes some that chords on an acute
    // crease's two faces make).
    constexpr double kOverlapArea = 1.25;
    if (repair && !creased && estimated_area > 0 && tracker->area() > kOverlapArea * estimated_area) {
      double seen = 0;  // the area as the grid sees it
      for (const auto& t : mesh.triangles) {
        const Vec3& a = mesh.positions[t[0]];
        const Vec3 n = (mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a);  // twice the area
        seen += 0.5 * n.cwiseAbs().sum() / kMeanCrossings;
      }
      if (seen > kOverlapArea * estimated_area) {
        options.cancel.check("adaptive");
        phases.enter("checks");
        check_mesh(mesh, seeding.seeds + crease_components, options.check_self_intersections, options.threads, options.cancel);
      }
    }
    if (repair) {
      enter("quality", "repairing triangles");
      adaptive::QualityOptions qo;
      qo.improve_below = kRepairBelowDegrees * std::numbers::pi / 180;
      qo.tolerance = s.sizing.mode == SizingMode::Tolerance ? tolerance : 0;
      qo.diagonal = s.diagonal;
      qo.min_edge = s.sizing.min_edge;
      // The default min_edge is the sizing's floor, not the caller's: where the distance bound
      // needs it, the last resort may halve edges down to kLastResortEdgeShare of it. A min_edge
      // the caller set holds for every split.
      qo.last_resort_min_edge = options.min_edge > 0 ? s.sizing.min_edge : kLastResortEdgeShare * s.sizing.min_edge;
      qo.threads = options.threads;
      qo.cancel = options.cancel;
      // Neither the search nor the dense measurement before a split where a field with branch
      // points (min, max, abs) is meshed without following its creases (CreaseHandling::Ignore,
      // or a crease layout that failed; see QualityOptions): the triangles across a crease stay
      // stretched, so the mean is no aim. Meshed so, the creased shapes of
      // results/creases came out as often further from it as nearer, and the two spheres at
      // 5e-4 fell from 19.7 to 13.6 degrees; meshed along their creases they all came nearer.
      // A field with branch points whose crease tracing ran and found no crease (the hollow
      // sphere: its two sheets meet nowhere) is a smooth surface; one meshed without its layout
      // may have creases the mesh crosses.
      const bool no_crease = options.creases == CreaseHandling::Follow && crease_fallback.empty() && traced.curves.empty();
      const bool across_creases = field.has_pieces() && !creased && !no_crease;
      qo.aim_mean_edge_ratio = across_creases ? 0 : kBoundMeanEdgeRatio;
      qo.measure_near_bound = !across_creases;
      quality = adaptive::improve_mesh(field, mesh, qo);
    }
    if (s.curvature_properties) {
      if (!repair) phases.enter("quality");
      if (quality.moves + quality.relaxed + quality.collapses + quality.splits + quality.inserts == 0) {
        mesh.vertex_scalars["mac"] = tracker->vertex_mac();
        mesh.vertex_scalars["shape_index"] = tracker->vertex_shape_index();
      } else {
        // The repair moved, removed or added vertices: measure them all where they are now.
        std::vector<double> mac(mesh.positions.size()), shape(mesh.positions.size());
        for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
          const Curvature c = curvature_at(field, mesh.positions[v]);
          mac[v] = c.mac;
          shape[v] = c.shape_index;
        }
        mesh.vertex_scalars["mac"] = std::move(mac);
        mesh.vertex_scalars["shape_index"] = std::move(shape);
      }
    }
    enter("checks", "checking the mesh");
    return check_mesh(mesh, seeding.seeds + crease_components, options.check_self_intersections, options.threads, options.cancel);
  };
  std::size_t components = 0;
  adaptive::NeckSearch necks;
  const auto attempt = [&] {
    necks = {};
    try {
      mesh_everything();
      // The patches' topology before the repair works on it; intersections after (the repair
      // removes some that chords on the two faces of an acute crease make).
      if (creased) {
        options.cancel.check("adaptive");
        phases.enter("checks");
        check_mesh(mesh, seeding.seeds + crease_components, false, options.threads, options.cancel);
      }
      components = repair_and_check();
    } catch (const NoSurfaceError& e) {
      if (!fall_back(e)) throw;
      components = repair_and_check();
    } catch (const LimitExceededError& e) {
      if (!fall_back(e)) throw;
      components = repair_and_check();
    }
    // The checks above pass a front that crossed a neck narrower than its edges and closed on
    // each side of it: two closed components where the surface has one (surface_gaps.h).
    if (components > 1)
      if (const auto at = adaptive::uncovered_between_components(field, mesh))
        throw NoSurfaceError("adaptive: two components of the mesh face each other across the solid near " +
                             format_point(*at) +
                             ", where the surface joins them: a front closed on each side of a neck narrower "
                             "than its edges");
    // They pass a mesh that stepped over a neck or a tunnel narrower than its edges, too: a
    // handle too few, each component whole (missed_necks.h).
    necks = adaptive::find_missed_necks(field, mesh, tracker->critical_starts());
    if (!necks.missed.empty()) {
      const adaptive::MissedNeck& m = necks.missed.front();
      std::ostringstream msg;
      msg << "adaptive: the mesh " << (m.value < 0 ? "cuts a neck of the solid" : "closes a tunnel") << " about "
          << m.width << " wide near " << format_point(m.point) << " (F has a saddle there, F = " << m.value
          << ", and it lies " << (m.value < 0 ? "outside" : "inside") << " the mesh)"
          << (m.width < s.sizing.min_edge ? ", narrower than min_edge" : "") << ": a front stepped over it";
      throw NoSurfaceError(msg.str());
    }
  };
  // A run that fails (a stalled front, a mesh that fails the checks) is made once more with
  // Settings::anticipate and the rollbacks on from the start: where a front with long edges met
  // a neck narrower than them (the fifty blobs at factor 2 capped one off, and a second seed
  // then meshed the whole blob again over the first mesh), the new points are placed closer,
  // and no edge turns the normal by more than a radian (a coarse tolerance on the needle).
  // Only after a failure, so that every surface that meshed before comes out bit for bit as
  // before; when the careful run fails too, the first error stands. The careful run meshes the
  // surface as smooth when the crease-aware meshing of the first attempt failed (fall_back has
  // dropped it by then).
  // The careful run's edges turn the normal by at most one radian (Sizing::max_turn).
  constexpr double kCarefulMaxTurn = 1;
  bool careful = false;
  // A neck or tunnel a run stepped over is approached with edges as short as its radius (not
  // below min_edge) from kNeckZoneEdges of that run's edges around it, so that the fronts reach
  // it with edges that cannot jump it: a front outside the ball places points at most about an
  // edge into it, and the grading lets the edges grow back only by kGrowth per edge. (3 edges
  // meshed the 11 runs of the topology sweep as well, with 1.1-2.9 times the triangles.)
  constexpr double kNeckZoneEdges = 1.5;
  const auto zone_missed_necks = [&] {
    for (const adaptive::MissedNeck& m : necks.missed)
      settings.finer_zones.push_back(
          {m.point, 0.5 * m.width + kNeckZoneEdges * m.edge, std::max(s.sizing.min_edge, 0.5 * m.width)});
  };
  // A run whose mesh stepped over necks is first made again as it was, with the balls around
  // them: the rest of its mesh passed every check, and the careful run's sizing is finer
  // everywhere and fails more often (blobs38 of the topology sweep at factor 1: its careful mesh
  // intersected itself far from the neck). Again while a run steps over more necks, at most
  // kNeckRuns runs; the careful run follows when they fail, with the balls found so far.
  constexpr int kNeckRuns = 3;
  std::size_t neck_reruns = 0;
  const bool may_mesh_again = remeshing_allowed(options);
  const auto rerun_around_necks = [&] {
    if (!may_mesh_again) return false;
    for (int run = 0; run < kNeckRuns && !necks.missed.empty(); ++run) {
      zone_missed_necks();
      ++neck_reruns;
      try {
        attempt();
        return true;
      } catch (const NoSurfaceError&) {
      } catch (const LimitExceededError&) {
        return false;
      }
    }
    return false;
  };
  // As the reruns (may_mesh_again), and not for a field whose seeding found no sign change (not
  // even by its search for small components); only the polygonizer's own errors are retried (an
  // exception from a callable field or a cancellation goes on unchanged).
  // A run made again must pass a test stricter than attempt's own: no two components may face
  // each other across the solid at all, joined or not (a shell thinner than two edges keeps its
  // first error).
  const auto attempt_strictly = [&] {
    attempt();
    return adaptive::facing_across_solid(field, mesh, 1).empty();
  };
  const auto retry_carefully = [&] {
    if (!may_mesh_again || no_crossing) return false;
    settings.anticipate = careful = true;
    settings.sizing.max_turn = kCarefulMaxTurn;
    // A careful run that steps over another neck is made again with a ball there too, at most
    // kCarefulRuns in all (blobs30 of the topology sweep at factors 1 and 2: the careful run,
    // its curvature sizing finer everywhere, met a second neck).
    constexpr int kCarefulRuns = 3;
    for (int run = 0; run < kCarefulRuns; ++run) {
      zone_missed_necks();
      try {
        return attempt_strictly();
      } catch (const NoSurfaceError&) {
        if (necks.missed.empty()) return false;
      } catch (const LimitExceededError&) {
        return false;
      }
    }
    return false;
  };
  // A careful run that fails too is made again with edges that turn the normal by half as much,
  // then a quarter (kFinerTurns): a front of edges as long as the radius of curvature that met a
  // fillet or neck tighter than min_edge (the dense blob fields of the topology sweep at factor 1
  // and at coarse tolerances, which mesh at factor 3) reaches it with edges short enough to
  // close there. The mesh is then finer than asked where the surface bends; Stats says how much
  // (careful_max_turn). The first error stands when the last of them fails too.
  // In factor mode the turns are shares of the factor's own, 1 / factor (a turn of 0.5 at the
  // default factor 2 would repeat the careful run): the sizing of twice and four times the factor
  // where the surface bends most.
  constexpr std::array<double, 2> kFinerTurns{0.5, 0.25};
  const auto retry_finer = [&] {
    if (!careful) return false;
    for (const double share : kFinerTurns) {
      const double turn = s.sizing.mode == SizingMode::Factor ? share / s.sizing.factor : share;
      settings.sizing.max_turn = turn;
      try {
        if (attempt_strictly()) return true;
      } catch (const NoSurfaceError&) {
      } catch (const LimitExceededError&) {
        // the neighbour searches' bound: shorter edges at the fillet may not crowd it
      }
    }
    return false;
  };
  try {
    const auto hopeless = [&] {
      note_tightest();
      return kink_in_black_box(field, tightest);
    };
    try {
      attempt();
    } catch (const NoSurfaceError&) {
      if (hopeless() || (!rerun_around_necks() && !retry_carefully() && !retry_finer())) throw;
    } catch (const LimitExceededError&) {
      if (hopeless() || (!retry_carefully() && !retry_finer())) throw;
    }
  } catch (const NoSurfaceError& e) {
    throw NoSurfaceError(why(e));
  } catch (const LimitExceededError& e) {
    throw LimitExceededError(why(e));
  }

  PolygonizeStats& st = result.stats;
  st.components = components;
  st.method = "adaptive";
  phases.close();  // the run's time ends here, the ledger's with it
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  st.field_evaluations = field.counts() - before;
  st.triangles = mesh.num_triangles();
  st.vertices = mesh.num_vertices();
  st.splits = tracker->splits() + (creased ? creased->splits : 0);
  st.merges = tracker->merges() + (creased ? creased->merges : 0);
  st.extra["seeds"] = seeding.seeds;
  st.extra["creases.handling"] = to_string(options.variant == Variant::Improved ? options.creases : CreaseHandling::Ignore);
  st.extra["creases.followed"] = creased.has_value();
  st.extra["creases.curves"] = traced.curves.size();
  st.extra["creases.corners"] = traced.corners.size();
  st.extra["creases.vertices"] = creased ? creased->crease_vertices : 0;
  st.extra["creases.pieces"] = creased ? creased->pieces : 0;
  st.extra["creases.components"] = crease_components;
  st.extra["creases.fallback"] = crease_fallback;
  st.extra["creases.steps"] = creased ? creased->steps : 0;
  st.extra["creases.tracing_resolution"] = crease_tracing_resolution;
  st.extra["creases.patch_refusals"] = creased ? creased->patch_refusals : 0;
  st.extra["seed_grid_seconds"] = seed_grid_seconds;
  st.extra["curvature_seconds"] = tracker->curvature_seconds();
  st.extra["hessian_seconds"] = tracker->hessian_seconds();
  st.extra["failed_seeds"] = seeding.failed_seeds;
  st.extra["sign_changes"] = seeding.sign_changes;
  st.extra["non_finite_samples"] = grid.non_finite;
  st.extra["covered_nearby"] = seeding.covered_nearby;
  st.extra["below_resolution"] = seeding.below_resolution;
  st.extra["uncovered_crossings"] = seeding.uncovered;
  st.extra["refined_cells"] = seeding.refined_cells;
  st.extra["unresolved_cells"] = seeding.unresolved_cells;
  st.extra["probes"] = seeding.probes;
  st.extra["steps"] = tracker->steps();
  st.extra["search_visits"] = tracker->search_visits();
  st.extra["deferrals"] = tracker->deferrals();
  st.extra["anticipations"] = tracker->anticipations();
  st.extra["side_points"] = tracker->side_points();
  st.extra["forced_closures"] = tracker->forced_closures() + (creased ? creased->forced_closures : 0);
  st.extra["rollbacks"] = tracker->rollbacks();
  st.extra["rollbacks_failed"] = tracker->failed_rollbacks();
  st.extra["remeshed_with_rollbacks"] = remeshed;
  st.extra["remeshed_carefully"] = careful;
  st.extra["turn_limited"] = max_turn > 0;
  st.extra["careful_max_turn"] = careful ? settings.sizing.max_turn : 0.0;
  st.extra["crease_points"] = tracker->crease_points();
  st.extra["over_mesh_rejections"] = tracker->over_mesh();
  st.extra["necks.walks"] = necks.walks;
  st.extra["necks.critical_points"] = necks.critical_points;
  st.extra["necks.tested"] = necks.tested;
  st.extra["necks.reruns"] = neck_reruns;
  note_tightest();
  st.extra["curvature.min_radius"] = std::isfinite(tightest.first) ? tightest.first : -1.0;
  // A mesh made across a crease of a black box (see kink_in_black_box) that held together: the
  // crease is cut across by chords, not followed.
  st.extra["creases.across_black_box"] = kink_in_black_box(field, tightest);
  st.extra["min_angle_degrees"] = min_angle_degrees(mesh);
  st.extra["edge_length.min"] = s.sizing.min_edge;
  st.extra["edge_length.max"] = s.sizing.max_edge;
  st.extra["sizing"] = to_string(s.sizing.mode);
  if (s.sizing.mode == SizingMode::Factor) st.extra["factor"] = s.sizing.factor;
  else st.extra["tolerance"] = tolerance;
  st.extra["variant"] = to_string(options.variant);
  st.extra["grading"] = s.grading;
  st.extra["quality_repair"] = repair;
  st.extra["tolerance_refinement"] = repair && s.sizing.mode == SizingMode::Tolerance;
  st.extra["quality.repair_below_degrees"] = kRepairBelowDegrees;
  st.extra["quality.bad_before"] = quality.bad_before;
  st.extra["quality.bad_after"] = quality.bad_after;
  st.extra["quality.flips"] = quality.flips;
  st.extra["quality.moves"] = quality.moves;
  st.extra["quality.relaxed"] = quality.relaxed;
  st.extra["quality.relax_flips"] = quality.relax_flips;
  st.extra["quality.refine_measured"] = quality.refine_measured;
  st.extra["quality.refine_cleared"] = quality.refine_cleared;
  st.extra["quality.relax_searched"] = quality.relax_searched;
  st.extra["quality.relax_search_sweeps"] = quality.relax_search_sweeps;
  st.extra["quality.relax_crossings"] = quality.relax_crossings;
  st.extra["quality.collapses"] = quality.collapses;
  st.extra["quality.splits"] = quality.splits;
  st.extra["quality.inserts"] = quality.inserts;
  st.extra["quality.last_resorts"] = quality.last_resorts;
  st.extra["quality.crease_vertices"] = quality.crease_vertices;
  st.extra["quality.measured_densely"] = quality.measured_densely;
  st.extra["quality.over_tolerance"] = quality.over_tolerance;
  if (quality.over_tolerance > 0) {
    st.extra["quality.over_tolerance_worst"] = quality.over_tolerance_worst;
    const Vec3& c = quality.over_tolerance_near;
    st.extra["quality.over_tolerance_near_x"] = c.x();
    st.extra["quality.over_tolerance_near_y"] = c.y();
    st.extra["quality.over_tolerance_near_z"] = c.z();
  }
  st.extra["triangle_count_rule"] = to_string(s.rule);
  st.extra["seed_resolution"] = options.seed_resolution;
  st.extra["min_edge_lowered"] = false;
  st.extra["look_ahead"] = look_ahead;
  st.extra["quality_rerun"] = false;
  st.extra["quality_rerun_kept"] = false;
  if (options.progress) options.progress(1.0);
  return result;
}

// A run that fails where the surface bends more tightly than the default min_edge lets edges
// follow is meshed once more with min_edge at kBendEdgeShare of the tightest radius of curvature
// its runs met: the perturbed Barth sextic clipped by a ball (its necks bend with a radius of
// 0.0083, the default min_edge is 0.0145) fails at factors 1-3 and meshes with min_edge 0.0021,
// a quarter of that radius, in 0.7-3.3 s. Not below kLowestMinEdge of the diagonal, a tenth of
// the default; a bend down to kLowestBendShare of that edge is meshed with it (a crowd of 200
// Wyvill blobs, two of them joined by a neck 0.006 wide that bends with a radius of 0.0012,
// meshes with min_edge 0.0018 at factors 1 and 2 and tolerance 1e-2, and failed at all three);
// a tighter radius is a crease or a singular point, not a bend to follow. Only where the caller
// left min_edge, max_triangles and max_steps to their defaults (a bound the caller set is
// kept), and not in paper mode.
constexpr double kBendEdgeShare = 0.25;
constexpr double kLowestMinEdge = 2e-4;
constexpr double kLowestBendShare = 0.5;

std::optional<double> lowered_min_edge(const Field& field, const AdaptiveOptions& o, const std::pair<double, Vec3>& bend) {
  if (!remeshing_allowed(o) || o.min_edge > 0) return std::nullopt;
  const adaptive::Settings s = resolve(field, o);
  const double lowest = kLowestMinEdge * s.diagonal;
  if (!(bend.first < s.sizing.min_edge) || !(bend.first >= kLowestBendShare * lowest)) return std::nullopt;
  return std::max(kBendEdgeShare * bend.first, lowest);
}

// How many of the quality bounds `mesh` misses (see kBoundMinDegrees): a smallest angle under
// kBoundMinDegrees, more than kBoundShareUnder30 of the triangles with one under 30 degrees, a
// mean longest/shortest edge over kBoundMeanEdgeRatio, triangles farther from the surface than
// the tolerance (`over_tolerance`, the repair's dense measurement).
// Without an arctangent: a triangle's smallest angle is the one opposite its shortest edge, and
// it is under a bound b when its corner's cross and dot products (|u x v|, u . v) satisfy
// |u x v| < tan(b) u . v (angle_statistics' atan2 for each corner cost 1.7% of a torus run at
// factor 5, where this costs a fifth of that, 0.3%). The figures agree with angle_statistics but for
// rounding at the bounds themselves.
int missed_bounds(const Mesh& mesh, std::size_t over_tolerance) {
  const double tan20 = std::tan(kBoundMinDegrees * std::numbers::pi / 180), tan30 = std::tan(std::numbers::pi / 6);
  bool under20 = false;
  std::size_t under30 = 0, counted = 0;
  double ratio_sum = 0;
  for (const auto& t : mesh.triangles) {
    const SmallestCorner c = smallest_corner(mesh, t);
    if (!(c.sine > 0)) {  // zero area: no angles (angle_statistics counts it apart); a sliver all the same
      under20 = true;
      continue;
    }
    ++counted;
    if (c.sine < tan30 * c.cosine) ++under30;
    if (c.sine < tan20 * c.cosine) under20 = true;
    ratio_sum += std::sqrt(c.longest2 / c.shortest2);
  }
  const double share_under_30 = counted ? static_cast<double>(under30) / counted : 0;
  const double mean_ratio = counted ? ratio_sum / counted : 0;
  return under20 + (share_under_30 > kBoundShareUnder30) + (mean_ratio > kBoundMeanEdgeRatio) + (over_tolerance > 0);
}

// A mesh of a smooth surface (no crease followed) that misses the quality bounds is made once more
// with the front look-ahead (Settings::look_ahead: an expansion's edges no longer than a nearby
// front point's target plus kLookAheadGradation times its distance), and the run that misses
// fewer bounds is kept, the first on a tie. Where the first run's slivers come from (a front
// whose edges are several times what a fillet ahead asks for: the point placed in the fillet
// keeps a front edge as long as the ones it came with, and the expansions beside it hinge a fan
// of slivers on it across the fillet, which no repair can split without folding), the
// look-ahead has the front grade its edges down before it gets there. Not on every run: over
// the 343 runs of experiments/fields and the topology sweep's 40 fields (factors 1, 2, 3, 5;
// tolerances 5e-2, 1e-2, 1e-3) it mends 4 of the 8 that miss a bound (blobs26 at factor 1,
// 2.4 -> 24.9 degrees; blobs27 and blobs39 at 5e-2, 4.9 and 2.2 -> 30.1 degrees, no triangle
// beyond the tolerance; the bunny MPU model at 1e-3, 4 triangles beyond it -> none) but misses
// bounds on 5 that met them (the horse MPU model at 1e-3: 18.4 degrees; blobs40 at factor 1:
// 2.3), so the first run stays the one without it, and surfaces that meet the bounds come out
// as before, bit for bit, at the cost of one run.
// Only where remeshing_allowed (the bounds are Variant::Improved's promise).
bool may_rerun_for_quality(const AdaptiveOptions& o, const PolygonizeResult& r) {
  return remeshing_allowed(o) && !r.stats.extra.at("creases.followed").get<bool>();
}

std::size_t over_tolerance(const PolygonizeResult& r) {
  return r.stats.extra.at("quality.over_tolerance").get<std::size_t>();
}

// Tolerance mode asks for chords up to the diameter of a bend tighter than the tolerance
// (chord_for_deviation), which can step over the necks of a surface like the Barth ball. Where
// every run below fails (the first, the careful and finer ones it makes again, and those with a
// lowered min_edge), the surface is meshed once more with every edge turning the normal by at
// most kTurnLimit radians from the start, the crease-aware patches included, at the lowered
// min_edge where there is one. The Barth ball at tolerances 1e-1 and 3e-2 failed every run before
// and meshes so (genus 30); a run that meshes before is the same as it was, and a coarse
// tolerance is not held to that bound where it meshes without it (the Igea VIS-4004 at 5e-2:
// 850 triangles, 3,020 with the bound on every run). The stats say so (`turn_limited`).
constexpr double kTurnLimit = 1;

// polygonize_adaptive without the re-run for the quality bounds: the first mesh, or the one made
// with min_edge lowered, or (tolerance mode) the turn-limited one.
PolygonizeResult polygonize_adaptive_once(const Field& field, const AdaptiveOptions& options, PhaseLedger& phases) {
  const auto start = std::chrono::steady_clock::now();
  const EvaluationCounts before = field.counts();
  std::pair<double, Vec3> bend{std::numeric_limits<double>::infinity(), Vec3::Zero()};
  std::optional<double> lowered;
  std::optional<NoSurfaceError> no_surface;
  std::optional<LimitExceededError> limit;
  // SizingMode::Chord limits the turn from the start (kChordMaxTurn): the same run again would fail again.
  const bool may_limit_turn = remeshing_allowed(options) && options.sizing == SizingMode::Tolerance;
  const auto finish = [&](PolygonizeResult result) {
    result.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    result.stats.field_evaluations = field.counts() - before;
    result.stats.extra["min_edge_lowered"] = lowered.has_value();
    return result;
  };
  try {
    return mesh_once(field, options, phases, bend);
  } catch (const NoSurfaceError& e) {
    if (kink_in_black_box(field, bend)) throw;
    lowered = lowered_min_edge(field, options, bend);
    if (!lowered && !may_limit_turn) throw;
    no_surface = e;
  } catch (const LimitExceededError& e) {
    if (kink_in_black_box(field, bend)) throw;
    lowered = lowered_min_edge(field, options, bend);
    if (!lowered && !may_limit_turn) throw;
    limit = e;
  }
  AdaptiveOptions again = options;
  if (lowered) again.min_edge = *lowered;
  // A run made again: its mesh, or nothing (and its error's text in `error`, where given).
  const auto retry = [&](double max_turn, std::string* error) -> std::optional<PolygonizeResult> {
    try {
      std::pair<double, Vec3> ignored;
      return finish(mesh_once(field, again, phases, ignored, false, max_turn));
    } catch (const NoSurfaceError& e) {
      if (error) *error = e.what();
    } catch (const LimitExceededError& e) {
      if (error) *error = e.what();
    }
    return std::nullopt;
  };
  std::string second;
  if (lowered)
    if (std::optional<PolygonizeResult> r = retry(0, &second)) return std::move(*r);
  if (may_limit_turn)
    if (std::optional<PolygonizeResult> r = retry(kTurnLimit, nullptr)) return std::move(*r);
  // The first error stands, with what the runs made again did.
  std::ostringstream retries;
  const char* const turn =
      may_limit_turn ? " (and with every edge turning the normal by at most a radian, which failed too)" : "";
  if (lowered)
    retries << " (meshed again with min_edge " << *lowered << ", which failed too: " << second << turn << ")";
  else
    retries << turn;
  if (no_surface) throw NoSurfaceError(no_surface->what() + retries.str());
  throw LimitExceededError(limit->what() + retries.str());
}

}  // namespace

PolygonizeResult polygonize_adaptive(const Field& field, const AdaptiveOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const EvaluationCounts before = field.counts();
  PhaseLedger phases(field);
  PolygonizeResult first = polygonize_adaptive_once(field, options, phases);
  const auto with_phases = [&](PolygonizeResult r) {
    phases.write(r.stats);
    return r;
  };
  if (!may_rerun_for_quality(options, first)) return with_phases(std::move(first));
  const int missed = missed_bounds(first.mesh, over_tolerance(first));
  if (missed == 0) return with_phases(std::move(first));
  // The same min_edge as the first mesh (lowered when that was needed).
  AdaptiveOptions again = options;
  const bool lowered = first.stats.extra.at("min_edge_lowered").get<bool>();
  if (lowered) again.min_edge = first.stats.extra.at("edge_length.min").get<double>();
  std::optional<PolygonizeResult> second;
  try {
    std::pair<double, Vec3> ignored;
    second = mesh_once(field, again, phases, ignored, true);
  } catch (const NoSurfaceError&) {
  } catch (const LimitExceededError&) {
  }
  const bool keep = second && missed_bounds(second->mesh, over_tolerance(*second)) < missed;
  PolygonizeResult result = keep ? std::move(*second) : std::move(first);
  if (keep && lowered) result.stats.extra["min_edge_lowered"] = true;
  result.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.stats.field_evaluations = field.counts() - before;
  result.stats.extra["quality_rerun"] = true;
  result.stats.extra["quality_rerun_kept"] = keep;
  return with_phases(std::move(result));
}

}  // namespace cdp
