#include "missed_necks.h"

#include <cdp/core/triangle_geometry.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

namespace cdp::adaptive {

namespace {

// Newton on grad F = 0 converges in a few steps near a nondegenerate critical point; a walk that
// has not settled by then, or has gone farther than kWalkReach edges, is given up.
constexpr int kNewtonSteps = 16;
constexpr double kWalkReach = 2 * kCriticalReach;
// Settled: the next step below this share of the start's edge (far below any neck the test is
// for; the noisy Hessians of the MPU models need not reach rounding for a walk to end).
constexpr double kSettled = 1e-6;
// Two walks that settle within this share of the edge reached the same critical point.
constexpr double kSamePoint = 1e-4;
// A start whose predicted critical point lies within this share of its step of one already
// walked to (or found) is skipped: the vertices around a saddle all point at it.
constexpr double kSameTarget = 0.5;
// Critical points whose zero set lies farther than this many edges are not tested: a neck or
// tunnel wider than a few edges is one the fronts follow, and the test costs a pass over the mesh.
constexpr double kThinWaist = 2;
// Bounds on the work whatever the field: walks started (each at most kNewtonSteps + 1 Hessians),
// at least kMinNeckWalks and one for every kVerticesPerWalk vertices of the mesh, so that a crowd
// of many necks is searched as well as a few. (A flat 4096, with the critical points tested
// capped at 1024, left the crowd of 200 Wyvill blobs at chord deviations 8.2e-3, 9.5e-3 and
// 1.1e-2 with a handle too few and exit 0: 5,000-5,200 walks and 1,180-1,220 tests find the
// lost necks.) Each walk reaches at most one critical point, so the tests, each a walk up a
// column of the triangles' hash, are bounded by the walks.
constexpr std::size_t kMinNeckWalks = 4096;
constexpr std::size_t kVerticesPerWalk = 4;
// A core whose side is right is looked at along its axis (the eigenvector along which F keeps its
// sign and grows): this many of its edges either way, the stretch where the field keeps its sign
// and |F| keeps growing sampled at steps of half the neck's radius, at most kAxisSamples a side.
// The crowd of 200 Wyvill blobs at chord deviation 4.8e-3 capped a neck 0.006 wide on both sides
// of its waist, 0.012 apart; its saddle lay 2e-5 outside one cap (genus 29, exit 0, before).
constexpr double kAxisReach = kThinWaist;
constexpr int kAxisSamples = 32;
// Crossings closer than this share of the reach are one (an edge both its triangles report).
constexpr double kSameCrossing = 1e-9;
// A neck is ringed by its surface: F changes sign within this many of the model's radii in each
// direction across the axis (the crowd's neck: 1.25 radii each way; the saddle under the horse
// MPU model's surface: 1-1.5 radii three ways, never the fourth), sampled this many times.
constexpr double kAcrossReach = 4;
constexpr int kAcrossSamples = 16;
// A cap: a triangle whose normal turns more than this from one of its corners' normals, a front
// closed across a tube narrower than its edges (cdp.sdf's torus with a hole 0.01 wide, whose
// core is a kink of the distance: closed at factor 2 by 13 such triangles, turned up to 116
// degrees). The smooth meshes tried (a sphere, a capsule, a rounded box, tori whose hole is 0.02
// and 0.05 wide, factors 2-8) have none; the tube 0.01 wide meshed right at factor 3 has 19, an
// edge spanning a quarter of its girth, which the side test then clears.
constexpr double kCapTurnDegrees = 60;
// F is sampled this many times on each stretch of a cap's normal between two crossings of the
// mesh (the stretch on one side of the mesh throughout).
constexpr int kCapSamples = 8;
// Steps up the field from a sample the mesh puts on the wrong side to the core it lies near
// (climb_to_core): halvings included, enough to reach the axis of a tube from its wall within a
// thousandth of its radius.
constexpr int kClimbSteps = 16;
// The widest core a cap is taken to close over, in its longest edges: the tunnels of cdp.sdf's
// tori that fronts closed were 0.4-0.9 of their caps' edges wide; at factor 1, where a cap's
// normal passed 0.28-0.37 deep into a tube 1 wide that the coarse mesh cut into, 1.5-2.6.
constexpr double kCapWidth = 1.2;
// A tube's solid or void runs on at least this many of its radii from the core both ways along
// its axis (tube_axis); the wedge cut off a cube's corner, 1.7 one way.
constexpr double kRunsOn = 2;
// Steps of its radius a core is walked along its axis each way, looking for the caps or the end of
// its tube (ends_along_core).
constexpr int kCoreSteps = 64;
// Directions across a cap's core in which the surface must ring it (ringed_all_round).
constexpr int kRoundDirections = 12;
// The climb stops where the gradient has less than this share of its length across the axis.
constexpr double kFlatAcross = 1e-3;

struct Critical {
  Vec3 point;
  double value = 0;
  double radius = 0;  // where the quadratic model reaches zero, along the steepest such direction
  double edge = 0;
  Vec3 axis = Vec3::Zero();  // the one eigenvector along which F keeps its sign, zero if not one
  std::array<Vec3, 2> across = {Vec3::Zero(), Vec3::Zero()};  // the other two, when there is one
};

}  // namespace

std::optional<Vec3> step_to_critical_point(const Vec3& gradient, const Mat3& hessian) {
  const Eigen::FullPivLU<Mat3> lu(hessian);
  if (!lu.isInvertible()) return std::nullopt;
  const Vec3 s = -lu.solve(gradient);
  if (!s.allFinite()) return std::nullopt;
  return s;
}

namespace {

// The mean longest edge of the triangles: the hash's cell, so that a cell holds a few triangles.
double mean_longest_edge(const Mesh& mesh) {
  double sum = 0;
  for (const auto& t : mesh.triangles)
    sum += longest_edge(mesh.positions[static_cast<std::size_t>(t[0])], mesh.positions[static_cast<std::size_t>(t[1])],
                        mesh.positions[static_cast<std::size_t>(t[2])]);
  const double mean = mesh.triangles.empty() ? 1 : sum / static_cast<double>(mesh.triangles.size());
  return mean > 0 && std::isfinite(mean) ? mean : 1;
}

}  // namespace

MeshSides::MeshSides(const Mesh& mesh) : mesh_(mesh), hash_(mean_longest_edge(mesh)), seen_(mesh.triangles.size(), -1) {
  top_ = -std::numeric_limits<double>::infinity();
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const auto& t = mesh.triangles[f];
    const Vec3 &a = mesh.positions[static_cast<std::size_t>(t[0])], &b = mesh.positions[static_cast<std::size_t>(t[1])],
               &c = mesh.positions[static_cast<std::size_t>(t[2])];
    hash_.insert_box(static_cast<int>(f), a.cwiseMin(b).cwiseMin(c), a.cwiseMax(b).cwiseMax(c));
    top_ = std::max(top_, std::max({a.z(), b.z(), c.z()}));
  }
}

