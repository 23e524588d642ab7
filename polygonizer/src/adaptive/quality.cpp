#include "quality.h"

#include "crease_probe.h"
#include "spatial_hash.h"
#include "../parallel.h"

#include <cdp/core/errors.h>
#include <cdp/core/newton_projection.h>
#include <cdp/core/triangle_intersection.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <numbers>
#include <numeric>
#include <optional>
#include <span>
#include <vector>

namespace cdp::adaptive {

namespace {

// Rounds over the work list. Each round visits every triangle still under the bound once and
// every accepted operation raises the smallest angle it touches by kMinGain, so the pass ends
// on its own; the bound caps the cost (measured: the bunny VIS-800 and tanglecube settle in
// under 10 rounds).
constexpr int kQualityRounds = 24;
// An operation must raise the smallest angle it touches by at least a quarter of a degree:
// operations cannot undo each other on floating-point ties, and a vertex cannot creep by tiny
// moves round after round while the stronger operations further down the list wait.
constexpr double kMinGain = 0.25 * 3.14159265358979323846 / 180;
// The crease test is the tracker's (crease_probe.h).
// A vertex whose stored normal (the tracker's mean of both sides on a crease) is this far from
// its own gradient lies on a crease too.
constexpr double kCreaseNormalCosine = 0.985;
// A new triangle must face like the surface at its corners: its normal within about 78 degrees
// of each corner's surface normal. Far looser than the surface's own turn over one edge (under
// 60 degrees at factor 1, where an edge is one radius long), so it only refuses folds.
constexpr double kFaceNormalCos = 0.2;
// Where a crease vertex is among a flip's four corners, the two triangles must be this close to
// one plane (about 10 degrees), so that no flip cuts across a crease.
constexpr double kCreaseFlatCos = 0.985;
// A moved vertex keeps its surface normal within about 30 degrees: Newton must land it on the
// same sheet and the same side of any crease nearby.
constexpr double kMoveNormalCos = 0.866;
// How far off the arc between an edge's end normals its collapsed midpoint's normal may turn
// (see lands_between): the 30 degrees a moved vertex's normal may turn (kMoveNormalCos = cos 30).
constexpr double kArcSlack = 30 * std::numbers::pi / 180;
// Tangential moves tried, as shares of the way to each target (see try_move).
constexpr double kMoveShares[] = {1.0, 0.5, 0.25};
// A needle's shortest edge is collapsed when it is shorter than this share of the triangle's
// second-shortest edge (the other ops cannot open an angle opposite an edge that short).
constexpr double kNeedleShare = 0.5;
// Distance sampling with a tolerance: the largest distance must come out at most this share of
// the tolerance. The estimate interpolates the distances at the edge midpoints quadratically
// and scales it by how far the centroid's measured distance exceeds the interpolation's, which
// captures the sagitta of a curved patch to second order; the 10% margin covers the
// third-order remainder (measured under 4% on the torus and tanglecube at eps = 1e-2).
constexpr double kToleranceMargin = 0.9;
// The refinement measures densely (as the tolerance is defined) a triangle whose estimate is
// over kToleranceMargin of the tolerance but not over the tolerance, and leaves it unsplit when
// it measures at most this share of the tolerance (a margin for the surface between the dense
// grid's samples). The estimate's margin is for its own error, under 4 %, but rings of nearly
// equilateral triangles at the target length estimate at 0.87-0.93 of the tolerance (a
// triangle's sagitta is 4/3 of its edges'), and splitting them all left bands of triangles of
// edge ratio 1.6: a sphere capped by a plane at 1e-3, 7036 triangles (1009 splits) and a mean
// ratio of 1.239 -> 5286 (132 splits) and 1.131 with this (5298 at 0.945, 5222 at 0.99, 7016
// at 0.9: the estimate's own margin clears almost nothing).
constexpr double kDenseClearShare = 0.95;
// Rounds of splitting triangles beyond the tolerance; each round halves the longest edge of
// every offending triangle, and 24 halvings take any edge below min_edge.
constexpr int kRefineRounds = 24;
// Rounds of the last resort (see last_resort) on what the refinement left beyond the tolerance.
// A round ends with the refinement and the angle repair of what it split.
constexpr int kLastResortRounds = 4;
// relax: the triangles whose longest edge exceeds this times their shortest have their edges
// flipped and their vertices moved (an equilateral triangle is 1; the fronts make 1.22 on
// average where sizes do not change). On the bunny VIS-800 at factor 3 most of the vertices are
// candidates: a smoothing of most of the mesh, though not a re-meshing (flips only, no vertex
// added or removed). Measured mean ratios, bunny VIS-800 at factor 1 / Igea MPU at 2 / horse
// MPU at 1: 1.246 / 1.255 / 1.263 with 1.15; 1.250 / 1.259 / 1.267 with 1.3; 1.0 (every
// vertex) gains under 0.001 more.
constexpr double kRelaxRatio = 1.15;
// Plain sweeps of the relaxation, each flips then moves; where they leave the mesh's mean ratio
// over the aim, the search sweeps below take over. One, because the later ones buy little for
// what they cost. Over a 343-run sweep of the quality bounds (the 9 experiment fields and the 40
// topology-sweep fields, factors 1-5 and tolerances 5e-2-1e-3), against 4:
// - every run within every bound; the same triangle counts but in 25 tolerance runs (up to 8
//   triangles either way: the tolerance's refinement sees other positions);
// - the mean over runs of the mean ratio 1.186 -> 1.208 (the worst 1.2487 -> 1.2499; 43 runs
//   instead of 5 finish with search sweeps);
// - the smallest angle over all runs the same (21.13 degrees); a run's own lower in 181 runs and
//   higher in 58, the mean 31.67 -> 30.87, by up to 11 degrees where it was far above 30 (coarse
//   meshes of few blobs), and 30.01 -> 25.50 on one (blobs37 at 1e-3);
// - 0.76 of the time and of the field evaluations;
// - the mean Phong error of bunny VIS-800, Igea VIS-4004, tanglecube and random blobs at factors
//   3 and 5 0.3-1.3 % higher (tanglecube at 5: 0.4 % lower), what edges 0.3-1.3 % shorter would
//   win back if the error goes as the edge length.
// 2 sweeps: a mean ratio of 1.194 in 0.86 of the time. Instructions in polygonize_adaptive
// (callgrind, one thread, -O2 -g): torus factor 20 3913M -> 2645M, bunny VIS-800 factor 3
// 2030M -> 1571M.
constexpr int kRelaxSweeps = 1;
// A flip of the relaxation that brings the valences nearer 6 may raise the two triangles'
// summed edge ratio by up to this share, which the moves that follow more than make up for.
// The same three cases and random blobs at tolerance 1e-3: 1.246 / 1.255 / 1.263 / 1.203; with
// 1.0 (only flips that lower it) 1.253 / 1.258 / 1.267 / 1.205; without the flips 1.262 /
// 1.263 / 1.274 / 1.236 (the tolerance's edge splits leave vertices of valence 4 and 8 that no
// move can make equilateral).
constexpr double kFlipRatioSlack = 1.1;
// A move must lower its star's mean edge ratio by this share: no creeping by rounding.
constexpr double kRelaxMinGain = 1e-3;
// At most this many sweeps of the relaxation's search (see relax and searched_step), each made
// only while the mesh's mean edge ratio is over QualityOptions::aim_mean_edge_ratio. The four
// runs of that sweep that four plain sweeps left over 1.25 (bunny VIS-800 at 1e-2,
// Igea MPU at 5e-2 and 1e-2, Igea VIS-4004 at 5e-2: 1.253-1.258; ten plain sweeps reach only
// 1.2545 on Igea MPU at 1e-2) ended at 1.239-1.245 after the first. After one plain sweep, 43 of
// the 343 runs are over 1.25 and all end under it.
constexpr int kRelaxSearchSweeps = 4;
// Stars judged per vertex and search sweep (searched_step): a few dozen flops per triangle of
// the star each, no evaluation. Igea MPU at 1e-2 with the search in all four sweeps, as a
// measure of what the budget buys: 1.234 with 4 stars, 1.230 with 8, 1.229 with 12 or 24.
constexpr int kRelaxSearchStars = 8;
// A move may lower its star's smallest angle only while it stays at or above this (the repair's
// bound), so the relaxation never undoes the repair.
constexpr double kRelaxKeepDegrees = 30;
// The relaxation's vertices per block of its parallel passes: enough to outweigh handing a
// block to a thread (a target costs about a microsecond, a projection a few field calls).
constexpr std::size_t kRelaxBlock = 256;
// On several threads (with a tolerance, on any number) the relaxation judges at most this many
// candidates between two tests of their moves for intersections (see relax_sweeps), few enough
// that a move refused there takes back at most this many judged after it. The chunks start at
// kRelaxBlock candidates and double up to this while no move is refused.
constexpr std::size_t kRelaxChunk = 4096;
// Moves per block of those tests: a test costs a microsecond or two, so that the first chunk's
// moves (at most kRelaxBlock) already spread over several threads.
constexpr std::size_t kTurnBlock = 64;
// hash_box: a triangle's box is stored grown by this share of a hash cell (about a fifth of an
// edge), so that moving a corner by less than that stores it again nowhere.
constexpr double kHashSlack = 0.1;

double angle_at(const Vec3& p, const Vec3& q, const Vec3& r) {
  const Vec3 u = q - p, v = r - p;
  return std::atan2(u.cross(v).norm(), u.dot(v));
}

double min_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  return std::min({angle_at(a, b, c), angle_at(b, c, a), angle_at(c, a, b)});
}

// The barycentric coordinates (i/12, j/12, 1 - i/12 - j/12), i + j <= 12, where estimate_from
// samples a triangle's quadratic; the last slot pads to whole SIMD packets with (0, 0, 0),
// where the quadratic is 0, which the maximum of its absolute value starts from anyway.
struct BarycentricGrid {
  static constexpr int kSteps = 12;
  static constexpr int kPoints = (kSteps + 1) * (kSteps + 2) / 2;
  using Column = Eigen::Array<double, kPoints + 1, 1>;
  Column a = Column::Zero(), b = Column::Zero(), c = Column::Zero();
};
const BarycentricGrid& barycentric_grid() {
  static const BarycentricGrid grid = [] {
    BarycentricGrid g;
    int k = 0;
    for (int i = 0; i <= BarycentricGrid::kSteps; ++i)
      for (int j = 0; i + j <= BarycentricGrid::kSteps; ++j, ++k) {
        g.a[k] = double(i) / BarycentricGrid::kSteps;
        g.b[k] = double(j) / BarycentricGrid::kSteps;
        g.c[k] = 1 - g.a[k] - g.b[k];
      }
    return g;
  }();
  return grid;
}

using Tri = std::array<int, 3>;

class Improver {
 public:
  Improver(const Field& field, Mesh& mesh, const QualityOptions& o)
      : field_(field), smooth_(field.smooth()), m_(mesh), o_(o), workers_(detail::worker_count(o.threads)),
        vt_(mesh.positions.size()), crease_(mesh.positions.size(), -1),
        alive_(mesh.triangles.size(), 1), hash_(cell_size(mesh)) {
    // Nothing reads its visits, and intersecting_turn queries it on several threads at once.
    hash_.set_counting(false);
    for (int t = 0; t < static_cast<int>(m_.triangles.size()); ++t) {
      poll(static_cast<std::size_t>(t));
      for (int v : m_.triangles[t]) vt_[v].push_back(t);
      hash_box(t);
    }
    stamp_.assign(m_.triangles.size(), 0);
  }

