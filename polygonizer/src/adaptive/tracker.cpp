#include "tracker.h"
#include "crease_probe.h"
#include "../background_release.h"
#include "../polled_growth.h"

#include <cdp/core/crease.h>
#include <cdp/core/errors.h>
#include <cdp/core/triangle_geometry.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>

namespace cdp::adaptive {

namespace {
// A placement walks on when Newton lands less than this share of the step from where it
// started, in up to kWalkLegs legs (a cube's crease takes three: onto the crease, off it, on).
constexpr double kShortLanding = 0.75;
constexpr int kWalkLegs = 4;
// A landing curved more tightly than the step by this many radii, whose normal turned more than
// kJumpTurnExplained times what the origin's curvature explains over the step, is suspected of a
// jump to another sheet (see jumped). Beads of radius 0.015-0.025 a few hundredths beside a unit
// sphere at factor 3 (steps of 0.33) landed at 13-23 radii, turned 3.6 times that; a neck between
// two of 200 Wyvill blobs at factor 2 at 9 radii, 5.6 times, and is the same sheet.
constexpr double kJumpRadii = 8;
constexpr double kJumpTurnExplained = 2;
// A suspected landing is the same sheet when two half steps end within this share of the step
// of it, with normals within kHalvesCosine of its (a neck: the same point; a bead: the half
// steps stay on the sheet, 0.05-0.08 and 60-70 degrees away).
constexpr double kHalvesReach = 0.25;
constexpr double kHalvesCosine = 0.866;
// A black box's placement whose normal turned more than kKinkTurn beyond what the curvature at
// its two ends explains (Tracker::unexplained_turn) is looked at for a crease between them
// (kink_between): its path is halved towards the half whose own turn is the less explained while
// that half keeps at least kKinkConcentration of it and more than kKinkTurn (across a crease
// nearly all of it, its angle; curvature the ends did not predict, where it changes along the
// step, about half, and less each halving), at most kKinkHalvings times, and while each halving
// shortens the step by kKinkShrink at least (two ends on two sheets a gap apart stay that far).
// What counts is a turn of kKinkTurn within the differences' step h, so a fillet whose radius is
// under about 7-14 h, where the curvature jumps from a face's to its own, is one too: a box
// rounded by 2 and 5 h stopped, by 10 h and more meshed (h = 1e-4 of the diagonal: fillets far
// under the default min_edge). The first test takes the far end's curvature alone, no
// evaluation, at half the threshold (its one-sided prediction misses more).
constexpr double kKinkTurn = 4 * std::numbers::pi / 180;
constexpr double kKinkShrink = 0.75;
constexpr double kKinkConcentration = 0.6;
constexpr int kKinkHalvings = 30;
// place_points' Newton evaluates a point with its Hessian where the point before it was within
// this many tolerances of the surface (BatchProjector::project's hessians_below): a Newton step
// from there nearly always converges (the error squares), and where it does, the curvature's
// Hessian is at hand instead of evaluated again at the same point. Every projection of the
// bunny VIS-800 at factor 3 (13,208, the relaxation's too) traced and replayed: with 1e4,
// 10,111 points would be evaluated so and every one ends its projection; with 3e4, 12,933 of
// which 12,441 end; with 1e3, 8,269 and 8,269. The run then makes 35,506 value-and-gradient
// calls instead of 41,014 and the same 8,267 Hessians, and the same mesh.
constexpr double kHessianResidualTolerances = 1e4;
// A new point this close to a finished vertex (in units of the step) lies on finished mesh.
constexpr double kOverMesh = 0.3;
// A manifold mesh with c components, genus g and b borders of E_b edges in all has
// T = 2V - E_b + 2b + 4g - 4c triangles on V vertices, at most 2V + 4g; a handle of a mesh the
// tracker makes holds far more than 4 vertices, so T stays below 3V. The Barth ball at factor 3
// went on making triangles between the 415,118 vertices it had (5.7 million triangles after
// 18 million steps, about 0.3 a step and 0.4 units of area per 262,144 steps): a front stuck
// in a cycle of closures and splits over finished mesh. The search bound used to stop it, by
// the cost of its searches among crowded vertices, until the vertex hash split crowded cells.
constexpr std::size_t kTrianglesPerVertex = 3;
constexpr std::size_t kTriangleSlack = 64;  // the first hexagon and other tiny meshes, with room
// longest_front_edge polls the cancel token every so many stale entries popped: about a
// millisecond's work, and an atomic load next to it costs nothing.
constexpr std::size_t kStalePollEvery = 4096;
}  // namespace

Tracker::Tracker(const Field& field, const Settings& settings, Mesh& mesh)
    : field_(field), s_(settings), mesh_(mesh),
      front_hash_(settings.hash_cell), vertex_hash_(settings.hash_cell, Crowding::split), finer_zones_(settings.finer_zones) {
  front_hash_.set_cancel(s_.cancel);
  vertex_hash_.set_cancel(s_.cancel);
  fs_.cancel = s_.cancel;
  // A black box its caller promises smooth is not searched for kinks between vertices
  // (kink_between also takes a fillet of a few differences' steps for one).
  kink_radius_ = field.smooth() ? 0 : field.derivative_step().value_or(0);
}

TrackerReport Tracker::report() const {
  TrackerReport r;
  r.steps = steps_;
  r.search_visits = search_visits();
  r.deferrals = deferrals_;
  r.anticipations = anticipations_;
  r.side_points = side_points_;
  r.forced_closures = forced_closures_;
  r.rollbacks = rollbacks_;
  r.rollbacks_failed = failed_rollbacks_;
  r.crease_points = crease_points_;
  r.over_mesh_rejections = over_mesh_;
  r.sheet_jumps = sheet_jumps_;
  r.curvature_seconds = curvature_seconds_;
  r.hessian_seconds = hessian_seconds_;
  return r;
}

void add_tracker_counts(TrackerReport& sum, const TrackerReport& r) {
  sum.steps += r.steps;
  sum.search_visits += r.search_visits;
  sum.deferrals += r.deferrals;
  sum.anticipations += r.anticipations;
  sum.side_points += r.side_points;
  sum.forced_closures += r.forced_closures;
  sum.rollbacks += r.rollbacks;
  sum.rollbacks_failed += r.rollbacks_failed;
  sum.crease_points += r.crease_points;
  sum.over_mesh_rejections += r.over_mesh_rejections;
  sum.sheet_jumps += r.sheet_jumps;
  sum.curvature_seconds += r.curvature_seconds;
  sum.hessian_seconds += r.hessian_seconds;
}

void Tracker::release_bulk() {
  released_visits_ = search_visits();
  const auto drop = [](auto& x) { std::decay_t<decltype(x)>(std::move(x)); };
  drop(front_hash_), drop(vertex_hash_), drop(fs_), drop(front_edges_);
  unhashed_ = 0;
  drop(target_), drop(mac_), drop(shape_index_), drop(front_refs_), drop(dead_), drop(loop_vertex_);
}

void Tracker::release_in_background() noexcept {
  detail::release_in_background(front_hash_, vertex_hash_, fs_, target_, mac_, shape_index_, front_refs_, dead_,
                                loop_vertex_, critical_starts_);
}

void Tracker::measure(std::span<const Vec3> points, std::vector<std::optional<Placed>>& out,
                      std::span<const Known> known) const {
  // Timed in two parts, so that the stats can show what the paper claims (curvature costs
  // little) for each of its costs: the field's Hessian, and the eigen-decomposition of C.
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  const std::size_t n = points.size();
  DerivativeBuffers& d = derivatives_;
  // The points without a known Hessian, evaluated in one call.
  d.which.clear();
  d.points.clear();
  for (std::size_t i = 0; i < n; ++i)
    if (known.empty() || !known[i].hessian) d.which.push_back(i), d.points.push_back(points[i]);
  const std::size_t m = d.which.size();
  d.values.resize(m);
  d.gradients.resize(m);
  d.hessians.resize(m);
  if (m > 0) field_.gradients_hessians(d.points.data(), d.values.data(), d.gradients.data(), d.hessians.data(), m);
  const auto evaluated = Clock::now();
  out.assign(n, std::nullopt);
  for (std::size_t i = 0, k = 0; i < n; ++i) {
    const bool here = k < m && d.which[k] == i;
    const Vec3& g = here ? d.gradients[k] : *known[i].gradient;
    const Mat3& h = here ? d.hessians[k] : *known[i].hessian;
    if (here) ++k;
    try {
      out[i] = Placed{points[i], curvature_from_derivatives(g, h), step_to_critical_point(g, h)};
    } catch (const NoSurfaceError&) {
    }
    if (out[i] && s_.grading)
      out[i]->seam_target =
          seam_edge_length(field_, s_.sizing, points[i], edge_length(s_.sizing, out[i]->curvature.min_radius));
    if (out[i] && !out[i]->curvature.normal.allFinite()) out[i].reset();
  }
  const auto done = Clock::now();
  hessian_seconds_ += std::chrono::duration<double>(evaluated - start).count();
  curvature_seconds_ += std::chrono::duration<double>(done - start).count();
}

int Tracker::add_vertex(const Placed& placed) {
  const Curvature& c = placed.curvature;
  const int v = static_cast<int>(mesh_.positions.size());
  detail::grow_apart(s_.cancel, "adaptive", 1, mesh_.positions, mesh_.normals, target_, mac_, shape_index_, front_refs_);
  mesh_.positions.push_back(placed.point);
  mesh_.normals.push_back(c.normal);
  target_.push_back(placed_target(placed));
  if (c.min_radius < tightest_.first) tightest_ = {c.min_radius, placed.point};
  if (s_.stop_at_kink && c.min_radius < kink_radius_)
    throw BlackBoxKinkError("adaptive: a vertex placed near " + format_point(placed.point) +
                            " lies on a kink of a field without branch data, which creases: follow cannot follow");
  if (placed.to_critical && placed.to_critical->norm() <= kCriticalReach * target_.back())
    critical_starts_.push_back({placed.point, *placed.to_critical, target_.back()});
  mac_.push_back(c.mac);
  shape_index_.push_back(c.shape_index);
  front_refs_.push_back(0);
  vertex_hash().insert(v, placed.point, vertex_position());
  return v;
}

std::vector<Tracker::Placed> Tracker::place_points(int v, std::span<const Vec3> dirs, double d) const {
  // Walk d along the surface in each direction: a straight step in the tangent plane, then Newton.
  // Where Newton lands on a crease well short of d (the projection does not cross creases), the
  // walk goes on from there in the tangent plane of the crease point with what is left of d, at
  // most kWalkLegs legs, so that fronts fold over creases instead of piling points onto them.
  // The walks advance together, each leg's field evaluations batched across them; a walk's
  // course depends on nothing but its own direction, so it ends as it would alone.
  PlacementBuffers& b = placement_;
  const Vec3& origin = mesh_.positions[v];
  b.walks.clear();
  for (const Vec3& dir : dirs) {
    Walk& w = b.walks.emplace_back();
    w.at = origin;
    w.normal = mesh_.normals[v];
    w.heading = dir;
    w.left = d;
  }
  ProjectionOptions po;
  po.tolerance = 1e-10 * s_.diagonal;

  for (int leg = 0; leg < kWalkLegs; ++leg) {
    b.legging.clear();
    b.starts.clear();
    b.options.clear();
    for (std::size_t i = 0; i < b.walks.size(); ++i) {
      const Walk& w = b.walks[i];
      if (!w.walking) continue;
      b.legging.push_back(i);
      b.starts.push_back(w.at + w.left * w.heading);
      po.max_step = w.left;
      po.max_travel = w.left;
      b.options.push_back(po);
    }
    if (b.legging.empty()) break;
    const std::span<const ProjectionResult> r =
        b.newton.project(field_, b.starts, b.options, kHessianResidualTolerances * po.tolerance);
    hessian_seconds_ += b.newton.hessian_seconds();
    curvature_seconds_ += b.newton.hessian_seconds();
    b.landed.clear();
    b.known.clear();
    for (std::size_t k = 0; k < b.legging.size(); ++k) {
      if (r[k].ok()) {
        b.landed.push_back(r[k].point), b.walks[b.legging[k]].start_gradient = r[k].start_gradient;
        b.known.push_back({&r[k].gradient, b.newton.hessian(k)});
      } else {
        b.walks[b.legging[k]].failed = true, b.walks[b.legging[k]].walking = false;
      }
    }
    measure(b.landed, b.measured, b.known);
    // Across a crease of a CSG shape the gradient turns at once; a point on the crease gets the
    // mean of the normals on both sides, so that both sides see it as theirs. Newton runs along
    // the gradient, which turns little on the way over a smooth surface; a gradient at the start
    // that points elsewhere than the one where it lands means the path crossed a crease, and the
    // landing point may lie on it even though its own gradient is one side's (at a tie of max or
    // min, the cube's edges, the gradient is one piece's, the same as the origin's face).
    const auto probe = [&](const Walk& w) {
      const Vec3& g0 = w.start_gradient;
      const Vec3& landed = w.placed->curvature.normal;
      const bool turned = !(g0.squaredNorm() > 0) || g0.normalized().dot(landed) < kCreaseCosine;
      return turned || !same_side(w.normal, landed);
    };
    b.crease_at.clear();
    b.crease_n.clear();
    std::size_t m = 0;
    for (const std::size_t i : b.legging) {
      Walk& w = b.walks[i];
      if (w.failed) continue;
      w.placed = std::move(b.measured[m++]);
      if (!w.placed) w.failed = true, w.walking = false;
      else if (probe(w))
        b.crease_at.push_back(w.placed->point), b.crease_n.push_back(w.placed->curvature.normal);
    }
    crease_normals(b.crease_at, b.crease_n, b.creases);
    std::size_t c = 0;
    for (const std::size_t i : b.legging) {
      Walk& w = b.walks[i];
      if (w.failed) continue;
      bool on_crease = false;
      if (probe(w)) {
        const std::optional<Vec3>& crease = b.creases[c++];
        if (crease) {
          if (!same_side(w.normal, *crease)) {
            w.failed = true, w.walking = false;
            continue;
          }
          w.placed->curvature.normal = *crease;
          ++w.creases;
          on_crease = true;
        } else if (!same_side(w.normal, w.placed->curvature.normal)) {
          w.failed = true, w.walking = false;
          continue;
        }
      }
      // A black box's crease crossed between two points the differences resolve: the chord cuts it.
      // Meshing across (no stop_at_kink), one kink found is all the report says (across_black_box,
      // and no run made again): the halvings are not paid at every crossing after it.
      if (kink_radius_ > 0 && !on_crease && (s_.stop_at_kink || !(tightest_.first < kink_radius_))) {
        if (const auto kink = kink_between(w.at, w.normal, *w.placed)) {
          if (kink->first < tightest_.first) tightest_ = *kink;
          if (s_.stop_at_kink)
            throw BlackBoxKinkError("adaptive: a step from " + format_point(w.at) + " to " +
                                    format_point(w.placed->point) + " crosses a kink of a field without branch data near " +
                                    format_point(kink->second) + ", which creases: follow cannot follow");
        }
      }
      if (leg == 0 && !on_crease && d > s_.sizing.min_edge &&
          w.normal.dot(w.placed->curvature.normal) < kMaxTurnCosine) {
        w.failed = true, w.walking = false;
        continue;
      }
      // Only where Newton ran straight: a path that turned crossed a crease (see probe), where
      // a black box's differences curve tightly on the sheet itself.
      if (leg == 0 && !on_crease && d > s_.sizing.min_edge && !probe(w) && jumped(v, w.heading, d, *w.placed)) {
        ++sheet_jumps_;
        w.failed = true, w.walking = false;
        continue;
      }
      const double moved = (w.placed->point - w.at).norm();
      w.left -= moved;
      w.at = w.placed->point;
      if (!on_crease || w.left <= (1 - kShortLanding) * d || leg + 1 == kWalkLegs) {
        w.walking = false;
        continue;
      }
      w.normal = w.placed->curvature.normal;
      w.heading -= w.normal * w.normal.dot(w.heading);
      if (!(w.heading.squaredNorm() > 1e-12)) w.walking = false;
      else w.heading.normalize();
    }
  }

  // The points as placing them one after another gives them: up to the first that fails, whose
  // creases still count; the final checks look at the mesh and run only for the points wanted.
  std::vector<Placed> out;
  out.reserve(b.walks.size());
  for (const Walk& w : b.walks) {
    crease_points_ += w.creases;
    if (w.failed) break;
    // Newton may jump to a nearby sheet of the surface; such a point is not a neighbour of v.
    const double dist = (w.at - origin).norm();
    if (dist < 0.25 * d || dist > 1.75 * d) break;
    if (over_finished_mesh(w.placed->point, w.placed->curvature.normal, d)) break;
    if (point_test_ && !point_test_(w.placed->point, d)) {
      ++patch_refusals_;
      break;
    }
    out.push_back(*w.placed);
  }
  return out;
}

namespace {

double angle_between(const Vec3& p, const Vec3& q) { return std::acos(std::clamp(p.dot(q), -1.0, 1.0)); }

// n turned by the rotation vector r (its axis, its angle in radians; Rodrigues).
Vec3 rotated(const Vec3& n, const Vec3& r) {
  const double angle = r.norm();
  if (!(angle > 0)) return n;
  const Vec3 k = r / angle;
  return n * std::cos(angle) + k.cross(n) * std::sin(angle) + k * k.dot(n) * (1 - std::cos(angle));
}

// The rotation the unit normal makes along the chord `c` by the curvature C (dn = C dx) at one of
// its ends, normal n: the chord's tangent part carried by C, as an axis times an angle.
Vec3 rotation_along(const Vec3& n, const Mat3& C, const Vec3& c) {
  const Vec3 t = c - n * n.dot(c);
  const double tangent = t.norm();
  if (!(tangent > 0)) return Vec3::Zero();
  // Stretched to the chord's length (the arc the normal turns over), at most twice: a chord
  // nearly along the normal has no tangent part worth stretching.
  return n.cross(C * (t * std::min(2.0, c.norm() / tangent)));
}

// How far the normal n at p, carried to x by the curvature C at p alone, misses nx, x's own.
double one_sided_miss(const Vec3& p, const Vec3& n, const Mat3& C, const Vec3& x, const Vec3& nx) {
  return angle_between(rotated(n, rotation_along(n, C, x - p)), nx);
}

}  // namespace

double Tracker::unexplained_turn(const Vec3& pa, const Curvature& ka, const Vec3& pb, const Curvature& kb) {
  // The normal at b predicted from a's by the mean of the rotations the two ends' curvature
  // gives along the chord (second order: a sphere at factor 1, a chord of a radian, 2 degrees
  // off), against b's own. Across a crease the faces' curvature explains the faces' turn and
  // leaves the crease's angle, convex or concave alike (where the raw turn, a concave crease's
  // angle taken from the faces' turn, can be none at all).
  const Vec3 c = pb - pa;
  const Vec3 r = 0.5 * (rotation_along(ka.normal, ka.C, c) + rotation_along(kb.normal, kb.C, c));
  return angle_between(rotated(ka.normal, r), kb.normal);
}

std::optional<std::pair<double, Vec3>> Tracker::kink_between(const Vec3& a, const Vec3& na, const Placed& landed) const {
  // A crease the differences do not straddle at either end: both ends' curvature is a face's,
  // and only the turn between them that curvature does not explain shows it.
  const Curvature& kb = landed.curvature;
  const Vec3& b = landed.point;
  // First from b's curvature alone (no evaluation: a crease is rare): a's normal as b's predicts.
  if (!(one_sided_miss(b, kb.normal, kb.C, a, na) > 0.5 * kKinkTurn)) return {};
  Curvature ka;
  try {
    ka = curvature_at(field_, a);
  } catch (const NoSurfaceError&) {
    return {};  // no normal at a after all: nothing to compare
  }
  double turn = unexplained_turn(a, ka, b, kb);
  if (!(turn > kKinkTurn)) return {};
  // Halved towards the crease: the midpoint's normal (from its gradient, whose differences are
  // narrower than the Hessian's by default) as each end's face curvature carries its own normal there;
  // the face that predicts it holds the midpoint, the crease lies in the other half. Each end
  // keeps its face's curvature (the midpoint's own, within the Hessian's step of the crease,
  // would be the differences' blur of it).
  Vec3 pa = a, pb = b, qa = ka.normal, qb = kb.normal;
  ProjectionOptions po;
  po.tolerance = 1e-10 * s_.diagonal;
  double before = std::numeric_limits<double>::infinity();
  for (int i = 0; i < kKinkHalvings; ++i) {
    const double length = (pb - pa).norm();
    // A turn of a crease's within the differences' step: what they cannot resolve. The bend
    // reported is that length (Tracking::tightest: under the step, as a vertex's radius on a kink).
    if (length < kink_radius_) return std::pair(length, Vec3(0.5 * (pa + pb)));
    if (!(length < kKinkShrink * before)) return {};
    before = length;
    po.max_step = po.max_travel = length;
    const ProjectionResult m = project_to_surface(field_, 0.5 * (pa + pb), po);
    if (!m.ok() || !(m.gradient.squaredNorm() > 0) || !m.gradient.allFinite()) return {};
    const Vec3 nm = m.gradient.normalized();
    const double from_a = one_sided_miss(pa, qa, ka.C, m.point, nm), from_b = one_sided_miss(pb, qb, kb.C, m.point, nm);
    const double left = std::max(from_a, from_b);
    // Neither face holds the midpoint (a bend the ends' curvature did not predict, as within a
    // fillet), or what is left fades under a crease's turn: no kink.
    if (!(left >= kKinkConcentration * turn) || !(left > kKinkTurn)) return {};
    if (from_a <= from_b) pa = m.point, qa = nm;
    else pb = m.point, qb = nm;
    turn = left;
  }
  return {};
}

bool Tracker::jumped(int v, const Vec3& heading, double d, const Placed& landed) const {
  // Newton from a point of the tangent plane lands on whatever sheet lies nearest, and a small
  // component beside the surface (a bead a step away, whose normal there can lie within the turn
  // bound) can be nearer than the sheet the front walks on. Its landing is curved far more tightly
  // than the step, and turned more than the origin's curvature explains; the sheet's own
  // landings seldom are both (a neck between blobs is), so only those are checked, by walking
  // the same way in two half steps: on the same sheet they end where the one step did.
  const Vec3& origin = mesh_.positions[v];
  const Vec3& normal = mesh_.normals[v];
  const Curvature& k = landed.curvature;
  if (!(d * k.mac > kJumpRadii)) return false;
  const double turn = angle_between(normal, k.normal);
  if (!(turn > kJumpTurnExplained * mac_[v] * d)) return false;
  ProjectionOptions po;
  po.tolerance = 1e-10 * s_.diagonal;
  po.max_step = po.max_travel = 0.5 * d;
  const ProjectionResult half = project_to_surface(field_, origin + 0.5 * d * heading, po);
  if (!half.ok() || !(half.gradient.squaredNorm() > 0) || !half.gradient.allFinite()) return true;
  const Vec3 n = half.gradient.normalized();
  Vec3 on = heading - n * n.dot(heading);
  if (!same_side(normal, n) || !(on.squaredNorm() > 1e-12)) return true;
  const ProjectionResult end = project_to_surface(field_, half.point + 0.5 * d * on.normalized(), po);
  if (!end.ok() || !(end.gradient.squaredNorm() > 0) || !end.gradient.allFinite()) return true;
  return (end.point - landed.point).norm() > kHalvesReach * d || end.gradient.normalized().dot(k.normal) < kHalvesCosine;
}

bool Tracker::over_finished_mesh(const Vec3& x, const Vec3& normal, double d) const {
  // A new point next to a vertex that has left every front lies on finished mesh: a front has
  // run over it and would go on meshing the surface again. Refused, such placements turn a
  // runaway front into a stalled one, which the stall bounds end with an error naming the place.
  const double r = kOverMesh * d;
  const bool hit = vertex_hash().any_in(x.array() - r, x.array() + r, [&](int w) {
    return front_refs_[w] == 0 && (mesh_.positions[w] - x).norm() < r && same_side(normal, w);
  });
  if (hit) ++over_mesh_;
  return hit;
}

void Tracker::crease_normals(std::span<const Vec3> xs, std::span<const Vec3> ns,
                             std::vector<std::optional<Vec3>>& out) const {
  // On a crease of max(f, g) (or min) the gradient at x is one side's; a step just inside or
  // just outside along it makes the other side's piece the active one. Both probes of every
  // point go to the field in one batch: 2i just inside, 2i + 1 just outside.
  const std::size_t n = xs.size();
  out.assign(n, std::nullopt);
  if (n == 0) return;
  const CreaseProbe probe(s_.diagonal);
  std::vector<Vec3> probes(2 * n), gradients(2 * n);
  std::vector<double> values(2 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::array<Vec3, 2> around = probe.points(xs[i], ns[i]);
    probes[2 * i] = around[0];
    probes[2 * i + 1] = around[1];
  }
  field_.values_gradients(probes.data(), values.data(), gradients.data(), 2 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3& x_normal = ns[i];
    Vec3 best = x_normal;
    for (int s = 0; s < 2; ++s) {
      const Vec3& g = gradients[2 * i + s];
      if (!(g.squaredNorm() > 0) || !g.allFinite()) continue;
      const Vec3 u = g.normalized();
      if (u.dot(x_normal) < best.dot(x_normal)) best = u;
    }
    if (!(best.dot(x_normal) < kCreaseCosine)) continue;
    const Vec3 mean = x_normal + best;
    if (!(mean.squaredNorm() > 1e-6)) continue;
    out[i] = mean.normalized();
  }
}

std::string Tracker::sheets_closer_than_edges(const Vec3& p, double edge) {
  sheets_gap_ = sheets_apart(field_, p, edge);
  return sheets_gap_ ? sheets_advice(field_, *sheets_gap_, edge, s_.sizing.min_edge) : "";
}

std::optional<double> sheets_apart(const Field& field, const Vec3& p, double edge) {
  // The nearest other sheet along the normal at p, within kOtherSheetReach edges either way: the
  // first sample of the sign p's side of the surface does not have, then halvings to it.
  Vec3 g;
  field.value_gradient(p, g);
  if (!(g.norm() > 0) || !g.allFinite() || !(edge > 0) || !std::isfinite(edge)) return std::nullopt;
  const Vec3 n = g.normalized();
  const double h = kOtherSheetReach * edge / kOtherSheetSamples;
  double gap = std::numeric_limits<double>::infinity();
  for (const double side : {-1.0, 1.0}) {
    const auto other_sheet = [&](double s) { return field.value(p + side * s * n) * side < 0; };
    for (int k = 1; k <= kOtherSheetSamples && k * h < gap; ++k) {
      if (!other_sheet(k * h)) continue;
      double lo = (k - 1) * h, hi = k * h;  // the second sheet lies between
      for (int i = 0; i < kOtherSheetHalvings; ++i) (other_sheet(0.5 * (lo + hi)) ? hi : lo) = 0.5 * (lo + hi);
      gap = std::min(gap, hi);
      break;
    }
  }
  if (!(gap < edge)) return std::nullopt;
  return gap;
}

std::string sheets_advice(const Field& field, double gap, double edge, double min_edge) {
  // A front meets the other sheet's mesh as its own where they are closer than its edges, and the
  // seed grid misses the sheets' area where they are closer than about a third of its cells: a
  // sphere's shell 0.02 thick meshes at factor 1 with max_edge 0.04, one 0.01 thick with max_edge
  // 0.02 once the grid's cells are 0.034 (seed_resolution 64 in a box of 2.2).
  const double side = field.bounds().size().maxCoeff();
  const double resolution = std::ceil(side / (kSheetGridCells * gap));
  std::string advice = "; the surface there has two sheets " + std::to_string(gap) +
                       " apart (a thin wall or gap), closer than the edges there (" + std::to_string(edge) +
                       "): max_edge at most " + std::to_string(2 * gap);
  if (2 * gap < min_edge) advice += " with min_edge below it";
  if (std::isfinite(resolution)) advice += " and seed_resolution at least " + std::to_string(static_cast<long>(resolution));
  return advice + " keep each front on its own sheet";
}

void Tracker::emit_triangle(int a, int b, int c) {
  // The last triangle again, either way round: no manifold mesh has a triangle twice, and a
  // front that has made it twice makes it again and again (fogleman/sdf's knurling example,
  // meshed across its creases at factor 1: one triangle 39,178 times, each way round in turn,
  // its front pinched at a corner of it, for 50 s until kTrianglesPerVertex's bound below).
  if (!mesh_.triangles.empty()) {
    std::array<int, 3> last = mesh_.triangles.back(), made{a, b, c};
    std::sort(last.begin(), last.end());
    std::sort(made.begin(), made.end());
    if (last == made)
      throw LimitExceededError("adaptive: a front is meshing finished mesh again near " +
                               format_point(mesh_.positions[a]) + ": it made the same triangle twice");
  }
  detail::grow_apart(s_.cancel, "adaptive", 1, mesh_.triangles);
  mesh_.triangles.push_back({a, b, c});
  const Vec3& pa = mesh_.positions[a];
  area_ += 0.5 * (mesh_.positions[b] - pa).cross(mesh_.positions[c] - pa).norm();
  if (estimated_area_ > 0 && area_ > kAreaBound * estimated_area_)
    throw LimitExceededError("adaptive: the mesh covers more than " + std::to_string(static_cast<int>(kAreaBound)) +
                             " times the area the seed grid measures; a front is running over finished mesh near " +
                             format_point(pa) + sheets_closer_than_edges(pa, longest_edge(pa, mesh_.positions[b], mesh_.positions[c])));
  // Triangles made again on vertices already meshed, which the area bound sees late or never
  // (each adds little area; kTrianglesPerVertex says why no manifold mesh gets here).
  if (mesh_.triangles.size() > kTrianglesPerVertex * mesh_.positions.size() + kTriangleSlack)
    throw LimitExceededError("adaptive: the mesh has " + std::to_string(mesh_.triangles.size()) + " triangles on " +
                             std::to_string(mesh_.positions.size()) +
                             " vertices, more than a manifold mesh can have; a front is meshing finished mesh "
                             "again near " +
                             format_point(pa));
  if (mesh_.triangles.size() > s_.max_triangles)
    throw LimitExceededError("adaptive: more than " + std::to_string(s_.max_triangles) +
                             " triangles (AdaptiveOptions::max_triangles); raise the limit, the minimum edge "
                             "length or lower the factor");
}

void Tracker::link(int a, int b) {
  fs_.link(a, b);
  if (front_edges_.size() >= drop_stale_at_) drop_stale_front_edges();
  detail::grow_apart(s_.cancel, "adaptive", 1, front_edges_);
  const Vec3& from = mesh_.positions[fs_.nodes[a].vertex];
  const double length = (from - mesh_.positions[fs_.nodes[b].vertex]).norm();
  front_edges_.emplace_back(length, a, b);
  std::push_heap(front_edges_.begin(), front_edges_.end());
  front_hash_.widen_reach(from, length);
}

void Tracker::drop_stale_front_edges() {
  // Lazy deletion alone keeps every edge a front ever had: millions of entries at 2*10^6
  // triangles (28 MiB of the peak), which longest_front_edge popped a million at a time. Each
  // time the heap has doubled, the entries that are stale now are dropped (they never become
  // live again: a node's next changes only through link, which pushes the new edge, and a node
  // that left the fronts does not come back) and the heap made anew: amortized constant work a
  // link. Only the longest live length is ever read, and it is the same.
  std::size_t kept = 0;
  for (std::size_t i = 0; i < front_edges_.size(); ++i) {
    if (i % kStalePollEvery == 0) s_.cancel.check("adaptive");
    const auto& [length, a, b] = front_edges_[i];
    if (fs_.nodes[a].front >= 0 && fs_.nodes[a].next == b) front_edges_[kept++] = front_edges_[i];
  }
  front_edges_.resize(kept);
  std::make_heap(front_edges_.begin(), front_edges_.end());
  drop_stale_at_ = std::max(kMinStaleDrop, 2 * kept);
}

double Tracker::longest_front_edge() const {
  // Where the last long edges close, one call may pop many stale entries (at most the heap,
  // which drop_stale_front_edges keeps under twice what its last pass left, or 2^16; before
  // it, millions of entries and a second at 2*10^6 triangles), so it polls the cancel token.
  std::size_t popped = 0;
  while (!front_edges_.empty()) {
    const auto& [length, a, b] = front_edges_.front();
    if (fs_.nodes[a].front >= 0 && fs_.nodes[a].next == b) return length;
    std::pop_heap(front_edges_.begin(), front_edges_.end());
    front_edges_.pop_back();
    if (++popped % kStalePollEvery == 0) s_.cancel.check("adaptive");
  }
  return 0;
}

int Tracker::insert_node(int vertex, int front) {
  const int n = fs_.new_node(vertex, front);
  ++front_refs_[vertex];
  front_hash_.insert(n, mesh_.positions[vertex]);
  return n;
}

void Tracker::remove_node(int node) {
  FrontNode& n = fs_.nodes[node];
  --front_refs_[n.vertex];
  front_hash_.remove(node, mesh_.positions[n.vertex]);
  --fs_.fronts[n.front].size;
  n.front = -1;
  ++n.version;
}

void Tracker::refresh(int node) {
  fs_.nodes[node].angle = front_angle(node);
  fs_.push(node);
}

void Tracker::relabel(int start, int front) {
  int n = start;
  do {
    fs_.nodes[n].front = front;
    fs_.push(n);
    n = fs_.nodes[n].next;
  } while (n != start);
}

double Tracker::local_edge_length(int node) const {
  // The paper evaluates the heuristic at the point and at both front neighbours and keeps the
  // smallest, so that an expansion never outruns a region of higher curvature next to it.
  const FrontNode& n = fs_.nodes[node];
  double delta = std::min({target_[n.vertex], target_[fs_.nodes[n.prev].vertex], target_[fs_.nodes[n.next].vertex]});
  if (!s_.look_ahead) return delta;
  const Vec3& p = mesh_.positions[n.vertex];
  const double gradation = s_.look_ahead_gradation;
  front_hash_.for_each_near(p, delta / gradation, [&](int q) {
    const int w = fs_.nodes[q].vertex;
    delta = std::min(delta, target_[w] + gradation * (mesh_.positions[w] - p).norm());
  });
  return delta;
}

bool Tracker::mesh_from_seed(const Vec3& seed) {
  first_vertex_ = mesh_.positions.size();
  first_triangle_ = mesh_.triangles.size();
  std::vector<std::optional<Placed>> measured;
  measure(std::span(&seed, 1), measured);
  const std::optional<Placed>& seed_placed = measured.front();
  if (!seed_placed) return false;
  const int c = add_vertex(*seed_placed);
  const Vec3 n = mesh_.normals[c];
  Vec3 axis = Vec3::UnitX();
  if (std::abs(n.y()) < std::abs(n[0]) && std::abs(n.y()) <= std::abs(n.z())) axis = Vec3::UnitY();
  else if (std::abs(n.z()) < std::abs(n[0]) && std::abs(n.z()) < std::abs(n.y())) axis = Vec3::UnitZ();
  const Vec3 e0 = axis.cross(n).normalized();
  const Vec3 e1 = n.cross(e0);

  // The hexagon of Figure 5a; shrink it where Newton cannot place its corners.
  std::vector<Vec3> dirs(6);
  for (int k = 0; k < 6; ++k) {
    const double t = k * std::numbers::pi / 3;
    dirs[k] = std::cos(t) * e0 + std::sin(t) * e1;
  }
  std::vector<Placed> corners;
  for (double d = target_[c]; d >= kShortestEdgeLoop * s_.sizing.min_edge && corners.size() < 6; d *= 0.5)
    corners = place_points(c, dirs, d);
  if (corners.size() < 6) {
    // Keep the mesh free of an isolated vertex: the seed vertex is the last one added.
    vertex_hash().remove(c, mesh_.positions[c]);
    mesh_.positions.pop_back();
    mesh_.normals.pop_back();
    target_.pop_back();
    mac_.pop_back();
    shape_index_.pop_back();
    front_refs_.pop_back();
    return false;
  }
  std::vector<int> v(6);
  for (int k = 0; k < 6; ++k) v[k] = add_vertex(corners[k]);
  for (int k = 0; k < 6; ++k) emit_triangle(c, v[k], v[(k + 1) % 6]);

  const int f = fs_.new_front();
  std::vector<int> nodes(6);
  for (int k = 0; k < 6; ++k) nodes[k] = insert_node(v[k], f);
  // Triangle (c, v_k, v_k+1) owns the edge v_k -> v_k+1, so the front runs the other way.
  for (int k = 0; k < 6; ++k) link(nodes[(k + 1) % 6], nodes[k]);
  for (int k = 0; k < 6; ++k) refresh(nodes[k]);
  stack_.push_back(f);
  run_fronts();
  return true;
}

std::vector<std::vector<int>> Tracker::mesh_from_loops(std::span<const std::vector<Placed>> loops) {
  first_vertex_ = mesh_.positions.size();
  first_triangle_ = mesh_.triangles.size();
  std::vector<std::vector<int>> ids;
  std::vector<int> nodes;
  for (const std::vector<Placed>& loop : loops) {
    if (loop.size() < 3) throw std::logic_error("adaptive: a boundary loop of fewer than three points");
    const int f = fs_.new_front();
    std::vector<int>& v = ids.emplace_back();
    const std::size_t first = nodes.size();
    for (const Placed& p : loop) {
      v.push_back(add_vertex(p));
      nodes.push_back(insert_node(v.back(), f));
    }
    loop_vertex_.resize(mesh_.positions.size(), 0);
    for (const int w : v) loop_vertex_[static_cast<std::size_t>(w)] = 1;
    for (std::size_t k = first; k < nodes.size(); ++k) link(nodes[k], nodes[k + 1 < nodes.size() ? k + 1 : first]);
    // A loop vertex asks for no longer edges than the loop's own next to it: the loop was spaced
    // for both sides of a crease, and the fronts grow from it at the grading's pace (a flat cap
    // on a cylinder would otherwise start with edges ten times its rim's, as spikes).
    const std::size_t m = v.size();
    for (std::size_t k = 0; k < m; ++k) {
      const Vec3& p = mesh_.positions[v[k]];
      const double around = 0.5 * ((mesh_.positions[v[(k + 1) % m]] - p).norm() + (mesh_.positions[v[(k + m - 1) % m]] - p).norm());
      target_[v[k]] = std::min(target_[v[k]], around);
    }
    stack_.push_back(f);
  }
  for (const int n : nodes) refresh(n);
  run_fronts();
  return ids;
}

void Tracker::adopt_finished(std::span<const double> target, std::span<const double> mac,
                             std::span<const double> shape_index) {
  adopt_finished(std::vector<double>(target.begin(), target.end()), std::vector<double>(mac.begin(), mac.end()),
                 std::vector<double>(shape_index.begin(), shape_index.end()));
}

void Tracker::adopt_finished(std::vector<double>&& target, std::vector<double>&& mac,
                             std::vector<double>&& shape_index) {
  const std::size_t n = mesh_.positions.size();
  if (target.size() != n || mac.size() != n || shape_index.size() != n || !target_.empty())
    throw std::logic_error("adaptive: adopt_finished needs one value per vertex, before any vertex of its own");
  target_ = std::move(target);
  mac_ = std::move(mac);
  shape_index_ = std::move(shape_index);
  front_refs_.assign(n, 0);
  unhashed_ = n;  // hashed when first asked for (vertex_hash)
  for (const auto& t : mesh_.triangles) {
    const Vec3& pa = mesh_.positions[t[0]];
    area_ += 0.5 * (mesh_.positions[t[1]] - pa).cross(mesh_.positions[t[2]] - pa).norm();
  }
}

void Tracker::hash_vertices() const {
  const std::size_t n = std::exchange(unhashed_, 0);
  for (std::size_t v = 0; v < n; ++v) vertex_hash_.insert(static_cast<int>(v), mesh_.positions[v], vertex_position());
}

void Tracker::check_limits() {
  s_.cancel.check("adaptive");
  if (++steps_ > s_.max_steps)
    throw LimitExceededError("adaptive: more than " + std::to_string(s_.max_steps) +
                             " front steps (AdaptiveOptions::max_steps) without closing the surface");
  // Every 64 steps: cheap next to a step, and often enough that a run whose steps have become
  // slow still shows it is moving (the reporter decides how often to print).
  if (progress_ && estimated_area_ > 0 && (steps_ & 63) == 0) {
    const double f = std::min(0.99, area_ / estimated_area_);
    if (f > last_progress_) {
      last_progress_ = f;
      progress_(f);
    }
  }
}

void Tracker::check_search_budget(int node) {
  if (steps_ % kSearchWindow != 0) return;
  const std::uint64_t visits = search_visits();
  const std::uint64_t in_window = visits - window_visits_;
  window_visits_ = visits;
  if (in_window <= s_.search_visits_per_step * kSearchWindow) return;
  const Vec3& p = mesh_.positions[fs_.nodes[node].vertex];
  const std::string message("adaptive: the fronts' neighbour searches looked at " +
                            std::to_string(in_window / kSearchWindow) + " points a step over the last " +
                            std::to_string(kSearchWindow) + " steps (bound " + std::to_string(s_.search_visits_per_step) +
                            "), near " + format_point(p) +
                            ": edges far shorter than elsewhere crowd the search cells there, or a front is "
                            "running over finished mesh; raise min_edge");
  // Two spheres on a bar, meshed smooth across their creases at factors 5 and 6, crowded the
  // searches where fronts went wrong at a crease; meshed again with rollbacks, they mesh.
  if (s_.callers_search_bound) throw LimitExceededError(message);
  throw StalledFrontError(message);
}

void Tracker::run_fronts() {
  while (!stack_.empty()) {
    int f = stack_.back();
    stack_.pop_back();
    while (fs_.fronts[f].alive) {
      if (fs_.fronts[f].size <= 3) {
        // Figure 6, line 21: the last three points form one triangle.
        Front& fr = fs_.fronts[f];
        if (fr.size < 3) throw std::logic_error("adaptive: a front shrank below three points");
        const int a = fs_.pop_min(f);
        if (a < 0) throw std::logic_error("adaptive: a front lost its queue");
        const int b = fs_.nodes[a].next, c = fs_.nodes[b].next;
        const int va = fs_.nodes[a].vertex, vb = fs_.nodes[b].vertex, vc = fs_.nodes[c].vertex;
        // A three-point front through one vertex twice encloses nothing (see zip_spike).
        if (va != vb && vb != vc && va != vc) emit_triangle(va, vb, vc);
        remove_node(a);
        remove_node(b);
        remove_node(c);
        fr.alive = false;
        fr.release_heap();
        break;
      }
      step(f);
    }
  }
}

std::optional<std::pair<int, int>> Tracker::thin_feature_at(int node, double radius) const {
  // Only called when a run is about to fail: every vertex of the stuck front against the
  // vertices within min_edge of it. Normals more than 120 degrees apart at surface points that
  // close mean a slab or a gap thinner than min_edge (the gyroid ball at factor 2: the gyroid
  // 0.009 under the sphere, min_edge 0.015). The faces of a crease whose solid angle is over 60
  // degrees (a cube's 90) have normals less than 120 degrees apart and do not qualify.
  constexpr double kOppositeCosine = -0.5;
  std::optional<std::pair<int, int>> best;
  double best_d = std::numeric_limits<double>::infinity();
  int x = node;
  do {
    const int u = fs_.nodes[x].vertex;
    const Vec3& pu = mesh_.positions[u];
    vertex_hash().for_each_near(pu, radius, [&](int w) {
      const double d = (mesh_.positions[w] - pu).norm();
      if (d >= radius || mesh_.normals[u].dot(mesh_.normals[w]) > kOppositeCosine) return;
      if (d < best_d || (d == best_d && best && std::pair(u, w) < *best)) best_d = d, best = std::pair(u, w);
    });
    x = fs_.nodes[x].next;
  } while (x != node);
  return best;
}

std::optional<Tracker::AcuteCrease> Tracker::acute_crease_between(const Vec3& a, const Vec3& b) const {
  // Each point on its own piece (to a tenth of their distance), the two pieces' crease within
  // two min_edge of their midpoint: a wedge. Two pieces whose zero sets run side by side without
  // meeting (a slab between two shapes) have no crease there, and a smooth field no pieces.
  const double d = (a - b).norm();
  const Vec3 mid = 0.5 * (a + b);
  const double reach = 2 * s_.sizing.min_edge;
  const std::vector<FieldPiece> pieces = field_.pieces(mid, reach);
  if (pieces.size() < 2) return std::nullopt;
  const auto nearest_piece = [&](const Vec3& p) {
    int best = -1;
    double best_r = 0.1 * d;
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      const FieldPiece q = field_.piece(p, pieces[i].branch);
      const double r = std::abs(q.value) / q.gradient.norm();
      if (r <= best_r) best_r = r, best = static_cast<int>(i);
    }
    return best;
  };
  const int ia = nearest_piece(a), ib = nearest_piece(b);
  if (ia < 0 || ib < 0 || ia == ib) return std::nullopt;
  const std::vector<std::vector<std::uint8_t>> two{pieces[static_cast<std::size_t>(ia)].branch,
                                                   pieces[static_cast<std::size_t>(ib)].branch};
  const CreaseProjection c = project_to_crease(field_, mid, two);
  if (!c.ok() || (c.point - mid).norm() > reach) return std::nullopt;
  const Vec3 na = field_.piece(c.point, two[0]).gradient.normalized();
  const Vec3 nb = field_.piece(c.point, two[1]).gradient.normalized();
  // Outward normals n_a, n_b: the faces meet at pi minus the angle between them.
  const double between = std::atan2(na.cross(nb).norm(), na.dot(nb));
  return AcuteCrease{c.point, 180.0 - between * 180.0 / std::numbers::pi};
}