std::optional<bool> MeshSides::inside(const Vec3& p) const {
  if (mesh_.triangles.empty() || !(p.z() <= top_)) return false;
  // The side of p's projection from each edge, computed from the edge's lower vertex id so that
  // the two triangles of an edge get exactly opposite values: p's projection is in at most one
  // of them, whatever the rounding.
  const auto side = [&](int u, int v) {
    const bool flip = u > v;
    if (flip) std::swap(u, v);
    const Vec3 &a = mesh_.positions[static_cast<std::size_t>(u)], &b = mesh_.positions[static_cast<std::size_t>(v)];
    const double d = (b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x());
    return flip ? -d : d;
  };
  ++stamp_;
  int crossings = 0;
  bool undecided = false;
  hash_.any_in(p, Vec3(p.x(), p.y(), top_), [&](int f) {
    if (seen_[static_cast<std::size_t>(f)] == stamp_) return false;
    seen_[static_cast<std::size_t>(f)] = stamp_;
    const auto& t = mesh_.triangles[static_cast<std::size_t>(f)];
    const double d0 = side(t[1], t[2]), d1 = side(t[2], t[0]), d2 = side(t[0], t[1]);
    if ((d0 < 0 || d1 < 0 || d2 < 0) && (d0 > 0 || d1 > 0 || d2 > 0)) return false;  // projection misses
    const double sum = d0 + d1 + d2;
    if (d0 == 0 || d1 == 0 || d2 == 0 || sum == 0) {
      undecided = true;
      return true;
    }
    const double z = (d0 * mesh_.positions[static_cast<std::size_t>(t[0])].z() +
                      d1 * mesh_.positions[static_cast<std::size_t>(t[1])].z() +
                      d2 * mesh_.positions[static_cast<std::size_t>(t[2])].z()) /
                     sum;
    if (z == p.z()) {
      undecided = true;
      return true;
    }
    if (z > p.z()) ++crossings;
    return false;
  });
  if (undecided) return std::nullopt;
  return crossings % 2 == 1;
}