  // The cancel poll of the loops below: an atomic load every kPollEvery items.
  static constexpr std::size_t kPollEvery = 256;
  void poll(std::size_t i = 0) const {
    if (i % kPollEvery == 0) o_.cancel.check("adaptive: repair");
  }

  QualityReport run() {
    if (!(o_.tolerance > 0)) {
      repair();
      relax();
      compact();
      return r_;
    }
    // Every triangle is checked once; after that only what an operation made or changed (the
    // operations keep the bound they were tested against, so only triangles that were beyond it
    // already can be beyond it after them).
    std::vector<int> all(tri_count());
    std::iota(all.begin(), all.end(), 0);
    std::vector<int> over = refine(all);
    since_check_.clear();
    repair();
    relax();
    over = refine(merged(over, since_check_));
    since_check_.clear();
    repair();
    // What the estimate cannot clear (it keeps kToleranceMargin for its own error) is measured
    // as the tolerance is defined, densely over the triangle; a triangle farther than the
    // tolerance there gets the last resort (last_resort) on a smooth field, and whatever that
    // cannot clear is reported, with its distance. Not on a field with creases: a triangle
    // across a crease meshed as smooth stays beyond the tolerance however it is split (the
    // capped cylinder with its creases ignored at 1e-3: 3.6 times the time and 19% more
    // triangles, with the same triangles reported).
    std::vector<Beyond> beyond = measure_densely(merged(over, since_check_));
    for (int round = 0; round < kLastResortRounds && smooth_ && !beyond.empty(); ++round) {
      since_check_.clear();
      std::vector<int> left;
      for (const Beyond& b : beyond)
        if (!last_resort(b)) left.push_back(b.t);
      if (since_check_.empty()) break;  // nothing could be split: what is left is reported
      left = merged(left, refine(since_check_));
      repair();
      beyond = measure_densely(merged(left, since_check_));
    }
    for (const Beyond& b : beyond) {
      ++r_.over_tolerance;
      if (!(b.d <= r_.over_tolerance_worst)) {
        r_.over_tolerance_worst = b.d;
        r_.over_tolerance_near = (P(b.T[0]) + P(b.T[1]) + P(b.T[2])) / 3;
      }
    }
    compact();
    return r_;
  }

 private:
  // ---- geometry
  static double cell_size(const Mesh& m) {
    // About two typical edges, so that a query box around a new triangle touches a few cells.
    std::vector<double> lengths;
    const std::size_t stride = std::max<std::size_t>(1, m.triangles.size() / 256);
    for (std::size_t t = 0; t < m.triangles.size(); t += stride)
      lengths.push_back((m.positions[m.triangles[t][0]] - m.positions[m.triangles[t][1]]).norm());
    if (lengths.empty()) return 1;
    std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
    return std::max(2 * lengths[lengths.size() / 2], 1e-12);
  }
  int tri_count() const { return static_cast<int>(m_.triangles.size()); }
  const Vec3& P(int v) const { return m_.positions[v]; }
  // A triangle's edge lengths (edge k: T[k]-T[k+1]) and its edges longest first (ties by index).
  std::pair<std::array<double, 3>, std::array<int, 3>> edges_longest_first(const Tri& T) const {
    const std::array<double, 3> len{(P(T[1]) - P(T[0])).norm(), (P(T[2]) - P(T[1])).norm(), (P(T[0]) - P(T[2])).norm()};
    std::array<int, 3> order{0, 1, 2};
    std::sort(order.begin(), order.end(), [&](int x, int y) { return len[x] != len[y] ? len[x] > len[y] : x < y; });
    return {len, order};
  }
  double tri_min_angle(const Tri& t) const { return min_angle(P(t[0]), P(t[1]), P(t[2])); }
  // tri_min_angle(t) < limit, with one arc tangent for most triangles instead of three: the
  // smallest angle is the one facing the shortest edge, and the two differ only by rounding
  // (far below kSurelyAbove) where edges tie, so a triangle whose angle there is clearly above
  // the limit is above it; the others are decided by tri_min_angle itself (same answers).
  bool tri_below(const Tri& t, double limit) const {
    constexpr double kSurelyAbove = 1e-9;  // radians
    int k = 0;
    double shortest = (P(t[2]) - P(t[1])).squaredNorm();  // faces t[0]
    for (int i = 1; i < 3; ++i) {
      const double l = (P(t[(i + 2) % 3]) - P(t[(i + 1) % 3])).squaredNorm();
      if (l < shortest) shortest = l, k = i;
    }
    if (angle_at(P(t[k]), P(t[(k + 1) % 3]), P(t[(k + 2) % 3])) > limit + kSurelyAbove) return false;
    return tri_min_angle(t) < limit;
  }
  Vec3 face_normal(const Tri& t) const {
    const Vec3 n = (P(t[1]) - P(t[0])).cross(P(t[2]) - P(t[0]));
    const double l = n.norm();
    return l > 0 ? Vec3(n / l) : Vec3::Zero();
  }
  // The smallest cosine between the triangle's normal and its corners' surface normals (0 for
  // a zero-area triangle).
  double facing(const Tri& t) const {
    const Vec3 n = face_normal(t);
    double worst = 1;
    for (int v : t) worst = std::min(worst, n.dot(m_.normals[v]));
    return worst;
  }
  // What new triangles must exceed: kFaceNormalCos, or, where the triangles they replace already
  // faced the surface worse (a fold the fronts left on a sharply curved spot of a coarse mesh),
  // the worst of those: an operation never makes the facing worse, and may repair it.
  double facing_floor(const std::vector<int>& replaced) const {
    double floor = kFaceNormalCos;
    for (int t : replaced) floor = std::min(floor, facing(m_.triangles[t]));
    return floor;
  }
  bool faces_surface(const Tri& t, double floor) const { return facing(t) > floor; }
  // Signed first-order distance F / |grad F| of p to the surface.
  double signed_distance(const Vec3& p) const {
    Vec3 g;
    const double f = field_.value_gradient(p, g);
    const double l = g.norm();
    return l > 0 ? f / l : std::numeric_limits<double>::infinity();
  }
  // The largest distance between triangle t and the surface, estimated from the edge midpoints
  // and the centroid (see kToleranceMargin).
  // `memo` (optional) keeps the edge midpoints' distances of the triangles it has seen at the
  // current positions: the triangles of a star share their edges to the centre.
  // `table` (optional, read only): edges measured beforehand at the current positions, by
  // edge_key, sorted.
  struct EdgeTable {
    std::vector<std::uint64_t> keys;
    std::vector<double> d;
  };
  struct MidpointMemo {
    std::vector<std::pair<std::pair<int, int>, double>> known;
    const EdgeTable* table = nullptr;
  };
  static std::uint64_t edge_key(int x, int y) {
    const auto [lo, hi] = std::minmax(x, y);
    return static_cast<std::uint64_t>(static_cast<std::uint32_t>(lo)) << 32 | static_cast<std::uint32_t>(hi);
  }
  double midpoint_distance(int x, int y, MidpointMemo* memo) const {
    const std::pair<int, int> key = std::minmax(x, y);
    if (memo && memo->table) {
      const auto& keys = memo->table->keys;
      const std::uint64_t k = edge_key(x, y);
      const auto it = std::lower_bound(keys.begin(), keys.end(), k);
      if (it != keys.end() && *it == k) return memo->table->d[static_cast<std::size_t>(it - keys.begin())];
    }
    if (memo)
      for (const auto& [k, d] : memo->known)
        if (k == key) return d;
    const double d = signed_distance(0.5 * (P(x) + P(y)));
    if (memo) memo->known.push_back({key, d});
    return d;
  }
  // The estimate of the triangle in slot `slot` (its corners `t`, which an operation may be
  // trying at new positions), remembered with the corners, their positions and the edges'
  // midpoint distances, and reused only where those compare equal (the estimate is a function
  // of the positions alone, so the answers are those computed afresh): the refinement after
  // the relaxation re-measures only triangles last measured at other positions (a move refused
  // after its measurement), and a star's outer edges keep their midpoints when its centre
  // moves. On the torus at tolerance 1e-3: 486k evaluations in the whole run without this
  // memo, 327k with it (the relaxation's 277k -> 195k; the refinement after it, 77k -> 0).
  struct EstimateEntry {
    Tri t{-1, -1, -1};
    std::array<Vec3, 3> p;
    std::array<double, 3> mid;  // edges t[0] t[1], t[1] t[2], t[2] t[0]
    double d = 0;
  };
  // Which corners of `t`, at the current positions, entry e was made with (none when e is of
  // other corners).
  std::array<bool, 3> kept_corners(const EstimateEntry& e, const Tri& t) const {
    const bool same = e.t == t;
    return {same && e.p[0] == P(t[0]), same && e.p[1] == P(t[1]), same && e.p[2] == P(t[2])};
  }
  // Whether slot `slot` remembers the estimate of its triangle at the current positions.
  bool remembered(int slot) const {
    if (static_cast<std::size_t>(slot) >= estimates_.size()) return false;
    const std::array<bool, 3> kept =
        kept_corners(estimates_[static_cast<std::size_t>(slot)], m_.triangles[static_cast<std::size_t>(slot)]);
    return kept[0] && kept[1] && kept[2];
  }
  double estimate_distance(const Tri& t, int slot, MidpointMemo* memo = nullptr) const {
    if (static_cast<std::size_t>(slot) >= estimates_.size()) estimates_.resize(static_cast<std::size_t>(slot) + 1);
    EstimateEntry& e = estimates_[static_cast<std::size_t>(slot)];
    const std::array<bool, 3> kept = kept_corners(e, t);
    if (kept[0] && kept[1] && kept[2]) return e.d;
    const std::array<Vec3, 3> p{P(t[0]), P(t[1]), P(t[2])};
    std::array<double, 3> mid;
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3;
      if (kept[i] && kept[j]) {
        mid[i] = e.mid[i];
        if (memo) memo->known.push_back({std::minmax(t[i], t[j]), mid[i]});
      } else {
        mid[i] = midpoint_distance(t[i], t[j], memo);
      }
    }
    e = {t, p, mid, estimate_from(p[0], p[1], p[2], mid[0], mid[1], mid[2])};
    return e.d;
  }
  double estimate_distance(const Tri& t, MidpointMemo* memo = nullptr) const {
    return estimate_from(P(t[0]), P(t[1]), P(t[2]), midpoint_distance(t[0], t[1], memo),
                         midpoint_distance(t[1], t[2], memo), midpoint_distance(t[2], t[0], memo));
  }
  // ... from the midpoints' signed distances.
  double estimate_from(const Vec3& a, const Vec3& b, const Vec3& c, double mab, double mbc, double mca) const {
    const double centroid = signed_distance((a + b + c) / 3);
    if (!std::isfinite(mab + mbc + mca + centroid)) return std::numeric_limits<double>::infinity();
    // The quadratic through 0 at the corners and these at the midpoints, sampled on a grid of
    // step 1/12 (its maximum lies within 1% of a grid point's), from a table of the grid's
    // barycentric coordinates, all points at once: a loop computing them took two divisions a
    // point and was 15 % of the instructions of tanglecube at tolerance 1e-3.
    // Each point's value is the scalar expression's, (m_ab l_a) l_b + ..., bit for bit; the
    // maximum of finite values is the same in any order.
    const BarycentricGrid& g = barycentric_grid();
    const double q_max = (4 * (mab * g.a * g.b + mbc * g.b * g.c + mca * g.c * g.a)).abs().maxCoeff();
    const double predicted = std::abs(4.0 / 9.0 * (mab + mbc + mca));
    const double scale = predicted > 0 ? std::max(1.0, std::abs(centroid) / predicted) : 1.0;
    return std::max({q_max * scale, std::abs(centroid), std::abs(mab), std::abs(mbc), std::abs(mca)});
  }
  // The largest distance from triangle t to the surface over a barycentric grid of
  // kDenseGrid + 1 points a side (28 points: corners, 5 more on each side, 10 inside), each the
  // length of Newton's path onto the surface (at least the point's true distance); `fallback`
  // where Newton does not land within the triangle's longest edge. `worst_at` (optional): the
  // projection of the farthest sample.
  double sampled_distance(const Tri& t, double fallback, ProjectionResult* worst_at = nullptr) const {
    constexpr int kDenseGrid = 6;
    const std::array<Vec3, 3> p{P(t[0]), P(t[1]), P(t[2])};
    ProjectionOptions po;
    po.tolerance = 1e-10 * o_.diagonal;
    po.max_travel = std::sqrt(std::max({(p[1] - p[0]).squaredNorm(), (p[2] - p[1]).squaredNorm(), (p[0] - p[2]).squaredNorm()}));
    double worst = 0;
    for (int i = 0; i <= kDenseGrid; ++i)
      for (int j = 0; i + j <= kDenseGrid; ++j) {
        const double a = double(i) / kDenseGrid, b = double(j) / kDenseGrid;
        const Vec3 x = a * p[0] + b * p[1] + (1 - a - b) * p[2];
        const ProjectionResult r = project_to_surface(field_, x, po);
        if (!r.ok()) return fallback;
        const double d = (r.point - x).norm();
        if (d > worst) {
          worst = d;
          if (worst_at) *worst_at = r;
        }
      }
    return worst;
  }
  // With a tolerance: new triangles may be no farther from the surface than the tolerance or
  // (before the refinement has run) than the worst of the triangles they replace.
  bool keeps_tolerance(const std::vector<Tri>& added, const std::vector<int>& removed) const {
    return may_replace(worst_distance(added), removed);
  }
  // The largest estimated distance of triangles `ts` at the current positions; 0 without a
  // tolerance (nothing to keep, no evaluations spent).
  double worst_distance(const std::vector<Tri>& ts) const {
    double worst = 0;
    if (o_.tolerance > 0) {
      MidpointMemo memo;
      for (const Tri& t : ts) worst = std::max(worst, estimate_distance(t, &memo));
    }
    return worst;
  }
  // ... of v's star at the current positions, remembered by slot (see estimate_distance).
  double worst_star_distance(int v) const {
    double worst = 0;
    if (o_.tolerance > 0) {
      MidpointMemo memo;
      for (int u : vt_[v]) worst = std::max(worst, estimate_distance(m_.triangles[u], u, &memo));
    }
    return worst;
  }
  // Whether triangles whose worst distance is `worst_new` may replace `removed`, read at the
  // current positions: a move measures its new star at the new place, puts the vertex back, then
  // asks this.
  bool may_replace(double worst_new, const std::vector<int>& removed) const {
    if (!(o_.tolerance > 0) || worst_new <= kToleranceMargin * o_.tolerance) return true;
    double worst_old = 0;
    MidpointMemo memo;
    for (int t : removed) worst_old = std::max(worst_old, estimate_distance(m_.triangles[t], t, &memo));
    return worst_new <= worst_old;
  }

