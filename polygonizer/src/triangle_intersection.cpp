// The exact triangle-triangle test and a hash-grid broad phase (triangle_intersection.h).
// The test is built on two orientation predicates, each evaluated in double with Shewchuk's error
// bound (Adaptive Precision Floating-Point Arithmetic and Fast Robust Geometric Predicates, 1997)
// and, when the bound cannot certify the sign, again with exact expansion arithmetic, so its sign
// is exact as long as no product overflows or underflows (every coordinate 0 or between about
// 1e-50 and 1e100 in magnitude).
#include <cdp/core/triangle_intersection.h>

#include "fresh_vector.h"
#include "parallel.h"
#include "polled_growth.h"
#include "vertex_triangles.h"

#include <cdp/core/errors.h>

#include <algorithm>
#include <atomic>
#include <climits>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <numbers>
#include <span>
#include <string>

namespace cdp {

namespace {

// ---- Exact arithmetic: expansions are sums of doubles, non-overlapping, in increasing
// magnitude, without zeros except a lone 0 for zero (Shewchuk's representation).
using Expansion = std::vector<double>;

constexpr double kEpsilon = 0x1p-53;  // half an ulp of 1
constexpr double kOrient2dBound = (3.0 + 16.0 * kEpsilon) * kEpsilon;
constexpr double kOrient3dBound = (7.0 + 56.0 * kEpsilon) * kEpsilon;

void two_sum(double a, double b, double& x, double& y) {
  x = a + b;
  const double bv = x - a, av = x - bv;
  y = (a - av) + (b - bv);
}

// a - b as an expansion of at most two terms.
Expansion difference(double a, double b) {
  const double x = a - b;
  const double bv = a - x, av = x + bv;
  const double y = (a - av) + (bv - b);
  if (y == 0.0) return {x};
  return {y, x};
}

// e + b (Shewchuk's GROW-EXPANSION with zero elimination).
Expansion grow(const Expansion& e, double b) {
  Expansion h;
  h.reserve(e.size() + 1);
  double q = b;
  for (double c : e) {
    double sum, err;
    two_sum(q, c, sum, err);
    q = sum;
    if (err != 0.0) h.push_back(err);
  }
  if (q != 0.0 || h.empty()) h.push_back(q);
  return h;
}

Expansion add(Expansion e, const Expansion& f) {
  for (double c : f) e = grow(e, c);
  return e;
}

Expansion negate(Expansion e) {
  for (double& c : e) c = -c;
  return e;
}

// e * b (SCALE-EXPANSION with zero elimination; products split exactly by fma).
Expansion scale(const Expansion& e, double b) {
  Expansion h;
  h.reserve(2 * e.size());
  double q = e[0] * b;
  double err = std::fma(e[0], b, -q);
  if (err != 0.0) h.push_back(err);
  for (std::size_t i = 1; i < e.size(); ++i) {
    const double p1 = e[i] * b;
    const double p0 = std::fma(e[i], b, -p1);
    double sum;
    two_sum(q, p0, sum, err);
    if (err != 0.0) h.push_back(err);
    two_sum(p1, sum, q, err);
    if (err != 0.0) h.push_back(err);
  }
  if (q != 0.0 || h.empty()) h.push_back(q);
  return h;
}

Expansion multiply(const Expansion& e, const Expansion& f) {
  Expansion h{0.0};
  for (double c : f) h = add(std::move(h), scale(e, c));
  return h;
}

// The sign of a non-overlapping expansion is the sign of its largest component.
int sign(const Expansion& e) {
  for (auto it = e.rbegin(); it != e.rend(); ++it)
    if (*it != 0.0) return *it > 0.0 ? 1 : -1;
  return 0;
}

// ---- Predicates.

// The sign of det [a-d; b-d; c-d]: which side of the plane through a, b, c the point d is on
// (zero: the four points are coplanar).
int orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double adx = a.x() - d.x(), bdx = b.x() - d.x(), cdx = c.x() - d.x();
  const double ady = a.y() - d.y(), bdy = b.y() - d.y(), cdy = c.y() - d.y();
  const double adz = a.z() - d.z(), bdz = b.z() - d.z(), cdz = c.z() - d.z();
  const double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy;
  const double cdxady = cdx * ady, adxcdy = adx * cdy;
  const double adxbdy = adx * bdy, bdxady = bdx * ady;
  const double det = adz * (bdxcdy - cdxbdy) + bdz * (cdxady - adxcdy) + cdz * (adxbdy - bdxady);
  const double permanent = (std::abs(bdxcdy) + std::abs(cdxbdy)) * std::abs(adz) +
                           (std::abs(cdxady) + std::abs(adxcdy)) * std::abs(bdz) +
                           (std::abs(adxbdy) + std::abs(bdxady)) * std::abs(cdz);
  const double bound = kOrient3dBound * permanent;
  if (det > bound) return 1;
  if (-det > bound) return -1;
  // Four points with one coordinate equal, bit for bit, lie in a plane normal to that axis: a
  // column of the determinant is zero (a difference of doubles is 0 only between equal ones).
  // Meshes of boxes and CSG shapes put whole faces so, and their coplanar neighbours, which the
  // bound above cannot settle, took the exact path below at every test (a Menger sponge's
  // repair: a fifth of its run in the expansions' allocations).
  if ((adx == 0 && bdx == 0 && cdx == 0) || (ady == 0 && bdy == 0 && cdy == 0) || (adz == 0 && bdz == 0 && cdz == 0))
    return 0;
  // The same determinant, exactly.
  const Expansion eadx = difference(a.x(), d.x()), ebdx = difference(b.x(), d.x()), ecdx = difference(c.x(), d.x());
  const Expansion eady = difference(a.y(), d.y()), ebdy = difference(b.y(), d.y()), ecdy = difference(c.y(), d.y());
  const Expansion eadz = difference(a.z(), d.z()), ebdz = difference(b.z(), d.z()), ecdz = difference(c.z(), d.z());
  const auto minor = [](const Expansion& p, const Expansion& q, const Expansion& r, const Expansion& s) {
    return add(multiply(p, q), negate(multiply(r, s)));  // p q - r s
  };
  Expansion sum = multiply(eadz, minor(ebdx, ecdy, ecdx, ebdy));
  sum = add(std::move(sum), multiply(ebdz, minor(ecdx, eady, eadx, ecdy)));
  sum = add(std::move(sum), multiply(ecdz, minor(eadx, ebdy, ebdx, eady)));
  return sign(sum);
}

// orient3d(v, p, q, x) for several x against one plane (v, p, q): the cross product of p - v and
// q - v, its products kept for the error bound, is computed once. The determinant, expanded along
// x's row, is -(x - v) . ((p - v) x (q - v)): the same sum of three terms, each a difference
// times a difference of products of differences, as orient3d's expansion along a column, so the
// same bound holds for it (the bound does not depend on which entries play which part); an
// uncertain sign is settled by orient3d itself, exactly.
class PlaneSides {
 public:
  PlaneSides(const Vec3& v, const Vec3& p, const Vec3& q) : v_(v), p_(p), q_(q) {
    const double px = p.x() - v.x(), py = p.y() - v.y(), pz = p.z() - v.z();
    const double qx = q.x() - v.x(), qy = q.y() - v.y(), qz = q.z() - v.z();
    const double pyqz = py * qz, pzqy = pz * qy, pzqx = pz * qx, pxqz = px * qz, pxqy = px * qy, pyqx = py * qx;
    n_ = {pyqz - pzqy, pzqx - pxqz, pxqy - pyqx};
    abs_ = {std::abs(pyqz) + std::abs(pzqy), std::abs(pzqx) + std::abs(pxqz), std::abs(pxqy) + std::abs(pyqx)};
  }
  int side(const Vec3& x) const {
    const double dx = x.x() - v_.x(), dy = x.y() - v_.y(), dz = x.z() - v_.z();
    const double det = dx * n_[0] + dy * n_[1] + dz * n_[2];
    const double bound = kOrient3dBound * (std::abs(dx) * abs_[0] + std::abs(dy) * abs_[1] + std::abs(dz) * abs_[2]);
    if (det > bound) return -1;
    if (-det > bound) return 1;
    return orient3d(v_, p_, q_, x);
  }