void MeshSides::crossings(const Vec3& a, const Vec3& b, std::vector<double>& at) const {
  at.clear();
  const Vec3 d = b - a;
  ++stamp_;
  hash_.any_in(a.cwiseMin(b), a.cwiseMax(b), [&](int f) {
    if (seen_[static_cast<std::size_t>(f)] == stamp_) return false;
    seen_[static_cast<std::size_t>(f)] = stamp_;
    const auto& t = mesh_.triangles[static_cast<std::size_t>(f)];
    const Vec3& p0 = mesh_.positions[static_cast<std::size_t>(t[0])];
    const Vec3 e1 = mesh_.positions[static_cast<std::size_t>(t[1])] - p0;
    const Vec3 e2 = mesh_.positions[static_cast<std::size_t>(t[2])] - p0;
    // Moller and Trumbore: the crossing's barycentric coordinates and parameter by Cramer's rule.
    const Vec3 pv = d.cross(e2);
    const double det = e1.dot(pv);
    if (det == 0) return false;
    const Vec3 tv = a - p0;
    const double u = tv.dot(pv) / det;
    if (!(u >= 0 && u <= 1)) return false;
    const Vec3 qv = tv.cross(e1);
    const double v = d.dot(qv) / det;
    if (!(v >= 0 && u + v <= 1)) return false;
    const double s = e2.dot(qv) / det;
    if (s >= 0 && s <= 1) at.push_back(s);
    return false;
  });
}