  // Whether the normal n where an edge's midpoint landed belongs to the edge: within about 30
  // degrees of both ends' normals, or on the arc between them, its angles to the two ends adding
  // up to at most theirs plus kArcSlack. Either keeps Newton on the same sheet (a landing on
  // another sheet turns the normal far off both); the arc admits what the first refuses where
  // the ends' normals are far apart: an edge across a ridge narrower than itself, below the
  // sizing's resolution (the horse MPU model has one of radius 1e-4 near (-0.012, 0.081, 0.073)
  // under edges of 1.5-5e-4, min_edge 5.9e-4: its ends' normals are 100-150 degrees apart, and
  // no normal is within 30 degrees of both), which may now collapse onto the ridge.
  static bool lands_between(const Vec3& n, const Vec3& na, const Vec3& nb) {
    if (n.dot(na) > kMoveNormalCos && n.dot(nb) > kMoveNormalCos) return true;
    const auto angle = [](const Vec3& p, const Vec3& q) { return std::atan2(p.cross(q).norm(), p.dot(q)); };
    return angle(na, n) + angle(n, nb) <= angle(na, nb) + kArcSlack;
  }

  // ---- crease vertices
  bool on_crease(int v) {
    if (smooth_) return false;  // no crease to find (Field::smooth): no probes
    if (crease_[v] >= 0) return crease_[v];
    const Vec3& x = P(v);
    Vec3 g0;
    field_.value_gradient(x, g0);
    bool crease = !(g0.squaredNorm() > 0) || !(g0.normalized().dot(m_.normals[v]) > kCreaseNormalCosine);
    if (!crease) {
      const double eps = kCreaseProbe * o_.diagonal;
      const Vec3 n = g0.normalized();
      const Vec3 g1 = field_.gradient(x + eps * n), g2 = field_.gradient(x - eps * n);
      crease = !(g1.squaredNorm() > 0 && g2.squaredNorm() > 0) ||
               !(g1.normalized().dot(g2.normalized()) > kCreaseCosine);
    }
    crease_[v] = crease;
    if (crease) ++r_.crease_vertices;
    return crease;
  }

  // ---- adjacency
  // The triangle other than t on edge (a, b), or -1.
  int across(int t, int a, int b) const {
    int found = -1;
    for (int u : vt_[a]) {
      if (u == t || !alive_[u]) continue;
      const Tri& x = m_.triangles[u];
      if (x[0] == b || x[1] == b || x[2] == b) {
        if (found >= 0) return -1;  // not manifold here: leave it alone
        found = u;
      }
    }
    return found;
  }
  bool has_edge(int a, int b) const {
    for (int u : vt_[a]) {
      const Tri& x = m_.triangles[u];
      if (alive_[u] && (x[0] == b || x[1] == b || x[2] == b)) return true;
    }
    return false;
  }
  std::vector<int> neighbours(int v) const {
    std::vector<int> out;
    for (int u : vt_[v])
      for (int w : m_.triangles[u])
        if (w != v) out.push_back(w);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }
  static void erase_value(std::vector<int>& v, int x) {
    const auto it = std::find(v.begin(), v.end(), x);
    if (it != v.end()) v.erase(it);
  }

  // ---- intersections with the triangles nearby
  // A triangle of the star star_hits tests.
  struct StarTriangle {
    Tri ids;
    std::array<Vec3, 3> p;
    Vec3 lo, hi, normal;  // box; unnormalized normal (apart_by_plane)
  };
  void hash_box(int t) {
    const Tri& x = m_.triangles[t];
    hash_cover(t, P(x[0]).cwiseMin(P(x[1])).cwiseMin(P(x[2])), P(x[0]).cwiseMax(P(x[1])).cwiseMax(P(x[2])));
  }
  // Makes the box triangle t is stored with in the hash hold [lo, hi] (its box, or one over
  // several positions of its corners, see intersecting_turn).
  void hash_cover(int t, const Vec3& lo, const Vec3& hi) {
    // Stale entries of earlier shapes stay and are filtered. A triangle is stored with its box
    // grown by kHashSlack cells, and not again while its box stays inside that: the small moves
    // of the relaxation would otherwise add a copy of each triangle around v at every move.
    if (static_cast<std::size_t>(t) < hashed_lo_.size() && (lo.array() >= hashed_lo_[t].array()).all() &&
        (hi.array() <= hashed_hi_[t].array()).all())
      return;
    const double slack = kHashSlack * hash_.cell_size();
    const Vec3 glo = lo.array() - slack, ghi = hi.array() + slack;
    if (hashed_lo_.size() <= static_cast<std::size_t>(t)) {
      hashed_lo_.resize(t + 1);
      hashed_hi_.resize(t + 1);
    }
    hashed_lo_[t] = glo;
    hashed_hi_[t] = ghi;
    hash_.insert_box(t, glo, ghi);
  }
  // Whether a triangle of `added` intersects a live triangle other than those in `ignored`
  // (which the operation replaces), with the operation's positions `moved` for vertex `mv`.
  bool intersects(const std::vector<Tri>& added, const std::vector<int>& ignored, int mv = -1,
                  const Vec3& moved = Vec3::Zero()) {
    const auto pos = [&](int v) -> const Vec3& { return v == mv ? moved : P(v); };
    for (const Tri& a : added) {
      const std::array<Vec3, 3> pa{pos(a[0]), pos(a[1]), pos(a[2])};
      if (triangle_is_degenerate(pa[0], pa[1], pa[2])) return true;
      const Vec3 lo = pa[0].cwiseMin(pa[1]).cwiseMin(pa[2]), hi = pa[0].cwiseMax(pa[1]).cwiseMax(pa[2]);
      ++stamp_id_;
      for (int t : ignored) stamp_[t] = stamp_id_;
      const bool hit = hash_.any_in(lo, hi, [&](int u) {
        if (stamp_[u] == stamp_id_ || !alive_[u]) return false;
        stamp_[u] = stamp_id_;
        const Tri& x = m_.triangles[u];
        const std::array<Vec3, 3> pb{pos(x[0]), pos(x[1]), pos(x[2])};
        const Vec3 blo = pb[0].cwiseMin(pb[1]).cwiseMin(pb[2]), bhi = pb[0].cwiseMax(pb[1]).cwiseMax(pb[2]);
        if ((blo.array() > hi.array()).any() || (bhi.array() < lo.array()).any()) return false;
        return exact_intersect(pa, pb);
      });
      if (hit) return true;
    }
    return false;
  }

  // triangles_intersect(a, b) for an `a` known to be non-degenerate: b's own tests (finite
  // corners, degenerate) and then the exact test, without a's degeneracy test again (an exact
  // orientation test per axis, most of triangles_intersect's cost on the pairs the repair meets).
  // Corners of a that are not finite go through triangles_intersect, which throws.
  static bool exact_intersect(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b) {
    if (!all_finite(a) || !all_finite(b)) return triangles_intersect(a, b);
    return !triangle_is_degenerate(b[0], b[1], b[2]) && nondegenerate_triangles_intersect(a, b);
  }
  static bool all_finite(const std::array<Vec3, 3>& t) { return t[0].allFinite() && t[1].allFinite() && t[2].allFinite(); }