 private:
  const Vec3 &v_, &p_, &q_;
  std::array<double, 3> n_, abs_;
};

// The orientation of a, b, c projected onto the two axes other than `drop` (the axes (drop+1)%3
// and (drop+2)%3, in that order): positive counter-clockwise, zero collinear.
int orient2d(const Vec3& a, const Vec3& b, const Vec3& c, int drop) {
  const int i = (drop + 1) % 3, j = (drop + 2) % 3;
  const double acx = a[i] - c[i], bcx = b[i] - c[i], acy = a[j] - c[j], bcy = b[j] - c[j];
  const double left = acx * bcy, right = acy * bcx;
  const double det = left - right;
  const double bound = kOrient2dBound * (std::abs(left) + std::abs(right));
  if (det > bound) return 1;
  if (-det > bound) return -1;
  // Three points with one coordinate equal lie on a line along the other axis (as in orient3d).
  if ((acx == 0 && bcx == 0) || (acy == 0 && bcy == 0)) return 0;
  const Expansion exact = add(multiply(difference(a[i], c[i]), difference(b[j], c[j])),
                              negate(multiply(difference(a[j], c[j]), difference(b[i], c[i]))));
  return sign(exact);
}

using Tri = std::array<Vec3, 3>;

// The axis to drop so that the projection of the (non-degenerate) triangle is non-degenerate,
// preferring the largest component of its normal; -1 for a degenerate triangle. All incidences
// between points of the triangle's plane survive this projection (it is an affine bijection).
// The largest component first settles almost every triangle with one filtered orient2d; the
// other two follow in any order (any non-degenerate projection serves).
int projection_axis(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a).cwiseAbs();
  const int first = n[0] >= n[1] ? (n[0] >= n[2] ? 0 : 2) : (n[1] >= n[2] ? 1 : 2);
  for (int k = 0; k < 3; ++k)
    if (orient2d(a, b, c, (first + k) % 3) != 0) return (first + k) % 3;
  return -1;
}

// r, collinear with p and q in the projection, lies on the closed segment [p, q].
bool between(const Vec3& p, const Vec3& q, const Vec3& r, int drop) {
  for (int axis : {(drop + 1) % 3, (drop + 2) % 3})
    if (r[axis] < std::min(p[axis], q[axis]) || r[axis] > std::max(p[axis], q[axis])) return false;
  return true;
}

// Closed segments [p1, p2] and [q1, q2] of one plane meet (projected with `drop`).
bool segments_meet_2d(const Vec3& p1, const Vec3& p2, const Vec3& q1, const Vec3& q2, int drop) {
  const int d1 = orient2d(q1, q2, p1, drop), d2 = orient2d(q1, q2, p2, drop);
  const int d3 = orient2d(p1, p2, q1, drop), d4 = orient2d(p1, p2, q2, drop);
  if (d1 * d2 < 0 && d3 * d4 < 0) return true;
  return (d1 == 0 && between(q1, q2, p1, drop)) || (d2 == 0 && between(q1, q2, p2, drop)) ||
         (d3 == 0 && between(p1, p2, q1, drop)) || (d4 == 0 && between(p1, p2, q2, drop));
}

// p lies in the closed triangle t of its plane.
bool point_in_triangle_2d(const Vec3& p, const Tri& t, int drop) {
  const int s0 = orient2d(t[0], t[1], p, drop), s1 = orient2d(t[1], t[2], p, drop), s2 = orient2d(t[2], t[0], p, drop);
  const bool negative = s0 < 0 || s1 < 0 || s2 < 0, positive = s0 > 0 || s1 > 0 || s2 > 0;
  return !(negative && positive);
}

// Two closed triangles of one plane meet.
bool coplanar_triangles_meet(const Tri& a, const Tri& b, int drop) {
  for (int e = 0; e < 3; ++e)
    for (int f = 0; f < 3; ++f)
      if (segments_meet_2d(a[e], a[(e + 1) % 3], b[f], b[(f + 1) % 3], drop)) return true;
  // No boundaries cross: either one triangle holds the other or they are apart.
  return point_in_triangle_2d(a[0], b, drop) || point_in_triangle_2d(b[0], a, drop);
}

// The closed segment [p, q] meets the closed (non-degenerate) triangle t, given the sides sp and
// sq of p and q of t's plane (orient3d(t[0], t[1], t[2], .)), which callers may have already.
bool segment_meets_closed_triangle(const Vec3& p, const Vec3& q, const Tri& t, int sp, int sq) {
  if (sp * sq > 0) return false;
  if (sp == 0 && sq == 0) {  // the segment lies in the triangle's plane
    const int drop = projection_axis(t[0], t[1], t[2]);
    if (point_in_triangle_2d(p, t, drop) || point_in_triangle_2d(q, t, drop)) return true;
    for (int e = 0; e < 3; ++e)
      if (segments_meet_2d(p, q, t[e], t[(e + 1) % 3], drop)) return true;
    return false;
  }
  // The line through p and q crosses the plane at one point of [p, q]: that point lies in the
  // closed triangle when the line passes no edge on the wrong side.
  const int s0 = orient3d(p, q, t[0], t[1]), s1 = orient3d(p, q, t[1], t[2]), s2 = orient3d(p, q, t[2], t[0]);
  const bool negative = s0 < 0 || s1 < 0 || s2 < 0, positive = s0 > 0 || s1 > 0 || s2 > 0;
  return !(negative && positive);
}

// Closed non-degenerate triangles without shared vertices meet. Each corner's side of the other
// triangle's plane is computed once and shared by the tests below.
bool triangles_meet(const Tri& a, const Tri& b) {
  int sa[3], sb[3];  // sides of a's corners of b's plane, and of b's corners of a's plane
  for (int i = 0; i < 3; ++i) sa[i] = orient3d(b[0], b[1], b[2], a[i]);
  const auto one_side = [](const int* s) { return (s[0] > 0 && s[1] > 0 && s[2] > 0) || (s[0] < 0 && s[1] < 0 && s[2] < 0); };
  if (one_side(sa)) return false;
  for (int i = 0; i < 3; ++i) sb[i] = orient3d(a[0], a[1], a[2], b[i]);
  if (one_side(sb)) return false;
  if (sa[0] == 0 && sa[1] == 0 && sa[2] == 0) return coplanar_triangles_meet(a, b, projection_axis(a[0], a[1], a[2]));
  // Different planes: the intersection is a segment of their common line whose end points lie
  // on the triangles' boundaries, so it is empty unless an edge of one meets the other.
  for (int e = 0; e < 3; ++e) {
    const int f = (e + 1) % 3;
    if (segment_meets_closed_triangle(a[e], a[f], b, sa[e], sa[f]) ||
        segment_meets_closed_triangle(b[e], b[f], a, sb[e], sb[f]))
      return true;
  }
  return false;
}