bool Tracker::zip_spike(int node) {
  // After a merge a front may pass twice through one vertex. Once the points between the two
  // passes are used up, the front runs p -> y -> p (both sides of edge p-y are meshed) or
  // p -> p: a loop enclosing nothing, which is cut out without a triangle.
  FrontNode& n = fs_.nodes[node];
  const int v = n.vertex;
  if (fs_.nodes[n.next].vertex == v) {
    const int prev = n.prev;
    remove_node(node);
    link(prev, fs_.nodes[node].next);
    refresh(prev);
    refresh(fs_.nodes[node].next);
    return true;
  }
  if (fs_.nodes[n.prev].vertex != fs_.nodes[n.next].vertex) return false;
  const int before = n.prev, twin = n.next, after = fs_.nodes[twin].next;
  remove_node(node);
  remove_node(twin);
  link(before, after);
  refresh(before);
  refresh(after);
  return true;
}

namespace {
// Fronts up to this size that are stuck get closed by ears (see step).
constexpr int kSmallFront = 8;
// is_slit: the least length of the mean of a slit's unit normals. The Barth ball's narrow stuck
// fronts at factor 9 had 0.98-0.9996 but one (0.77); a loop around a round tube has about 0.
constexpr double kSlitAlignment = 0.9;
}  // namespace

