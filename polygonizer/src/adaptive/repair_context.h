// The context the repair's algorithms share (quality.h): the mesh being repaired, its
// adjacency, its hash of triangle boxes, its distance estimates and crease vertices, the field,
// and the mesh operations every algorithm is made of (flip, move, collapse, split), each tested
// before it is applied. The algorithms are free functions on it, one header each:
//   repair_angles.h       the angle repair of triangles under improve_below
//   repair_relax.h        the relaxation of stretched triangles (mean edge ratio)
//   repair_refine.h       the tolerance's refinement (edge splits)
//   repair_last_resort.h  the dense measurement and the last resort for what is still beyond it
// and quality.cpp's improve_mesh runs them in order. The context's own definitions:
//   repair_context.cpp     geometry, distance estimates, crease vertices, adjacency, the
//                          intersection tests against the triangles nearby, compaction
//   repair_operations.cpp  the mesh operations
// The crease probe (crease_probe.h) and the hash (spatial_hash.h) are the tracker's too.
// Private to src/adaptive.
#pragma once

#include "quality.h"

#include "crease_probe.h"
#include "spatial_hash.h"
#include "../background_release.h"
#include "../polled_growth.h"
#include "../parallel.h"

#include <cdp/core/errors.h>
#include <cdp/core/newton_projection.h>
#include <cdp/core/triangle_intersection.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <numbers>
#include <numeric>
#include <optional>
#include <span>
#include <unordered_map>
#include <vector>

namespace cdp::adaptive::repair {

// An operation must raise the smallest angle it touches by at least a quarter of a degree:
// operations cannot undo each other on floating-point ties, and a vertex cannot creep by tiny
// moves round after round while the stronger operations further down the list wait.
inline constexpr double kMinGain = 0.25 * 3.14159265358979323846 / 180;
// The crease test is the tracker's (crease_probe.h).
// A vertex whose stored normal (the tracker's mean of both sides on a crease) is this far from
// its own gradient lies on a crease too.
inline constexpr double kCreaseNormalCosine = 0.985;
// A new triangle must face like the surface at its corners: its normal within about 78 degrees
// of each corner's surface normal. Far looser than the surface's own turn over one edge (under
// 60 degrees at factor 1, where an edge is one radius long), so it only refuses folds.
inline constexpr double kFaceNormalCos = 0.2;
// Where a crease vertex is among a flip's four corners, the two triangles must be this close to
// one plane (about 10 degrees), so that no flip cuts across a crease.
inline constexpr double kCreaseFlatCos = 0.985;
// A moved vertex keeps its surface normal within about 30 degrees: Newton must land it on the
// same sheet and the same side of any crease nearby.
inline constexpr double kMoveNormalCos = 0.866;
// How far off the arc between an edge's end normals its collapsed midpoint's normal may turn
// (see lands_between): the 30 degrees a moved vertex's normal may turn (kMoveNormalCos = cos 30).
inline constexpr double kArcSlack = 30 * std::numbers::pi / 180;
// Tangential moves tried, as shares of the way to each target (see try_move).
inline constexpr double kMoveShares[] = {1.0, 0.5, 0.25};
// Distance sampling with a tolerance: the largest distance must come out at most this share of
// the tolerance. The estimate interpolates the distances at the edge midpoints quadratically
// and scales it by how far the centroid's measured distance exceeds the interpolation's, which
// captures the sagitta of a curved patch to second order; the 10% margin covers the
// third-order remainder (measured under 4% on the torus and tanglecube at eps = 1e-2).
inline constexpr double kToleranceMargin = 0.9;
// Predicted estimates (RepairContext::predict_): an edge's midpoint is predicted from its ends'
// values, gradients and Hessians (no evaluation at the midpoint) where two predictions exact for
// cubics, the mean of the ends' second-order Taylor expansions (A) and the Hermite cubic through
// the ends' values and slopes (H), agree to within this share of the tolerance. (A + 3H) / 4 is
// exact for quartics, and |A - H| bounded its error on every one-dimensional case tried: 0.7 of
// it where the second derivative jumps between the ends (a C1 seam, max(x, 0)^2), 0.05 for x^8,
// 0.6 for a sine whose ends are 8 radians apart (the repair tests check it against the field on
// the sphere and across a seam). A triangle's centroid is predicted from its corners where its
// three midpoints were (predicted_centroid), under the same share. 4/3 of the midpoints' largest
// bound (the most a midpoint moves the quadratic through them) and the centroid's are added to
// the triangle's estimate: at most about 0.1 of the tolerance with this share, 0.01 on the unit
// sphere's 1,280 triangles at 1e-2. A seam, a crease or a feature between the corners disagrees
// far more, and is measured. A share of 0.1 saved a fifth more evaluations in the same time
// (bunny VIS-800 at 3e-4: 43k against 52k values and gradients), but its bounds, raising the
// estimates near the bound, changed what the repair could do on the Igea VIS-4004 at 3e-3
// (smallest angle 27.4 degrees, 30.1 measured or with this share).
inline constexpr double kPredictShare = 0.03;
// A flip of the relaxation that brings the valences nearer 6 may raise the two triangles'
// summed edge ratio by up to this share, which the moves that follow more than make up for.
// The same three cases and random blobs at tolerance 1e-3: 1.246 / 1.255 / 1.263 / 1.203; with
// 1.0 (only flips that lower it) 1.253 / 1.258 / 1.267 / 1.205; without the flips 1.262 /
// 1.263 / 1.274 / 1.236 (the tolerance's edge splits leave vertices of valence 4 and 8 that no
// move can make equilateral).
inline constexpr double kFlipRatioSlack = 1.1;
// A move must lower its star's mean edge ratio by this share: no creeping by rounding.
inline constexpr double kRelaxMinGain = 1e-3;
// A move may lower its star's smallest angle only while it stays at or above this (the repair's
// bound), so the relaxation never undoes the repair.
inline constexpr double kRelaxKeepDegrees = 30;
// Items per block of the repair's parallel passes (the relaxation's targets and projections,
// the refinement's estimates): enough to outweigh handing a block to a thread (a target costs
// about a microsecond, a projection a few field calls).
inline constexpr std::size_t kRepairBlock = 256;
// hash_box: a triangle's box is stored grown by this share of a hash cell (about a fifth of an
// edge), so that moving a corner by less than that stores it again nowhere.
inline constexpr double kHashSlack = 0.1;

inline double angle_at(const Vec3& p, const Vec3& q, const Vec3& r) {
  const Vec3 u = q - p, v = r - p;
  return std::atan2(u.cross(v).norm(), u.dot(v));
}

// A triangle's smallest angle faces its shortest edge: the arc tangent is taken there, and at a
// corner whose opposite edge's squared length is within a share kAngleTie of the shortest's (where
// the two angles differ by rounding, either may come out smaller), so the result is the least of
// the three arc tangents but where a sliver's cross product is lost to rounding. One arc tangent
// for most triangles instead of three: the repair asks for a star's angles at every position it
// tries.
inline constexpr double kAngleTie = 1e-9;
inline double min_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  const std::array<double, 3> l2{(b - c).squaredNorm(), (c - a).squaredNorm(), (a - b).squaredNorm()};
  if (!std::isfinite(l2[0] + l2[1] + l2[2]))  // as the three arc tangents have it
    return std::min({angle_at(a, b, c), angle_at(b, c, a), angle_at(c, a, b)});
  const double shortest = std::min({l2[0], l2[1], l2[2]});
  const std::array<const Vec3*, 3> p{&a, &b, &c};
  double out = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k)
    if (l2[k] <= shortest * (1 + kAngleTie)) out = std::min(out, angle_at(*p[k], *p[(k + 1) % 3], *p[(k + 2) % 3]));
  return out;
}