// d - v lies in the closed cone at v spanned by u1 - v and u2 - v (an angle below pi), in the
// projection `drop` of their common plane.
bool in_cone(const Vec3& d, const Vec3& v, const Vec3& u1, const Vec3& u2, int drop) {
  const int s = orient2d(v, u1, u2, drop);
  return orient2d(v, u1, d, drop) * s >= 0 && orient2d(v, d, u2, drop) * s >= 0;
}

}  // namespace

// The exact test for two non-degenerate triangles (see the header for the rules).
bool nondegenerate_triangles_intersect(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b) {
  int shared = 0, ia[3], ib[3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (a[i] == b[j]) {
        ia[shared] = i;
        ib[shared] = j;
        ++shared;
      }
  if (shared == 0) return triangles_meet(a, b);
  if (shared >= 3) return true;  // the same triangle twice
  if (shared == 2) {
    // Edge (u, w) shared, third vertices p and q. Different planes meet only along the edge's
    // line; in one plane the triangles overlap when p and q lie on the same side of the edge.
    const Vec3& u = a[ia[0]];
    const Vec3& w = a[ia[1]];
    const Vec3& p = a[3 - ia[0] - ia[1]];
    const Vec3& q = b[3 - ib[0] - ib[1]];
    if (orient3d(u, w, p, q) != 0) return false;
    const int drop = projection_axis(u, w, p);
    return orient2d(u, w, p, drop) == orient2d(u, w, q, drop);
  }
  // One shared vertex v; the other vertices a1, a2 and b1, b2.
  const Vec3& v = a[ia[0]];
  const Vec3& a1 = a[(ia[0] + 1) % 3];
  const Vec3& a2 = a[(ia[0] + 2) % 3];
  const Vec3& b1 = b[(ib[0] + 1) % 3];
  const Vec3& b2 = b[(ib[0] + 2) % 3];
  // The sides of a1 and a2 of b's plane (v, b1, b2 is b turned cyclically: the same plane and
  // orientation). Both strictly on one side: a meets that plane only at v, which does not count.
  const PlaneSides b_plane(v, b1, b2);
  const int s1 = b_plane.side(a1), s2 = b_plane.side(a2);
  if (s1 * s2 > 0) return false;
  if (s1 == 0 && s2 == 0) {
    // One plane: near v each triangle is its angle at v, and the intersection is convex, so the
    // triangles meet beyond v when the angles overlap, i.e. when a side of one lies in the other.
    const int drop = projection_axis(v, a1, a2);
    return in_cone(a1, v, b1, b2, drop) || in_cone(a2, v, b1, b2, drop) || in_cone(b1, v, a1, a2, drop) ||
           in_cone(b2, v, a1, a2, drop);
  }
  // Different planes: the common line passes through v, and each triangle's part of it runs from
  // v to a point of the opposite side, so they meet beyond v when an opposite side meets the
  // other triangle (which it cannot do at v). Likewise b's far corners strictly on one side of
  // a's plane leave b meeting that plane only at v.
  const PlaneSides a_plane(v, a1, a2);
  const int t1 = a_plane.side(b1), t2 = a_plane.side(b2);
  if (t1 * t2 > 0) return false;
  return segment_meets_closed_triangle(a1, a2, b, s1, s2) || segment_meets_closed_triangle(b1, b2, a, t1, t2);
}

namespace {

Tri corners(const Mesh& mesh, int f) {
  const auto& t = mesh.triangles[static_cast<std::size_t>(f)];
  return {mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]};
}

bool boxes_overlap(const Box& p, const Box& q) {
  return p.min.x() <= q.max.x() && q.min.x() <= p.max.x() && p.min.y() <= q.max.y() && q.min.y() <= p.max.y() &&
         p.min.z() <= q.max.z() && q.min.z() <= p.max.z();
}

// The intersecting pairs as they are found: their number and the max_pairs lexicographically
// smallest (a max-heap), so memory stays bounded however many pairs there are.
class PairCollector {
 public:
  explicit PairCollector(std::size_t max_pairs) : max_pairs_(max_pairs) {}
  void add(int f, int g) {
    ++count_;
    if (max_pairs_ == 0) return;
    const std::pair<int, int> p(f, g);
    if (smallest_.size() < max_pairs_) {
      smallest_.push_back(p);
      std::push_heap(smallest_.begin(), smallest_.end());
    } else if (p < smallest_.front()) {
      std::pop_heap(smallest_.begin(), smallest_.end());
      smallest_.back() = p;
      std::push_heap(smallest_.begin(), smallest_.end());
    }
  }
  std::size_t count() const { return count_; }
  std::size_t max_pairs() const { return max_pairs_; }
  // Adds another collector's pairs: the same count and smallest pairs as adding them one by one.
  void merge(PairCollector&& other) {
    const std::size_t count = count_ + other.count_;
    for (const auto& [f, g] : other.smallest_) add(f, g);
    count_ = count;
  }
  std::vector<std::pair<int, int>> sorted_pairs() {
    std::sort_heap(smallest_.begin(), smallest_.end());
    return std::move(smallest_);
  }

 private:
  std::size_t max_pairs_;
  std::size_t count_ = 0;
  std::vector<std::pair<int, int>> smallest_;
};

// ---- Stars that cannot intersect themselves.
//
// On a closed mesh of even triangles almost every pair that the broad phase passes shares a
// vertex or an edge (a triangle's boxes overlap those of its 3 neighbours across edges and of
// about 9 more around its corners), and on a smooth surface almost every vertex's star is a flat
// fan, whose triangles meet only where they share a vertex or an edge. flat_stars proves that
// per vertex, once, so that the check skips those pairs instead of testing them.
//
// The proof. Let v's triangles close one fan (v, a_0, a_1), (v, a_1, a_2), ..., (v, a_{k-1}, a_0),
// and let n be a direction along which each triangle, projected, turns counter-clockwise from
// a_i to a_{i+1} by an angle in (0, pi), the turns adding up to one full turn. Then every
// direction from v's image lies in exactly one triangle's open angle, or on the common side of
// two consecutive ones: the projection is one-to-one on the star, so two of its triangles have no
// common point besides their shared vertex or edge, and triangles_intersect says no for them.
// Its answer is exact, so skipping the test changes no result.
//
// Certainty in double. n is any computed vector, normalized (the proof holds for every n). Each
// triangle must turn by a clear margin: det = ((a_i - v) x (a_{i+1} - v)) . n at least
// kTurnMargin |a_i - v| |a_{i+1} - v|, where the rounding error of det is below 1e-15 times that
// product (orient3d's bound of 7 eps times its permanent, at most 2 sqrt 3 times the product).
// Sides between 1e-50 and 1e50 long keep every product away from underflow and overflow. The
// projected sides are then no shorter than kTurnMargin times the sides, so each turn is known to
// within about 1e-9 radians (plus turn_angle's approximation), and since the true sum is a whole
// number of full turns, a computed sum below 3 pi proves it is one. Anything else (a fan that
// does not close, a star folded over itself, a degenerate triangle, a pinched vertex) is not
// certified, and its pairs are tested.
constexpr double kTurnMargin = 1e-6;
constexpr std::size_t kMaxStar = 64;  // larger stars are tested pair by pair

// The angle of the vector (x, y), y > 0, in (0, pi), within 0.0016 radians: the arctangent of the
// ratio at most 1 by Rajan, Wang, Inkol and Joyal's polynomial (Efficient approximations for the
// arctangent function, 2006; largest error 0.0015). A star's sum of at most kMaxStar of them is
// then within 0.11 of the true sum, far inside the pi that separates one full turn from two, and
// costs a tenth of std::atan2's.
double turn_angle(double y, double x) {
  constexpr double kPi = std::numbers::pi;
  const auto atan_unit = [](double z) { return kPi / 4 * z - z * (std::abs(z) - 1.0) * (0.2447 + 0.0663 * std::abs(z)); };
  if (std::abs(x) <= y) return kPi / 2 - atan_unit(x / y);
  return x > 0.0 ? atan_unit(y / x) : kPi + atan_unit(y / x);
}

// `wanted` (optional, one flag per vertex): only those vertices are certified (the others are
// left uncertified): the vertices of the triangles a restricted check tests.
std::vector<unsigned char> flat_stars(const Mesh& mesh, unsigned workers, const CancelToken* cancel,
                                      const std::vector<char>* wanted = nullptr) {
  const std::size_t nv = mesh.positions.size();
  const VertexTriangles stars(mesh, cancel, "self-intersections");
  std::vector<unsigned char> flat(nv, 0);
  const auto certify = [&](std::size_t v) {
    const auto begin = static_cast<std::size_t>(stars.offsets[v]);
    const std::size_t k = static_cast<std::size_t>(stars.offsets[v + 1]) - begin;
    if (k < 3 || k > kMaxStar) return false;
    int b[kMaxStar], c[kMaxStar];  // each triangle's corners after v, counter-clockwise
    for (std::size_t j = 0; j < k; ++j) {
      const auto& t = mesh.triangles[static_cast<std::size_t>(stars.incident[begin + j])];
      const int at = t[0] == static_cast<int>(v) ? 0 : t[1] == static_cast<int>(v) ? 1 : 2;
      b[j] = t[(at + 1) % 3];
      c[j] = t[(at + 2) % 3];
      if (b[j] == static_cast<int>(v) || c[j] == static_cast<int>(v) || b[j] == c[j]) return false;
    }
    // One fan: the corners b are distinct, and going from each triangle to the one whose b is its
    // c comes back to the first after exactly k steps. side[i] = a_i - v in the fan's order.
    for (std::size_t i = 0; i < k; ++i)
      for (std::size_t j = i + 1; j < k; ++j)
        if (b[i] == b[j]) return false;
    const Vec3& p = mesh.positions[v];
    Vec3 side[kMaxStar + 1];
    std::size_t at = 0;
    for (std::size_t step = 0; step < k; ++step) {
      side[step] = mesh.positions[static_cast<std::size_t>(b[at])] - p;
      std::size_t next = k;
      for (std::size_t j = 0; j < k; ++j)
        if (b[j] == c[at]) next = j;
      if (next == k || (next == 0) != (step + 1 == k)) return false;
      at = next;
    }
    side[k] = side[0];
    double length2[kMaxStar + 1];
    for (std::size_t i = 0; i < k; ++i) {
      length2[i] = side[i].squaredNorm();
      if (!(length2[i] >= 1e-100 && length2[i] <= 1e100)) return false;
    }
    length2[k] = length2[0];
    Vec3 turn[kMaxStar];
    Vec3 n = Vec3::Zero();
    for (std::size_t i = 0; i < k; ++i) {
      turn[i] = side[i].cross(side[i + 1]);
      n += turn[i];
    }
    const double n2 = n.squaredNorm();
    if (!(n2 > 0.0) || !std::isfinite(n2)) return false;
    n /= std::sqrt(n2);
    double height[kMaxStar + 1];
    for (std::size_t i = 0; i < k; ++i) height[i] = side[i].dot(n);
    height[k] = height[0];
    double total = 0.0;
    for (std::size_t i = 0; i < k; ++i) {
      const double det = turn[i].dot(n);
      if (!(det > 0.0) || det * det < kTurnMargin * kTurnMargin * length2[i] * length2[i + 1]) return false;
      total += turn_angle(det, side[i].dot(side[i + 1]) - height[i] * height[i + 1]);
    }
    return total < 3.0 * std::numbers::pi;
  };
  constexpr std::size_t kBlock = 4096;
  detail::parallel_blocks(nv, kBlock, nv >= 2 * kBlock ? workers : 1, [&](std::size_t begin, std::size_t end, unsigned) {
    if (cancel) cancel->check("self-intersections");
    for (std::size_t v = begin; v < end; ++v) flat[v] = (!wanted || (*wanted)[v]) && certify(v) ? 1 : 0;
  });
  return flat;
}

// The hash grid's cell side in median longest edges. Larger cells enter each triangle in fewer
// cells (fewer hashes and entries to sort) and put more triangles in each bucket (more box
// comparisons, in the cache); one edge entered a graded mesh's triangles in many cells.
// Instructions of whole paper-variant runs (torus at factor 5 / bunny VIS-800 at factor 3) for
// 1, 1.5, 2 and 3: 93.8M / 1099.5M, 91.3M / 1085.9M, 90.5M / 1082.1M, 90.7M / 1081.0M.
constexpr double kCellEdges = 2;
// Items (triangles, vertices, buckets) between two polls of the cancel token: a few hundred
// microseconds of work, an atomic load each.
constexpr std::size_t kPollEvery = 4096;
// A triangle whose box spans more than this many cells along an axis is "large": it is tested
// against every triangle instead of being put in the grid (at most kMaxSpan^3 cells each).
constexpr int kMaxSpan = 4;
// hash_grid_pairs tells a pair's bucket by the place of a cell in its block of 8 x 8 x 8 cells.
static_assert(kMaxSpan < 8);

// Calls fn(slice, begin, end) for each slice [begin, end) of kPollEvery items of [0, count), on
// up to `workers` threads, polling `cancel` at each slice's start. Each slice writes only its own
// items, or its own results that the caller gathers in slice order: the same on any number of
// threads.
template <class Fn>
void in_slices(std::size_t count, unsigned workers, const CancelToken* cancel, const char* what, const Fn& fn) {
  detail::parallel_blocks(count, kPollEvery, workers, [&](std::size_t begin, std::size_t end, unsigned) {
    if (cancel) cancel->check(what);
    fn(begin / kPollEvery, begin, end);
  });
}

std::size_t slice_count(std::size_t count) { return (count + kPollEvery - 1) / kPollEvery; }

// n copies of `value` in a FreshVector, its pages first written (faulted in) on the threads.
template <class T>
detail::FreshVector<T> filled_on_threads(std::size_t n, const T& value, unsigned workers, const CancelToken* cancel) {
  detail::FreshVector<T> v(n);
  in_slices(n, workers, cancel, "self-intersections", [&](std::size_t, std::size_t begin, std::size_t end) {
    std::fill(v.begin() + static_cast<std::ptrdiff_t>(begin), v.begin() + static_cast<std::ptrdiff_t>(end), value);
  });
  return v;
}

// The bounds of no box, and `bounds` grown to hold `b`.
Box no_bounds() {
  return {Vec3::Constant(std::numeric_limits<double>::infinity()), Vec3::Constant(-std::numeric_limits<double>::infinity())};
}
void extend(Box& bounds, const Box& b) {
  bounds.min = bounds.min.cwiseMin(b.min);
  bounds.max = bounds.max.cwiseMax(b.max);
}

std::uint64_t cell_hash(int x, int y, int z) {
  std::uint64_t k = static_cast<std::uint64_t>(x) * 0x9E3779B97F4A7C15ull ^
                    static_cast<std::uint64_t>(y) * 0xC2B2AE3D27D4EB4Full ^
                    static_cast<std::uint64_t>(z) * 0x165667B19E3779F9ull;
  k ^= k >> 31;
  k *= 0xBF58476D1CE4E5B9ull;
  k ^= k >> 29;
  return k;
}

// Every intersecting pair of the triangles with non-empty boxes, each pair decided once (tested,
// or known apart because the triangles share a vertex with a flat star: flat_stars).
//
// Cells are cubes of side h, at least kCellEdges median longest edges; a triangle whose box spans more
// than kMaxSpan cells along an axis is large, and h grows (to a third of the extent of the
// (16 + sqrt n)-th widest triangle) so that few are. Every other triangle is entered in each cell
// its box touches (at most kMaxSpan^3), the cells hashed into about as many buckets as entries
// (counting sort by bucket, so each bucket lists its triangles in increasing order). Of the pairs
// f < g of a bucket, one is tested only when the boxes overlap and the bucket is that of the
// cell of the lower corner of their intersection: that cell holds both triangles, so each
// overlapping pair is tested exactly once, even when distinct cells share a bucket. Large
// triangles are tested against all others (two large ones from the lower index): at most about
// (16 + sqrt n) n box comparisons.
// With `involved`, only the pairs with at least one involved triangle (a bucket with none is
// passed over).
void hash_grid_pairs(const Mesh& mesh, std::span<const Box> boxes, PairCollector& out, int threads,
                     const CancelToken* cancel, const std::vector<char>* involved = nullptr) {
  const auto either = [involved](int f, int g) {
    return !involved || (*involved)[static_cast<std::size_t>(f)] || (*involved)[static_cast<std::size_t>(g)];
  };
  const auto poll = [cancel](std::size_t i) {
    if (cancel && i % kPollEvery == 0) cancel->check("self-intersections");
  };
  // The preparation's passes over the triangles and buckets run on the threads, kPollEvery
  // items a slice (polled at its start), each slice writing its own elements, or its own results
  // gathered in slice order: the same on any number of threads. Its fresh arrays are
  // FreshVectors whose pages those passes write first: made and zero-filled on one thread, their
  // page faults (30-40 MB for the 6 * 10^5 triangles near the seams of the blocks' torus at
  // tolerance 1e-5, at 8-13 us a page on the test machine) were most of the serial preparation's
  // 0.2 s. The counting sort stays serial. Below kParallelTriangles threads cost more than they
  // save (see the pairs' pass below).
  constexpr std::size_t kParallelTriangles = 2048, kBlocksPerWorker = 8, kMinBlock = 1024;
  const unsigned workers = boxes.size() >= kParallelTriangles ? detail::worker_count(threads) : 1;
  const auto slices = [&](std::size_t count, const auto& fn) { in_slices(count, workers, cancel, "self-intersections", fn); };
  std::vector<std::vector<int>> slice_live(slice_count(boxes.size()));
  slices(boxes.size(), [&](std::size_t s, std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f)
      if ((boxes[f].min.array() <= boxes[f].max.array()).all()) slice_live[s].push_back(static_cast<int>(f));
  });
  std::vector<int> live;
  for (std::vector<int>& s : slice_live) live.insert(live.end(), s.begin(), s.end()), s = {};
  const std::size_t n = live.size();
  if (n < 2) return;

  // Cell size: kCellEdges median longest edges, grown so that at most about 16 + sqrt(n)
  // triangles are wider than kMaxSpan - 1 cells.
  detail::FreshVector<double> sizes(n);
  slices(n, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const Tri t = corners(mesh, live[k]);
      sizes[k] = std::sqrt(std::max({(t[1] - t[0]).squaredNorm(), (t[2] - t[1]).squaredNorm(), (t[0] - t[2]).squaredNorm()}));
    }
  });
  std::nth_element(sizes.begin(), sizes.begin() + static_cast<std::ptrdiff_t>(n / 2), sizes.end());
  poll(0);  // each selection takes tens of milliseconds at 2*10^6 triangles
  double h = kCellEdges * sizes[n / 2];
  const auto max_large = static_cast<std::size_t>(16.0 + std::sqrt(static_cast<double>(n)));
  std::vector<Box> slice_bounds(slice_count(n), no_bounds());
  slices(n, [&](std::size_t s, std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const Box& b = boxes[static_cast<std::size_t>(live[k])];
      sizes[k] = b.size().maxCoeff();
      extend(slice_bounds[s], b);
    }
  });
  Box all = no_bounds();
  for (const Box& b : slice_bounds) extend(all, b);
  if (n > max_large) {
    std::nth_element(sizes.begin(), sizes.begin() + static_cast<std::ptrdiff_t>(max_large), sizes.end(), std::greater<>());
    poll(0);
    h = std::max(h, sizes[max_large] / static_cast<double>(kMaxSpan - 1));
  }
  // Cell coordinates fit in int (at most 2^30 cells along an axis).
  h = std::max(h, all.size().maxCoeff() * 0x1p-30);
  if (!(h > 0.0) || !std::isfinite(h)) h = 1.0;
  sizes = {};

  // The cell of a coordinate is monotone in it, so a box's cells hold every point of the box, and
  // the cell of the larger of two coordinates is the larger of their cells.
  const Vec3 origin = all.min;
  // x >= origin, so the conversion's truncation is the floor (without std::floor's library call).
  const auto cell = [&](double x, int axis) { return static_cast<int>((x - origin[axis]) / h); };
  struct CellRange {
    int lo[3], hi[3];
  };
  // Written for the live triangles only, the only ones read.
  detail::FreshVector<CellRange> ranges(boxes.size());
  detail::FreshVector<unsigned char> is_large(boxes.size());
  std::vector<std::vector<int>> slice_large(slice_count(n));
  std::vector<std::size_t> slice_entries(slice_count(n), 0);
  slices(n, [&](std::size_t s, std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const int f = live[k];
      const Box& b = boxes[static_cast<std::size_t>(f)];
      CellRange& r = ranges[static_cast<std::size_t>(f)];
      for (int a = 0; a < 3; ++a) {
        r.lo[a] = cell(b.min[a], a);
        r.hi[a] = cell(b.max[a], a);
      }
      const bool wide = r.hi[0] - r.lo[0] >= kMaxSpan || r.hi[1] - r.lo[1] >= kMaxSpan || r.hi[2] - r.lo[2] >= kMaxSpan;
      is_large[static_cast<std::size_t>(f)] = wide ? 1 : 0;
      if (wide)
        slice_large[s].push_back(f);
      else
        slice_entries[s] += static_cast<std::size_t>(r.hi[0] - r.lo[0] + 1) * static_cast<std::size_t>(r.hi[1] - r.lo[1] + 1) *
                            static_cast<std::size_t>(r.hi[2] - r.lo[2] + 1);
    }
  });
  std::vector<int> large;
  std::size_t entries = 0;
  for (std::size_t s = 0; s < slice_large.size(); ++s) {
    large.insert(large.end(), slice_large[s].begin(), slice_large[s].end());
    entries += slice_entries[s];
  }
  slice_large = {};
  if (entries >= std::numeric_limits<std::uint32_t>::max())
    throw LimitExceededError("self-intersections: too many triangles for the hash grid");

  // Buckets: a power of two, at least the number of entries; counting sort of the entries.
  int bits = 0;
  while ((std::size_t{1} << bits) < entries) ++bits;
  const std::size_t buckets = std::size_t{1} << bits;
  // Blocks of 8 x 8 x 8 cells hashed to runs of 512 consecutive buckets: neighbouring cells
  // share cache lines, and distinct blocks collide only at random. With fewer buckets than 512
  // the mask keeps only part of a cell's place in its block.
  const std::size_t block_mask = std::min<std::size_t>(511, buckets - 1);
  const auto local_bits = [&](int x, int y, int z) {
    return static_cast<std::size_t>((x & 7) | (y & 7) << 3 | (z & 7) << 6) & block_mask;
  };
  const auto bucket_of = [&](int x, int y, int z) {
    return static_cast<std::size_t>((cell_hash(x >> 3, y >> 3, z >> 3) << 9 | local_bits(x, y, z)) & (buckets - 1));
  };
  const auto for_each_cell = [&](int f, const auto& visit) {
    const CellRange& r = ranges[static_cast<std::size_t>(f)];
    for (int z = r.lo[2]; z <= r.hi[2]; ++z)
      for (int y = r.lo[1]; y <= r.hi[1]; ++y)
        for (int x = r.lo[0]; x <= r.hi[0]; ++x) visit(x, y, z, bucket_of(x, y, z));
  };
  // Counts, then their running sums (the end of each bucket), then filled backwards from the last
  // triangle: start[b] ends at the beginning of bucket b, its triangles in increasing order.
  // Both arrays' pages are written first on the threads (zeros), for the serial sort.
  detail::FreshVector<std::uint32_t> start = filled_on_threads<std::uint32_t>(buckets + 1, 0, workers, cancel);
  for (const int f : live) {
    poll(static_cast<std::size_t>(f));
    if (!is_large[static_cast<std::size_t>(f)]) for_each_cell(f, [&](int, int, int, std::size_t b) { ++start[b]; });
  }
  for (std::size_t b = 1; b <= buckets; ++b) {
    poll(b);
    start[b] += start[b - 1];
  }
  detail::FreshVector<int> members = filled_on_threads<int>(entries, 0, workers, cancel);
  for (auto it = live.rbegin(); it != live.rend(); ++it) {
    poll(static_cast<std::size_t>(*it));
    if (!is_large[static_cast<std::size_t>(*it)])
      for_each_cell(*it, [&](int, int, int, std::size_t b) { members[--start[b]] = *it; });
  }

  // Each bucket's pairs are enumerated from its own list, its members' boxes and lower cells
  // copied side by side first: a list holds few triangles on an even mesh, and its
  // pairs then cost comparisons in the cache instead of a search and a random load of a box for
  // each (the torus at factor 20, 102k triangles: 860 -> 740 ns per triangle on one core).
  // Buckets are shared among threads in blocks; each thread collects its own pairs and the
  // collectors are merged, which gives the same count and smallest pairs in any order. Below
  // kParallelTriangles threads cost more than they save (starting one costs tens of
  // microseconds; 2048 triangles take about a millisecond).
  const std::size_t block = std::max(kMinBlock, buckets / (kBlocksPerWorker * workers));
  std::vector<PairCollector> found(workers, PairCollector(out.max_pairs()));
  // Pairs that share a vertex with a flat star do not intersect (see flat_stars): skipped.
  std::vector<char> wanted;  // with `involved`: the vertices of the triangles left in
  if (involved) {
    wanted.assign(mesh.positions.size(), 0);
    for (const int f : live)
      for (const int v : mesh.triangles[static_cast<std::size_t>(f)]) wanted[static_cast<std::size_t>(v)] = 1;
  }
  const std::vector<unsigned char> flat = flat_stars(mesh, workers, cancel, involved ? &wanted : nullptr);
  struct Member {
    Box box;
    int lo[3];
    int id;
    int flat[3];  // the triangle's vertices whose stars are flat, -1 for the others
  };
  const auto shares_flat_star = [](const Member& p, const Member& q) {
    for (const int v : p.flat)
      if (v >= 0 && (v == q.flat[0] || v == q.flat[1] || v == q.flat[2])) return true;
    return false;
  };
  std::vector<std::vector<Member>> lists(workers);
  detail::parallel_blocks(buckets, block, workers, [&](std::size_t begin, std::size_t end, unsigned worker) {
    PairCollector& mine = found[worker];
    std::vector<Member>& list = lists[worker];
    for (std::size_t b = begin; b < end; ++b) {
      poll(b);
      if (start[b + 1] - start[b] < 2) continue;
      // A triangle with several cells in the bucket appears several times, consecutively.
      list.clear();
      bool any = !involved;
      for (std::uint32_t e = start[b]; e < start[b + 1]; ++e) {
        const int f = members[e];
        if (!list.empty() && list.back().id == f) continue;
        any = any || (*involved)[static_cast<std::size_t>(f)];
        const CellRange& r = ranges[static_cast<std::size_t>(f)];
        const auto& t = mesh.triangles[static_cast<std::size_t>(f)];
        const auto flat_or_none = [&](int v) { return flat[static_cast<std::size_t>(v)] ? v : -1; };
        list.push_back({boxes[static_cast<std::size_t>(f)], {r.lo[0], r.lo[1], r.lo[2]}, f,
                        {flat_or_none(t[0]), flat_or_none(t[1]), flat_or_none(t[2])}});
      }
      if (!any) continue;
      for (std::size_t i = 0; i + 1 < list.size(); ++i) {
        const Member& p = list[i];
        for (std::size_t j = i + 1; j < list.size(); ++j) {
          const Member& q = list[j];
          if (!boxes_overlap(p.box, q.box) || !either(p.id, q.id)) continue;
          // The pair is tested in the bucket of the cell c of the lower corner of the boxes'
          // intersection (in both boxes, so both triangles are listed there): once. c's place
          // in its block (the bucket's low bits) is enough: a triangle spans fewer than 8 cells
          // along each axis, so c is its only cell with that place, and the only one that can
          // have put it in a bucket with these low bits.
          const int x = std::max(p.lo[0], q.lo[0]), y = std::max(p.lo[1], q.lo[1]), z = std::max(p.lo[2], q.lo[2]);
          if (local_bits(x, y, z) != (b & block_mask) || shares_flat_star(p, q)) continue;
          if (nondegenerate_triangles_intersect(corners(mesh, p.id), corners(mesh, q.id))) mine.add(p.id, q.id);
        }
      }
    }
  });
  for (PairCollector& c : found) out.merge(std::move(c));
  const auto test = [&](int f, int g) {  // f < g
    if (nondegenerate_triangles_intersect(corners(mesh, f), corners(mesh, g))) out.add(f, g);
  };
  for (const int f : large) {
    const Box& p = boxes[static_cast<std::size_t>(f)];
    for (const int g : live) {
      if (g == f || (is_large[static_cast<std::size_t>(g)] && g < f)) continue;
      if (!boxes_overlap(p, boxes[static_cast<std::size_t>(g)]) || !either(f, g)) continue;
      test(std::min(f, g), std::max(f, g));
    }
  }
}

}  // namespace