bool Tracker::is_slit(int node) const {
  // The front's mean width is twice its vector area over its perimeter (for a thin loop of
  // length L and width w, 2 L w / 2 L); the vector area is that of any surface the loop bounds.
  // Closing a front by ears makes a disc, which is right where the front lies on one sheet:
  // its normals then point about one way. A loop around a tube also has a small width (the
  // tube's radius) but normals all round, summing to about none; it is not a slit.
  Vec3 twice_area = Vec3::Zero(), normals = Vec3::Zero();
  double perimeter = 0;
  int points = 0, x = node;
  const Vec3& origin = mesh_.positions[fs_.nodes[node].vertex];
  do {
    const Vec3 a = mesh_.positions[fs_.nodes[x].vertex] - origin;
    const Vec3 b = mesh_.positions[fs_.nodes[fs_.nodes[x].next].vertex] - origin;
    twice_area += a.cross(b);
    perimeter += (b - a).norm();
    normals += mesh_.normals[fs_.nodes[x].vertex];
    ++points;
    x = fs_.nodes[x].next;
  } while (x != node);
  return twice_area.norm() < s_.sizing.min_edge * perimeter && normals.norm() >= kSlitAlignment * points;
}

void Tracker::step(int& f) {
  check_limits();
  const int node = fs_.pop_min(f);
  if (node < 0) throw std::logic_error("adaptive: a front lost its queue");
  check_search_budget(node);
  if (zip_spike(node)) {
    fs_.fronts[f].stall = 0;
    return;
  }
  // A front whose every point has been deferred in turn is stuck at this edge length (a tube
  // thinner than the edge, a gap narrower than it): each further round retries with half the
  // length, down to a quarter of min_edge, before giving up with an error instead of spinning.
  const int size = std::max(fs_.fronts[f].size, 1);
  const int rounds = fs_.fronts[f].stall / size;
  // A larger stuck front that is a slit (is_slit) has no room for an edge the sizing allows
  // either, and is closed the same way: the Barth ball at factor 9 left an 11-point slit 0.21
  // long and 0.002 wide (min_edge 0.0021) along a crease loop on the ball, and every round of
  // shorter expansions stalled on it.
  if (rounds >= 2 && (size <= kSmallFront || is_slit(node))) {
    // A small hole that no expansion fits into is closed like the paper's last three points:
    // the ear of smallest front angle first (it is below pi, since the angles of a small
    // front sum to about (size - 2) pi), among the ears that hold no other point of the
    // front. A thin loop along a crease (the Barth ball at factor 5) has its smallest angle
    // at an ear over the rest of the loop: cut off, that ear covered finished triangles and
    // the fronts ran on over them. A simple polygon always has such an ear; a front folded
    // so that none is clear keeps the old choice.
    int best = -1, smallest = node, x = node;
    do {
      if (fs_.nodes[x].angle < fs_.nodes[smallest].angle) smallest = x;
      if ((best < 0 || fs_.nodes[x].angle < fs_.nodes[best].angle) && ear_is_clear(x)) best = x;
      x = fs_.nodes[x].next;
    } while (x != node);
    if (best < 0) best = smallest;
    if (best != node) fs_.push(node);
    close_angle(best);
    ++forced_closures_;
    fs_.fronts[f].stall = 0;
    return;
  }
  double delta = local_edge_length(node);
  if (rounds > 0) {
    const double shrunk = delta * std::ldexp(1.0, -rounds);
    if (shrunk < kShortestEdge * s_.sizing.min_edge && rounds > 1) {
      if (rollback(f, node, false)) return;  // undo the region and mesh it again (rollback.cpp)
      const Vec3& p = mesh_.positions[fs_.nodes[node].vertex];
      std::string message = "adaptive: a front of " + std::to_string(fs_.fronts[f].size) + " points near " + format_point(p) +
                            " cannot advance even at a quarter of min_edge";
      // The closest facing pair within kCreaseSearchEdges min_edge: the two faces of an acute
      // crease may face each other from farther than min_edge (the box minus a ball meshed
      // across its creases, whose rim the front reaches with edges of several min_edge), and
      // are named only when the field has a crease between them; a pair closer than min_edge
      // that is not a crease is a thin feature.
      constexpr double kCreaseSearchEdges = 4;
      const auto faces = thin_feature_at(node, kCreaseSearchEdges * s_.sizing.min_edge);
      const auto crease = faces ? acute_crease_between(mesh_.positions[faces->first], mesh_.positions[faces->second])
                                : std::nullopt;
      const auto thin =
          faces && (mesh_.positions[faces->first] - mesh_.positions[faces->second]).norm() < s_.sizing.min_edge
              ? faces
              : std::nullopt;
      if (crease) {
        const auto& [u, w] = *faces;
        message += ": the surface there folds into a crease whose faces meet at " +
                   std::to_string(static_cast<int>(std::lround(crease->degrees))) + " degrees, near " +
                   format_point(crease->point) + " (the points " + format_point(mesh_.positions[u]) + " and " +
                   format_point(mesh_.positions[w]) + " on its two faces are " +
                   std::to_string((mesh_.positions[u] - mesh_.positions[w]).norm()) +
                   " apart): " + std::string(kAlongCreaseAdvice);
      } else if (thin) {
        const auto& [u, w] = *thin;
        message += ": the surface there has two sheets facing opposite ways " +
                   std::to_string((mesh_.positions[u] - mesh_.positions[w]).norm()) + " apart, near " +
                   format_point(mesh_.positions[u]) + " and " + format_point(mesh_.positions[w]) +
                   ", a feature thinner than min_edge (" + std::to_string(s_.sizing.min_edge) +
                   "); lower min_edge to resolve it";
      } else {
        message += "; lower min_edge or raise the factor";
      }
      throw StalledFrontError(message);
    }
    delta = std::max(shrunk, kShortestEdge * s_.sizing.min_edge);
  }
  int q = find_collision(node, delta);
  if (q < 0) {
    const std::size_t over_before = over_mesh_;
    const ExpandOutcome r = expand(node, delta);
    // A point that cannot expand because its placements land on finished mesh: the front lies
    // over finished mesh there; undo the region rather than let it run on (rollback.cpp).
    if (!r.expanded && over_mesh_ > over_before && rollback(f, node, true)) return;
    if (r.expanded) {
      fs_.fronts[f].stall = 0;
      return;
    }
    q = r.obstacle;
    // A stuck front looks farther for a point to bridge to.
    if (q < 0 && rounds > 0) q = find_bridge(node, 3 * s_.collision_factor * local_edge_length(node));
    if (q < 0) {
      // Nothing to bridge to and no room to expand: let the other points of the front move
      // first.
      // Keys grow with the front's stall count, so deferred points queue up behind every point
      // not deferred yet and take their turns in order.
      ++deferrals_;
      const int stall = ++fs_.fronts[f].stall;
      fs_.push_with_key(node, fs_.nodes[node].angle + 2 * std::numbers::pi * stall);
      return;
    }
  }
  if (fs_.nodes[q].front == f) split_front(node, q);
  else f = merge_fronts(node, q);
  fs_.fronts[f].stall = 0;
}

}  // namespace cdp::adaptive
