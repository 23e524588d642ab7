#include "surface_passes.h"

#include <cdp/core/crease_curves.h>
#include <cdp/core/errors.h>
#include <cdp/core/grid_cell.h>
#include <cdp/core/newton_projection.h>
#include <cdp/core/surface_seeds.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <optional>
#include <utility>
#include <unordered_map>

namespace cdp {

namespace {

using Branch = std::vector<std::uint8_t>;

// A point on two pieces to within the Newton tolerance tol lies within tol / sin(angle / 2) of
// where their branch switches (angle: the crease's dihedral angle); this many tolerances cover
// angles down to about 6 degrees and are still far below any step.
constexpr double kActiveRadius = 20;
// How many times a step is halved when the tangent turns too much or the projection fails.
constexpr int kMaxHalvings = 12;

// Points already on a curve (with the curve's and the point's index), hashed by cell, to skip
// grid crossings whose crease is traced already.
class PointGrid {
 public:
  explicit PointGrid(double cell) : cell_(cell) {}
  void insert(const Vec3& p, std::size_t curve, std::size_t index) { cells_[key(cell_of(p))].push_back({p, curve, index}); }
  // Whether fn(curve, index) holds for a point within r of p (visited in a fixed order).
  template <class Fn>
  bool any_within(const Vec3& p, double r, Fn&& fn) const {
    const auto c = cell_of(p);
    const int reach = static_cast<int>(std::ceil(r / cell_));
    for (int dz = -reach; dz <= reach; ++dz)
      for (int dy = -reach; dy <= reach; ++dy)
        for (int dx = -reach; dx <= reach; ++dx) {
          const auto it = cells_.find(key({c[0] + dx, c[1] + dy, c[2] + dz}));
          if (it == cells_.end()) continue;
          for (const Entry& e : it->second)
            if ((e.p - p).squaredNorm() <= r * r && fn(e.curve, e.index)) return true;
        }
    return false;
  }

 private:
  struct Entry {
    Vec3 p;
    std::size_t curve, index;
  };
  GridCell cell_of(const Vec3& p) const { return grid_cell(p, cell_); }
  static std::uint64_t key(const GridCell& c) { return grid_cell_key(c); }
  double cell_;
  std::unordered_map<std::uint64_t, std::vector<Entry>> cells_;
};

// Whether pieces a and b are one function at p, to rounding: the switch between them is hidden
// there by another branch.
bool one_function(const Field& field, const Vec3& p, const Branch& a, const Branch& b) {
  const auto [va, ga] = field.piece_first_order(p, a);
  const auto [vb, gb] = field.piece_first_order(p, b);
  return same_to_rounding(va, ga, vb, gb);
}

// Distance from p to segment a-b.
double segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

// A point on a crease lies on a traced polyline of it when it is this share of the longest step
// from one of its segments: the segments are chords of a curve turning at most max_turn (0.1) a
// step, which stray from it by under 0.0125 of the step; another crease of the same two pieces
// passing close by (two of the gyroid ball's loops come within 0.18) is farther.
constexpr double kOnTracedCurve = 0.05;

// Whether two pieces' unit normals are opposite (to kSamePieceCosine): the faces of two solids
// that touch, a box standing on another or a leg flush with a table top. Where both are zero the
// union's field only touches zero (it is negative on either side) and the intersection's is
// positive on either side: no surface, no crease, however the branches are taken there.
bool touching_faces(const Vec3& g0, const Vec3& g1) { return g0.dot(g1) < -kSamePieceCosine; }

// trace_creases' test of a crease's faces: each face's point this many min_spacing from the crease
// (across it, on the side where F is that piece), and F this many min_spacing either way along
// the face's normal there, must differ in sign. A depth far below the reach: two faces meeting at
// a small angle leave a wedge of solid or air only the reach times the angle thick there (the
// gyroid ball's sheets cut its sphere at a few degrees), and far above the Newton tolerance.
constexpr double kFaceReach = 2;
constexpr double kFaceDepth = 1e-3;
// ... the point found by this many Newton steps on the face's piece (a plane's in one, a curved
// face's to rounding in three), the piece taken there if its switch lies within this share of
// the step.
constexpr int kFaceNewtonSteps = 3;
constexpr double kFaceTakenShare = 0.1;
// How far from the last point of a hidden seam a crease of other pieces is looked for
// (Tracer::seam_meets_crease), in min_spacing: the seam's last step is at least min_step
// (at most min_spacing) short of where it stops.
constexpr double kSeamCreaseReach = 4;
// Bisections that put a corner on a hidden seam (Tracer::seam_corner) to the Newton tolerance:
// from a step of max_spacing, 0.02 of the diagonal, to 1e-10 of it takes 28.
constexpr int kSeamCornerBisections = 40;

// trace_creases' pass over the corners: the pieces within this many min_spacing of a corner are
// those meeting there (a corner is found to the Newton tolerance, so a little reach does), and a
// crease leaving it is started this many min_spacing along its tangent: far enough from the
// corner that the third piece is not taken there, near enough to fit on a crease a few
// min_spacing long.
constexpr double kCornerReach = 1;
constexpr double kCornerStep = 2;
// The hidden seams leaving a corner where a seam ends alone: the field's choices are looked at in
// kSeamProbes points round the corner, kCornerStep min_spacing from it on each face there; two
// neighbours that differ by one switch the value depends on, hidden between them, have a seam
// between them. A seam is known when a curve ends at the corner leaving within about 25 degrees
// of it (seams meeting at a corner leave at the angles of the switches, 45 degrees or more apart
// on a box).
constexpr int kSeamProbes = 24;
constexpr double kKnownSeamCosine = 0.9;
constexpr int kSeamProbeNewtonSteps = 4;
// Progress is reported every this many grid crossings or corners looked at: a call some
// milliseconds apart where each costs piece searches (knurling: 2,040 crossings in 4.5 s, then
// 1,963 corners in 7.4 s).
constexpr std::size_t kProgressSteps = 16;

struct Tracer {
  const Field& field;
  const CreaseTracingOptions& o;
  double max_spacing, min_spacing, tol;
  double min_step = o.min_step > 0 ? std::min(o.min_step, min_spacing) : min_spacing;
  std::size_t points = 0;

  // The pieces taken on the surface right at p: those whose switch lies within a radius of
  // the Newton tolerance's size.
  std::vector<FieldPiece> active(const Vec3& p) const { return field.pieces_first_order(p, kActiveRadius * tol); }

  // Whether both pieces (gradients g1, g2) are among those taken at p: then p is on the crease
  // of the surface, not on an intersection of pieces that another branch hides.
  bool both_active(const Vec3& p, const Vec3& g1, const Vec3& g2) const {
    bool f1 = false, f2 = false;
    for (const FieldPiece& q : active(p)) {
      const Vec3 g = q.gradient.normalized();
      f1 = f1 || g.dot(g1.normalized()) > kSamePieceCosine;
      f2 = f2 || g.dot(g2.normalized()) > kSamePieceCosine;
    }
    return f1 && f2;
  }