namespace {

// The distance from a core of the k-th sample along `dir` (unit): k kAcrossSamples-ths of
// kAcrossReach radii.
double across_sample(double radius, int k) { return k * kAcrossReach * radius / kAcrossSamples; }

// The first k in 1, ..., samples at whose sample along `dir` (unit) F does not keep the sign it
// has at the core (F = value there); 0 when it keeps it at every one.
int sign_change_along(const Field& field, const Vec3& core, double value, double radius, const Vec3& dir,
                      int samples = kAcrossSamples) {
  for (int k = 1; k <= samples; ++k)
    if (!(field.value(core + across_sample(radius, k) * dir) * value > 0)) return k;
  return 0;
}

// Whether the surface rings a core (F = value there): F changes sign within kAcrossReach radii
// of it in the four directions across its axis, as round a tube, not on one side only as under
// the near side of a surface.
bool ringed(const Field& field, const Vec3& core, double value, double radius, const std::array<Vec3, 2>& across) {
  for (const Vec3& dir : {across[0], Vec3(-across[0]), across[1], Vec3(-across[1])})
    if (sign_change_along(field, core, value, radius, dir) == 0) return false;
  return true;
}

// How far F keeps its sign from a core both ways along `dir` (unit), the lesser of the two, in
// steps of a kAcrossSamples-th of kAcrossReach radii up to kAcrossReach radii.
double run_both_ways(const Field& field, const Vec3& core, double value, double radius, const Vec3& dir) {
  int least = kAcrossSamples;  // samples kept on the sides looked at so far
  for (const Vec3& way : {Vec3(-dir), dir})
    if (const int k = sign_change_along(field, core, value, radius, way, least)) least = k - 1;
  return across_sample(radius, least);
}

// The axis of a tube round a core found without a Hessian's word on it (a distance field's kink):
// of the cap's normal and the 13 directions of a cube's neighbours (no axis more than about 20
// degrees from one of them), the one along which F keeps its sign farthest both ways; nothing
// when that is under kRunsOn radii. The solid of a neck and the void of a tunnel run on from
// the waist both ways; the wedge a chord cuts off a corner of the solid, which the corner's faces
// ring too, ends at the corner, under 2 radii from its core one way.
std::optional<Vec3> tube_axis(const Field& field, const Vec3& core, double value, double radius, const Vec3& normal) {
  Vec3 best = normal;
  double longest = run_both_ways(field, core, value, radius, normal);
  for (int i = -1; i <= 1; ++i)
    for (int j = -1; j <= 1; ++j)
      for (int k = -1; k <= 1; ++k) {
        const Vec3 d(i, j, k);
        // one of each antipodal pair: the first nonzero coordinate positive
        if (d.isZero() || (i < 0 || (i == 0 && (j < 0 || (j == 0 && k < 0))))) continue;
        const Vec3 dir = d.normalized();
        const double run = run_both_ways(field, core, value, radius, dir);
        if (run > longest) longest = run, best = dir;
      }
  if (longest < kRunsOn * radius) return std::nullopt;
  return best;
}

// Whether the surface rings a core all round the axis `along` (unit) with no wall of the mesh
// between: F changes sign within kAcrossReach radii in each of kRoundDirections directions across
// it, and the segment from the core to where it does crosses no triangle. Four directions suffice
// where the Hessian says the core is a tube's (one eigenvalue along, two across); a core found
// without one may lie in a plate (a thin shell's solid, a wedge a chord cut off a crease), whose
// plane any direction tilted more than 15 degrees from it leaves within 4 radii, but not the
// one direction in it, which 12 directions 15 degrees apart come within 7.5 degrees of. And a
// tube narrower than the edges meshed as one can leave its core outside the mesh's own thinner
// tube (the ellipsoid 5 x 0.05 x 0.05 at tolerance 1e-2, near its tips), whose walls lie between
// the core and the surface one way or another; a neck cut or a tunnel closed has none there.
bool ringed_all_round(const Field& field, const MeshSides& sides, const Vec3& core, double value, double radius,
                      const Vec3& along, std::vector<double>& at) {
  const Vec3 off = std::abs(along.x()) < 0.6 ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 u = along.cross(off).normalized(), w = along.cross(u);
  for (int d = 0; d < kRoundDirections; ++d) {
    const double angle = 2 * std::numbers::pi * d / kRoundDirections;
    const Vec3 dir = std::cos(angle) * u + std::sin(angle) * w;
    const int wall = sign_change_along(field, core, value, radius, dir);
    if (wall == 0) return false;
    sides.crossings(core, core + across_sample(radius, wall) * dir, at);
    if (!at.empty()) return false;
  }
  return true;
}

// Whether a thin core c, its side of the mesh right or undecided, has two sheets of the mesh
// across its axis where the field says the neck's solid (or the tunnel's void) runs on, and the
// surface rings it: a neck a front capped at its waist. `at` is scratch for the crossings.
bool capped_at_waist(const Field& field, const MeshSides& sides, const Critical& c, std::vector<double>& at) {
  if (c.axis.isZero()) return false;
  const double reach = kAxisReach * c.edge;
  sides.crossings(c.point - reach * c.axis, c.point + reach * c.axis, at);
  if (at.size() < 2) return false;  // the common case, decided without evaluating F
  // Where the field keeps its sign and |F| grows from the core, on each side: the solid (or the
  // void) of the neck runs on there, and the surface is a radius away or more.
  const double step = std::max(c.radius / 2, reach / kAxisSamples);
  double extent[2] = {0, 0};
  for (int side = 0; side < 2; ++side) {
    const Vec3 dir = side == 0 ? Vec3(-c.axis) : c.axis;
    double last = std::abs(c.value);
    for (int k = 1; k <= kAxisSamples; ++k) {
      const double s = std::min(reach, k * step);
      const double v = field.value(c.point + s * dir);
      if (!(v * c.value > 0) || std::abs(v) < last) break;
      last = std::abs(v);
      extent[side] = s;
      if (s == reach) break;
    }
  }
  // Crossings in [-extent[0], extent[1]], one where the segment passes through an edge or a
  // vertex and both its triangles report it.
  std::sort(at.begin(), at.end());
  int within = 0;
  double previous = -std::numeric_limits<double>::infinity();
  for (double t : at) {
    const double s = (2 * t - 1) * reach;
    if (s < -extent[0] || s > extent[1]) continue;
    if (s - previous > kSameCrossing * reach) ++within;
    previous = s;
  }
  if (within < 2) return false;
  // And a neck, not the near side of a surface.
  return ringed(field, c.point, c.value, c.radius, c.across);
}

Vec3 triangle_middle(const Mesh& mesh, std::size_t f) {
  const auto& t = mesh.triangles[f];
  return (mesh.positions[static_cast<std::size_t>(t[0])] + mesh.positions[static_cast<std::size_t>(t[1])] +
          mesh.positions[static_cast<std::size_t>(t[2])]) /
         3;
}

// The longest edge and the unit normal of triangle f, and whether the normal turns more than
// kCapTurnDegrees from one of its corners' normals (the corner normals of a crease's vertex where
// the mesh has them, so that a crease is no cap; else the vertex normals, which must be there).
bool is_cap(const Mesh& mesh, std::size_t f, Vec3& normal, double& edge) {
  static const double cos_turn = std::cos(kCapTurnDegrees * std::numbers::pi / 180);
  const auto& t = mesh.triangles[f];
  const Vec3& a = mesh.positions[static_cast<std::size_t>(t[0])];
  const Vec3& b = mesh.positions[static_cast<std::size_t>(t[1])];
  const Vec3& c = mesh.positions[static_cast<std::size_t>(t[2])];
  const Vec3 n = (b - a).cross(c - a);
  const double length = n.norm();
  if (!(length > 0) || !std::isfinite(length)) return false;
  normal = n / length;
  edge = longest_edge(a, b, c);
  for (int k = 0; k < 3; ++k) {
    const Vec3& corner = mesh.corner_normals.size() == mesh.triangles.size()
                             ? mesh.corner_normals[f][static_cast<std::size_t>(k)]
                             : mesh.normals[static_cast<std::size_t>(t[static_cast<std::size_t>(k)])];
    if (!corner.isZero() && corner.dot(normal) < cos_turn * corner.norm()) return true;
  }
  return false;
}

// Climbs from p (F = value there, not zero) across the axis `along` (unit) to where |F| peaks in
// the plane through p normal to it, at most kClimbSteps steps and within `reach` of p, and returns
// the distance to the surface there, |F| / |grad F|. Across only: along a tunnel's axis |F| grows
// without bound as the tunnel widens.
double climb_to_core(const Field& field, const Vec3& along, double reach, Vec3& p, double& value) {
  const Vec3 start = p;
  Vec3 g;
  value = field.value_gradient(p, g);
  double step = std::abs(value) / g.norm();
  for (int k = 0; k < kClimbSteps && std::isfinite(step) && step > 0; ++k) {
    const Vec3 across = g - g.dot(along) * along;
    if (!(across.norm() > kFlatAcross * g.norm())) break;  // at the core's kink or a smooth core
    const Vec3 q = p + (value > 0 ? step : -step) * across.normalized();
    Vec3 gq;
    const double vq = (q - start).norm() <= reach ? field.value_gradient(q, gq) : 0;
    if (std::isfinite(vq) && vq * value > 0 && std::abs(vq) > std::abs(value) && gq.allFinite() && gq.norm() > 0) {
      p = q, value = vq, g = gq;
      step = std::abs(value) / g.norm();
    } else {
      step /= 2;
    }
  }
  return std::abs(value) / g.norm();
}

// Whether the tube round a core ends before the mesh crosses it, one way or the other along its
// axis: walked from the core in steps of its radius, each step's end climbed back to the core
// across the way it went (climb_to_core), at most kCoreSteps steps a way, until F changes sign
// there (the end) or the step crosses the mesh (a cap). A neck cut or a tunnel closed has caps
// both ways (or runs on past the walk); a needle's tip that the chords cut off ends one way
// (the ellipsoid 5 x 0.05 x 0.05 at tolerance 1e-2: 4.4 radii from the core).
bool ends_along_core(const Field& field, const MeshSides& sides, const Vec3& core, double value, double radius,
                     const Vec3& axis, std::vector<double>& at) {
  for (const double side : {-1.0, 1.0}) {
    Vec3 p = core, dir = side * axis;
    double r = radius;
    for (int k = 0; k < kCoreSteps; ++k) {
      Vec3 q = p + r * dir;
      double v = field.value(q);
      if (!(v * value > 0)) return true;
      const double next = climb_to_core(field, dir, r, q, v);
      sides.crossings(p, q, at);
      if (!at.empty()) break;  // a cap this way
      if (!((q - p).norm() > 0) || !(next > 0) || !std::isfinite(next)) break;
      dir = (q - p).normalized();
      p = q, r = next;
    }
  }
  return false;
}

// Looks along a cap's normal, kAxisReach of its longest edge either way, for a stretch between
// two crossings of the mesh where F's sign disagrees with the mesh's side (solid the mesh leaves
// outside, or void it encloses) at a point the surface rings: the core of a neck cut or a tunnel
// closed there, F's kink or not. `at` is scratch for the crossings.
std::optional<MissedNeck> along_cap(const Field& field, const MeshSides& sides, const Mesh& mesh, std::size_t f,
                                    const Vec3& normal, double edge, std::vector<double>& at) {
  const Vec3 middle = triangle_middle(mesh, f);
  const double reach = kAxisReach * edge;
  const Vec3 from = middle - reach * normal, to = middle + reach * normal;
  sides.crossings(from, to, at);
  at.push_back(0);
  at.push_back(1);
  std::sort(at.begin(), at.end());
  for (std::size_t i = 0; i + 1 < at.size(); ++i) {
    const double t0 = at[i], t1 = at[i + 1];
    if (t1 - t0 <= kSameCrossing) continue;  // an edge both its triangles report
    const auto inside = sides.inside(from + ((t0 + t1) / 2) * (to - from));
    if (!inside) continue;
    // The sample that disagrees most: F of the sign the mesh's side denies, largest in magnitude.
    Vec3 core = Vec3::Zero();
    double value = 0;
    for (int k = 0; k < kCapSamples; ++k) {
      const Vec3 p = from + (t0 + (k + 0.5) / kCapSamples * (t1 - t0)) * (to - from);
      const double v = field.value(p);
      if (std::isfinite(v) && (*inside ? v > 0 : v < 0) && std::abs(v) > std::abs(value)) core = p, value = v;
    }
    if (value == 0) continue;
    // Up the field to the core, across the cap's normal: a sample off the axis of a tube narrower
    // than the cap's edges lies closer to one wall than to the other, where the ring below would
    // not see the far wall; the core does.
    double radius = climb_to_core(field, normal, reach, core, value);
    // A tube a front can close over is narrower than its edges (a coarse mesh that cuts deep into
    // a wide one is no neck it stepped over), and its core stays on the side the mesh denies.
    if (!(radius > 0) || !(2 * radius <= kCapWidth * edge)) continue;
    if (sides.inside(core) != inside) continue;
    const auto axis = tube_axis(field, core, value, radius, normal);
    if (axis && ringed_all_round(field, sides, core, value, radius, *axis, at) &&
        !ends_along_core(field, sides, core, value, radius, *axis, at))
      return MissedNeck{core, value, 2 * radius, edge, true};
  }
  return std::nullopt;
}

// Newton's walks from the starts to the critical points of F (find_missed_necks' first part).
void walk_to_critical_points(const Field& field, std::span<const CriticalStart> starts, std::size_t max_walks,
                             NeckSearch& out, std::vector<Critical>& found) {
  double mean_edge = 0;
  for (const CriticalStart& s : starts) mean_edge += s.edge;
  mean_edge /= static_cast<double>(starts.size());
  if (!(mean_edge > 0) || !std::isfinite(mean_edge)) return;
  SpatialHash claimed(mean_edge);
  std::vector<Vec3> targets;
  const auto near_claimed = [&](const Vec3& q, double r) {
    bool hit = false;
    claimed.for_each_near(q, r, [&](int id) {
      if ((targets[static_cast<std::size_t>(id)] - q).squaredNorm() <= r * r) hit = true;
    });
    return hit;
  };
  const auto claim = [&](const Vec3& q) {
    claimed.insert(static_cast<int>(targets.size()), q);
    targets.push_back(q);
  };

  for (const CriticalStart& start : starts) {
    const Vec3 predicted = start.point + start.step;
    if (near_claimed(predicted, kSameTarget * start.step.norm())) continue;
    if (out.walks == max_walks) {
      ++out.unwalked;
      continue;
    }
    ++out.walks;
    claim(predicted);
    Vec3 x = predicted;
    bool settled = false;
    double value = 0;
    Vec3 g;
    Mat3 H;
    for (int it = 0; it < kNewtonSteps; ++it) {
      value = field.gradient_hessian(x, g, H);
      const auto s = step_to_critical_point(g, H);
      if (!s) break;
      if (s->norm() <= kSettled * start.edge) {  // value, g and H are those at x
        settled = true;
        break;
      }
      x += *s;
      if ((x - start.point).norm() > kWalkReach * start.edge) break;
    }
    if (!settled || !std::isfinite(value) || value == 0) continue;  // F = 0: a singular point, not a neck
    claim(x);
    if (std::any_of(found.begin(), found.end(),
                    [&](const Critical& c) { return (c.point - x).norm() <= kSamePoint * start.edge; }))
      continue;
    // The quadratic model F(c) + d^T H d / 2 reaches zero along eigenvectors whose eigenvalue has
    // the opposite sign of F(c); the nearest such zero is the neck's or the tunnel's radius.
    const Eigen::SelfAdjointEigenSolver<Mat3> eig(H);
    Critical c{x, value, std::numeric_limits<double>::infinity(), start.edge};
    int along = 0, across = 0;
    for (int k = 0; k < 3; ++k) {
      const double lambda = eig.eigenvalues()[k];
      if (lambda * value < 0) {
        c.radius = std::min(c.radius, std::sqrt(2 * std::abs(value) / std::abs(lambda)));
        if (across < 2) c.across[static_cast<std::size_t>(across)] = eig.eigenvectors().col(k);
        ++across;
      }
      if (lambda * value > 0) {
        ++along;
        c.axis = eig.eigenvectors().col(k);
      }
    }
    if (along != 1 || across != 2) c.axis = Vec3::Zero();
    found.push_back(c);
  }
}

}  // namespace