  // A floating-point filter before the exact test, which most pairs of neighbouring triangles
  // would otherwise reach (their shared corners put them on each other's planes): true when the
  // corners of b (vertex ids ib) not shared with a (ids ia) lie strictly on one side of a's plane
  // (normal n), by more than `bound`, a bound on the rounding. Then b meets a's plane only in the
  // shared corners, which triangles_intersect does not count as an intersection (and a and b,
  // neither degenerate, cannot share all three). False when unsure. A shared id is a shared
  // position; two ids at one position (which triangles_intersect shares too) give a side within
  // the rounding of 0, so unsure, and the exact test decides as it would have.
  static bool apart_by_plane(const std::array<Vec3, 3>& a, const Tri& ia, const Vec3& n,
                             const std::array<Vec3, 3>& b, const Tri& ib, double bound) {
    int side = 0;
    for (int k = 0; k < 3; ++k) {
      if (ib[k] == ia[0] || ib[k] == ia[1] || ib[k] == ia[2]) continue;
      const double s = n.dot(b[k] - a[0]);
      const int q_side = s > bound ? 1 : s < -bound ? -1 : 0;
      if (q_side == 0 || (side != 0 && q_side != side)) return false;
      side = q_side;
    }
    return side != 0;
  }
  // apart_at_shared_vertex for a and b when they share exactly one vertex id (the pairs that
  // apart_by_plane leaves unsure are nearly all such: in star_intersects, a star triangle and a
  // triangle around one of the star's outer corners; none of them intersected on the torus or the
  // bunny, and the exact test was a seventh of star_intersects). The same position under two
  // ids is not shared here; apart_at_shared_vertex cannot find it strictly on both sides of its
  // plane, so it answers false and the exact test decides.
  static bool apart_at_shared_corner(const std::array<Vec3, 3>& a, const Tri& ia, const std::array<Vec3, 3>& b,
                                     const Tri& ib) {
    int i = -1, j = -1;
    for (int p = 0; p < 3; ++p)
      for (int q = 0; q < 3; ++q)
        if (ia[p] == ib[q]) {
          if (i >= 0) return false;  // an edge shared: apart_by_plane's case
          i = p, j = q;
        }
    return i >= 0 && apart_at_shared_vertex(a[i], a[(i + 1) % 3], a[(i + 2) % 3], b[(j + 1) % 3], b[(j + 2) % 3]);
  }
  // The rounding bound of apart_by_plane for two triangles within a box of diagonal d whose
  // coordinates are at most m in absolute value: each difference is off by about 1e-16 m, each
  // product of three lengths (at most d) by about 1e-16 of itself; 1e-13 of the terms leaves a
  // wide margin.
  static double plane_bound(double m, double d) { return 1e-13 * (m + d) * 3 * d * d; }

  // Whether v's star, with v at `moved`, intersects a live triangle outside the star: one query
  // of the hash over the whole star's box, each triangle found tested against every star
  // triangle whose box meets its own (the star's triangles share v and are not tested against
  // each other: the facing test keeps them from folding over one another).
  bool star_intersects(int v, const Vec3& moved) {
    return star_hits(v, moved, [&](int w) -> const Vec3& { return P(w); }, stamp_.data(), ++stamp_id_, star_buffer_);
  }
  // Whether triangle x, with corners pb, meets a triangle of `star` (its box lo, hi and its
  // corners' largest magnitude): star_hits' test of each triangle found near the star. Out of
  // line: inlined into star_hits' hash loop, the whole relaxation took 3% more instructions on
  // the torus (callgrind), star_intersects' one thread included.
  [[gnu::noinline]] static bool meets_star(const std::vector<StarTriangle>& star, const Vec3& lo, const Vec3& hi, double magnitude,
                         const Tri& x, const std::array<Vec3, 3>& pb) {
    const Vec3 blo = pb[0].cwiseMin(pb[1]).cwiseMin(pb[2]), bhi = pb[0].cwiseMax(pb[1]).cwiseMax(pb[2]);
    if ((blo.array() > hi.array()).any() || (bhi.array() < lo.array()).any()) return false;
    const Vec3 nb = (pb[1] - pb[0]).cross(pb[2] - pb[0]);
    // One rounding bound for x against every star triangle, from the whole star's box and
    // magnitude: at least each pair's own (plane_bound grows with both), so as safe, and the
    // exact test decides whatever it leaves unsure.
    const double bound = plane_bound(std::max(std::max(blo.cwiseAbs().maxCoeff(), bhi.cwiseAbs().maxCoeff()), magnitude),
                                     (hi.cwiseMax(bhi) - lo.cwiseMin(blo)).norm());
    for (const StarTriangle& a : star) {
      if ((blo.array() > a.hi.array()).any() || (bhi.array() < a.lo.array()).any()) continue;
      if (apart_by_plane(a.p, a.ids, a.normal, pb, x, bound) || apart_by_plane(pb, x, nb, a.p, a.ids, bound)) continue;
      if (apart_at_shared_corner(a.p, a.ids, pb, x)) continue;
      if (exact_intersect(a.p, pb)) return true;  // the star's triangles are not degenerate (star_hits)
    }
    return false;
  }
  // star_intersects with every vertex but v at at(w), where the box each triangle is stored
  // with in the hash must hold it (hash_box, hash_cover).
  // Reads the mesh and the hash only (stamp and star are the caller's), so that calls with
  // their own stamp and star may run on several threads while nothing changes the mesh.
  template <class At>
  bool star_hits(int v, const Vec3& moved, const At& at, std::uint32_t* stamp, std::uint32_t id,
                 std::vector<StarTriangle>& star) const {
    const auto pos = [&](int w) -> const Vec3& { return w == v ? moved : at(w); };
    star.clear();
    Vec3 lo = moved, hi = moved;
    double magnitude = 0;
    for (int u : vt_[v]) {
      stamp[u] = id;
      const Tri& t = m_.triangles[u];
      StarTriangle x{t, {pos(t[0]), pos(t[1]), pos(t[2])}, {}, {}, {}};
      if (triangle_is_degenerate(x.p[0], x.p[1], x.p[2])) return true;
      x.lo = x.p[0].cwiseMin(x.p[1]).cwiseMin(x.p[2]);
      x.hi = x.p[0].cwiseMax(x.p[1]).cwiseMax(x.p[2]);
      x.normal = (x.p[1] - x.p[0]).cross(x.p[2] - x.p[0]);
      lo = lo.cwiseMin(x.lo);
      hi = hi.cwiseMax(x.hi);
      magnitude = std::max({magnitude, x.lo.cwiseAbs().maxCoeff(), x.hi.cwiseAbs().maxCoeff()});
      star.push_back(x);
    }
    const auto hits = [&](int u) {
      if (stamp[u] == id) return false;
      stamp[u] = id;
      // The box u is stored with holds its triangle (hash_box): one apart from the star's
      // rules it out before its corners are read (most of the triangles found).
      if ((hashed_lo_[u].array() > hi.array()).any() || (hashed_hi_[u].array() < lo.array()).any() || !alive_[u])
        return false;
      const Tri& x = m_.triangles[u];  // not in v's star, so v is not among its corners
      return meets_star(star, lo, hi, magnitude, x, {at(x[0]), at(x[1]), at(x[2])});
    };
    return hash_.any_in(lo, hi, hits);
  }

  // A move of the relaxation: the vertex, its position and normal before, and its candidate
  // (index among the sweep's projected moves).
  struct Turn {
    int v;
    Vec3 from, from_normal;
    std::size_t candidate;
  };
  // intersecting_turn's arrays, made once a sweep (the mesh's connectivity does not change
  // while the relaxation moves vertices) and left clean after each call.
  struct TurnScratch {
    static constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
    TurnScratch(std::size_t vertices, unsigned workers)
        : turn_of(vertices, kNone), stamps(std::max(workers, 1u)), ids(stamps.size(), 0), stars(stamps.size()) {}
    std::vector<std::size_t> turn_of;  // by vertex: its turn in the call, or kNone
    std::vector<std::vector<std::uint32_t>> stamps;  // by worker, as star_hits wants them
    std::vector<std::uint32_t> ids;
    std::vector<std::vector<StarTriangle>> stars;
    std::vector<char> hit;
  };
  // The first of `turns` (moves made in this order, all applied now) whose star at the
  // positions of its turn (the moves before it made, those after it not) intersects a triangle
  // outside it, as star_intersects would have found then; turns.size() if none. First every
  // triangle the turns changed is stored in the hash with a box over its corners before and
  // after (which holds it at any turn; most already are, see hash_cover); then the turns are
  // tested on all cores, the hash only read.
  std::size_t intersecting_turn(const std::vector<Turn>& turns, TurnScratch& scratch) {
    if (turns.empty()) return 0;
    constexpr std::size_t kNone = TurnScratch::kNone;
    for (std::size_t k = 0; k < turns.size(); ++k) scratch.turn_of[static_cast<std::size_t>(turns[k].v)] = k;
    for (const Turn& turn : turns)
      for (int u : vt_[turn.v]) {
        Vec3 lo = P(m_.triangles[u][0]), hi = lo;
        for (int w : m_.triangles[u]) {
          lo = lo.cwiseMin(P(w)), hi = hi.cwiseMax(P(w));
          if (const std::size_t j = scratch.turn_of[static_cast<std::size_t>(w)]; j != kNone)
            lo = lo.cwiseMin(turns[j].from), hi = hi.cwiseMax(turns[j].from);
        }
        hash_cover(u, lo, hi);
      }
    scratch.hit.assign(turns.size(), 0);
    detail::parallel_blocks(turns.size(), kTurnBlock, workers_, [&](std::size_t begin, std::size_t end, unsigned w) {
      std::vector<std::uint32_t>& stamp = scratch.stamps[w];
      if (stamp.empty()) stamp.assign(m_.triangles.size(), 0);
      std::uint32_t& id = scratch.ids[w];  // a worker's stamps outlive its blocks and calls
      for (std::size_t k = begin; k < end; ++k) {
        if (id == std::numeric_limits<std::uint32_t>::max()) std::fill(stamp.begin(), stamp.end(), 0), id = 0;
        const auto at = [&](int q) -> const Vec3& {
          const std::size_t j = scratch.turn_of[static_cast<std::size_t>(q)];
          return j != kNone && j > k ? turns[j].from : P(q);
        };
        scratch.hit[k] = star_hits(turns[k].v, P(turns[k].v), at, stamp.data(), ++id, scratch.stars[w]);
      }
    });
    for (const Turn& turn : turns) scratch.turn_of[static_cast<std::size_t>(turn.v)] = kNone;
    return static_cast<std::size_t>(std::find(scratch.hit.begin(), scratch.hit.end(), 1) - scratch.hit.begin());
  }

  // ---- operations. Each returns whether it was applied and pushes the triangles it changed.
  // By default a flip must raise the smallest angle of the pair by kMinGain (the repair); with
  // `for_ratio` (the relaxation) it must bring the four corners' valences nearer 6, or keep them
  // and lower the pair's summed edge ratio by kRelaxMinGain (see below), and keep the pair's
  // smallest angle or at least kRelaxKeepDegrees.
  bool try_flip(int t, int k, bool for_ratio = false) {
    const Tri T = m_.triangles[t];
    const int a = T[k], b = T[(k + 1) % 3], c = T[(k + 2) % 3];
    const int u = across(t, a, b);
    if (u < 0) return false;
    const Tri& U = m_.triangles[u];
    int d = -1;
    for (int w : U)
      if (w != a && w != b) d = w;
    if (d < 0 || d == c) return false;
    // Each relaxation flip lowers the valences' summed squared distance from 6, or keeps it and
    // lowers the summed edge ratio (below): no flip can be undone, and the relaxation's moves
    // then have a more regular mesh to work on (an interior vertex of valence 6 can have six
    // equilateral triangles, one of 4 or 8 cannot). The valences first: on an even mesh nearly
    // every edge the relaxation tries fails on them (573,809 of 574,422 tries on the torus at
    // factor 20), before the other tests' edge scans and square roots.
    const auto dev = [&](int x, int add) {
      const int q = static_cast<int>(vt_[x].size()) + add - 6;
      return q * q;
    };
    const int val_before = for_ratio ? dev(a, 0) + dev(b, 0) + dev(c, 0) + dev(d, 0) : 0;
    const int val_after = for_ratio ? dev(a, -1) + dev(b, -1) + dev(c, 1) + dev(d, 1) : 0;
    if (val_after > val_before) return false;
    if (has_edge(c, d)) return false;
    // The tests that need no field evaluation first.
    const Tri n1{c, a, d}, n2{d, b, c};
    if (for_ratio) {
      const double ratio_before = tri_ratio(T) + tri_ratio(U), ratio_after = tri_ratio(n1) + tri_ratio(n2);
      const bool better = ratio_after < ratio_before * (1 - kRelaxMinGain)
                              ? val_after <= val_before
                              : val_after < val_before && ratio_after < ratio_before * kFlipRatioSlack;
      if (!better) return false;
    }
    const double before = std::min(tri_min_angle(T), tri_min_angle(U));
    const double after = std::min(tri_min_angle(n1), tri_min_angle(n2));
    if (for_ratio ? !(after >= std::min(before, kRelaxKeepDegrees * std::numbers::pi / 180))
                  : !(after > before + kMinGain))
      return false;
    const double floor = facing_floor({t, u});
    if (!faces_surface(n1, floor) || !faces_surface(n2, floor)) return false;
    // A flip must not remove a crease edge nor cut across one.
    const bool creased = on_crease(a) || on_crease(b) || on_crease(c) || on_crease(d);
    if (creased && !(face_normal(T).dot(face_normal(U)) > kCreaseFlatCos)) return false;
    // The new diagonal may lie no farther from the surface than the worst edge of the quad.
    const auto mid = [&](int x, int y) { return std::abs(signed_distance(0.5 * (P(x) + P(y)))); };
    const double allowed = std::max({mid(a, b), mid(a, d), mid(d, b), mid(b, c), mid(c, a)});
    if (!(mid(c, d) <= allowed)) return false;
    if (!keeps_tolerance({n1, n2}, {t, u})) return false;
    if (intersects({n1, n2}, {t, u})) return false;
    m_.triangles[t] = n1;
    m_.triangles[u] = n2;
    erase_value(vt_[a], u);
    erase_value(vt_[b], t);
    vt_[c].push_back(u);
    vt_[d].push_back(t);
    hash_box(t);
    hash_box(u);
    touch(t);
    touch(u);
    if (for_ratio) {
      ++r_.relax_flips;
      for (int w : {a, b, c, d}) flipped_[w] = 1;
    } else {
      ++r_.flips;
    }
    return true;
  }

