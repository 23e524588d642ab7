#include <cdp/core/errors.h>
#include <cdp/core/models/mpu.h>

#include <Eigen/QR>

#include <chrono>
#include <cmath>
#include <limits>

#include "point_kdtree.h"

namespace cdp {

namespace {

// The quadratic B-spline centred at 0 with support |t| < 3/2, and its derivatives.
inline double bspline(double t) {
  if (t < 0.5) return 0.75 - t * t;
  if (t < 1.5) {
    const double s = 1.5 - t;
    return 0.5 * s * s;
  }
  return 0.0;
}

// Auxiliary points take their signed distance from this many nearest points (Ohtake et al.).
constexpr std::size_t kAuxNeighbours = 6;

// Two unit vectors completing n to a right-handed orthonormal frame, chosen deterministically.
void complete_frame(const Vec3& n, Vec3& e1, Vec3& e2) {
  int axis = 0;
  n.cwiseAbs().minCoeff(&axis);
  e1 = n.cross(Vec3::Unit(axis)).normalized();
  e2 = n.cross(e1);
}

}  // namespace

// The octree build: a recursive fit-and-split over the cells, with the point tree for queries.
struct Mpu::Builder {
  const OrientedPoints& pts;
  const MpuOptions& opt;
  Mpu& mpu;
  PointKdTree tree;
  std::vector<std::uint32_t> ball;
  std::vector<double> weight;

  Builder(const OrientedPoints& p, const MpuOptions& o, Mpu& m) : pts(p), opt(o), mpu(m), tree(p.positions) {}

  struct Fit {
    Leaf leaf;
    double error = 0;
    enum Kind { Bivariate, Quadric, Plane } kind = Plane;
  };

  // Writes the quadric fitted in normalized coordinates yh = (x - c) / R, with values in units of
  // R, into model units: Q(x) = R q(yh) = y^T (Ah / R) y + bh . y + R ch.
  static void set_quadric(Leaf& leaf, const Mat3& Ah, const Vec3& bh, double ch, double R) {
    leaf.A = Ah / R;
    leaf.b = bh;
    leaf.c = R * ch;
  }

  // Largest Taubin distance over the ball's points with positive weight.
  double taubin_error(const Leaf& L) const {
    double worst = 0;
    for (std::size_t k = 0; k < ball.size(); ++k) {
      if (!(weight[k] > 0)) continue;
      const Vec3 y = pts.positions[ball[k]] - L.centre;
      const Vec3 Ay = L.A * y;
      const double q = y.dot(Ay) + L.b.dot(y) + L.c;
      const double g = (2.0 * Ay + L.b).norm();
      const double e = g > 0 ? std::abs(q) / g : std::numeric_limits<double>::infinity();
      worst = std::max(worst, e);
    }
    return worst;
  }

  bool fit_bivariate(const Vec3& c, double R, const Vec3& n, Fit& fit) const {
    Vec3 e1, e2;
    complete_frame(n, e1, e2);
    Eigen::Matrix<double, 6, 6> G = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> rhs = Eigen::Matrix<double, 6, 1>::Zero();
    for (std::size_t k = 0; k < ball.size(); ++k) {
      if (!(weight[k] > 0)) continue;
      const Vec3 y = (pts.positions[ball[k]] - c) / R;
      const double u = e1.dot(y), v = e2.dot(y), h = n.dot(y);
      Eigen::Matrix<double, 6, 1> phi;
      phi << u * u, u * v, v * v, u, v, 1.0;
      G.noalias() += weight[k] * phi * phi.transpose();
      rhs.noalias() += (weight[k] * h) * phi;
    }
    const Eigen::CompleteOrthogonalDecomposition<Eigen::Matrix<double, 6, 6>> cod(G);
    if (cod.rank() < 3) return false;  // not even a plane
    const Eigen::Matrix<double, 6, 1> a = cod.solve(rhs);
    if (!a.allFinite()) return false;
    // Q = n.y - h(u, v): the quadratic part of h as a 3x3 form in y.
    const Mat3 M = a(0) * e1 * e1.transpose() + 0.5 * a(1) * (e1 * e2.transpose() + e2 * e1.transpose()) +
                   a(2) * e2 * e2.transpose();
    set_quadric(fit.leaf, -M, n - a(3) * e1 - a(4) * e2, -a(5), R);
    fit.kind = Fit::Bivariate;
    return true;
  }