  // Whether both faces of the crease of a and b at c (on both; gradients ga, gb there) bound
  // the solid: false where one is a face only where two solids touch, the field of one sign on
  // either side of it (a leg flush under a table top: the edge where the leg's side meets its
  // top face, which lies on the table's underside, is no crease; the leg's side meets the
  // underside along the same line, and that is one). Each face is looked at a step across the
  // crease either way (kFaceReach min_spacing), where its piece is among those taken: it bounds
  // the solid if F changes sign across it at one of them, or where no point of it was found on
  // one side (not where the points found on both sides are not the surface's).
  bool faces_bound_solid(const Vec3& c, const Branch& a, const Branch& b, const Vec3& ga, const Vec3& gb) const {
    const double reach = kFaceReach * min_spacing, depth = kFaceDepth * min_spacing;
    const std::array<std::pair<const Branch*, Vec3>, 2> faces{std::pair{&a, ga}, std::pair{&b, gb}};
    for (int k = 0; k < 2; ++k) {
      const Branch& mine = *faces[static_cast<std::size_t>(k)].first;
      const Vec3 n = faces[static_cast<std::size_t>(k)].second.normalized();
      const Vec3 other = faces[static_cast<std::size_t>(1 - k)].second;
      const Vec3 across = (other - other.dot(n) * n).normalized();
      if (!across.allFinite()) continue;
      bool bounds = false, touches = false;
      int absent = 0;  // sides where the face's point is found and the face is not the surface's there
      for (const double side : {1.0, -1.0}) {
        Vec3 q = c + side * reach * across;
        for (int it = 0; it < kFaceNewtonSteps; ++it) {  // onto the piece's zero set
          const FirstOrder f = piece(q, mine);
          if (!(f.gradient.squaredNorm() > 0)) break;
          q -= f.value / f.gradient.squaredNorm() * f.gradient;
        }
        const FirstOrder f = piece(q, mine);
        if (!q.allFinite() || !(f.gradient.squaredNorm() > 0) || (q - c).norm() > 2 * reach ||
            !(std::abs(f.value) <= kActiveRadius * tol * f.gradient.norm()))
          continue;
        const Vec3 m = f.gradient.normalized();
        bool taken = std::abs(field.value(q)) <= kActiveRadius * tol * f.gradient.norm();
        if (taken) {
          taken = false;
          for (const FieldPiece& p : field.pieces_first_order(q, kFaceTakenShare * reach))
            taken = taken || p.gradient.normalized().dot(m) > kSamePieceCosine;
        }
        if (!taken) {
          ++absent;
          continue;
        }
        (surface_passes(field, q, m, depth) ? bounds : touches) = true;
      }
      // Not the surface's on either side: the face is not there (the crossbar of an H whose faces
      // are flush with its posts' runs on inside a post's face, its edges no crease; a cutter
      // flush with a box's face leaves its own side faces off the box).
      if (!bounds && (touches || absent == 2)) return false;
    }
    return true;
  }

  // A piece's value and gradient: the walk needs no Hessian.
  struct FirstOrder {
    double value;
    Vec3 gradient;
  };
  FirstOrder piece(const Vec3& p, const Branch& b) const {
    const auto [value, gradient] = field.piece_first_order(p, b);
    return {value, gradient};
  }

  Vec3 tangent(const Vec3& p, const Branch& a, const Branch& b) const {
    return piece(p, a).gradient.cross(piece(p, b).gradient).normalized();
  }

  // The corner where the walk from p along tangent t meets a third piece: one whose zero set
  // lies within `reach` of p and which is taken there, if the projection onto the three reaches
  // a point on the surface within 2 reach that is p itself (within the active radius) or lies
  // ahead; the nearest such. Corners behind are where the walk came from. Every third piece is
  // looked at, not only the first: where a sphere's seam meets the face of a bar, three corners
  // lie within 0.03 of each other (two spheres on a bar, where the bar's edge leaves one sphere
  // and enters the other), and the walk from one of them towards the next found the one it
  // started at, stepped past the next, and stopped without a corner. A corner ahead must also
  // lie within max_turn of the tangent, as a step would (closer than min_spacing, any way
  // ahead): the chord to a corner 0.23 away along a sphere's arc on the bar's side strayed from
  // the crease by more than kOnTracedCurve, and the arc was traced three times.
  bool corner_near(const Vec3& p, const Vec3& t, const Branch& a, const Branch& b, double reach, Vec3& corner) const {
    const Vec3 ga = piece(p, a).gradient.normalized(), gb = piece(p, b).gradient.normalized();
    bool found = false;
    double nearest = std::numeric_limits<double>::infinity();
    for (const FieldPiece& q : field.pieces_first_order(p, reach)) {
      const Vec3 g = q.gradient.normalized();
      if (g.dot(ga) > kSamePieceCosine || g.dot(gb) > kSamePieceCosine) continue;
      // A piece facing one of the two the opposite way is the face of a solid touching that one
      // (touching_faces): the three meet along the whole crease, at no corner.
      if (touching_faces(g, ga) || touching_faces(g, gb)) continue;
      if (!(std::abs(q.value) <= reach * q.gradient.norm())) continue;
      const std::vector<Branch> three{a, b, q.branch};
      const CreaseProjection c = project_to_crease(field, p, three, o.newton);
      const double d = (c.point - p).norm();
      if (!c.ok() || d > 2 * reach || d >= nearest) continue;
      if (d > kActiveRadius * tol) {
        const double along = (c.point - p).dot(t);
        if (along <= 0 || (d > min_spacing && along < std::cos(o.max_turn) * d)) continue;
      }
      if (!both_active(c.point, ga, g)) continue;
      corner = c.point;
      nearest = d;
      found = true;
    }
    return found;
  }

  // The one branch point where a and b differ (neither free), or -1: the switch that separates
  // them, followed where they become one function.
  static int differing_branch(const Branch& a, const Branch& b) {
    int k = -1;
    for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) {
      if (a[i] == b[i] || a[i] == Field::kFreeBranch || b[i] == Field::kFreeBranch) continue;
      if (k >= 0) return -1;
      k = static_cast<int>(i);
    }
    return k;
  }

  // The branch points the value depends on at q (Field::live_branches) with the choices `code`
  // and either of a's and b's at their seam's branch point k.
  std::uint64_t live_either_side(const Vec3& q, std::vector<std::uint8_t> code, const Branch& a, const Branch& b,
                                 std::size_t k) const {
    std::uint64_t mask = 0;
    for (const Branch* side : {&a, &b}) {
      code[k] = (*side)[k];
      mask |= field.live_branches(q, code).value_or(0);
    }
    return mask;
  }