bool triangle_is_degenerate(const Vec3& a, const Vec3& b, const Vec3& c) {
  return projection_axis(a, b, c) < 0;
}

// A computed m.d, with d = q - s computed too, is off from the exact value of m.(q - s) by at most
// about 4 units in the last place of sum |m_i| |d_i| (m is any vector: it is chosen, not computed
// exactly); the margin is 1e-14 of that sum, and a margin below the smallest normal double (an
// underflow) decides nothing.
bool apart_at_shared_vertex(const Vec3& s, const Vec3& a1, const Vec3& a2, const Vec3& b1, const Vec3& b2) {
  const Vec3 da1 = a1 - s, da2 = a2 - s, db1 = b1 - s, db2 = b2 - s;
  const Vec3 m = (da1.normalized() + da2.normalized()).normalized() - (db1.normalized() + db2.normalized()).normalized();
  const auto side = [&](const Vec3& d) {
    const double x = m.dot(d), margin = 1e-14 * m.cwiseAbs().dot(d.cwiseAbs());
    if (!(margin >= std::numeric_limits<double>::min())) return 0;
    return x > margin ? 1 : x < -margin ? -1 : 0;
  };
  return side(da1) == 1 && side(da2) == 1 && side(db1) == -1 && side(db2) == -1;
}