  bool fit_quadric(const Vec3& c, double R, double half, Fit& fit) const {
    using Vec10 = Eigen::Matrix<double, 10, 1>;
    auto basis = [](const Vec3& y) {
      Vec10 phi;
      phi << y.x() * y.x(), y.y() * y.y(), y.z() * y.z(), y.x() * y.y(), y.x() * y.z(), y.y() * y.z(), y.x(), y.y(),
          y.z(), 1.0;
      return phi;
    };
    // Auxiliary points: the cell's corners and centre, with the distance their 6 nearest points'
    // tangent planes agree on.
    std::vector<std::pair<Vec3, double>> aux;
    for (int corner = 0; corner <= 8; ++corner) {
      Vec3 a = c;
      if (corner < 8)
        a += half * Vec3((corner & 1) ? 1 : -1, (corner & 2) ? 1 : -1, (corner & 4) ? 1 : -1);
      const auto nn = tree.nearest(a, kAuxNeighbours);
      double sum = 0;
      int positive = 0, negative = 0;
      for (const auto& [d2, i] : nn) {
        const double s = (a - pts.positions[i]).dot(pts.normals[i]);
        sum += s;
        positive += s > 0;
        negative += s < 0;
      }
      if (nn.empty() || (positive > 0 && negative > 0) || positive + negative == 0) continue;
      aux.emplace_back((a - c) / R, sum / static_cast<double>(nn.size()) / R);
    }
    if (aux.empty()) return false;
    Eigen::Matrix<double, 10, 10> G = Eigen::Matrix<double, 10, 10>::Zero();
    Vec10 rhs = Vec10::Zero();
    double wsum = 0;
    for (std::size_t k = 0; k < ball.size(); ++k) wsum += weight[k];
    for (std::size_t k = 0; k < ball.size(); ++k) {
      if (!(weight[k] > 0)) continue;
      const Vec10 phi = basis((pts.positions[ball[k]] - c) / R);
      G.noalias() += (weight[k] / wsum) * phi * phi.transpose();
    }
    const double wa = 1.0 / static_cast<double>(aux.size());
    for (const auto& [y, d] : aux) {
      const Vec10 phi = basis(y);
      G.noalias() += wa * phi * phi.transpose();
      rhs.noalias() += (wa * d) * phi;
    }
    const Eigen::CompleteOrthogonalDecomposition<Eigen::Matrix<double, 10, 10>> cod(G);
    const Vec10 a = cod.solve(rhs);
    if (!a.allFinite()) return false;
    Mat3 Ah;
    Ah << a(0), 0.5 * a(3), 0.5 * a(4), 0.5 * a(3), a(1), 0.5 * a(5), 0.5 * a(4), 0.5 * a(5), a(2);
    set_quadric(fit.leaf, Ah, Vec3(a(6), a(7), a(8)), a(9), R);
    fit.kind = Fit::Quadric;
    return true;
  }

  Fit fit_cell(const Vec3& c, double R, double half) {
    Fit fit;
    fit.leaf.centre = c;
    fit.leaf.radius2 = R * R;
    fit.leaf.k = 1.5 / R;
    weight.resize(ball.size());
    Vec3 nsum = Vec3::Zero();
    for (std::size_t k = 0; k < ball.size(); ++k) {
      weight[k] = bspline(fit.leaf.k * (pts.positions[ball[k]] - c).norm());
      nsum += weight[k] * pts.normals[ball[k]];
    }
    bool agree = nsum.norm() > 0;
    const Vec3 n = agree ? Vec3(nsum.normalized()) : Vec3::UnitZ();
    for (std::size_t k = 0; k < ball.size() && agree; ++k)
      if (weight[k] > 0 && !(pts.normals[ball[k]].dot(n) > 0)) agree = false;
    bool ok = agree ? fit_bivariate(c, R, n, fit) : fit_quadric(c, R, half, fit);
    if (!ok && !agree && nsum.norm() > 0) ok = fit_bivariate(c, R, n, fit);
    if (!ok) {
      // The tangent plane of the point nearest the centre: always defined.
      const std::uint32_t i = tree.nearest(c, 1).front().second;
      fit.leaf.A.setZero();
      fit.leaf.b = pts.normals[i];
      fit.leaf.c = pts.normals[i].dot(c - pts.positions[i]);
      fit.kind = Fit::Plane;
    }
    fit.error = taubin_error(fit.leaf);
    return fit;
  }