  bool try_move(int v) {
    if (on_crease(v)) return false;
    const std::vector<int> ring = neighbours(v);
    if (ring.size() < 3) return false;
    Vec3 centroid = Vec3::Zero();
    for (int w : ring) centroid += P(w);
    centroid /= static_cast<double>(ring.size());
    const Vec3 x = P(v), n = m_.normals[v];
    // Two targets: the centroid of the neighbours (Laplacian smoothing), and the mean of the
    // apexes of equilateral triangles over the star's outer edges (equilateral_step), which
    // pulls v towards where each of its triangles would be equilateral and opens small angles
    // the centroid leaves.
    std::vector<Vec3> steps;
    Vec3 to_centroid = centroid - x;
    to_centroid -= n * n.dot(to_centroid);
    steps.push_back(to_centroid);
    const Vec3 to_equilateral = equilateral_step(v);
    steps.push_back(to_equilateral.squaredNorm() > 0 ? to_equilateral : to_centroid);
    double shortest = std::numeric_limits<double>::infinity();
    for (int w : ring) shortest = std::min(shortest, (P(w) - x).norm());
    double before = std::numeric_limits<double>::infinity();
    for (int u : vt_[v]) before = std::min(before, tri_min_angle(m_.triangles[u]));
    for (const double share : kMoveShares)
    for (const Vec3& step : steps) {
      // Newton moves the point by about the sagitta of its edges, which changes the angles
      // little: a tangential position that does not raise them is not worth projecting.
      {
        m_.positions[v] = x + share * step;
        double guess = std::numeric_limits<double>::infinity();
        for (int u : vt_[v]) guess = std::min(guess, tri_min_angle(m_.triangles[u]));
        m_.positions[v] = x;
        if (!(guess > before)) continue;
      }
      ProjectionOptions po;
      po.tolerance = 1e-10 * o_.diagonal;
      po.max_step = shortest;
      po.max_travel = shortest;
      const ProjectionResult pr = project_to_surface(field_, x + share * step, po);
      if (!pr.ok()) continue;
      const Vec3& g = pr.gradient;  // at pr.point: no second evaluation of the same point
      if (!(g.squaredNorm() > 0)) continue;
      const Vec3 ng = g.normalized();
      if (!(ng.dot(n) > kMoveNormalCos)) continue;
      // The star with v at its new place.
      const double floor = facing_floor(vt_[v]);
      const Vec3 saved = m_.positions[v], saved_n = m_.normals[v];
      m_.positions[v] = pr.point;
      m_.normals[v] = ng;
      double after = std::numeric_limits<double>::infinity();
      bool faces = true;
      std::vector<Tri> star;
      for (int u : vt_[v]) {
        star.push_back(m_.triangles[u]);
        after = std::min(after, tri_min_angle(m_.triangles[u]));
        faces = faces && faces_surface(m_.triangles[u], floor);
      }
      bool ok = after > before + kMinGain && faces;
      const double new_dist = ok ? worst_star_distance(v) : 0;
      m_.positions[v] = saved;
      m_.normals[v] = saved_n;
      if (ok) {
        const Vec3 target = pr.point;
        ok = may_replace(new_dist, vt_[v]) && !intersects(star, vt_[v], v, target);
        if (ok) {
          m_.positions[v] = target;
          m_.normals[v] = ng;
          crease_[v] = -1;
          for (int u : vt_[v]) {
            hash_box(u);
            touch(u);
          }
          ++r_.moves;
          return true;
        }
      }
    }
    return false;
  }

  // Collapses edge (a, b) of triangle t into one vertex (a keeps its index).
  bool try_collapse(int t, int a, int b) {
    const int u = across(t, a, b);
    if (u < 0) return false;
    const bool ca = on_crease(a), cb = on_crease(b);
    if (ca && cb) return false;
    int c = -1, d = -1;
    for (int w : m_.triangles[t])
      if (w != a && w != b) c = w;
    for (int w : m_.triangles[u])
      if (w != a && w != b) d = w;
    // The link condition: a and b share exactly the neighbours c and d, so the collapse keeps
    // the surface manifold and its topology; c and d keep at least three neighbours.
    const std::vector<int> na = neighbours(a), nb = neighbours(b);
    std::vector<int> common;
    std::set_intersection(na.begin(), na.end(), nb.begin(), nb.end(), std::back_inserter(common));
    if (common.size() != 2 || !((common[0] == c && common[1] == d) || (common[0] == d && common[1] == c))) return false;
    if (neighbours(c).size() < 4 || neighbours(d).size() < 4) return false;
    // The merged vertex: a crease end stays where it is; otherwise the midpoint, on the surface.
    Vec3 x, nx;
    // Across a ridge narrower than the edge (the landing's normal within 30 degrees of neither
    // end's, see lands_between), the merged vertex stands for both flanks.
    bool ridge = false;
    if (ca || cb) {
      x = ca ? P(a) : P(b);
      nx = ca ? m_.normals[a] : m_.normals[b];
    } else {
      ProjectionOptions po;
      po.tolerance = 1e-10 * o_.diagonal;
      const double l = (P(a) - P(b)).norm();
      po.max_step = l;
      po.max_travel = l;
      const ProjectionResult pr = project_to_surface(field_, 0.5 * (P(a) + P(b)), po);
      if (!pr.ok()) return false;
      const Vec3& g = pr.gradient;  // at pr.point
      if (!(g.squaredNorm() > 0)) return false;
      x = pr.point;
      nx = g.normalized();
      if (!lands_between(nx, m_.normals[a], m_.normals[b])) return false;
      ridge = !(nx.dot(m_.normals[a]) > kMoveNormalCos && nx.dot(m_.normals[b]) > kMoveNormalCos);
      // Not across a crease of the field (two of its min/max/abs pieces meet within the edge):
      // that edge stands on both faces of a real crease, which a collapse would round off.
      if (ridge && field_.pieces(x, l).size() > 1) return false;
    }
    std::vector<int> old;  // every triangle around a or b
    for (int w : vt_[a]) old.push_back(w);
    for (int w : vt_[b])
      if (std::find(old.begin(), old.end(), w) == old.end()) old.push_back(w);
    std::sort(old.begin(), old.end());
    double before = std::numeric_limits<double>::infinity();
    for (int w : old) before = std::min(before, tri_min_angle(m_.triangles[w]));
    std::vector<Tri> added;
    std::vector<int> kept;
    for (int w : old) {
      if (w == t || w == u) continue;
      Tri x3 = m_.triangles[w];
      for (int& y : x3)
        if (y == b) y = a;
      added.push_back(x3);
      kept.push_back(w);
    }
    const double floor = facing_floor(old);
    const Vec3 saved = m_.positions[a], saved_n = m_.normals[a];
    const Vec3 flank_a = m_.normals[a], flank_b = m_.normals[b];
    m_.positions[a] = x;
    m_.normals[a] = nx;
    double after = std::numeric_limits<double>::infinity();
    bool faces = true;
    for (const Tri& s : added) {
      after = std::min(after, tri_min_angle(s));
      if (!ridge) {
        faces = faces && faces_surface(s, floor);
        continue;
      }
      // On a ridge the crest's normal is up to half the ridge's turn (50-75 degrees on the horse)
      // from either flank, so a triangle lying on a flank faces it edge-on; at the merged corner
      // it must face one of the three normals the vertex stands for (crest, either flank), at the
      // other corners their own as everywhere.
      const Vec3 fn = face_normal(s);
      for (int v : s) {
        const double c = v == a ? std::max({fn.dot(nx), fn.dot(flank_a), fn.dot(flank_b)}) : fn.dot(m_.normals[v]);
        faces = faces && c > floor;
      }
    }
    bool ok = after > before + kMinGain && faces;
    const double new_dist = ok ? worst_distance(added) : 0;
    m_.positions[a] = saved;
    m_.normals[a] = saved_n;
    ok = ok && may_replace(new_dist, old);
    if (ok) ok = !intersects(added, old, a, x);
    if (!ok) return false;
    m_.positions[a] = x;
    m_.normals[a] = nx;
    crease_[a] = ca || cb ? 1 : -1;
    alive_[t] = alive_[u] = 0;
    for (std::size_t i = 0; i < kept.size(); ++i) m_.triangles[kept[i]] = added[i];
    std::vector<int> star;
    for (int w : old)
      if (w != t && w != u) star.push_back(w);
    vt_[a] = star;
    vt_[b].clear();
    erase_value(vt_[c], t);
    erase_value(vt_[d], u);
    dead_vertex_.push_back(b);
    for (int w : star) {
      hash_box(w);
      touch(w);
    }
    ++r_.collapses;
    return true;
  }