  // Whether the seam of a and b (the switch of branch point k, where they are one function)
  // crosses, between two of its points, the switch of another branch point that shapes the
  // pieces beside it: a corner of the patches, hidden as the seam is. A box smoothly intersected
  // with a ball whose edges stick out of it: each edge's crease fades into the ball, and its
  // seam (the box's switch between two faces) goes on over the ball to where three faces' switches
  // meet, and on along another's; the patch of a face is bounded there. Such a switch is one
  // of a Creased branch point (a Smooth one, the blend's clamp, shapes no patch) that the field
  // takes the other way at either point, and that the value depends on with either side's choice
  // at k (not a box's abs(x) where x is not the box's largest). Found to the Newton tolerance by
  // bisection along the seam; the corner is put in `corner`.
  bool seam_corner(const Vec3& from, const Vec3& to, const Branch& a, const Branch& b, int k, Vec3& corner) const {
    Field::BranchRecord r0, r1;
    if (!field.branch_record(from, r0) || !field.branch_record(to, r1) || r0.taken.size() != r1.taken.size()) return false;
    const std::vector<Field::BranchKind>& kinds = field.branch_kinds();
    const auto kk = static_cast<std::size_t>(k);
    // Evaluated once a point, and only where some switch was crossed.
    std::optional<std::uint64_t> live;
    std::size_t j = r0.taken.size();
    for (std::size_t i = 0; i < r0.taken.size() && i < kinds.size() && i < 64; ++i) {
      if (i == kk || kinds[i] != Field::BranchKind::Creased || r0.taken[i] == r1.taken[i]) continue;
      if (!live) live = live_either_side(from, r0.taken, a, b, kk) | live_either_side(to, r1.taken, a, b, kk);
      if (*live >> i & 1u) {
        j = i;
        break;
      }
    }
    if (j == r0.taken.size()) return false;
    Vec3 lo = from, hi = to;
    const std::uint8_t taken_lo = r0.taken[j];
    for (int it = 0; it < kSeamCornerBisections && (hi - lo).norm() > tol; ++it) {
      const CreaseProjection c = project_to_seam(field, 0.5 * (lo + hi), a, kk, o.newton);
      Field::BranchRecord r;
      if (!c.ok() || !field.branch_record(c.point, r) || j >= r.taken.size()) break;
      (r.taken[j] == taken_lo ? lo : hi) = c.point;
    }
    const CreaseProjection c = project_to_seam(field, 0.5 * (lo + hi), a, kk, o.newton);
    corner = c.ok() ? c.point : 0.5 * (lo + hi);
    return true;
  }

  // The hidden seams that leave `corner`, where a seam ends alone (the pieces meeting there in
  // `at`), other than along `leaving` (the ways curves leave it, to which theirs are added): each
  // walked from the corner to its other end (ends_at_corner, or a stop). Seams are not found from
  // the grid's crossings (no crease there), only walked on from a faded crease. Where a box's
  // edge fades into a pocket a smooth difference cut, and runs on down the pocket's wall as the
  // box's switch, hidden behind the blend, into the corner where the box's three switches meet,
  // the two other switches go on from there and bound the wall's patches too: without them the
  // patch boundary broke off at that corner.
  std::vector<CreaseCurve> seams_leaving(const Vec3& corner, const std::vector<FieldPiece>& at, std::vector<Vec3>& leaving) {
    std::vector<CreaseCurve> out;
    const double r = kCornerStep * min_spacing;
    const std::vector<Field::BranchKind>& kinds = field.branch_kinds();
    std::vector<Vec3> faces;
    for (const FieldPiece& q : at) {
      const Vec3 n = q.gradient.normalized();
      if (n.allFinite() && std::none_of(faces.begin(), faces.end(), [&](const Vec3& m) { return m.dot(n) > kSamePieceCosine; }))
        faces.push_back(n);
    }
    for (const Vec3& n : faces) {
      struct Probe {
        Vec3 q;
        std::vector<std::uint8_t> taken;
        bool ok = false;
      };
      std::array<Probe, kSeamProbes> probes;
      const Vec3 u = n.unitOrthogonal(), v = n.cross(u);
      for (int i = 0; i < kSeamProbes; ++i) {
        const double angle = 2 * std::numbers::pi * i / kSeamProbes;
        Probe& pr = probes[static_cast<std::size_t>(i)];
        pr.q = corner + r * (std::cos(angle) * u + std::sin(angle) * v);
        Vec3 g;
        double value = 0;
        for (int it = 0; it < kSeamProbeNewtonSteps; ++it) {  // onto the surface along its normal
          value = field.value_gradient(pr.q, g);
          if (!std::isfinite(value) || !(g.squaredNorm() > 0)) break;
          pr.q -= value / g.squaredNorm() * g;
        }
        value = field.value_gradient(pr.q, g);
        Field::BranchRecord record;
        pr.ok = std::abs(value) <= kActiveRadius * tol * g.norm() && g.normalized().dot(n) > kSamePieceCosine &&
                (pr.q - corner).norm() <= 2 * r && field.branch_record(pr.q, record);
        if (pr.ok) pr.taken = std::move(record.taken);
      }
      for (int i = 0; i < kSeamProbes; ++i) {
        const Probe& p0 = probes[static_cast<std::size_t>(i)];
        const Probe& p1 = probes[static_cast<std::size_t>((i + 1) % kSeamProbes)];
        if (!p0.ok || !p1.ok || p0.taken.size() != p1.taken.size()) continue;
        const int k = differing_branch(p0.taken, p1.taken);
        if (k < 0 || static_cast<std::size_t>(k) >= kinds.size() || kinds[static_cast<std::size_t>(k)] != Field::BranchKind::Creased)
          continue;
        const Vec3 mid = 0.5 * (p0.q + p1.q);
        // Hidden between them, and shaping the value (not a choice a later min or max discards).
        if (!one_function(mid, p0.taken, p1.taken) || !(field.live_branches(mid, p0.taken).value_or(0) >> k & 1u)) continue;
        const CreaseProjection c = project_to_seam(field, mid, p0.taken, static_cast<std::size_t>(k), o.newton);
        if (!c.ok() || (c.point - corner).norm() > 2 * r || (c.point - corner).norm() < 0.25 * r) continue;
        const Vec3 d = (c.point - corner).normalized();
        if (std::any_of(leaving.begin(), leaving.end(), [&](const Vec3& l) { return l.dot(d) > kKnownSeamCosine; }))
          continue;
        // The pieces as the field's pieces at the probe (hidden choices free), the seam's switch
        // fixed either way.
        const std::vector<FieldPiece> own = field.pieces_first_order(p0.q, 0);
        Branch a = own.empty() ? p0.taken : own.front().branch;
        if (a.size() != p0.taken.size()) continue;
        a[static_cast<std::size_t>(k)] = p0.taken[static_cast<std::size_t>(k)];
        Branch b = a;
        b[static_cast<std::size_t>(k)] = p1.taken[static_cast<std::size_t>(k)];
        CreaseCurve& curve = out.emplace_back();
        curve.pieces = {a, b};
        curve.seam_branch = k;
        curve.starts_at_corner = true;
        std::vector<Vec3> forward;
        bool on_seam = true;
        curve.ends_at_corner = walk(c.point, a, b, 0, nullptr, forward, on_seam, &d) == End::Corner;
        curve.points = {corner, c.point};
        curve.points.insert(curve.points.end(), forward.begin(), forward.end());
        leaving.push_back(d);
      }
    }
    return out;
  }