  // Fills node `slot` for the cell of centre c and half side `half`; returns its reach.
  double build(int slot, const Vec3& c, double half, int depth) {
    MpuStats& st = mpu.stats_;
    st.depth = std::max(st.depth, depth);
    double R = opt.support_factor * 2.0 * half * std::sqrt(3.0);
    ball.clear();
    tree.ball(c, R, ball);
    bool enlarged = false;
    if (ball.empty()) {
      // No data in the cell's support: a fit would be extrapolated from far away (quadratics
      // then curl back into stray sheets, and even a tangent plane cuts the ball at a ridge or a
      // tip). The signed distance to the nearest point never vanishes in the ball (that point is
      // outside it); its side is that of the nearest points' tangent planes at the centre.
      const auto nn = tree.nearest(c, kAuxNeighbours);
      double side = 0;
      for (const auto& [d2, i] : nn) side += pts.normals[i].dot(c - pts.positions[i]);
      Leaf leaf;
      leaf.centre = c;
      leaf.radius2 = R * R;
      leaf.k = 1.5 / R;
      leaf.A.setZero();
      leaf.b = pts.positions[nn.front().second];  // the apex
      leaf.c = side < 0 ? -1.0 : 1.0;
      leaf.distance = true;
      ++st.leaves;
      ++st.empty;
      Node& node = mpu.nodes_[slot];
      node.centre = c;
      node.reach2 = R * R;
      node.leaf = static_cast<int>(mpu.leaves_.size());
      mpu.leaves_.push_back(leaf);
      return R;
    }
    if (ball.size() < static_cast<std::size_t>(opt.min_points)) {
      const auto nn = tree.nearest(c, static_cast<std::size_t>(opt.min_points));
      R = std::sqrt(nn.back().first) * (1 + 1e-9) + 1e-12 * half;
      ball.clear();
      tree.ball(c, R, ball);
      enlarged = true;
    }
    const Fit fit = fit_cell(c, R, half);
    if (fit.error > st.tolerance && depth < opt.max_depth && !enlarged) {
      const int first = static_cast<int>(mpu.nodes_.size());
      mpu.nodes_.resize(mpu.nodes_.size() + 8);
      double reach = 0;
      for (int k = 0; k < 8; ++k) {
        const Vec3 cc = c + 0.5 * half * Vec3((k & 1) ? 1 : -1, (k & 2) ? 1 : -1, (k & 4) ? 1 : -1);
        const double r = build(first + k, cc, 0.5 * half, depth + 1);
        reach = std::max(reach, (cc - c).norm() + r);
      }
      Node& node = mpu.nodes_[slot];
      node.centre = c;
      node.reach2 = reach * reach;
      node.first_child = first;
      return reach;
    }
    ++st.leaves;
    st.enlarged += enlarged;
    st.at_max_depth += fit.error > st.tolerance && depth >= opt.max_depth;
    st.bivariate += fit.kind == Fit::Bivariate;
    st.quadric += fit.kind == Fit::Quadric;
    st.plane += fit.kind == Fit::Plane;
    st.max_leaf_error = std::max(st.max_leaf_error, fit.error);
    Node& node = mpu.nodes_[slot];
    node.centre = c;
    node.reach2 = R * R;
    node.leaf = static_cast<int>(mpu.leaves_.size());
    mpu.leaves_.push_back(fit.leaf);
    return R;
  }
};

Mpu::Mpu(const OrientedPoints& points, const MpuOptions& options, std::string source) {
  const auto start = std::chrono::steady_clock::now();
  const std::size_t n = points.positions.size();
  if (points.normals.size() != n) throw InvalidInputError(source + ": positions and normals differ in number");
  if (!(options.max_error > 0) || !std::isfinite(options.max_error))
    throw InvalidInputError(source + ": max_error must be positive");
  if (!(options.support_factor > 0.5) || !std::isfinite(options.support_factor))
    throw InvalidInputError(source + ": support_factor must be above 0.5");
  if (options.min_points < 10) throw InvalidInputError(source + ": min_points must be at least 10");
  if (options.max_depth < 1 || options.max_depth > 20) throw InvalidInputError(source + ": max_depth must be in 1..20");
  if (n < static_cast<std::size_t>(options.min_points))
    throw InvalidInputError(source + ": an MPU implicit needs at least min_points = " +
                            std::to_string(options.min_points) + " points, got " + std::to_string(n));
  if (n >= std::numeric_limits<std::uint32_t>::max()) throw InvalidInputError(source + ": too many points");
  for (std::size_t i = 0; i < n; ++i)
    if (!points.positions[i].allFinite() || !points.normals[i].allFinite() ||
        std::abs(points.normals[i].norm() - 1) > 1e-6)
      throw InvalidInputError(source + ": point " + std::to_string(i) + " has a non-finite position or a non-unit normal");
  const Box box = bounding_box(points.positions);
  if (!(box.diagonal() > 0)) throw InvalidInputError(source + ": all points coincide");

  stats_.points = n;
  stats_.tolerance = options.max_error * box.diagonal();
  root_centre_ = box.center();
  // The root cube leaves room around the box below, so that the whole box lies inside it.
  const double half = 0.6 * box.size().maxCoeff();
  nodes_.resize(1);
  Builder builder(points, options, *this);
  builder.build(0, root_centre_, half, 0);
  stats_.cells = nodes_.size();
  set_bounds(box.inflated(kMpuBoxMargin * box.diagonal()));
  stats_.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The leaf's local function at y = p - centre: value, and gradient and Hessian when asked for.
inline double Mpu::local_value(const Leaf& L, const Vec3& p, const Vec3& y, Vec3* gradient, Mat3* hessian) {
  if (L.distance) {
    const Vec3 d = p - L.b;
    const double r = d.norm();
    if (gradient) *gradient = (L.c / r) * d;
    if (hessian) *hessian = (L.c / r) * (Mat3::Identity() - d * d.transpose() / (r * r));
    return L.c * r;
  }
  const Vec3 Ay = L.A * y;
  if (gradient) *gradient = 2.0 * Ay + L.b;
  if (hessian) *hessian = 2.0 * L.A;
  return y.dot(Ay) + L.b.dot(y) + L.c;
}

template <class Visit>
void Mpu::for_each_leaf(const Vec3& p, Visit&& visit) const {
  int stack[8 * 24];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if ((p - node.centre).squaredNorm() >= node.reach2) continue;
    if (node.leaf >= 0) {
      visit(leaves_[node.leaf]);
    } else {
      for (int k = 7; k >= 0; --k) stack[top++] = node.first_child + k;
    }
  }
}

double Mpu::weight_sum(const Vec3& p) const {
  double s = 0;
  for_each_leaf(p, [&](const Leaf& L) { s += bspline(L.k * (p - L.centre).norm()); });
  return s;
}

double Mpu::eval_value(const Vec3& p) const {
  double S = 0, N = 0;
  for_each_leaf(p, [&](const Leaf& L) {
    const Vec3 y = p - L.centre;
    const double w = bspline(L.k * y.norm());
    const double q = local_value(L, p, y, nullptr, nullptr);
    S += w;
    N += w * q;
  });
  if (!(S > 0)) return (p - root_centre_).norm();
  return N / S;
}

double Mpu::eval_value_gradient(const Vec3& p, Vec3& gradient) const {
  double S = 0, N = 0;
  Vec3 gS = Vec3::Zero(), gN = Vec3::Zero();
  for_each_leaf(p, [&](const Leaf& L) {
    const Vec3 y = p - L.centre;
    const double r = y.norm();
    const double t = L.k * r;
    const double w = bspline(t);
    Vec3 gq;
    const double q = local_value(L, p, y, &gq, nullptr);
    S += w;
    N += w * q;
    // grad w: -2 k^2 y inside t < 1/2, dw/dr y / r = -k (3/2 - t) y / r beyond.
    const Vec3 gw = t < 0.5 ? Vec3(-2.0 * L.k * L.k * y) : Vec3((t < 1.5 ? -L.k * (1.5 - t) / r : 0.0) * y);
    gS += gw;
    gN += q * gw + w * gq;
  });
  if (!(S > 0)) {
    const Vec3 d = p - root_centre_;
    gradient = d.normalized();
    return d.norm();
  }
  const double f = N / S;
  gradient = (gN - f * gS) / S;
  return f;
}

double Mpu::eval_gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const {
  double S = 0, N = 0;
  Vec3 gS = Vec3::Zero(), gN = Vec3::Zero();
  Mat3 hS = Mat3::Zero(), hN = Mat3::Zero();
  for_each_leaf(p, [&](const Leaf& L) {
    const Vec3 y = p - L.centre;
    const double r = y.norm();
    const double t = L.k * r;
    const double w = bspline(t);
    Vec3 gq;
    Mat3 hq;
    const double q = local_value(L, p, y, &gq, &hq);
    S += w;
    N += w * q;
    Vec3 gw;
    Mat3 hw;
    if (t < 0.5) {  // w = 3/4 - k^2 |y|^2
      gw = -2.0 * L.k * L.k * y;
      hw = -2.0 * L.k * L.k * Mat3::Identity();
    } else if (t < 1.5) {  // w = (3/2 - k r)^2 / 2: w' = -k (3/2 - t), w'' = k^2
      const double dw = -L.k * (1.5 - t);
      const Vec3 u = y / r;
      gw = dw * u;
      hw = (L.k * L.k) * (u * u.transpose()) + (dw / r) * (Mat3::Identity() - u * u.transpose());
    } else {
      gw.setZero();
      hw.setZero();
    }
    gS += gw;
    gN += q * gw + w * gq;
    hS += hw;
    hN += q * hw + gw * gq.transpose() + gq * gw.transpose() + w * hq;
  });
  if (!(S > 0)) {
    const Vec3 d = p - root_centre_;
    const double r = d.norm();
    const Vec3 u = d / r;
    gradient = u;
    hessian = (Mat3::Identity() - u * u.transpose()) / r;
    return r;
  }
  const double f = N / S;
  gradient = (gN - f * gS) / S;
  hessian = (hN - f * hS - gradient * gS.transpose() - gS * gradient.transpose()) / S;
  return f;
}

}  // namespace cdp