  // A new vertex, not yet in any triangle (a split tries it, then keeps or drops it).
  void add_vertex(const Vec3& x, const Vec3& normal) {
    m_.positions.push_back(x);
    m_.normals.push_back(normal);
    vt_.emplace_back();
    crease_.push_back(-1);
  }
  void drop_last_vertex() {
    m_.positions.pop_back();
    m_.normals.pop_back();
    vt_.pop_back();
    crease_.pop_back();
  }
  // Splits edge (a, b) at its midpoint moved onto the surface (the tolerance's refinement), or
  // with `repair`, inserts a vertex at the centre of the quad of the two triangles on the edge,
  // moved onto the surface: a cap whose flip would make a worse pair (the far apex sits near
  // one end of the edge) opens into four triangles around it. A repair insertion must raise
  // the smallest angle and keep the new edges no farther from the surface than the quad's.
  // The halves must be at least `shortest` long (0: min_edge).
  bool try_split(int t, int a, int b, bool repair = false, double shortest = 0) {
    const int u = across(t, a, b);
    if (u < 0) return false;
    if ((P(a) - P(b)).norm() < 2 * (shortest > 0 ? shortest : o_.min_edge)) return false;
    int c = -1, d = -1;
    for (int w : m_.triangles[t])
      if (w != a && w != b) c = w;
    for (int w : m_.triangles[u])
      if (w != a && w != b) d = w;
    // Next to a crease, a repair insertion keeps to one face: the quad flat (the flip's test,
    // kCreaseFlatCos), the edge it removes not both of whose ends lie on the crease (it may run
    // along it), and the new vertex landing with its gradient on that face (below). The Barth
    // ball's crease patches left caps there that nothing else could open: a crease finely
    // spaced for the steep side, the flat side's vertices far off along its tangent (0.61
    // degrees at factor 6).
    const bool creased = repair && (on_crease(a) || on_crease(b) || on_crease(c) || on_crease(d));
    const Vec3 face_t = creased ? face_normal(m_.triangles[t]) : Vec3::Zero();
    const Vec3 face_u = creased ? face_normal(m_.triangles[u]) : Vec3::Zero();
    if (creased && ((on_crease(a) && on_crease(b)) || !(face_t.dot(face_u) > kCreaseFlatCos))) return false;
    ProjectionOptions po;
    po.tolerance = 1e-10 * o_.diagonal;
    const double l = (P(a) - P(b)).norm();
    po.max_step = 0.5 * l;
    po.max_travel = 0.5 * l;
    const Vec3 start = repair ? Vec3(0.25 * (P(a) + P(b) + P(c) + P(d))) : Vec3(0.5 * (P(a) + P(b)));
    const ProjectionResult pr = project_to_surface(field_, start, po);
    if (!pr.ok()) return false;
    const Vec3& g = pr.gradient;  // at pr.point
    if (!(g.squaredNorm() > 0)) return false;
    const Vec3 ng = g.normalized();
    if (!(ng.dot(m_.normals[a]) > 0 && ng.dot(m_.normals[b]) > 0)) return false;
    if (creased && !(ng.dot(face_t) > kCreaseFlatCos && ng.dot(face_u) > kCreaseFlatCos)) return false;
    // t = (a, b, c) in its own rotation, u = (b, a, d).
    const int m = static_cast<int>(m_.positions.size());
    add_vertex(pr.point, ng);
    const std::vector<Tri> added{{a, m, c}, {m, b, c}, {b, m, d}, {m, a, d}};
    bool ok = true;
    const double floor = facing_floor({t, u});
    for (const Tri& s : added) ok = ok && faces_surface(s, floor);
    if (ok && repair) {
      double after = std::numeric_limits<double>::infinity();
      for (const Tri& s : added) after = std::min(after, tri_min_angle(s));
      ok = after > std::min(tri_min_angle(m_.triangles[t]), tri_min_angle(m_.triangles[u])) + kMinGain;
      const auto mid = [&](int x, int y) { return std::abs(signed_distance(0.5 * (P(x) + P(y)))); };
      const double allowed = std::max({mid(a, b), mid(a, d), mid(d, b), mid(b, c), mid(c, a)});
      ok = ok && std::max({mid(m, a), mid(m, b), mid(m, c), mid(m, d)}) <= allowed;
      ok = ok && keeps_tolerance(added, {t, u});
    }
    if (ok) ok = !intersects(added, {t, u});
    if (!ok) {
      drop_last_vertex();
      return false;
    }
    const int t2 = tri_count(), u2 = t2 + 1;
    m_.triangles[t] = added[0];
    m_.triangles.push_back(added[1]);
    m_.triangles[u] = added[2];
    m_.triangles.push_back(added[3]);
    alive_.push_back(1);
    alive_.push_back(1);
    stamp_.push_back(0);
    stamp_.push_back(0);
    // a: t, u2 (was t, u); b: t2, u (was t, u); c: t, t2; d: u, u2; m: all four.
    erase_value(vt_[a], u);
    vt_[a].push_back(u2);
    erase_value(vt_[b], t);
    vt_[b].push_back(t2);
    vt_[c].push_back(t2);
    vt_[d].push_back(u2);
    vt_[m] = {t, t2, u, u2};
    for (int s : {t, t2, u, u2}) {
      hash_box(s);
      touch(s);
    }
    ++(repair ? r_.inserts : r_.splits);
    return true;
  }

  // Rotates a triangle so that the edge (k, k+1) is given as (T[k], T[k+1]).
  bool repair_triangle(int t) {
    const Tri T = m_.triangles[t];
    const auto [len, order] = edges_longest_first(T);
    // A cap (an angle near 180 degrees) opens by flipping its longest edge; other edges may flip
    // too. Flips change nothing but connectivity, so they go first.
    for (int k : order)
      if (try_flip(t, k)) return true;
    // A needle: its shortest edge goes.
    const int shortest = order[2];
    if (len[shortest] < kNeedleShare * len[order[1]] &&
        try_collapse(t, T[shortest], T[(shortest + 1) % 3]))
      return true;
    // Otherwise move a corner: the one at the smallest angle first.
    std::array<std::pair<double, int>, 3> corners{};
    for (int k = 0; k < 3; ++k) corners[k] = {angle_at(P(T[k]), P(T[(k + 1) % 3]), P(T[(k + 2) % 3])), k};
    std::sort(corners.begin(), corners.end());
    for (const auto& [angle, k] : corners)
      if (try_move(T[k])) return true;
    // Then the neighbours of the corners (the second ring), which reshape it from outside.
    for (int v : T)
      for (int w : neighbours(v))
        if (w != T[0] && w != T[1] && w != T[2] && try_move(w)) return true;
    // A cap: a vertex inside the quad on its longest edge.
    if (try_split(t, T[order[0]], T[(order[0] + 1) % 3], true)) return true;
    // Last, removing a vertex: any edge of the triangle, shortest first, where that raises the
    // smallest angle around (a vertex squeezed between neighbours that cannot move).
    for (int i = 2; i >= 0; --i) {
      const int k = order[i];
      if (k == shortest && len[shortest] < kNeedleShare * len[order[1]]) continue;  // tried above
      if (try_collapse(t, T[k], T[(k + 1) % 3])) return true;
    }
    return false;
  }

  void repair() {
    std::vector<int> work;
    for (int t = 0; t < tri_count(); ++t)
      if (alive_[t] && tri_below(m_.triangles[t], o_.improve_below)) work.push_back(t);
    r_.bad_before = std::max(r_.bad_before, work.size());
    for (int round = 0; round < kQualityRounds && !work.empty(); ++round) {
      std::vector<std::pair<double, int>> order;
      for (int t : work)
        if (alive_[t]) order.push_back({tri_min_angle(m_.triangles[t]), t});
      std::sort(order.begin(), order.end());
      touched_.clear();
      bool changed = false;
      for (std::size_t i = 0; i < order.size(); ++i) {
        poll(i);
        const int t = order[i].second;
        if (!alive_[t] || !(tri_min_angle(m_.triangles[t]) < o_.improve_below)) continue;
        changed = repair_triangle(t) || changed;
      }
      if (!changed) break;
      // Next round: what is still bad among the triangles visited or changed.
      std::vector<int> next;
      for (const auto& [angle, t] : order) next.push_back(t);
      next.insert(next.end(), touched_.begin(), touched_.end());
      std::sort(next.begin(), next.end());
      next.erase(std::unique(next.begin(), next.end()), next.end());
      work.clear();
      for (int t : next)
        if (alive_[t] && tri_below(m_.triangles[t], o_.improve_below)) work.push_back(t);
    }
    std::size_t bad = 0;
    for (int t = 0; t < tri_count(); ++t)
      if (alive_[t] && tri_below(m_.triangles[t], o_.improve_below)) ++bad;
    r_.bad_after = bad;
  }