bool triangles_intersect(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b) {
  for (const Tri* t : {&a, &b})
    for (const Vec3& p : *t)
      if (!p.allFinite()) throw InvalidInputError("triangles_intersect: a vertex position is not finite");
  if (triangle_is_degenerate(a[0], a[1], a[2]) || triangle_is_degenerate(b[0], b[1], b[2])) return false;
  return nondegenerate_triangles_intersect(a, b);
}

bool triangles_intersect(const Mesh& mesh, int f, int g) {
  const auto n = static_cast<long long>(mesh.triangles.size());
  if (f < 0 || f >= n || g < 0 || g >= n || f == g)
    throw InvalidInputError("triangles_intersect: expects two different triangles of the mesh");
  const auto nv = static_cast<long long>(mesh.positions.size());
  for (int h : {f, g})
    for (int i : mesh.triangles[static_cast<std::size_t>(h)])
      if (i < 0 || i >= nv) throw InvalidInputError("triangles_intersect: a triangle index is out of range");
  return triangles_intersect(corners(mesh, f), corners(mesh, g));
}

namespace {

// The checks of triangle_boxes_for_intersection before any box: every index in range, every
// position a triangle uses finite; `cancel` (when given) polled every kPollEvery triangles.
// Each pass on the threads, a slice at a time: the error is the lowest slice's, the one a single
// thread meets first, and every index is checked before any position.
void validate_for_intersection(const Mesh& mesh, const char* what, const CancelToken* cancel, int threads = 1) {
  if (mesh.triangles.size() > static_cast<std::size_t>(INT_MAX))
    throw InvalidInputError(std::string(what) + ": too many triangles");
  const auto nv = static_cast<long long>(mesh.positions.size());
  const std::size_t n = mesh.triangles.size();
  const auto slices = [&](const auto& fn) {
    in_slices(n, detail::worker_count(threads), cancel, what, [&](std::size_t, std::size_t begin, std::size_t end) {
      for (std::size_t f = begin; f < end; ++f) fn(mesh.triangles[f]);
    });
  };
  slices([&](const std::array<int, 3>& t) {
    for (int i : t)
      if (i < 0 || i >= nv) throw InvalidInputError(std::string(what) + ": a triangle index is out of range");
  });
  slices([&](const std::array<int, 3>& t) {
    for (int i : t)
      if (!mesh.positions[static_cast<std::size_t>(i)].allFinite())
        throw InvalidInputError(std::string(what) + ": a vertex position is not finite");
  });
}

// triangle_boxes_for_intersection, polling `cancel` (when given) every kPollEvery triangles.
detail::FreshVector<Box> boxes_for_intersection(const Mesh& mesh, std::size_t* degenerate, const char* what,
                                                const CancelToken* cancel, int threads = 1) {
  validate_for_intersection(mesh, what, cancel, threads);
  const std::size_t n = mesh.triangles.size();
  const auto poll = [&](std::size_t f) {
    if (cancel && f % kPollEvery == 0) cancel->check(what);
  };
  // Each slice of triangles on a thread, into its own slots of the fresh array, whose pages it
  // faults in (a hundred megabytes at 2*10^6 triangles): the degeneracy test was a fifth of the
  // blocks' final check on the torus at factor 40, all of it serial.
  detail::FreshVector<Box> boxes(n);
  std::atomic<std::size_t> skipped{0};
  detail::parallel_blocks(n, kPollEvery, detail::worker_count(threads), [&](std::size_t begin, std::size_t end, unsigned) {
    poll(begin);
    std::size_t here = 0;
    for (std::size_t f = begin; f < end; ++f) {
      const Tri t = corners(mesh, static_cast<int>(f));
      if (triangle_is_degenerate(t[0], t[1], t[2])) {
        boxes[f] = {Vec3::Ones(), Vec3::Zero()};
        ++here;
        continue;
      }
      boxes[f] = {t[0].cwiseMin(t[1]).cwiseMin(t[2]), t[0].cwiseMax(t[1]).cwiseMax(t[2])};
    }
    skipped.fetch_add(here, std::memory_order_relaxed);
  });
  if (degenerate) *degenerate = skipped.load();
  return boxes;
}

}  // namespace