using Tri = std::array<int, 3>;

// All public: the algorithms (the headers above) are free functions that read and change it.
// One thread changes it; the passes that run on several threads only read it (see
// star_hits).
class RepairContext {
 public:
  RepairContext(const Field& field, Mesh& mesh, const QualityOptions& o)
      : field_(field), smooth_(field.smooth()), mesh_(mesh), options_(o), workers_(detail::worker_count(o.threads)),
        // Made a block at a time between polls (polled_growth.h): 10^6 empty stars are 24 MB of
        // fresh pages.
        vt_(detail::polled_vector<std::vector<int>>(mesh.positions.size(),
                                                    [&o] { o.cancel.check("adaptive: repair"); })),
        crease_(mesh.positions.size(), -1),
        alive_(mesh.triangles.size(), 1), hash_(cell_size(mesh)) {
    // Nothing reads its visits, and intersecting_turn queries it on several threads at once.
    hash_.set_counting(false);
    hash_.set_cancel(options_.cancel);
    using Predict = QualityOptions::Predict;
    predict_ = o.tolerance > 0 && field.smooth() && !field.derivative_step() &&
               (o.predict_estimates == Predict::Always ||
                (o.predict_estimates == Predict::CostlyFields && (field.predicts_from_hessians() || field.costly_calls())));
    try {
      // Room for every triangle's box at once (no page is touched before its box is stored):
      // grown a triangle at a time, the two arrays doubled together, 0.1-0.2 s in one call at
      // 2*10^6 triangles.
      hashed_lo_.reserve(mesh_.triangles.size());
      hashed_hi_.reserve(mesh_.triangles.size());
      reserve_stars();
      for (int t = 0; t < static_cast<int>(mesh_.triangles.size()); ++t) {
        poll(static_cast<std::size_t>(t));
        const Tri& x = mesh_.triangles[t];
        for (int v : x) vt_[v].push_back(t);
        // hash_box's box, the hash filled at once below.
        const auto [lo, hi] = tri_box(x);
        const auto [glo, ghi] = grown_box(lo, hi);
        hashed_lo_.push_back(glo);
        hashed_hi_.push_back(ghi);
      }
      hash_.insert_boxes(hashed_lo_, hashed_hi_);
    } catch (...) {
      release_if_cancelled();  // a constructor that throws runs no destructor
      throw;
    }
    if (o.improve_below > 0 && o.improve_below < std::numbers::pi / 2) below_tan_ = std::tan(o.improve_below);
    stamp_.assign(mesh_.triangles.size(), 0);
    renumbered_.resize(mesh_.positions.size());
    std::iota(renumbered_.begin(), renumbered_.end(), 0);
    if (options_.keep_boundary) mark_boundary();
  }
  ~RepairContext() { release_if_cancelled(); }