  // Whether a hidden seam that can go no further from p (along t) stops at a switch that shapes
  // the patches beside it, within `step` ahead: the seam's own switch, continued on a's code past
  // it, crosses that switch there (seam_corner finds it). The field's switch itself turns away
  // there (beyond, the choice it separated is hidden by the other), so no step of the walk crosses
  // it: the four seams of a cube's body diagonals' ends, hidden under another box's face by a
  // smooth intersection, each stopped one step short of the next corner of their square.
  bool seam_corner_ahead(const Vec3& p, const Vec3& t, double step, const Branch& a, const Branch& b, int k,
                         Vec3& corner) const {
    double s = step;
    for (int h = 0; h <= kMaxHalvings && s >= min_step; ++h, s *= 0.5) {
      const CreaseProjection c = project_to_seam(field, p + s * t, a, static_cast<std::size_t>(k), o.newton);
      if (!c.ok() || !((c.point - p).dot(t) > 0) || (c.point - p).norm() > 2 * s) continue;
      if (seam_corner(p, c.point, a, b, k, corner)) return true;
    }
    // Or p lies on that switch already, where the seam turns along it: every projection ahead
    // lands back on p.
    Field::BranchRecord r;
    if (!field.branch_record(p, r)) return false;
    const std::vector<Field::BranchKind>& kinds = field.branch_kinds();
    const auto kk = static_cast<std::size_t>(k);
    std::optional<std::uint64_t> live;
    for (std::size_t j = 0; j < r.taken.size() && j < kinds.size() && j < 64; ++j) {
      if (j == kk || kinds[j] != Field::BranchKind::Creased || !(r.distance[j] <= kActiveRadius * tol)) continue;
      if (!live) live = live_either_side(p, r.taken, a, b, kk);
      if (*live >> j & 1u) {
        corner = p;
        return true;
      }
    }
    return false;
  }

  // Whether the field has a crease within a few min_spacing of p, the last point of a hidden
  // seam that can go no further: the seam has run into a crease of other pieces, which it
  // meets at a corner there (a tetrahedron smoothly united with an octahedron: the
  // tetrahedron's switch between two faces, hidden under the octahedron, runs into the
  // octahedron's edge). The corner is put on that crease, nearest p.
  bool seam_meets_crease(const Vec3& p, Vec3& corner) const {
    const double reach = kSeamCreaseReach * min_spacing;
    const std::vector<FieldPiece> near = field.pieces_first_order(p, reach);
    double nearest = reach;
    bool found = false;
    for (std::size_t i = 0; i < near.size(); ++i)
      for (std::size_t j = i + 1; j < near.size(); ++j) {
        const Vec3 gi = near[i].gradient.normalized(), gj = near[j].gradient.normalized();
        if (!(gi.dot(gj) <= kSamePieceCosine) || touching_faces(gi, gj)) continue;
        const std::vector<Branch> two{near[i].branch, near[j].branch};
        const CreaseProjection c = project_to_crease(field, p, two, o.newton);
        if (!c.ok() || !((c.point - p).norm() <= nearest) || !both_active(c.point, c.gradients[0], c.gradients[1])) continue;
        nearest = (c.point - p).norm();
        corner = c.point;
        found = true;
      }
    return found;
  }

  // Whether a and b are one function at p, to rounding: their switch is hidden there by another
  // branch (a box's edge where a smooth union's blend has left the box: its clamp at 0 multiplies
  // the box's difference from the ball by 0).
  bool one_function(const Vec3& p, const Branch& a, const Branch& b) const { return cdp::one_function(field, p, a, b); }
  // Whether a and b are the same piece at p (kSamePieceCosine): no crease between them there.
  bool same_piece(const Vec3& p, const Branch& a, const Branch& b) const {
    return piece(p, a).gradient.normalized().dot(piece(p, b).gradient.normalized()) > kSamePieceCosine;
  }

  // One step from p along t: the longest of step, step / 2, ... (down to min_step) whose
  // projection lies ahead and turns the tangent by less than max_turn (by less than a right
  // angle at the last). On the crease of a and b, its tangent dir * ga x gb; or (seam) on the
  // switch of branch point k where a and b are one function, its tangent along t. On success
  // moves p, t and step there.
  bool advance(Vec3& p, Vec3& t, double& step, double& dir, const Branch& a, const Branch& b, int k, bool seam) {
    double s = step;
    for (int h = 0; h <= kMaxHalvings && s >= min_step; ++h, s *= 0.5) {
      const std::vector<Branch> two{a, b};
      const CreaseProjection c = seam ? project_to_seam(field, p + s * t, a, static_cast<std::size_t>(k), o.newton)
                                      : project_to_crease(field, p + s * t, two, o.newton);
      if (!c.ok()) continue;
      // On the crease, the projection's own last evaluation of a and b.
      const Vec3 ga = seam ? piece(c.point, a).gradient : c.gradients[0];
      const Vec3 gb = seam ? piece(c.point, b).gradient : c.gradients[1];
      Vec3 tn = dir * ga.cross(gb).normalized();
      double new_dir = dir;
      if (seam) {
        if (!same_piece(c.point, a, b)) continue;
        const std::optional<Field::BranchSwitch> sw = field.branch_switch(c.point, static_cast<std::size_t>(k));
        if (!sw) continue;
        tn = ga.cross(sw->normal).normalized();
        if (tn.dot(t) < 0) tn = -tn;
      } else if (dir == 0) {  // back on the crease after a seam: the way the walk goes
        // (From the crease's own tangent: tn, dir times it, is zero here; taken for the way,
        // it made every return +1, half of them backwards, and the walk stopped there.)
        const Vec3 tangent = ga.cross(gb).normalized();
        new_dir = tangent.dot(t) < 0 ? -1.0 : 1.0;
        tn = new_dir * tangent;
      }
      // The turn bound sets the spacing, down to min_step: a crease that turns faster still
      // is followed at min_step (less than a right angle a step).
      const bool last = h == kMaxHalvings || 0.5 * s < min_step;
      const double turn = last ? 0.0 : std::cos(o.max_turn);
      if (!tn.allFinite() || tn.dot(t) <= turn || (c.point - p).dot(t) <= 0) continue;
      if (!both_active(c.point, ga, gb)) continue;
      p = c.point;
      t = tn;
      step = s;
      dir = new_dir;
      return true;
    }
    return false;
  }