NeckSearch find_missed_necks(const Field& field, const Mesh& mesh, std::span<const CriticalStart> starts) {
  NeckSearch out;
  if (mesh.triangles.empty()) return out;
  const std::size_t max_walks = std::max(kMinNeckWalks, mesh.positions.size() / kVerticesPerWalk);
  std::vector<Critical> found;
  if (!starts.empty()) walk_to_critical_points(field, starts, max_walks, out, found);
  out.critical_points = found.size();

  std::vector<const Critical*> thin;
  for (const Critical& c : found)
    if (c.radius <= kThinWaist * c.edge) thin.push_back(&c);
  std::stable_sort(thin.begin(), thin.end(), [](const Critical* a, const Critical* b) { return a->radius < b->radius; });
  struct Cap {
    std::size_t triangle;
    Vec3 normal;
    double edge;
  };
  std::vector<Cap> caps;
  if (mesh.normals.size() == mesh.positions.size() || mesh.corner_normals.size() == mesh.triangles.size())
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
      Cap cap{f, Vec3::Zero(), 0};
      if (is_cap(mesh, f, cap.normal, cap.edge)) caps.push_back(cap);
    }
  if (thin.empty() && caps.empty()) return out;
  const MeshSides sides(mesh);
  std::vector<double> at;
  for (const Critical* c : thin) {
    ++out.tested;
    const auto inside = sides.inside(c->point);
    if (inside && *inside != (c->value < 0)) {
      out.missed.push_back({c->point, c->value, 2 * c->radius, c->edge});
      continue;
    }
    if (!capped_at_waist(field, sides, *c, at)) continue;
    ++out.capped;
    out.missed.push_back({c->point, c->value, 2 * c->radius, c->edge});
  }
  // The caps only where no saddle was found missed: one is enough to fail the mesh, and a cap near
  // a saddle found is the front that stepped over it.
  if (!out.missed.empty()) return out;
  for (const Cap& cap : caps) {
    // A cap within its edge of a core found is one of the front's caps over the same tube.
    const Vec3 middle = triangle_middle(mesh, cap.triangle);
    if (std::any_of(out.missed.begin(), out.missed.end(),
                    [&](const MissedNeck& m) { return (m.point - middle).norm() <= cap.edge + m.width; }))
      continue;
    if (out.caps == max_walks) {
      ++out.unwalked;
      continue;
    }
    ++out.caps;
    if (const auto neck = along_cap(field, sides, mesh, cap.triangle, cap.normal, cap.edge, at)) out.missed.push_back(*neck);
  }
  std::stable_sort(out.missed.begin(), out.missed.end(),
                   [](const MissedNeck& a, const MissedNeck& b) { return a.width < b.width; });
  return out;
}


}  // namespace cdp::adaptive