  // Each star's array allocated once, at the capacity its push_backs would reach (the next power
  // of two of the vertex's triangles): pushed one at a time, a star of six was allocated four
  // times, 4*10^6 allocations at 2*10^6 triangles.
  void reserve_stars() {
    std::vector<unsigned> valence = polled_vector<unsigned>(vt_.size(), 0);
    for (std::size_t t = 0; t < mesh_.triangles.size(); ++t) {
      poll(t);
      for (int v : mesh_.triangles[t]) ++valence[static_cast<std::size_t>(v)];
    }
    for (std::size_t v = 0; v < vt_.size(); ++v) {
      poll(v);
      if (valence[v] > 0) vt_[v].reserve(std::bit_ceil(valence[v]));
    }
  }
  RepairContext(const RepairContext&) = delete;
  RepairContext& operator=(const RepairContext&) = delete;

  // The cancel poll of the loops below: an atomic load every kPollEvery items.
  static constexpr std::size_t kPollEvery = 256;
  void poll(std::size_t i = 0) const {
    if (i % kPollEvery == 0) options_.cancel.check("adaptive: repair");
  }
  // n copies of `value`, filled a block at a time with a poll before each (polled_growth.h).
  template <class T>
  std::vector<T> polled_vector(std::size_t n, const T& value = T()) const {
    return detail::polled_vector(n, [this] { poll(); }, value);
  }