  // Walks from `start` along the crease of a and b in direction `dir` (+1 or -1 times the
  // tangent ga x gb) until a corner, back at `loop_to` (a loop), or a stop. Appends the points
  // after `start`; sets `on_seam` when it went along a seam (CreaseCurve::seam_branch).
  //
  // Where the crease fades (its pieces' normals closer than kSamePieceCosine: no crease by the
  // pieces' own measure) the walk goes on along the switch of the branch point that separates
  // them, as a seam, and back onto the crease where it comes back. A seam is kept only if the
  // pieces are one function somewhere along it (one_function: the switch hidden, a crease that
  // ended); pieces that are only tangent, where two creases cross, make a stop as before, which
  // join_crossings turns into the corner it is.
  enum class End { Corner, Loop, Stop };
  //
  // With `seam_tangent`, the walk starts on a hidden seam (a and b one function at `start`) along
  // that direction, as one that went on from a faded crease would there.
  End walk(const Vec3& start, const Branch& a, const Branch& b, double dir, const Vec3* loop_to,
           std::vector<Vec3>& out, bool& on_seam, const Vec3* seam_tangent = nullptr) {
    const int k = differing_branch(a, b);
    Vec3 p = start;
    Vec3 t = seam_tangent ? *seam_tangent : dir * tangent(p, a, b);
    double step = max_spacing;
    double travelled = 0;
    bool seam = seam_tangent != nullptr, hidden = seam, left_start = false;
    if (seam_tangent) on_seam = true;
    std::size_t seam_begin = 0;
    Vec3 seam_from = p;
    // The end of a seam: kept where the pieces were one function on it, else a stop where the seam began.
    const auto end_seam = [&](End end) {
      if (!seam || hidden) return end;
      out.resize(seam_begin);
      p = seam_from;
      return End::Stop;
    };
    for (;;) {
      if (o.cancel) o.cancel->check("trace_creases");
      if (++points > o.max_points)
        throw LimitExceededError("trace_creases: more than " + std::to_string(o.max_points) +
                                 " crease points (CreaseTracingOptions::max_points)");
      Vec3 corner;
      if (corner_near(p, t, a, b, step, corner)) {
        if (end_seam(End::Corner) == End::Stop) return End::Stop;
        if ((corner - p).norm() <= kActiveRadius * tol) return End::Corner;  // p is the corner
        out.push_back(corner);
        return End::Corner;
      }
      // Predictor along the tangent, corrector onto the crease; shorter steps where the crease
      // turns fast or the projection fails.
      const Vec3 from = p;
      bool moved = advance(p, t, step, dir, a, b, k, seam);
      if (!moved && k >= 0) {
        if (end_seam(End::Loop) == End::Stop) return End::Stop;
        seam = !seam;
        if (seam) {
          seam_begin = out.size();
          seam_from = p;
          hidden = false;
        } else {
          dir = 0;  // the crease's direction is taken again from the way the walk goes
        }
        moved = advance(p, t, step, dir, a, b, k, seam);
      }
      if (!moved) {
        Vec3 corner;
        if (hidden && (seam_corner_ahead(p, t, step, a, b, k, corner) || seam_meets_crease(p, corner))) {
          if ((corner - p).norm() > kActiveRadius * tol) out.push_back(corner);
          return End::Corner;
        }
        return end_seam(End::Stop);
      }
      // A step back to where the walk was two steps before goes nowhere: where two pieces are
      // tangent their switch's direction (ga x gb) is lost, and the tee of two equal pipes
      // walked to and fro there until max_points.
      const Vec3& before = out.size() >= 2 ? out[out.size() - 2] : start;
      if (!out.empty() && (p - before).norm() < 0.5 * (p - from).norm()) return end_seam(End::Stop);
      if (seam && !hidden && one_function(p, a, b)) hidden = on_seam = true;
      if (seam && hidden) {
        Vec3 corner;
        if (seam_corner(from, p, a, b, k, corner)) {
          if ((corner - from).norm() > kActiveRadius * tol) out.push_back(corner);
          return End::Corner;
        }
      }
      const double stepped = (p - from).norm();
      travelled += stepped;
      step = std::min(max_spacing, 2 * step);
      // Back within a step of the start, once the walk has been more than two steps away from
      // it: the segment from p closes the loop. Closing only after travelling two max_spacing
      // took a loop shorter than that round twice: a rod of radius 0.02 through a ball has a rim
      // 0.13 long, max_spacing was 0.1, and the rim laid out doubly wound tangled its patches'
      // fronts, so the shape was meshed as smooth. The distance travelled still closes a loop
      // too tight for its steps to leave its start.
      if (loop_to) {
        const double to_start = (p - *loop_to).norm();
        left_start = left_start || to_start > 2 * stepped;
        if ((left_start || travelled > 2 * max_spacing) && to_start < step) {
          if (end_seam(End::Loop) == End::Stop) return End::Stop;
          if (to_start > min_spacing) out.push_back(p);
          return End::Loop;
        }
      }
      out.push_back(p);
    }
  }
};

}  // namespace

