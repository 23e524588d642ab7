// Multi-level Partition of Unity implicit (Ohtake, Belyaev, Alexa, Turk & Seidel 2003) of
// oriented points: F(x) = sum_i w_i(x) Q_i(x) / sum_i w_i(x) over the leaf cells of an octree.
//
// Build: starting from a cube around the points, each cell of diagonal d gets a support ball of
// radius R = support_factor * d about its centre; when the ball holds fewer than min_points
// points, R grows to the distance of the min_points-th nearest point (Ohtake's enlargement, taken
// to its limit) and the cell becomes a leaf (its children would see the same few points). A cell
// whose ball holds no point at all is a leaf with the unenlarged ball whose function is the
// signed distance to the point nearest its centre (side from the nearest points' tangent planes):
// it never vanishes in the ball, whereas a quadratic fitted to distant points and extrapolated
// over empty space curls back into stray sheets. Otherwise the
// local function Q is fitted by weighted least squares (weights w_i(p) on the points):
//  - a bivariate quadratic w = h(u, v) in a frame whose w axis is the weighted mean normal, when
//    every normal in the ball makes an angle below 90 degrees with it (Q = w - h(u, v));
//  - a general quadric otherwise, held away from the trivial solution by auxiliary points at the
//    cell's corners and centre, with the signed distance estimated from their 6 nearest points
//    (kept only when the 6 agree on the side, as in the paper);
// the fit's error is the largest Taubin distance |Q(p)| / |grad Q(p)| over the ball's points;
// a cell whose error exceeds max_error (a fraction of the points' box diagonal) is split into 8
// children, down to max_depth. Sharp-feature fits (the paper's edge and corner quadrics) are not
// used: the scans are smooth. w_i(x) = b(3 |x - c_i| / (2 R_i)) with the quadratic B-spline b,
// so F is C^1; its Hessian is exact (weights' derivatives included) wherever it exists, and jumps
// across the spheres |x - c_i| = R_i / 3 and R_i where b'' does.
//
// Every point of the root cube lies in the ball of the leaf that contains it (with weight at
// least b(3 / (4 support_factor)) > 0, 1/8 for the default), so the weights sum to a positive value everywhere
// in the cube; beyond it F falls back to the distance from the cube's centre (positive, never
// zero). The leaves whose balls hold a point are found through the octree: each node knows how far
// from its centre its leaves' balls reach.
#pragma once

#include <cdp/core/field.h>
#include <cdp/core/oriented_points.h>

#include <cstddef>
#include <string>
#include <vector>

namespace cdp {

struct MpuOptions {
  // The fit tolerance epsilon_0 as a fraction of the points' bounding-box diagonal.
  double max_error = 0.002;
  // alpha: the support radius over the cell diagonal (Ohtake et al.: 0.75); above 0.5.
  double support_factor = 0.75;
  // N_min: the fewest points a local fit uses (Ohtake et al.: 15); at least 10.
  int min_points = 15;
  // Deepest octree level (the root is 0); cells there are leaves whatever their error.
  int max_depth = 12;
};

struct MpuStats {
  std::size_t points = 0;
  std::size_t cells = 0;   // octree nodes
  std::size_t leaves = 0;
  std::size_t bivariate = 0;  // leaves by fit
  std::size_t quadric = 0;
  std::size_t plane = 0;       // fall-back tangent plane when neither fit was possible
  std::size_t empty = 0;       // leaves without a point in their ball (signed distance to the nearest)
  std::size_t enlarged = 0;    // leaves whose ball had to grow to min_points
  std::size_t at_max_depth = 0;  // leaves over the tolerance at max_depth
  int depth = 0;                 // deepest level reached
  double tolerance = 0;          // epsilon_0 in model units
  double max_leaf_error = 0;     // largest fit error among leaves (model units)
  double seconds = 0;            // build time, point tree included
};

class Mpu : public Field {
 public:
  // InvalidInputError (naming `source`) for fewer than min_points points, inconsistent or
  // non-finite data, or options out of range. The box is that of the points, inflated by
  // kMpuBoxMargin of its diagonal.
  Mpu(const OrientedPoints& points, const MpuOptions& options = {}, std::string source = "mpu");

  std::string type_name() const override { return "mpu"; }
  bool thread_safe() const override { return true; }  // evaluation reads immutable data only
  bool smooth() const override { return true; }
  const MpuStats& stats() const { return stats_; }
  // sum_i w_i(p): positive wherever F is the blend (everywhere in the octree's root cube).
  double weight_sum(const Vec3& p) const;

 protected:
  double eval_value(const Vec3& p) const override;
  double eval_value_gradient(const Vec3& p, Vec3& gradient) const override;
  double eval_gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const override;

 private:
  // Q(x) = y^T A y + b . y + c with y = x - centre: both fits, written as one quadric. For a
  // `distance` leaf (no data in its ball) Q(x) = c |x - b| instead, c = +1 or -1.
  struct Leaf {
    Vec3 centre;
    double radius2;  // R^2
    double k;        // 3 / (2 R): t = k |x - centre|
    Mat3 A;
    Vec3 b;
    double c;
    bool distance = false;
  };
  struct Node {
    Vec3 centre;
    double reach2;        // squared reach of the balls of the leaves below
    int first_child = -1; // 8 consecutive nodes, or -1 for a leaf
    int leaf = -1;
  };
  struct Builder;

  static double local_value(const Leaf& L, const Vec3& p, const Vec3& y, Vec3* gradient, Mat3* hessian);
  template <class Visit>
  void for_each_leaf(const Vec3& p, Visit&& visit) const;

  std::vector<Node> nodes_;
  std::vector<Leaf> leaves_;
  Vec3 root_centre_ = Vec3::Zero();
  MpuStats stats_;
};

// Box margin, as a fraction of the points' box diagonal.
inline constexpr double kMpuBoxMargin = 0.05;

}  // namespace cdp