  // ---- geometry
  static double cell_size(const Mesh& m);
  int tri_count() const { return static_cast<int>(mesh_.triangles.size()); }
  const Vec3& P(int v) const { return mesh_.positions[v]; }
  // A triangle's edge lengths (edge k: T[k]-T[k+1]) and its edges longest first (ties by index).
  std::pair<std::array<double, 3>, std::array<int, 3>> edges_longest_first(const Tri& T) const {
    const std::array<double, 3> len{(P(T[1]) - P(T[0])).norm(), (P(T[2]) - P(T[1])).norm(), (P(T[0]) - P(T[2])).norm()};
    std::array<int, 3> order{0, 1, 2};
    std::sort(order.begin(), order.end(), [&](int x, int y) { return len[x] != len[y] ? len[x] > len[y] : x < y; });
    return {len, order};
  }
  double tri_min_angle(const Tri& t) const { return min_angle(P(t[0]), P(t[1]), P(t[2])); }
  // Whether t's smallest angle is under options_.improve_below, as tri_min_angle has it. The
  // arc tangent is taken only where the angle at the corner facing the shortest edge is not
  // clearly above the bound: its tangent |u x v| / u . v over the bound's by more than
  // kBelowMargin, far beyond the rounding of the arc tangents and of a corner that ties with it
  // (kAngleTie). The repair's scans of every triangle took an arc tangent each: 2.5% of the
  // torus at tolerance 1e-4.
  bool tri_below(const Tri& t) const {
    constexpr double kBelowMargin = 1e-6;
    const Vec3 &a = P(t[0]), &b = P(t[1]), &c = P(t[2]);
    const std::array<double, 3> l2{(b - c).squaredNorm(), (c - a).squaredNorm(), (a - b).squaredNorm()};
    const int k = l2[0] <= l2[1] ? (l2[0] <= l2[2] ? 0 : 2) : (l2[1] <= l2[2] ? 1 : 2);
    const std::array<const Vec3*, 3> p{&a, &b, &c};
    const Vec3 u = *p[(k + 1) % 3] - *p[k], v = *p[(k + 2) % 3] - *p[k];
    const double sine = u.cross(v).norm(), cosine = u.dot(v);
    if (below_tan_ > 0 && cosine > 0 && std::isfinite(sine) && sine > below_tan_ * cosine * (1 + kBelowMargin))
      return false;
    return tri_min_angle(t) < options_.improve_below;
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
    for (int v : t) worst = std::min(worst, n.dot(mesh_.normals[v]));
    return worst;
  }
  // What new triangles must exceed: kFaceNormalCos, or, where the triangles they replace already
  // faced the surface worse (a fold the fronts left on a sharply curved spot of a coarse mesh),
  // the worst of those: an operation never makes the facing worse, and may repair it.
  double facing_floor(const std::vector<int>& replaced) const {
    double floor = kFaceNormalCos;
    for (int t : replaced) floor = std::min(floor, facing(mesh_.triangles[t]));
    return floor;
  }
  bool faces_surface(const Tri& t, double floor) const { return facing(t) > floor; }
  // Signed first-order distance F / |grad F| of p to the surface (as prefetch_distances found
  // it, where it did).
  double signed_distance(const Vec3& p) const {
    if (!known_distances_.empty())
      if (const auto it = known_distances_.find(point_bits(p)); it != known_distances_.end()) return it->second;
    Vec3 g;
    const double f = field_.value_gradient(p, g);
    return signed_distance(f, g);
  }
  static double signed_distance(double f, const Vec3& g) {
    const double l = g.norm();
    return l > 0 ? f / l : std::numeric_limits<double>::infinity();
  }
  // signed_distance at every point of `ps`, the same numbers, in batched calls of the field of
  // at most kDistanceBatch points (a Python function's calls cost more than its points).
  void signed_distances(const std::vector<Vec3>& ps, std::vector<double>& out) const;
  // For a field whose calls cost more than their points (Field::costly_calls): signed_distance at
  // `points` asked for in batched calls beforehand and kept until forget_distances, so that the
  // judging of moves one after another, each measuring its star at its target, asks for none
  // where the prediction of its points held (the same numbers where the field's batched calls give
  // what its single ones do, as BatchProjector asks too). The random blobs as a numpy function at tolerance 1e-3 made 188,478 calls of
  // one point each in the repair, 11 of its 13 seconds.
  void prefetch_distances(const std::vector<Vec3>& points);
  void forget_distances() { known_distances_.clear(); }
  using PointBits = std::array<std::uint64_t, 3>;
  static PointBits point_bits(const Vec3& p) {
    return {std::bit_cast<std::uint64_t>(p[0]), std::bit_cast<std::uint64_t>(p[1]), std::bit_cast<std::uint64_t>(p[2])};
  }
  struct PointBitsHash {
    std::size_t operator()(const PointBits& b) const {
      std::uint64_t h = b[0] * 0x9e3779b97f4a7c15ull;
      h = (h ^ (h >> 29) ^ b[1]) * 0xbf58476d1ce4e5b9ull;
      h = (h ^ (h >> 31) ^ b[2]) * 0x94d049bb133111ebull;
      return static_cast<std::size_t>(h ^ (h >> 32));
    }
  };
  // Points per batch of signed_distances: with a Python field's central differences, seven points
  // each, its arrays stay near 10 MB as probe_creases' do.
  static constexpr std::size_t kDistanceBatch = 32768;
  // The largest distance between triangle t and the surface, estimated from the edge midpoints
  // and the centroid (see kToleranceMargin).
  // `memo` (optional) keeps the edge midpoints' distances of the triangles it has seen at the
  // current positions: the triangles of a star share their edges to the centre.
  // `table` (optional, read only): edges measured beforehand at the current positions.
  // A midpoint's signed distance d, and u: where predicted (kPredictShare), the bound of its
  // error; -1 where measured.
  struct Mid {
    double d = 0;
    double u = -1;
  };
  // Edges, each once, in the order first added, with a value each (`d`, filled by the caller in
  // that order), found by their lower vertex's chain: a star's few edges, where a sorted array
  // of them cost a sort (n log n) and a binary search a lookup (the torus at tolerance 1e-4 adds
  // half a million edges a pass of the refinement: 5% of its run).
  class EdgeTable {
   public:
    // Adds edge (x, y) unless there, and returns its index.
    std::size_t add(int x, int y) {
      const auto [lo, hi] = std::minmax(x, y);
      if (const std::optional<std::size_t> i = find(lo, hi)) return *i;
      if (static_cast<std::size_t>(lo) >= first_.size()) first_.resize(static_cast<std::size_t>(lo) + 1, -1);
      next_.push_back(first_[static_cast<std::size_t>(lo)]);
      first_[static_cast<std::size_t>(lo)] = static_cast<std::int64_t>(ends_.size());
      ends_.push_back({lo, hi});
      return ends_.size() - 1;
    }
    std::optional<std::size_t> find(int x, int y) const {
      const auto [lo, hi] = std::minmax(x, y);
      if (lo < 0 || static_cast<std::size_t>(lo) >= first_.size()) return std::nullopt;
      for (std::int64_t e = first_[static_cast<std::size_t>(lo)]; e >= 0; e = next_[static_cast<std::size_t>(e)])
        if (ends_[static_cast<std::size_t>(e)].second == hi) return static_cast<std::size_t>(e);
      return std::nullopt;
    }
    std::size_t size() const { return ends_.size(); }
    // Edge i's ends, the lower first.
    std::pair<int, int> ends(std::size_t i) const { return ends_[i]; }
    std::vector<Mid> d;