// Where two creases of the same two pieces cross, the pieces are tangent (two equal cylinders
// crossing at right angles: the two ellipses where they meet cross at the top and bottom of
// both), and each walk towards the crossing stops a little short of it, where the crease's
// direction is lost (the four arcs of the cylinders stopped 0.0007-0.0025 from it, min_spacing
// 0.002). Two or more stops within kCrossingReach min_spacing of each other are such a
// crossing: a corner on the surface at their mean, each of those curves ending there. Where a
// tee of two equal pipes has them tangent, two arcs end, one stop each (with three required,
// the tee was meshed as smooth with the crease warning). A stop alone stays a stop (a crease
// that fades out where its pieces become tangent).
namespace {

constexpr double kCrossingReach = 4;
constexpr std::size_t kCrossingStops = 2;

void join_crossings(const Field& field, double min_spacing, CreaseTracingResult& result, std::vector<Vec3>& corners) {
  struct End {
    std::size_t curve;
    bool back;  // the curve's last point, else its first
  };
  std::vector<End> ends;
  for (std::size_t c = 0; c < result.curves.size(); ++c) {
    const CreaseCurve& curve = result.curves[c];
    if (curve.closed || curve.points.empty()) continue;
    if (!curve.starts_at_corner) ends.push_back({c, false});
    if (!curve.ends_at_corner) ends.push_back({c, true});
  }
  const auto point = [&](const End& e) -> const Vec3& {
    const auto& P = result.curves[e.curve].points;
    return e.back ? P.back() : P.front();
  };
  std::vector<char> joined(ends.size(), 0);
  for (std::size_t i = 0; i < ends.size(); ++i) {
    if (joined[i]) continue;
    std::vector<std::size_t> group{i};
    for (std::size_t j = i + 1; j < ends.size(); ++j)
      if (!joined[j] && (point(ends[j]) - point(ends[i])).norm() <= kCrossingReach * min_spacing) group.push_back(j);
    if (group.size() < kCrossingStops) continue;
    Vec3 mean = Vec3::Zero();
    for (const std::size_t k : group) mean += point(ends[k]);
    const ProjectionResult at = project_to_surface(field, mean / static_cast<double>(group.size()));
    if (!at.ok()) continue;
    for (const std::size_t k : group) {
      joined[k] = 1;
      CreaseCurve& curve = result.curves[ends[k].curve];
      if (ends[k].back) {
        curve.points.push_back(at.point);
        curve.ends_at_corner = true;
      } else {
        curve.points.insert(curve.points.begin(), at.point);
        curve.starts_at_corner = true;
      }
      --result.stops;
    }
    corners.push_back(at.point);
  }
}

// A cut curve's codes are those it was traced with, which fix the choices hidden where tracing
// started. Where a hidden seam ends at the cut, the part beyond lies on the seam's other side,
// where the field takes the hidden choice the other way. So each part's codes take a choice
// hidden near both its ends and at its middle as the field takes it at all three; a choice the
// piece shows at one of them, or that the field takes both ways along the part (it crosses
// another hidden switch), is left as traced: trace_cycles matches the darts at a corner by their
// pieces there. Kept as traced, a smooth union's box edge, cut where the other box's hidden
// diagonal seam ends on it, coded its short part beyond the seam as the hidden box's other face:
// the patch whose boundary it began took that face's piece, and its front stalled on the box's
// visible edge.
// The probes near the ends lie this share of the end segment in from the corner.
constexpr double kEndProbe = 0.1;

void take_hidden_choices(const Field& field, CreaseCurve& curve) {
  const std::vector<Vec3>& P = curve.points;
  const std::size_t n = P.size();
  if (n < 2) return;
  const Vec3 middle = n % 2 ? P[n / 2] : Vec3(0.5 * (P[n / 2 - 1] + P[n / 2]));
  const std::array<Vec3, 3> at{Vec3(P[0] + kEndProbe * (P[1] - P[0])), middle,
                               Vec3(P[n - 1] + kEndProbe * (P[n - 2] - P[n - 1]))};
  std::array<Field::BranchRecord, 3> records;
  for (std::size_t i = 0; i < 3; ++i)
    if (!field.branch_record(at[i], records[i])) return;
  for (std::vector<std::uint8_t>& code : curve.pieces)
    for (std::size_t k = 0; k < code.size(); ++k) {
      if (code[k] == Field::kFreeBranch || static_cast<int>(k) == curve.seam_branch) continue;
      std::vector<std::uint8_t> taken = code;
      bool hidden = true;
      for (std::size_t i = 0; i < 3 && hidden; ++i) {
        if (k >= records[i].taken.size() || records[i].taken[k] == code[k]) hidden = false;
        else {
          taken[k] = records[i].taken[k];
          hidden = one_function(field, at[i], code, taken);
        }
      }
      if (hidden) code = std::move(taken);
    }
}

// An open curve between the same two corners as an earlier one and on it all along (every point
// within `on` of the earlier polyline) is the same crease traced twice, and is dropped
// (CreaseTracingResult::duplicates). A box's edge running into a smooth union's blend was traced
// from its corner and again as the part of a longer walk cut at the corner where the blend
// begins: the two darts of each side met at the box's corner along the same direction, and the
// layout refused them ("a piece meets the corner more than once").
void drop_duplicate_curves(double min_spacing, double on, CreaseTracingResult& result) {
  const auto polyline_distance = [](const Vec3& q, const std::vector<Vec3>& P) {
    double d = (q - P[0]).norm();
    for (std::size_t i = 0; i + 1 < P.size(); ++i) d = std::min(d, segment_distance(q, P[i], P[i + 1]));
    return d;
  };
  std::vector<CreaseCurve> kept;
  PointGrid starts(min_spacing);  // the kept open curves' first points (index 0) and last (1)
  for (CreaseCurve& curve : result.curves) {
    if (!curve.closed && curve.points.size() >= 2) {
      const Vec3 &a = curve.points.front(), &b = curve.points.back();
      // A kept curve with an end within min_spacing of a, whose other end is within it of b.
      const bool twice = starts.any_within(a, min_spacing, [&](std::size_t k, std::size_t end) {
        const std::vector<Vec3>& P = kept[k].points;
        return (b - (end == 0 ? P.back() : P.front())).norm() <= min_spacing &&
               std::all_of(curve.points.begin(), curve.points.end(), [&](const Vec3& q) { return polyline_distance(q, P) <= on; });
      });
      if (twice) {
        ++result.duplicates;
        continue;
      }
      starts.insert(a, kept.size(), 0);
      starts.insert(b, kept.size(), 1);
    }
    kept.push_back(std::move(curve));
  }
  result.curves = std::move(kept);
}

// Where a corner lies on a curve other than at its ends, the curve is cut there: a seam that
// runs into another crease (Tracer::seam_meets_crease) ends at a corner on it, and the
// crease it meets, traced through that point, must end there too, so that the patch beside
// it is bounded on both sides of the seam. A loop is opened there, starting and ending at
// the corner.
void split_at_corners(const Field& field, double min_spacing, CreaseTracingResult& result, const std::vector<Vec3>& corners) {
  // Each curve's points' bounds, grown by min_spacing: only a curve whose bounds hold the corner
  // is searched (a gyroid ball traced at a tenth of the default spacing has 961 corners and 2708
  // curves). The halves of a cut curve keep its bounds, which hold them.
  std::vector<std::pair<Vec3, Vec3>> bounds;
  for (const CreaseCurve& curve : result.curves) {
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const Vec3& q : curve.points) lo = lo.cwiseMin(q), hi = hi.cwiseMax(q);
    bounds.emplace_back(lo.array() - min_spacing, hi.array() + min_spacing);
  }
  for (const Vec3& corner : corners)
    for (std::size_t c = 0; c < result.curves.size(); ++c) {
      const auto& [lo, hi] = bounds[c];
      if ((corner.array() < lo.array()).any() || (corner.array() > hi.array()).any()) continue;
      CreaseCurve& curve = result.curves[c];
      const std::vector<Vec3>& P = curve.points;
      const std::size_t n = P.size();
      if (n < 2) continue;
      const auto near = [&](const Vec3& q) { return (q - corner).norm() <= min_spacing; };
      if (!curve.closed && (near(P.front()) || near(P.back()))) continue;
      const std::size_t segments = curve.closed ? n : n - 1;
      std::size_t best = segments;
      double distance = min_spacing;
      for (std::size_t i = 0; i < segments; ++i) {
        const double d = segment_distance(corner, P[i], P[(i + 1) % n]);
        if (d <= distance) distance = d, best = i;
      }
      if (best == segments) continue;
      // The points before the cut and after it, without one at the corner itself.
      std::vector<Vec3> before, after;
      for (std::size_t i = 0; i <= best; ++i)
        if (!near(P[i])) before.push_back(P[i]);
      for (std::size_t i = best + 1; i < n; ++i)
        if (!near(P[i])) after.push_back(P[i]);
      if (curve.closed) {
        CreaseCurve opened = curve;
        opened.closed = false;
        opened.starts_at_corner = opened.ends_at_corner = true;
        opened.points.assign(1, corner);
        opened.points.insert(opened.points.end(), after.begin(), after.end());
        opened.points.insert(opened.points.end(), before.begin(), before.end());
        opened.points.push_back(corner);
        curve = std::move(opened);
        continue;
      }
      CreaseCurve second = curve;
      second.starts_at_corner = true;
      second.points.assign(1, corner);
      second.points.insert(second.points.end(), after.begin(), after.end());
      curve.ends_at_corner = true;
      curve.points = std::move(before);
      curve.points.push_back(corner);
      take_hidden_choices(field, curve);
      take_hidden_choices(field, second);
      result.curves.push_back(std::move(second));
      bounds.push_back(bounds[c]);
    }
}

}  // namespace