std::vector<Box> triangle_boxes_for_intersection(const Mesh& mesh, std::size_t* degenerate, const char* what) {
  const detail::FreshVector<Box> boxes = boxes_for_intersection(mesh, degenerate, what, nullptr);
  return {boxes.begin(), boxes.end()};
}

std::vector<std::pair<int, int>> self_intersecting_pairs(const Mesh& mesh, std::size_t max_pairs, int threads,
                                                         const CancelToken* cancel) {
  const detail::FreshVector<Box> boxes = boxes_for_intersection(mesh, nullptr, "self_intersecting_pairs", cancel, threads);
  PairCollector out(max_pairs);
  hash_grid_pairs(mesh, boxes, out, threads, cancel);
  return out.sorted_pairs();
}

namespace {

// What a check of the pairs with an involved triangle needs of the mesh, one mark per triangle:
// kNearInvolved for every triangle whose box touches a cell of a coarse grid that an involved
// triangle's box touches (any other overlaps no involved box, so is in no pair to test), and
// kInStar for the others around their vertices (flat_stars certifies a vertex from its whole
// star). Cells of kCoarseCellEdges median involved box sides, or larger, up to kMaxCoarseCells
// cells; empty (everything is needed) where no such grid is found. The boxes are made on the
// way, never held: held for every triangle they were the largest part of a run's peak memory (89
// of 444 MB at 1.9 * 10^6 triangles, the blocks' torus at tolerance 1e-5), where most triangles
// are in no pair to test.
constexpr unsigned char kFarFromInvolved = 0, kNearInvolved = 1, kInStar = 2;
std::vector<unsigned char> near_involved(const Mesh& mesh, const std::vector<char>& involved, unsigned workers,
                                         const CancelToken* cancel) {
  constexpr double kCoarseCellEdges = 2;
  constexpr double kMaxCoarseCells = 1 << 27;  // a bit each: 16 MB
  constexpr double kCoarseCellGrowth = 1.25;
  const std::size_t n = mesh.triangles.size();
  // The passes over every triangle run on the threads, a slice of kPollEvery triangles at a time
  // (polled at its start); each writes only its own triangles' marks or its slice's results,
  // gathered in slice order, so the marks are the same on any number of threads. The function
  // takes 0.08-0.1 s on one thread for the blocks' torus at tolerance 1e-5 (1.85 * 10^6
  // triangles), all of it serial before.
  const auto slices = [&](const auto& fn) { in_slices(n, workers, cancel, "self-intersections", fn); };
  const auto box_of = [&](std::size_t f) {
    const Tri t = corners(mesh, static_cast<int>(f));
    return Box{t[0].cwiseMin(t[1]).cwiseMin(t[2]), t[0].cwiseMax(t[1]).cwiseMax(t[2])};
  };
  std::vector<Box> slice_bounds(slice_count(n), no_bounds());
  std::vector<std::vector<int>> slice_involved(slice_count(n));
  slices([&](std::size_t s, std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f) {
      extend(slice_bounds[s], box_of(f));
      if (involved[f]) slice_involved[s].push_back(static_cast<int>(f));
    }
  });
  Box all = no_bounds();
  std::vector<int> ids;  // the involved triangles, in increasing order
  for (std::size_t s = 0; s < slice_bounds.size(); ++s) {
    extend(all, slice_bounds[s]);
    ids.insert(ids.end(), slice_involved[s].begin(), slice_involved[s].end());
  }
  slice_involved = {};
  if (ids.empty()) return std::vector<unsigned char>(n, kFarFromInvolved);  // no pair to test
  std::vector<double> sides(ids.size());
  for (std::size_t k = 0; k < ids.size(); ++k) sides[k] = box_of(static_cast<std::size_t>(ids[k])).size().maxCoeff();
  std::nth_element(sides.begin(), sides.begin() + static_cast<std::ptrdiff_t>(sides.size() / 2), sides.end());
  double h = kCoarseCellEdges * sides[sides.size() / 2];
  if (!(h > 0)) return {};
  const Vec3 extent = all.max - all.min;
  if (!extent.allFinite()) return {};
  std::array<long long, 3> dims{};
  const auto count_cells = [&] {
    double cells = 1;
    for (int a = 0; a < 3; ++a) cells *= std::floor(extent[a] / h) + 1;  // in double: no overflow
    return cells;
  };
  // Larger cells where there would be too many: they keep more triangles, never fewer than needed
  // (at 1.8 * 10^7 triangles of the torus the cells of two median edges were 1.5 * 10^8, and the
  // check took every triangle: 2 GB and 10 s of the run's 55). Each step grows the cells by a
  // quarter, at most 4096 steps (10^397 times); where they do not suffice (an h below 10^-390 of
  // the box), every triangle is checked.
  double cells = count_cells();
  for (int step = 0; step < 4096 && !(cells <= kMaxCoarseCells); ++step) {
    h *= kCoarseCellGrowth;
    cells = count_cells();
  }
  if (!(cells <= kMaxCoarseCells)) return {};
  for (int a = 0; a < 3; ++a) dims[a] = static_cast<long long>(extent[a] / h) + 1;
  const auto cell = [&](double x, int a) {
    return std::clamp(static_cast<long long>((x - all.min[a]) / h), 0LL, dims[a] - 1);
  };
  // A bit per cell, set here and only read on the threads; zeroed there (16 MB of fresh pages at
  // most).
  detail::FreshVector<std::uint64_t> marked =
      filled_on_threads<std::uint64_t>((static_cast<std::size_t>(cells) + 63) / 64, 0, workers, cancel);
  const auto is_marked = [&](std::size_t c) { return (marked[c >> 6] >> (c & 63) & 1) != 0; };
  // Calls fn(index) for every coarse cell box f touches, until fn returns true.
  const auto any_cell = [&](std::size_t f, const auto& fn) {
    const Box b = box_of(f);
    for (long long z = cell(b.min.z(), 2); z <= cell(b.max.z(), 2); ++z)
      for (long long y = cell(b.min.y(), 1); y <= cell(b.max.y(), 1); ++y)
        for (long long x = cell(b.min.x(), 0); x <= cell(b.max.x(), 0); ++x)
          if (fn(static_cast<std::size_t>((z * dims[1] + y) * dims[0] + x))) return true;
    return false;
  };
  for (std::size_t k = 0; k < ids.size(); ++k) {
    if (cancel && k % kPollEvery == 0) cancel->check("self-intersections");
    any_cell(static_cast<std::size_t>(ids[k]), [&](std::size_t c) { return marked[c >> 6] |= std::uint64_t{1} << (c & 63), false; });
  }
  std::vector<unsigned char> near(n, kFarFromInvolved);
  slices([&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f)
      if (involved[f] || any_cell(f, is_marked)) near[f] = kNearInvolved;
  });
  // The vertices of the near triangles, marked on one thread (neighbouring slices share them).
  std::vector<unsigned char> at_vertex(mesh.positions.size(), 0);
  for (std::size_t f = 0; f < n; ++f) {
    if (cancel && f % kPollEvery == 0) cancel->check("self-intersections");
    if (near[f] == kNearInvolved)
      for (const int v : mesh.triangles[f]) at_vertex[static_cast<std::size_t>(v)] = 1;
  }
  slices([&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f) {
      if (near[f] != kFarFromInvolved) continue;
      const auto& t = mesh.triangles[f];
      if (at_vertex[static_cast<std::size_t>(t[0])] || at_vertex[static_cast<std::size_t>(t[1])] ||
          at_vertex[static_cast<std::size_t>(t[2])])
        near[f] = kInStar;
    }
  });
  return near;
}

}  // namespace

