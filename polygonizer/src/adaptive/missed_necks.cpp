#include "missed_necks.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

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
  for (const auto& t : mesh.triangles) {
    const Vec3 &a = mesh.positions[static_cast<std::size_t>(t[0])], &b = mesh.positions[static_cast<std::size_t>(t[1])],
               &c = mesh.positions[static_cast<std::size_t>(t[2])];
    sum += std::sqrt(std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()}));
  }
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
  // And a neck, not the near side of a surface: the field changes sign within kAcrossReach
  // radii of the core in the four directions across the axis, as round a tube.
  const auto changes_sign = [&](const Vec3& dir) {
    for (int k = 1; k <= kAcrossSamples; ++k)
      if (!(field.value(c.point + (k * kAcrossReach * c.radius / kAcrossSamples) * dir) * c.value > 0)) return true;
    return false;
  };
  return changes_sign(c.across[0]) && changes_sign(-c.across[0]) && changes_sign(c.across[1]) &&
         changes_sign(-c.across[1]);
}

}  // namespace

NeckSearch find_missed_necks(const Field& field, const Mesh& mesh, std::span<const CriticalStart> starts) {
  NeckSearch out;
  if (starts.empty() || mesh.triangles.empty()) return out;
  double mean_edge = 0;
  for (const CriticalStart& s : starts) mean_edge += s.edge;
  mean_edge /= static_cast<double>(starts.size());
  if (!(mean_edge > 0) || !std::isfinite(mean_edge)) return out;
  SpatialHash claimed(mean_edge);
  std::vector<Vec3> targets;
  std::vector<Critical> found;
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

  const std::size_t max_walks = std::max(kMinNeckWalks, mesh.positions.size() / kVerticesPerWalk);
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
  out.critical_points = found.size();

  std::vector<const Critical*> thin;
  for (const Critical& c : found)
    if (c.radius <= kThinWaist * c.edge) thin.push_back(&c);
  std::stable_sort(thin.begin(), thin.end(), [](const Critical* a, const Critical* b) { return a->radius < b->radius; });
  if (thin.empty()) return out;
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
  return out;
}

}  // namespace cdp::adaptive