   private:
    std::vector<std::pair<int, int>> ends_;
    std::vector<std::int64_t> first_, next_;  // by lower vertex, by edge: the chains, -1 ending them
  };
  struct MidpointMemo {
    std::vector<std::pair<std::pair<int, int>, Mid>> known;
    const EdgeTable* table = nullptr;
  };
  Mid midpoint_distance(int x, int y, MidpointMemo* memo) const;
  // The midpoint of edge x y, predicted where the prediction is trusted, else measured.
  Mid midpoint_sample(int x, int y) const;
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
    std::array<Mid, 3> mid;  // edges t[0] t[1], t[1] t[2], t[2] t[0]
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
        kept_corners(estimates_[static_cast<std::size_t>(slot)], mesh_.triangles[static_cast<std::size_t>(slot)]);
    return kept[0] && kept[1] && kept[2];
  }
  // `centroid` (optional): the centroid's sample, made beforehand as estimate_from would.
  double estimate_distance(const Tri& t, int slot, MidpointMemo* memo = nullptr, const Mid* centroid = nullptr) const;
  double estimate_distance(const Tri& t, MidpointMemo* memo = nullptr) const {
    return estimate_from(t, {midpoint_distance(t[0], t[1], memo), midpoint_distance(t[1], t[2], memo),
                             midpoint_distance(t[2], t[0], memo)});
  }
  // ... from the midpoints (edges t[0] t[1], t[1] t[2], t[2] t[0]) and the centroid: `centroid`
  // where given, else predicted where all three midpoints were and the prediction is trusted,
  // else measured. The predictions' error bounds are added: 4/3 of the midpoints' largest (the
  // most a midpoint moves the quadratic through them) and the centroid's.
  double estimate_from(const Tri& t, const std::array<Mid, 3>& mid, const Mid* centroid = nullptr) const;
  // ... from the midpoints' and the centroid's signed distances: the largest distance of the
  // quadratic through 0 at the corners and these at the midpoints (quadratic_max), scaled so that
  // it meets the centroid's, and of the samples themselves.
  static double estimate_from_samples(double mab, double mbc, double mca, double centroid);
  // The largest |q| over the triangle of the quadratic q in barycentric coordinates that is 0 at
  // the corners and x, y, z at the midpoints of edges ab, bc, ca: q = 4 (x a b + y b c + z c a),
  // in closed form (its edges' and its critical point's).
  static double quadratic_max(double x, double y, double z);

  // Predicted estimates (QualityOptions::predict_estimates): with a tolerance and a smooth field
  // (Field::smooth) whose derivatives are exact (not differences of values), the edge midpoints
  // and centroids come from their corners' value, gradient and Hessian (one evaluation a vertex,
  // kept while it stays put) instead of an evaluation each; see kPredictShare. (The torus at 1e-4, measuring:
  // 8.3 of its 12.3 evaluations a vertex were the estimates', 3.9 of them midpoints.)
  struct Jet {
    Vec3 p = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());  // where: never equal before set
    double f = 0;
    Vec3 g = Vec3::Zero();
    Mat3 h = Mat3::Zero();
  };
  // Vertex v's jet at its current position, evaluated where not kept. The jet it displaces is
  // kept aside once, so that a move tried and taken back evaluates once, not twice.
  // One thread only, but for jets fill_jets made.
  const Jet& jet(int v) const;
  // Evaluates the jets of `corners` not kept: a thread-safe field's on all cores, another's in
  // batches.
  void fill_jets(const std::vector<int>& corners) const;
  // Makes room for every vertex's jet (jet does not grow the array: its references stay).
  void reserve_jets() const {
    if (jets_.size() < mesh_.positions.size()) jets_.resize(mesh_.positions.size() + mesh_.positions.size() / 8);
  }
  std::optional<Mid> predicted_midpoint(int x, int y) const;
  // The centroid of t predicted from its corners, where its midpoints `mid` (edges t[0] t[1],
  // t[1] t[2], t[2] t[0]) all were predicted and the prediction is trusted; else none.
  std::optional<Mid> predicted_centroid(const Tri& t, const std::array<Mid, 3>& mid) const;
  // The largest distance from triangle t to the surface over a barycentric grid of
  // kDenseGrid + 1 points a side (28 points: corners, 5 more on each side, 10 inside), each the
  // length of Newton's path onto the surface (at least the point's true distance); `fallback`
  // where Newton does not land within the triangle's longest edge. `worst_at` (optional): the
  // projection of the farthest sample.
  double sampled_distance(const Tri& t, double fallback, ProjectionResult* worst_at = nullptr) const;
  // With a tolerance: new triangles may be no farther from the surface than the tolerance or
  // (before the refinement has run) than the worst of the triangles they replace.
  bool keeps_tolerance(const std::vector<Tri>& added, const std::vector<int>& removed) const {
    return may_replace(worst_distance(added), removed);
  }
  // The largest estimated distance of triangles `ts` at the current positions; 0 without a
  // tolerance (nothing to keep, no evaluations spent).
  double worst_distance(const std::vector<Tri>& ts) const;
  // ... of v's star at the current positions, remembered by slot (see estimate_distance).
  double worst_star_distance(int v) const;
  // Whether triangles whose worst distance is `worst_new` may replace `removed`, read at the
  // current positions: a move measures its new star at the new place, puts the vertex back, then
  // asks this.
  bool may_replace(double worst_new, const std::vector<int>& removed) const;

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
  bool on_crease(int v);
  // on_crease for every vertex of `vs` not yet probed, their probes in two batched calls of the
  // field (a Python function's calls cost more than its points): the same answers and counts.
  void probe_creases(const std::vector<int>& vs);
  // Vertices per chunk of probe_creases: its batches stay near 10 MB for a Python field.
  static constexpr std::size_t kCreaseProbeBatch = 8192;
  void probe_chunk(const std::vector<int>& vs);  // probe_creases' work on vertices marked 2

  // ---- the boundary kept (QualityOptions::keep_boundary)
  // Marks the ends of every edge with one triangle.
  void mark_boundary();
  // Whether v lies on the boundary (never moved, removed or merged). Vertices the splits add
  // never do.
  bool fixed(int v) const { return static_cast<std::size_t>(v) < fixed_.size() && fixed_[v]; }
  // Boundary vertices whose neighbourhood the caller repairs and measures again (improve_mesh's
  // `measured_again`; every one without QualityOptions::count_near_boundary): marked 2 in fixed_.
  void mark_measured_again(const std::vector<char>& again);
  // Whether triangle T has a corner on such a vertex or next to one, now.
  bool near_measured_again(const Tri& T) const;

  // ---- adjacency
  // The triangle other than t on edge (a, b), or -1.
  int across(int t, int a, int b) const;
  bool has_edge(int a, int b) const;
  std::vector<int> neighbours(int v) const;
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
    const auto [lo, hi] = tri_box(mesh_.triangles[t]);
    hash_cover(t, lo, hi);
  }
  // A triangle's box, and the box hash_cover stores a box [lo, hi] with: grown by kHashSlack of
  // a hash cell.
  std::pair<Vec3, Vec3> tri_box(const Tri& x) const {
    return {P(x[0]).cwiseMin(P(x[1])).cwiseMin(P(x[2])), P(x[0]).cwiseMax(P(x[1])).cwiseMax(P(x[2]))};
  }
  std::pair<Vec3, Vec3> grown_box(const Vec3& lo, const Vec3& hi) const {
    const double slack = kHashSlack * hash_.cell_size();
    return {lo.array() - slack, hi.array() + slack};
  }
  // Makes the box triangle t is stored with in the hash hold [lo, hi] (its box, or one over
  // several positions of its corners, see intersecting_turn).
  void hash_cover(int t, const Vec3& lo, const Vec3& hi);
  // Whether a triangle of `added` intersects a live triangle other than those in `ignored`
  // (which the operation replaces), with the operation's positions `moved` for vertex `mv` (a
  // vertex of no live triangle outside `ignored`, or a new one past the mesh's): as
  // star_intersects does it, the added triangles taken as a star (one query of the hash over
  // their box, the floating-point filters before the exact test). A query and an exact test for
  // each added triangle was a tenth of the random blobs' run at tolerance 1e-3 (callgrind).
  bool intersects(const std::vector<Tri>& added, const std::vector<int>& ignored, int mv = -1,
                  const Vec3& moved = Vec3::Zero());

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
                             const std::array<Vec3, 3>& b, const Tri& ib, double bound);
  // apart_at_shared_vertex for a and b when they share exactly one vertex id (the pairs that
  // apart_by_plane leaves unsure are nearly all such: in star_intersects, a star triangle and a
  // triangle around one of the star's outer corners; none of them intersected on the torus or the
  // bunny, and the exact test was a seventh of star_intersects). The same position under two
  // ids is not shared here; apart_at_shared_vertex cannot find it strictly on both sides of its
  // plane, so it answers false and the exact test decides.
  static bool apart_at_shared_corner(const std::array<Vec3, 3>& a, const Tri& ia, const std::array<Vec3, 3>& b,
                                     const Tri& ib);
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
                         const Tri& x, const std::array<Vec3, 3>& pb);
  // Appends triangle t with corners p to `star`, growing the star's box [lo, hi] and its
  // corners' largest magnitude; false (nothing added) for a degenerate triangle.
  static bool add_star_triangle(std::vector<StarTriangle>& star, const Tri& t, const std::array<Vec3, 3>& p, Vec3& lo,
                                Vec3& hi, double& magnitude) {
    StarTriangle x{t, p, {}, {}, {}};
    if (triangle_is_degenerate(x.p[0], x.p[1], x.p[2])) return false;
    x.lo = x.p[0].cwiseMin(x.p[1]).cwiseMin(x.p[2]);
    x.hi = x.p[0].cwiseMax(x.p[1]).cwiseMax(x.p[2]);
    x.normal = (x.p[1] - x.p[0]).cross(x.p[2] - x.p[0]);
    lo = lo.cwiseMin(x.lo);
    hi = hi.cwiseMax(x.hi);
    magnitude = std::max({magnitude, x.lo.cwiseAbs().maxCoeff(), x.hi.cwiseAbs().maxCoeff()});
    star.push_back(x);
    return true;
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
      const Tri& t = mesh_.triangles[u];
      if (!add_star_triangle(star, t, {pos(t[0]), pos(t[1]), pos(t[2])}, lo, hi, magnitude)) return true;
    }
    // The triangles found are not in v's star, so v is not among their corners.
    return star_meets(star, lo, hi, magnitude, at, stamp, id);
  }
  // Whether a live triangle in the hash, not stamped `id`, meets a triangle of `star` (whose box
  // is [lo, hi] and its corners' largest magnitude `magnitude`), its corners at at(w): one query
  // of the hash over the star's box, each triangle found stamped and tested once.
  template <class At>
  bool star_meets(const std::vector<StarTriangle>& star, const Vec3& lo, const Vec3& hi, double magnitude,
                  const At& at, std::uint32_t* stamp, std::uint32_t id) const {
    const auto hits = [&](int u) {
      if (stamp[u] == id) return false;
      stamp[u] = id;
      // The box u is stored with holds its triangle (hash_box): one apart from the star's
      // rules it out before its corners are read (most of the triangles found).
      if ((hashed_lo_[u].array() > hi.array()).any() || (hashed_hi_[u].array() < lo.array()).any() || !alive_[u])
        return false;
      const Tri& x = mesh_.triangles[u];
      return meets_star(star, lo, hi, magnitude, x, {at(x[0]), at(x[1]), at(x[2])});
    };
    return hash_.any_in(lo, hi, hits);
  }


  // ---- operations. Each returns whether it was applied and pushes the triangles it changed.
  // By default a flip must raise the smallest angle of the pair by kMinGain (the repair); with
  // `for_ratio` (the relaxation) it must bring the four corners' valences nearer 6, or keep them
  // and lower the pair's summed edge ratio by kRelaxMinGain (see below), and keep the pair's
  // smallest angle or at least kRelaxKeepDegrees.
  bool try_flip(int t, int k, bool for_ratio = false);
  // The flip of edge k of triangle t (corners a, b; apexes c of t and d of u across it), where
  // try_flip's tests that need no field pass now.
  struct FlipQuad {
    int u, a, b, c, d;
  };
  std::optional<FlipQuad> flip_candidate(int t, int k, bool for_ratio) const;
  // For a field whose calls cost more than their points (Field::costly_calls): what the
  // relaxation's flips of `triangles`' edges that pass the tests needing no field now
  // (flip_candidate) ask of the field in every case, asked in batched calls: their corners' crease probes
  // (probe_creases; so crease_vertices counts corners no flip reached, where they are on one) and
  // the distances of the six midpoints of each quad, kept in flip_mids_ until
  // forget_flip_samples. A flip moves no vertex, so those distances stay exact through a pass of
  // flips, and try_flip gets the numbers it would have measured one point a call (the band's
  // relaxation after blocks in lockstep made 1,068 calls of one point each on the torus callable
  // at factor 8). With a tolerance, keeps_tolerance's centroids are still measured one at a time.
  void prefetch_flip_samples(const std::vector<int>& triangles);
  void forget_flip_samples() { flip_mids_ = {}; }

  bool try_move(int v);

  // Collapses edge (a, b) of triangle t into one vertex (a keeps its index). Two crease vertices
  // are not merged, unless `apex_onto_crease`: then a is an end of a crease edge of t and b the
  // apex of the cap t, which the crease probes flag only for standing within their reach of the
  // crease, and b goes onto a (repair_angles).
  bool try_collapse(int t, int a, int b, bool apex_onto_crease = false);

  // A new vertex, not yet in any triangle (a split tries it, then keeps or drops it).
  void add_vertex(const Vec3& x, const Vec3& normal) {
    detail::grow_apart(options_.cancel, "adaptive: repair", 1, mesh_.positions, mesh_.normals, vt_, crease_);
    mesh_.positions.push_back(x);
    mesh_.normals.push_back(normal);
    vt_.emplace_back();
    crease_.push_back(-1);
  }
  // Room for n more triangles in the per-triangle arrays, made before an operation adds them.
  void make_room_for_triangles(std::size_t n) {
    detail::grow_apart(options_.cancel, "adaptive: repair", n, mesh_.triangles, alive_, stamp_);
  }
  void drop_last_vertex() {
    mesh_.positions.pop_back();
    mesh_.normals.pop_back();
    vt_.pop_back();
    crease_.pop_back();
  }
  // Splits edge (a, b) at its midpoint moved onto the surface (the tolerance's refinement), or
  // with `repair`, inserts a vertex at the centre of the quad of the two triangles on the edge,
  // moved onto the surface: a cap whose flip would make a worse pair (the far apex sits near
  // one end of the edge) opens into four triangles around it. A repair insertion must raise
  // the smallest angle and keep the new edges no farther from the surface than the quad's.
  // The halves must be at least `shortest` long (0: min_edge).
  bool try_split(int t, int a, int b, bool repair = false, double shortest = 0);

  // A triangle's longest edge over its shortest (the relaxation's measure; infinite for a
  // zero-length edge).
  double tri_ratio(const Tri& t) const {
    const double a = (P(t[1]) - P(t[0])).squaredNorm(), b = (P(t[2]) - P(t[1])).squaredNorm(),
                 c = (P(t[0]) - P(t[2])).squaredNorm();
    const double lo = std::min({a, b, c});
    return lo > 0 ? std::sqrt(std::max({a, b, c}) / lo) : std::numeric_limits<double>::infinity();
  }
  // Where v would make each of its triangles equilateral on its outer edge (the mean of those
  // apexes), moved into v's tangent plane; zero when v has no such triangle.
  Vec3 equilateral_step(int v) const;


  static std::vector<int> merged(std::vector<int> a, const std::vector<int>& b) {
    a.insert(a.end(), b.begin(), b.end());
    std::sort(a.begin(), a.end());
    a.erase(std::unique(a.begin(), a.end()), a.end());
    return a;
  }
  void touch(int t) {
    // Both grow to millions at 2*10^6 triangles: grown apart, polled (polled_growth.h).
    detail::grow_apart(options_.cancel, "adaptive: repair", 1, touched_, since_check_);
    touched_.push_back(t);
    since_check_.push_back(t);
  }

  double last_resort_edge() const { return options_.last_resort_min_edge > 0 ? options_.last_resort_min_edge : options_.min_edge; }

  // Drops removed triangles and vertices, renumbering what is left in its order.
  void compact();

  // Frees the stars and the hash's cells, a million small buffers each at 2*10^6 triangles,
  // with polls between blocks (detail::polled_clear), before the destructor frees the rest at
  // once. The context is then only to be destroyed.
  void release() {
    detail::polled_clear(vt_, [this] { poll(); });
    hash_.clear();
  }

  // A cancelled repair frees its million small buffers (the stars, the hash's cells) on a thread
  // of their own (background_release.h).
  void release_if_cancelled() noexcept {
    if (options_.cancel.cancelled())
      detail::release_in_background(vt_, hash_, estimates_, hashed_lo_, hashed_hi_, stamp_, alive_, crease_, flipped_,
                                    touched_, since_check_);
  }

  const Field& field_;
  const bool smooth_;  // Field::smooth
  Mesh& mesh_;
  QualityOptions options_;
  unsigned workers_;  // threads of the parallel passes (QualityOptions::threads)
  std::vector<std::vector<int>> vt_;
  std::vector<signed char> crease_;
  // The input's boundary vertices (mark_boundary): 1, or 2 for one the caller measures again
  // (mark_measured_again); empty without QualityOptions::keep_boundary.
  std::vector<char> fixed_;
  // Each input vertex's index after compact, -1 when removed.
  std::vector<int> renumbered_;
  std::vector<char> alive_;
  std::vector<std::uint32_t> stamp_;
  std::uint32_t stamp_id_ = 0;
  SpatialHash hash_;
  // The corners of the relaxation's flips in its current sweep.
  std::vector<char> flipped_;
  // Midpoint distances by edge (prefetch_flip_samples); empty outside a pass of flips.
  EdgeTable flip_mids_;
  // prefetch_distances' answers by their points' bits; empty outside its callers.
  std::unordered_map<PointBits, double, PointBitsHash> known_distances_;
  // star_intersects' triangles, kept from call to call.
  std::vector<StarTriangle> star_buffer_;
  // tan(options_.improve_below) where the bound lies in (0, pi/2), else 0 (tri_below).
  double below_tan_ = 0;
  // estimate_distance's memo, by triangle slot (see there).
  mutable std::vector<EstimateEntry> estimates_;
  // Predicted estimates (see Jet): whether, the vertices' jets, and the one jet set aside.
  bool predict_ = false;
  mutable std::vector<Jet> jets_;
  mutable Jet spare_;
  mutable int spare_v_ = -1;
  // The box each triangle is stored in the hash with (hash_box).
  std::vector<Vec3> hashed_lo_, hashed_hi_;
  // Triangles changed in the current round, and since the last tolerance check.
  std::vector<int> touched_, since_check_, dead_vertex_;
  QualityReport report_;
};

}  // namespace cdp::adaptive::repair