std::vector<std::pair<int, int>> self_intersecting_pairs_involving(const Mesh& mesh, const std::vector<char>& involved,
                                                                   std::size_t max_pairs, int threads,
                                                                   const CancelToken* cancel) {
  if (involved.size() != mesh.triangles.size())
    throw InvalidInputError("self_intersecting_pairs_involving: expects one flag per triangle");
  const char* what = "self_intersecting_pairs";
  validate_for_intersection(mesh, what, cancel, threads);
  const std::vector<unsigned char> near = near_involved(mesh, involved, detail::worker_count(threads), cancel);
  PairCollector out(max_pairs);
  if (near.empty()) {
    const detail::FreshVector<Box> boxes = boxes_for_intersection(mesh, nullptr, what, cancel, threads);
    hash_grid_pairs(mesh, boxes, out, threads, cancel, &involved);
    return out.sorted_pairs();
  }
  // The triangles needed, as a mesh of their own, in their order (so a pair's order and the
  // smallest max_pairs pairs are the same in either numbering), their vertices renumbered.
  Mesh part;
  std::vector<int> ids;  // part's triangle -> mesh's
  ids.reserve(static_cast<std::size_t>(std::count_if(near.begin(), near.end(), [](unsigned char m) { return m != kFarFromInvolved; })));
  part.triangles.reserve(ids.capacity());
  std::vector<int> vertex(mesh.positions.size(), -1);
  for (std::size_t f = 0; f < near.size(); ++f) {
    if (cancel && f % kPollEvery == 0) cancel->check(what);
    if (near[f] == kFarFromInvolved) continue;
    std::array<int, 3> t{};
    for (int c = 0; c < 3; ++c) {
      int& v = vertex[static_cast<std::size_t>(mesh.triangles[f][c])];
      if (v < 0) {
        v = static_cast<int>(part.positions.size());
        part.positions.push_back(mesh.positions[static_cast<std::size_t>(mesh.triangles[f][c])]);
      }
      t[c] = v;
    }
    part.triangles.push_back(t);
    ids.push_back(static_cast<int>(f));
  }
  vertex = {};
  detail::FreshVector<Box> boxes = boxes_for_intersection(part, nullptr, what, cancel, threads);
  std::vector<char> part_involved(ids.size(), 0);
  for (std::size_t k = 0; k < ids.size(); ++k) {
    const auto f = static_cast<std::size_t>(ids[k]);
    part_involved[k] = involved[f];
    if (near[f] == kInStar) boxes[k] = {Vec3::Ones(), Vec3::Zero()};  // in a star only: in no pair
  }
  hash_grid_pairs(part, boxes, out, threads, cancel, &part_involved);
  std::vector<std::pair<int, int>> pairs = out.sorted_pairs();
  for (auto& [f, g] : pairs) f = ids[static_cast<std::size_t>(f)], g = ids[static_cast<std::size_t>(g)];
  return pairs;
}

std::size_t count_self_intersecting_pairs(const Mesh& mesh, int threads) {
  const detail::FreshVector<Box> boxes = boxes_for_intersection(mesh, nullptr, "count_self_intersecting_pairs", nullptr, threads);
  PairCollector out(0);
  hash_grid_pairs(mesh, boxes, out, threads, nullptr);
  return out.count();
}

}  // namespace cdp