CreaseTracingResult trace_creases(const Field& field, const CreaseTracingOptions& options) {
  CreaseTracingResult result;
  const Box& box = field.bounds();
  const double diag = box.diagonal();
  Tracer tr{field, options, options.max_spacing > 0 ? options.max_spacing : 0.02 * diag,
            options.min_spacing > 0 ? options.min_spacing : 0.0005 * diag,
            options.newton.tolerance > 0 ? options.newton.tolerance : 1e-10 * diag};
  SeedOptions so;
  so.resolution = options.resolution;
  so.require_closed_in_box = false;
  // A model without branch points has no creases (and costs nothing, not a grid).
  if (!field.has_pieces()) return result;
  SeedGrid sampled;
  if (!options.grid) sampled = sample_seed_grid(field, so);
  const SeedGrid& grid = options.grid ? *options.grid : sampled;
  // Cells of the radius it is searched with (max_spacing): 27 cells a search. (Cells of the grid's
  // h, a little smaller, made it 125, the tracing's largest cost on a Menger sponge.)
  PointGrid traced(tr.max_spacing);
  std::vector<Vec3> corners;
  // The crease of the pieces `two` through c (on both, project_to_crease), traced both ways
  // unless a traced polyline passes through c already or c is not on the surface's crease;
  // true where it was traced (or found to meet the surface only at a corner).
  const auto start_curve = [&](const CreaseProjection& c, const std::vector<Branch>& two, bool check_traced) {
    const Vec3 g0 = c.gradients[0].normalized(), g1 = c.gradients[1].normalized();
    // Traced already: c lies on a traced polyline (a crossing is only skipped for the crease it
    // projects onto, so that a short crease right next to another, a sliver of a face between
    // two spheres 0.03 long, is not taken for it).
    const auto on_traced = [&](std::size_t k, std::size_t i) {
      const std::vector<Vec3>& P = result.curves[k].points;
      const double tol = kOnTracedCurve * tr.max_spacing;
      const bool closed = result.curves[k].closed;
      const std::size_t n = P.size();
      if (i + 1 < n || closed) {
        if (segment_distance(c.point, P[i], P[(i + 1) % n]) <= tol) return true;
      }
      if (i > 0 || closed) {
        if (segment_distance(c.point, P[(i + n - 1) % n], P[i]) <= tol) return true;
      }
      return n == 1 && (P[0] - c.point).norm() <= tol;
    };
    if (check_traced && traced.any_within(c.point, tr.max_spacing, on_traced)) return false;
    // On the surface: both_active compares normals only, and inside a table top under whose
    // corner a leg stands flush, the top's own two faces are taken where the leg's edge runs on
    // (their normals the leg's), the edge traced up through the top.
    if (!(std::abs(field.value(c.point)) <= kActiveRadius * tr.tol * c.gradients[0].norm())) return false;
    if (!tr.both_active(c.point, g0, g1)) return false;
    if (!tr.faces_bound_solid(c.point, two[0], two[1], c.gradients[0], c.gradients[1])) return false;
    // Trace both ways from c: a loop comes back to c; otherwise the curve runs from one
    // end to the other.
    CreaseCurve curve;
    curve.pieces = {two[0], two[1]};
    std::vector<Vec3> forward, backward;
    bool on_seam = false;
    const auto fe = tr.walk(c.point, two[0], two[1], 1, &c.point, forward, on_seam);
    if (fe == Tracer::End::Loop) {
      curve.closed = true;
      curve.points.push_back(c.point);
      curve.points.insert(curve.points.end(), forward.begin(), forward.end());
    } else {
      const auto be = tr.walk(c.point, two[0], two[1], -1, nullptr, backward, on_seam);
      curve.points.assign(backward.rbegin(), backward.rend());
      curve.points.push_back(c.point);
      curve.points.insert(curve.points.end(), forward.begin(), forward.end());
      curve.starts_at_corner = be == Tracer::End::Corner;
      curve.ends_at_corner = fe == Tracer::End::Corner;
      result.stops += (be == Tracer::End::Stop) + (fe == Tracer::End::Stop);
      // Two pieces that meet on the surface only at a corner: no crease between them. Where
      // a box's square hole meets its face, the hole's wall and the face of a crossing hole
      // are the same plane from two branches, and a crossing beside the corner projects
      // onto it (a Menger sponge of level 1: 5 such points among its 72 creases, which the
      // layout refused). Another pair at this crossing may still start a crease.
      if (curve.points.size() == 1 && curve.starts_at_corner && curve.ends_at_corner) return false;
      if (curve.starts_at_corner) corners.push_back(curve.points.front());
      if (curve.ends_at_corner) corners.push_back(curve.points.back());
    }
    if (on_seam) curve.seam_branch = Tracer::differing_branch(two[0], two[1]);
    for (std::size_t i = 0; i < curve.points.size(); ++i) traced.insert(curve.points[i], result.curves.size(), i);
    result.curves.push_back(std::move(curve));
    return true;
  };
  // Progress: the crossings looked at as the first half, the corners (a list that grows) as the
  // second, never going back.
  std::size_t crossings = 0, looked_at = 0;
  double reported = 0;
  const auto report = [&](double share) {
    if (share <= reported) return;
    reported = share;
    options.progress(share);
  };
  if (options.progress) grid.for_each_sign_change([&](const std::array<int, 3>&, const std::array<int, 3>&) { ++crossings; });
  grid.for_each_sign_change([&](const std::array<int, 3>& ia, const std::array<int, 3>& ib) {
    if (options.cancel) options.cancel->check("trace_creases");
    if (options.progress && ++looked_at % kProgressSteps == 0)
      report(0.5 * static_cast<double>(looked_at) / static_cast<double>(crossings));
    const Vec3 pa = grid.point(ia[0], ia[1], ia[2]), pb = grid.point(ib[0], ib[1], ib[2]);
    const double fa = grid.value(ia[0], ia[1], ia[2]), fb = grid.value(ib[0], ib[1], ib[2]);
    const ProjectionResult s = project_to_surface(field, pa + fa / (fa - fb) * (pb - pa));
    if (!s.ok()) return;
    // The two pieces taken nearest the crossing whose crease lies within a cell.
    const std::vector<FieldPiece> near = field.pieces_first_order(s.point, grid.h);
    if (near.size() < 2) return;
    for (std::size_t i = 0; i < near.size(); ++i)
      for (std::size_t j = i + 1; j < near.size(); ++j) {
        const std::vector<Branch> two{near[i].branch, near[j].branch};
        const std::array<std::pair<double, Vec3>, 2> at_s{std::pair{near[i].value, near[i].gradient},
                                                          std::pair{near[j].value, near[j].gradient}};
        const CreaseProjection c = project_to_crease(field, s.point, two, at_s, options.newton);
        if (!c.ok() || (c.point - s.point).norm() > 2 * grid.h) continue;
        const Vec3 g0 = c.gradients[0].normalized(), g1 = c.gradients[1].normalized();
        // Pieces that are one by their normals bend nothing there: no crease starts. Pieces that
        // differ only by rounding do (a smooth difference's blend, d0 - (d1 + d0) h at h = 1,
        // leaves the two sides of d0's max in its last bits: on fogleman/sdf's model with
        // smoothed holes, 227 crease curves of 1 to 21 points inside the holes' walls).
        if (g0.dot(g1) > kSamePieceCosine || touching_faces(g0, g1)) continue;
        if (start_curve(c, two, true)) return;
      }
  });
  join_crossings(field, tr.min_spacing, result, corners);
  split_at_corners(field, tr.min_spacing, result, corners);
  // Every crease that leaves a corner, traced from it where no curve ends there along it: a
  // crease shorter than about a grid cell between two corners may pass no crossed grid edge
  // near enough to be found from the crossings (a table top 0.05 thick with a leg under it: two
  // of its four vertical edges were missed, and the patch boundary broke off at their corners).
  // The corners found so grow the list, each taken once.
  //
  // And where a hidden seam ends alone at a corner, the other hidden seams that leave it
  // (Tracer::seams_leaving).
  struct Leaving {
    Vec3 direction, n0, n1;
  };
  std::vector<Vec3> visited;
  const std::size_t split_already = corners.size();
  for (std::size_t next = 0; next < corners.size(); ++next) {
    if (options.cancel) options.cancel->check("trace_creases");
    if (options.progress && next % kProgressSteps == 0)
      report(0.5 + 0.5 * static_cast<double>(next) / static_cast<double>(corners.size()));
    const Vec3 corner = corners[next];
    if (std::any_of(visited.begin(), visited.end(), [&](const Vec3& q) { return (q - corner).norm() <= tr.min_spacing; }))
      continue;
    visited.push_back(corner);
    // A corner this pass found (where a seam it walked ran into a crease) cuts the curves through
    // it too, before the ways they leave it are looked at: a box's bottom edge, crossed by the
    // seams from the corners of a smooth union's flat blend beside it, was traced twice more
    // from such corners, taken for a crease leaving them.
    if (next >= split_already) split_at_corners(field, tr.min_spacing, result, std::vector<Vec3>{corner});
    // The directions the curves ending here leave along, with their pieces' normals.
    std::vector<Leaving> leaving;
    // A seam that ends here (its index: the pass below may add curves), and whether at its back.
    std::optional<std::size_t> seam_end;
    bool seam_end_back = false;
    for (std::size_t c = 0; c < result.curves.size(); ++c) {
      const CreaseCurve& curve = result.curves[c];
      const std::size_t n = curve.points.size();
      if (curve.closed || n < 2) continue;
      for (const bool back : {false, true}) {
        if (!(back ? curve.ends_at_corner : curve.starts_at_corner)) continue;
        const Vec3& end = back ? curve.points[n - 1] : curve.points[0];
        if ((end - corner).norm() > tr.min_spacing) continue;
        if (curve.seam_branch >= 0) seam_end = c, seam_end_back = back;
        const Vec3& inner = back ? curve.points[n - 2] : curve.points[1];
        leaving.push_back({(inner - end).normalized(), field.piece_first_order(corner, curve.pieces[0]).second.normalized(),
                           field.piece_first_order(corner, curve.pieces[1]).second.normalized()});
      }
    }
    const std::vector<FieldPiece> at = field.pieces_first_order(corner, kCornerReach * tr.min_spacing);
    for (std::size_t i = 0; i < at.size(); ++i)
      for (std::size_t j = i + 1; j < at.size(); ++j) {
        const Vec3 g0 = at[i].gradient.normalized(), g1 = at[j].gradient.normalized();
        if (!(g0.dot(g1) <= kSamePieceCosine) || touching_faces(g0, g1)) continue;
        const Vec3 t = g0.cross(g1).normalized();
        const std::vector<Branch> two{at[i].branch, at[j].branch};
        for (const double dir : {1.0, -1.0}) {
          const bool known = std::any_of(leaving.begin(), leaving.end(), [&](const Leaving& l) {
            const bool same = (l.n0.dot(g0) > kSamePieceCosine && l.n1.dot(g1) > kSamePieceCosine) ||
                              (l.n0.dot(g1) > kSamePieceCosine && l.n1.dot(g0) > kSamePieceCosine);
            return same && l.direction.dot(dir * t) > 0;
          });
          if (known) continue;
          const double step = kCornerStep * tr.min_spacing;
          const CreaseProjection c = project_to_crease(field, corner + dir * step * t, two, options.newton);
          if (!c.ok() || (c.point - corner).norm() > 2 * step || (c.point - corner).dot(dir * t) <= 0) continue;
          if (start_curve(c, two, false))
            leaving.push_back({dir * t, g0, g1});
        }
      }
    if (seam_end && leaving.size() == 1) {  // a dead end: the patches beside the seam close nowhere
      // The way the seam leaves, to a point a few min_spacing off: a seam that ran into a crease
      // ends where the crease is nearest its last point, and its last segment may leave that
      // corner at any angle.
      const std::vector<Vec3>& P = result.curves[*seam_end].points;
      const std::size_t n = P.size();
      const Vec3& end = seam_end_back ? P[n - 1] : P[0];
      Vec3 far = seam_end_back ? P[n - 2] : P[1];
      for (std::size_t i = 1; i < n && (far - end).norm() < 2 * kCornerStep * tr.min_spacing; ++i)
        far = seam_end_back ? P[n - 1 - i] : P[i];
      std::vector<Vec3> seam_leaving{(far - end).normalized()};
      for (CreaseCurve& curve : tr.seams_leaving(corner, at, seam_leaving)) {
        if (curve.ends_at_corner) corners.push_back(curve.points.back());
        else ++result.stops;
        for (std::size_t j = 0; j < curve.points.size(); ++j) traced.insert(curve.points[j], result.curves.size(), j);
        result.curves.push_back(std::move(curve));
      }
    }
  }
  drop_duplicate_curves(tr.min_spacing, kOnTracedCurve * tr.max_spacing, result);
  // Corners once: the ends of several curves meet at each, each found to the Newton tolerance.
  for (const Vec3& c : corners) {
    const bool seen = std::any_of(result.corners.begin(), result.corners.end(),
                                  [&](const Vec3& q) { return (q - c).norm() <= tr.min_spacing; });
    if (!seen) result.corners.push_back(c);
  }
  return result;
}

}  // namespace cdp