  // ---- relaxation: the mean edge ratio (see relax)
  double tri_ratio(const Tri& t) const {
    const double a = (P(t[1]) - P(t[0])).squaredNorm(), b = (P(t[2]) - P(t[1])).squaredNorm(),
                 c = (P(t[0]) - P(t[2])).squaredNorm();
    const double lo = std::min({a, b, c});
    return lo > 0 ? std::sqrt(std::max({a, b, c}) / lo) : std::numeric_limits<double>::infinity();
  }
  // Where v would make each of its triangles equilateral on its outer edge (the mean of those
  // apexes), moved into v's tangent plane; zero when v has no such triangle.
  Vec3 equilateral_step(int v) const {
    const Vec3 x = P(v), n = m_.normals[v];
    Vec3 apex_mean = Vec3::Zero();
    int apexes = 0;
    for (int u : vt_[v]) {
      const Tri& t = m_.triangles[u];
      int k = 0;
      while (t[k] != v) ++k;
      const Vec3 &a = P(t[(k + 1) % 3]), &b = P(t[(k + 2) % 3]);
      const Vec3 side = n.cross(b - a);  // towards v's side of edge a -> b, seen from outside
      if (!(side.squaredNorm() > 0)) continue;
      apex_mean += 0.5 * (a + b) + std::sqrt(3.0) / 2 * (b - a).norm() * side.normalized();
      ++apexes;
    }
    if (apexes == 0) return Vec3::Zero();
    Vec3 step = apex_mean / apexes - x;
    return step - n * n.dot(step);
  }
  // Where in v's tangent plane v's star has the lowest mean edge ratio, as a step from v: a
  // compass search (the four directions of a tangent frame, the stride halved where none of
  // them gains) from the better of v and v + `first` (the equilateral step), at most
  // kRelaxSearchStars stars judged, none whose smallest angle would fall under both the star's
  // own and kRelaxKeepDegrees (cosine `keep_cos`). The equilateral step aims every triangle at
  // its outer edge at once, which where the edges around v differ in length (a graded mesh) is
  // not where their mean ratio is lowest; most of the vertices it leaves stretched gain nothing
  // from it, and a step the search finds for them does. Zero when no star judged gains
  // kRelaxMinGain. Read only: judged on several threads.
  Vec3 searched_step(int v, const Vec3& first, double keep_cos) const {
    const Vec3 x = P(v), n = m_.normals[v];
    const StarShape start = star_shape(v);
    const double cos_cap = std::max(start.max_cos, keep_cos);
    const auto score = [&](const Vec3& step) {
      const StarShape s = star_shape(v, x + step);
      return s.max_cos <= cos_cap ? s.mean_ratio : std::numeric_limits<double>::infinity();
    };
    Vec3 best = Vec3::Zero();
    double best_score = start.mean_ratio;
    if (const double f = score(first); f < best_score) best = first, best_score = f;
    const Vec3 e1 = n.unitOrthogonal(), e2 = n.cross(e1);
    const std::array<Vec3, 4> directions{e1, Vec3(-e1), e2, Vec3(-e2)};
    double stride = 0.5 * first.norm();
    for (int judged = 1; judged < kRelaxSearchStars;) {
      bool gained = false;
      for (const Vec3& d : directions) {
        if (judged++ >= kRelaxSearchStars) break;
        const Vec3 step = best + stride * d;
        if (const double f = score(step); f < best_score) {
          best = step, best_score = f, gained = true;
          break;
        }
      }
      if (!gained) stride *= 0.5;
    }
    return best_score < start.mean_ratio * (1 - kRelaxMinGain) ? best : Vec3::Zero();
  }
  // A star's mean edge ratio and the cosine of its smallest angle. Each triangle's smallest
  // angle faces its shortest edge; its cosine comes from the squared edge lengths by the law of
  // cosines, without an arc tangent (most of the relaxation's own time went to them).
  struct StarShape {
    double mean_ratio = 0, max_cos = -1;
  };
  StarShape star_shape(int v) const { return star_shape(v, P(v)); }
  // ... with v at `at` (read only: the relaxation's targets are judged on several threads).
  StarShape star_shape(int v, const Vec3& at) const {
    const auto pos = [&](int w) -> const Vec3& { return w == v ? at : P(w); };
    StarShape s;
    for (int u : vt_[v]) {
      const Tri& t = m_.triangles[u];
      const Vec3 &a = pos(t[0]), &b = pos(t[1]), &c = pos(t[2]);
      std::array<double, 3> l{(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()};
      std::sort(l.begin(), l.end());
      const double xy = l[1] * l[2];
      s.mean_ratio += l[0] > 0 ? std::sqrt(l[2] / l[0]) : std::numeric_limits<double>::infinity();
      s.max_cos = std::max(s.max_cos, xy > 0 ? std::min(1.0, (l[1] + l[2] - l[0]) / (2 * std::sqrt(xy))) : 1.0);
    }
    s.mean_ratio /= std::max<std::size_t>(1, vt_[v].size());
    return s;
  }

  // Moves the vertices of the triangles whose longest edge exceeds kRelaxRatio times their
  // shortest towards where their triangles would be equilateral (equilateral_step), projected
  // back onto the surface: in kRelaxSweeps sweeps, each finding all its targets and projecting
  // them first (on all cores where the field allows) and then taking them in index order, a
  // move kept only if it lowers the mean edge ratio of v's star by kRelaxMinGain, keeps its
  // smallest angle (or at least kRelaxKeepDegrees), its facing and the tolerance, and
  // intersects nothing. Crease vertices stay. A target that does not lower the star's mean ratio in the tangent plane is not
  // projected at all (no evaluation). Before the moves of each sweep, flips of the stretched
  // triangles' edges towards valence 6 (try_flip's for_ratio). The repair above aims at the
  // worst triangles; this aims at the many mildly stretched ones where the fronts' edge lengths
  // change (the mean ratio 1.30 -> 1.20 on the bunny VIS-800 at factor 3; no vertex is added or
  // removed). Where these sweeps leave the mesh's mean ratio over the aim
  // (QualityOptions::aim_mean_edge_ratio), up to kRelaxSearchSweeps more whose moves are searched
  // in the tangent plane (searched_step), judged and applied as above; a mesh they leave within
  // the aim is not touched by them.
  void relax() {
    relax_sweeps(kRelaxSweeps, false);
    if (o_.aim_mean_edge_ratio > 0 && mean_edge_ratio() > o_.aim_mean_edge_ratio)
      relax_sweeps(kRelaxSearchSweeps, true);
  }
  double mean_edge_ratio() const {
    double sum = 0;
    std::size_t n = 0;
    for (int t = 0; t < tri_count(); ++t)
      if (alive_[t]) sum += tri_ratio(m_.triangles[t]), ++n;
    return n ? sum / n : 0;
  }
  // `sweeps` sweeps of the relaxation (see relax), with searched_step's moves where `search`;
  // those stop once the mesh's mean edge ratio is at or under the aim.
  void relax_sweeps(int sweeps, bool search) {
    const double keep_cos = std::cos(kRelaxKeepDegrees * std::numbers::pi / 180);
    // Vertices moved in the previous sweep: a later sweep moves only those, the vertices whose
    // star holds one, and the corners of this sweep's flips (any other would compute the same
    // target and be refused again, but for the rare move refused for crossing a triangle beyond
    // its star that has moved since).
    std::vector<char> moved;
    for (int sweep = 0; sweep < sweeps; ++sweep) {
      if (search && sweep > 0 && mean_edge_ratio() <= o_.aim_mean_edge_ratio) break;
      if (search) ++r_.relax_search_sweeps;
      // First the flips (try_flip's for_ratio): each stretched triangle's edges, longest first.
      flipped_.assign(m_.positions.size(), 0);
      for (int t = 0; t < tri_count(); ++t) {
        poll(static_cast<std::size_t>(t));
        if (!alive_[t] || !(tri_ratio(m_.triangles[t]) > kRelaxRatio)) continue;
        const Tri T = m_.triangles[t];
        int k = 0;
        double longest = 0;
        for (int i = 0; i < 3; ++i) {
          const double l = (P(T[(i + 1) % 3]) - P(T[i])).squaredNorm();
          if (l > longest) longest = l, k = i;
        }
        for (int i = 0; i < 3; ++i)
          if (try_flip(t, (k + i) % 3, true)) break;
      }
      std::vector<char> mark(m_.positions.size(), 0);
      for (int t = 0; t < tri_count(); ++t) {
        if (!alive_[t] || !(tri_ratio(m_.triangles[t]) > kRelaxRatio)) continue;
        const Tri& x = m_.triangles[t];
        for (int v : x) mark[v] = 1;
      }
      if (sweep > 0)
        for (int v = 0; v < static_cast<int>(mark.size()); ++v) {
          if (!mark[v] || moved[v] || flipped_[v]) continue;
          bool star_moved = false;
          for (int u : vt_[v])
            for (int w : m_.triangles[u]) star_moved = star_moved || moved[w];
          mark[v] = star_moved;
        }
      moved.assign(m_.positions.size(), 0);
      // The marked vertices off creases (on_crease may evaluate and caches: one thread), then
      // their targets, each judged on its own (read only: on several threads, one slot each).
      std::vector<int> eligible;
      for (int v = 0; v < static_cast<int>(mark.size()); ++v)
        if (mark[v] && vt_[v].size() >= 3 && !on_crease(v)) eligible.push_back(v);
      std::vector<Vec3> target(eligible.size());
      std::vector<double> reach(eligible.size(), 0);
      std::vector<char> moves(eligible.size(), 0);
      detail::parallel_blocks(eligible.size(), kRelaxBlock, workers_, [&](std::size_t begin, std::size_t end, unsigned) {
        poll();
        for (std::size_t i = begin; i < end; ++i) {
          const int v = eligible[i];
          Vec3 step = equilateral_step(v);
          if (!(step.squaredNorm() > 0)) continue;
          // Judged first in the tangent plane, where it costs no evaluation: Newton moves the
          // point by far less than the step (the step squared times the curvature), so a move
          // that gains nothing there gains nothing on the surface.
          if (search) {
            step = searched_step(v, step, keep_cos);
            if (!(step.squaredNorm() > 0)) continue;
          } else if (!(star_shape(v, P(v) + step).mean_ratio < star_shape(v).mean_ratio * (1 - kRelaxMinGain))) {
            continue;
          }
          double shortest = std::numeric_limits<double>::infinity();
          for (int u : vt_[v])
            for (int w : m_.triangles[u])
              if (w != v) shortest = std::min(shortest, (P(w) - P(v)).norm());
          target[i] = P(v) + step;
          reach[i] = shortest;
          moves[i] = 1;
        }
      });
      std::vector<int> moving;
      std::vector<Vec3> starts;
      std::vector<ProjectionOptions> opts;
      for (std::size_t i = 0; i < eligible.size(); ++i) {
        if (!moves[i]) continue;
        ProjectionOptions po;
        po.tolerance = 1e-10 * o_.diagonal;
        po.max_step = reach[i];
        po.max_travel = reach[i];
        moving.push_back(eligible[i]);
        starts.push_back(target[i]);
        opts.push_back(po);
      }
      if (moving.empty()) break;
      // Each projection is independent of the others (the same point in any batch): a
      // thread-safe field's are shared among threads in blocks; any other field's go in one
      // batch (one call per Newton round: a Python function is called once per batch).
      std::vector<ProjectionResult> landed(moving.size());
      const bool shared = field_.thread_safe();
      detail::parallel_blocks(moving.size(), shared ? kRelaxBlock : moving.size(), shared ? workers_ : 1u,
                              [&](std::size_t begin, std::size_t end, unsigned) {
                                poll();
                                const std::vector<ProjectionResult> part = project_to_surface(
                                    field_, std::span(starts).subspan(begin, end - begin),
                                    std::span(opts).subspan(begin, end - begin));
                                std::copy(part.begin(), part.end(), landed.begin() + static_cast<std::ptrdiff_t>(begin));
                              });
      // The moves are judged in order, each at the positions the moves before it left, and
      // applied. On several threads the intersection test (star_intersects, the costliest
      // check) is left out of that loop: after every chunk of candidates judged, the moves they
      // made are tested on all cores, each at the positions of its turn (intersecting_turn). The
      // first refused there (1 in about 1250 moves kept over the 343-run sweep of kRelaxSweeps, the runs
      // made again included) and the moves after it are taken back, and the judging goes on
      // after it. So the moves kept are those of the loop with the test inside, which one thread
      // runs without a tolerance. With a tolerance, judging a move evaluates the field (its
      // star's distance estimate), and the moves judged twice after a refusal evaluate again:
      // there one thread takes the chunks too, so that the evaluation counts are the same on any
      // number of threads (the mesh is the same either way). That costs one thread about 2 % of
      // its instructions (tanglecube at 1e-3: 3.64G against 3.57G, callgrind), and two threads
      // save about 7 % of the time there.
      bool changed = false;
      // Candidate i's move, applied, or nothing when it is refused.
      const auto judge = [&](std::size_t i, bool test_intersections) -> std::optional<Turn> {
        if (!landed[i].ok() || !(landed[i].gradient.squaredNorm() > 0)) return std::nullopt;
        const int v = moving[i];
        const Vec3 ng = landed[i].gradient.normalized();
        const Vec3& target = landed[i].point;
        if (!(ng.dot(m_.normals[v]) > kMoveNormalCos)) return std::nullopt;
        const StarShape before = star_shape(v);
        const double floor = facing_floor(vt_[v]);
        const Vec3 saved = P(v), saved_n = m_.normals[v];
        m_.positions[v] = target;
        m_.normals[v] = ng;
        const StarShape after = star_shape(v);
        bool ok = after.mean_ratio < before.mean_ratio * (1 - kRelaxMinGain) &&
                  after.max_cos <= std::max(before.max_cos, keep_cos);
        for (int u : vt_[v]) ok = ok && faces_surface(m_.triangles[u], floor);
        const double new_dist = ok ? worst_star_distance(v) : 0;
        m_.positions[v] = saved;
        m_.normals[v] = saved_n;
        if (!(ok && may_replace(new_dist, vt_[v]))) return std::nullopt;
        if (test_intersections && star_intersects(v, target)) {
          ++r_.relax_crossings;
          return std::nullopt;
        }
        m_.positions[v] = target;
        m_.normals[v] = ng;
        // Unlike try_move, the crease test is not asked again (3 evaluations): v was not on a
        // crease, and Newton lands it on one piece's zero set, on a crease only by accident.
        moved[v] = 1;
        return Turn{v, saved, saved_n, i};
      };
      const auto keep = [&](const Turn& turn) {
        for (int u : vt_[turn.v]) {
          hash_box(u);
          touch(u);
        }
        ++r_.relaxed;
        if (search) ++r_.relax_searched;
        changed = true;
      };
      if (workers_ <= 1 && !(o_.tolerance > 0)) {
        for (std::size_t i = 0; i < moving.size(); ++i) {
          poll(i);
          if (const std::optional<Turn> turn = judge(i, true)) keep(*turn);
        }
      } else {
        TurnScratch scratch(m_.positions.size(), workers_);
        std::vector<Turn> turns;
        std::size_t chunk = kRelaxBlock;
        for (std::size_t i = 0; i < moving.size();) {
          poll();
          turns.clear();
          for (const std::size_t stop = std::min(moving.size(), i + chunk); i < stop; ++i)
            if (const std::optional<Turn> turn = judge(i, false)) turns.push_back(*turn);
          const std::size_t refused = intersecting_turn(turns, scratch);
          for (std::size_t k = turns.size(); k-- > refused;) {
            m_.positions[turns[k].v] = turns[k].from;
            m_.normals[turns[k].v] = turns[k].from_normal;
            moved[turns[k].v] = 0;
          }
          for (std::size_t k = 0; k < refused; ++k) keep(turns[k]);
          if (refused < turns.size()) {
            ++r_.relax_crossings;
            i = turns[refused].candidate + 1;
          }
          // Where moves are refused, shorter chunks, down to one candidate: the moves judged
          // again after a refusal stay a bounded share of the work (a blob field at 5e-2 with a
          // refusal every few moves: 790 chunks of 4096 made the run three times as long).
          chunk = refused < turns.size() ? std::max<std::size_t>(1, chunk / 4) : std::min(kRelaxChunk, 2 * chunk);
        }
      }
      if (!changed) break;
    }
  }

  static std::vector<int> merged(std::vector<int> a, const std::vector<int>& b) {
    a.insert(a.end(), b.begin(), b.end());
    std::sort(a.begin(), a.end());
    a.erase(std::unique(a.begin(), a.end()), a.end());
    return a;
  }
  void touch(int t) {
    touched_.push_back(t);
    since_check_.push_back(t);
  }

  double last_resort_edge() const { return o_.last_resort_min_edge > 0 ? o_.last_resort_min_edge : o_.min_edge; }
  // A triangle measured farther from the surface than the tolerance: by how much, and the
  // surface point its farthest sample's Newton path landed on.
  struct Beyond {
    int t;
    Tri T;
    double d;
    ProjectionResult worst;
  };
  // The triangles of `work` whose estimate does not clear them, measured densely (each at most
  // once per call); those beyond the tolerance there.
  std::vector<Beyond> measure_densely(const std::vector<int>& work) {
    std::vector<Beyond> out;
    for (int t : work) {
      if (!alive_[t]) continue;
      const Tri& T = m_.triangles[t];
      const double estimate = estimate_distance(T);
      if (!(estimate > kToleranceMargin * o_.tolerance)) continue;
      ++r_.measured_densely;
      ProjectionResult worst;
      const double d = sampled_distance(T, estimate, &worst);
      if (d > o_.tolerance) out.push_back({t, T, d, worst});
    }
    return out;
  }
  // The last resort for a triangle the refinement left beyond the tolerance (a ridge or fillet
  // narrower than the edges around it, whose corners' normals are too far apart for a midpoint
  // split to face like the surface; or edges under twice min_edge on a bend just above what
  // min_edge can follow): any of its edges halved, down to halves of
  // QualityOptions::last_resort_min_edge, else a new vertex inside it at the surface point nearest
  // its farthest sample, which splits it in three. The same checks as every split (the new
  // triangles face like the surface, intersect nothing); the angles are repaired after. Returns
  // whether it split.
  bool last_resort(const Beyond& b) {
    if (!alive_[b.t] || m_.triangles[b.t] != b.T) return true;  // changed since it was measured
    const std::array<int, 3> order = edges_longest_first(b.T).second;
    for (const int k : order)
      if (try_split(b.t, b.T[k], b.T[(k + 1) % 3], false, last_resort_edge())) {
        ++r_.last_resorts;
        return true;
      }
    if (try_insert_inside(b.t, b.worst)) {
      ++r_.last_resorts;
      return true;
    }
    return false;
  }
  // Splits triangle t in three at the surface point a projection landed on.
  bool try_insert_inside(int t, const ProjectionResult& landed) {
    const Tri T = m_.triangles[t];
    const Vec3& x = landed.point;
    const Vec3& g = landed.gradient;  // at x
    if (!landed.ok() || !(g.squaredNorm() > 0)) return false;
    const Vec3 ng = g.normalized();
    for (int v : T)
      if (!((x - P(v)).norm() >= last_resort_edge())) return false;
    const int m = static_cast<int>(m_.positions.size());
    add_vertex(x, ng);
    const std::vector<Tri> added{{T[0], T[1], m}, {T[1], T[2], m}, {T[2], T[0], m}};
    const double floor = facing_floor({t});
    bool ok = true;
    for (const Tri& s : added) ok = ok && faces_surface(s, floor);
    if (ok) ok = !intersects(added, {t});
    if (!ok) {
      drop_last_vertex();
      return false;
    }
    const int t2 = tri_count(), t3 = t2 + 1;
    m_.triangles[t] = added[0];
    m_.triangles.push_back(added[1]);
    m_.triangles.push_back(added[2]);
    alive_.push_back(1);
    alive_.push_back(1);
    stamp_.push_back(0);
    stamp_.push_back(0);
    // T[0]: t, t3 (was t); T[1]: t, t2; T[2]: t2, t3; m: all three.
    vt_[T[0]].push_back(t3);
    vt_[T[2]].push_back(t2);
    vt_[T[2]].push_back(t3);
    erase_value(vt_[T[2]], t);
    vt_[T[1]].push_back(t2);
    vt_[m] = {t, t2, t3};
    for (int s : {t, t2, t3}) {
      hash_box(s);
      touch(s);
    }
    ++r_.splits;
    return true;
  }

  // Splits the triangles of `work` beyond the bound, and then those the splits made, for at
  // most kRefineRounds rounds. Returns the triangles that may still be beyond it (a split that
  // failed its checks, or rounds run out).
  std::vector<int> refine(std::vector<int> work) {
    // A triangle whose longest edge cannot be split may have its other edges split when its
    // estimate is within this many times the bound: a ridge a little narrower than the edges
    // is resolved by a few such splits (the bunny VIS-2000 at 1.035e-3: 4 triangles up to 1.45
    // eps, none after), but a crease the sizing does not see never is, and splitting across it
    // without bound made the cube meshed as smooth at 5e-4 (creases ignored) take 162 s for
    // 11,780 triangles with a smallest angle of 0.06 degrees, against 0.3 s and 566 triangles.
    constexpr double kFallbackShare = 4;
    const double bound = kToleranceMargin * o_.tolerance;
    std::vector<int> left;
    for (int round = 0; round < kRefineRounds && !work.empty(); ++round) {
      touched_.clear();
      // A thread-safe field's estimates are made first, on all cores: each edge's midpoint once
      // (two triangles share it), then each triangle into its slot (the same on any number of
      // threads; a triangle a split changes before its turn is measured again there).
      if (field_.thread_safe()) {
        if (estimates_.size() < m_.triangles.size()) estimates_.resize(m_.triangles.size());
        std::vector<int> todo;
        EdgeTable table;
        for (std::size_t w = 0; w < work.size(); ++w) {
          poll(w);
          const int t = work[w];
          if (alive_[t] && !remembered(t)) {
            todo.push_back(t);
            const Tri& T = m_.triangles[t];
            for (int i = 0; i < 3; ++i) table.keys.push_back(edge_key(T[i], T[(i + 1) % 3]));
          }
        }
        poll();
        std::sort(table.keys.begin(), table.keys.end());
        table.keys.erase(std::unique(table.keys.begin(), table.keys.end()), table.keys.end());
        table.d.resize(table.keys.size());
        detail::parallel_blocks(table.keys.size(), kRelaxBlock, workers_, [&](std::size_t begin, std::size_t end, unsigned) {
          poll();
          for (std::size_t i = begin; i < end; ++i) {
            const int x = static_cast<int>(table.keys[i] >> 32), y = static_cast<int>(table.keys[i] & 0xffffffffu);
            table.d[i] = signed_distance(0.5 * (P(x) + P(y)));
          }
        });
        detail::parallel_blocks(todo.size(), kRelaxBlock, workers_, [&](std::size_t begin, std::size_t end, unsigned) {
          poll();
          MidpointMemo memo;
          memo.table = &table;
          for (std::size_t i = begin; i < end; ++i) estimate_distance(m_.triangles[todo[i]], todo[i], &memo);
        });
      }
      for (std::size_t i = 0; i < work.size(); ++i) {
        poll(i);
        const int t = work[i];
        if (!alive_[t]) continue;
        const Tri T = m_.triangles[t];
        const double estimate = estimate_distance(T, t);
        if (!(estimate > bound)) continue;
        if (o_.measure_near_bound && estimate <= o_.tolerance) {
          ++r_.refine_measured;
          if (sampled_distance(T, estimate) <= kDenseClearShare * o_.tolerance) {
            ++r_.refine_cleared;
            continue;
          }
        }
        // Halve the longest edge; after a split the edge is gone, so a neighbour visited later
        // in this round sees the new triangles. When the longest edge cannot be split (its
        // midpoint's normal or the new triangles would fold: a ridge narrower than the edges, as
        // on the bunny VIS-2000 where normals 110 degrees apart share a triangle), the next
        // longest is tried, then the shortest, on a triangle near the bound (kFallbackShare).
        const std::array<int, 3> order = edges_longest_first(T).second;
        bool split = false;
        for (const int k : order)
          if ((k == order[0] || estimate <= kFallbackShare * bound) && (split = try_split(t, T[k], T[(k + 1) % 3]))) break;
        if (!split) left.push_back(t);
      }
      std::sort(touched_.begin(), touched_.end());
      touched_.erase(std::unique(touched_.begin(), touched_.end()), touched_.end());
      work = touched_;
    }
    return merged(left, work);
  }

  // Drops removed triangles and vertices, renumbering what is left in its order.
  void compact() {
    if (dead_vertex_.empty()) return;
    std::vector<int> remap(m_.positions.size(), 0);
    for (int v : dead_vertex_) remap[v] = -1;
    Mesh out;
    int next = 0;
    for (std::size_t v = 0; v < m_.positions.size(); ++v) {
      if (remap[v] < 0) continue;
      remap[v] = next++;
      out.positions.push_back(m_.positions[v]);
      out.normals.push_back(m_.normals[v]);
    }
    for (int t = 0; t < tri_count(); ++t) {
      if (!alive_[t]) continue;
      const Tri& x = m_.triangles[t];
      out.triangles.push_back({remap[x[0]], remap[x[1]], remap[x[2]]});
    }
    m_.positions = std::move(out.positions);
    m_.normals = std::move(out.normals);
    m_.triangles = std::move(out.triangles);
  }

  const Field& field_;
  const bool smooth_;  // Field::smooth
  Mesh& m_;
  QualityOptions o_;
  unsigned workers_;  // threads of the parallel passes (QualityOptions::threads)
  std::vector<std::vector<int>> vt_;
  std::vector<signed char> crease_;
  std::vector<char> alive_;
  std::vector<std::uint32_t> stamp_;
  std::uint32_t stamp_id_ = 0;
  SpatialHash hash_;
  // The corners of the relaxation's flips in its current sweep.
  std::vector<char> flipped_;
  // star_intersects' triangles, kept from call to call.
  std::vector<StarTriangle> star_buffer_;
  // estimate_distance's memo, by triangle slot (see there).
  mutable std::vector<EstimateEntry> estimates_;
  // The box each triangle is stored in the hash with (hash_box).
  std::vector<Vec3> hashed_lo_, hashed_hi_;
  // Triangles changed in the current round, and since the last tolerance check.
  std::vector<int> touched_, since_check_, dead_vertex_;
  QualityReport r_;
};

}  // namespace

QualityReport improve_mesh(const Field& field, Mesh& mesh, const QualityOptions& options) {
  if (mesh.normals.size() != mesh.positions.size())
    throw std::logic_error("improve_mesh: the mesh needs one normal per vertex");
  if (mesh.triangles.empty()) return {};
  Improver improver(field, mesh, options);
  return improver.run();
}

}  // namespace cdp::adaptive
