// A sampled volume as a field: the samples of a regular grid (a CT or MRI scan, simulation
// output, a distance grid from another tool) interpolated by a tricubic B-spline, F = S - level
// (or level - S where the inside is above the level, as in a density scan).
//
// Why B-splines: the interpolant is C2 everywhere, so its gradient and Hessian are exact, the
// curvature the adaptive method sizes triangles by is the interpolant's own, and the surface
// has no crease (Field::smooth). The coefficients are prefiltered (Unser's recursive filter
// with mirror boundaries) so that S equals the samples at the grid nodes: the interpolant
// interpolates, it does not smooth. Beyond the grid's box F is its value at the nearest point of
// the box plus the distance to the box: outside, like the box's faces.
#pragma once

#include <cdp/core/field.h>

#include <array>
#include <cstddef>
#include <utility>
#include <vector>

namespace cdp {

// A regular grid of samples: values[(i * dims[1] + j) * dims[2] + k] is the sample at
// origin + (i, j, k) * spacing, i along x (the order of a C-ordered numpy array a[i, j, k]).
struct VolumeSamples {
  std::array<std::size_t, 3> dims{0, 0, 0};
  Vec3 origin = Vec3::Zero();
  Vec3 spacing = Vec3::Ones();
  std::vector<double> values;
};

// Which side of the level is the inside.
enum class VolumeInside {
  Below,  // values below the level are inside (a signed distance: negative inside)
  Above,  // values above the level are inside (a density: bone in a CT scan)
};

class Volume : public Field {
 public:
  // Fewest samples along an axis: a cubic spans four.
  static constexpr std::size_t kMinSamples = 4;
  // Most samples in all: 2^28 (a 645^3 grid) take 2 GiB of double coefficients.
  static constexpr std::size_t kMaxSamples = std::size_t{1} << 28;

  // The field's box is the grid's, origin to origin + (dims - 1) * spacing.
  // \throw InvalidInputError for fewer than kMinSamples along an axis or more than kMaxSamples
  //        in all, a values array of another size, a spacing not positive and finite, a
  //        non-finite origin, sample or level, or an interpolant that is not outside everywhere
  //        on the grid's faces (the surface would reach the edge of the data: pad the volume
  //        with two or more layers of outside values). Checked on the coefficients of the two
  //        layers next to each face, which bound it there.
  Volume(VolumeSamples samples, double level, VolumeInside inside = VolumeInside::Below);

  std::string type_name() const override { return "volume"; }
  bool thread_safe() const override { return true; }  // reads its coefficients only
  bool smooth() const override { return true; }       // C2 everywhere
  // From the coefficients' differences: a spline's derivative along an axis is a quadratic
  // B-spline of its coefficients' differences divided by the spacing, with weights that are
  // non-negative and sum to one; beyond the grid the distance to it adds a slope of 1.
  std::optional<double> lipschitz_bound() const override { return lipschitz_; }
  // The spline lies within its coefficients' range over a region (weights non-negative, sum 1):
  // the range of the coefficients whose support meets the region.
  std::optional<std::pair<double, double>> value_range(const Box& region) const override;
  // The derivative along an axis lies within its coefficients' differences along that axis
  // (divided by the spacing) over the coefficients whose support meets the region (the weights
  // of a quadratic B-spline times two cubic ones: non-negative, summing to one). Nothing for a
  // region that reaches beyond the grid's box or to its outermost two layers, where the
  // distance term and the mirrored coefficients change the derivative.
  std::optional<std::pair<Vec3, Vec3>> gradient_range(const Box& region) const override;

  std::optional<double> sample_spacing() const override { return spacing_.minCoeff(); }

  const std::array<std::size_t, 3>& dims() const { return dims_; }
  const Vec3& origin() const { return origin_; }
  const Vec3& spacing() const { return spacing_; }
  double level() const { return level_; }

 protected:
  double eval_value(const Vec3& p) const override;
  double eval_value_gradient(const Vec3& p, Vec3& gradient) const override;
  double eval_gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const override;
  // Separably: the weights of each lattice coordinate once per axis, then the contraction along
  // z, y and x in turn over the coefficients the lattice reaches, in evaluate's order of
  // operations (the same values bit for bit). Point by point where the lattice reaches beyond
  // the grid's box or its contraction would need much memory.
  void eval_values_on_lattice(const Vec3& origin, double step, int n, double* out) const override;

 private:
  template <int Order>
  double evaluate(const Vec3& p, Vec3* gradient, Mat3* hessian) const;
  // Per axis, the first and last coefficient index whose support meets [lo_point, hi_point]
  // (before mirroring or clamping to the grid).
  std::array<std::pair<long long, long long>, 3> support_meeting(const Vec3& lo_point, const Vec3& hi_point) const;
  double coefficient(std::size_t i, std::size_t j, std::size_t k) const {
    return coefficients_[(i * dims_[1] + j) * dims_[2] + k];
  }

  std::array<std::size_t, 3> dims_;
  Vec3 origin_, spacing_, far_corner_;  // the grid's box: origin_ to far_corner_
  double level_;
  double sign_;  // +1 when the inside is below the level, -1 above
  std::vector<double> coefficients_;
  double lipschitz_ = 0;
};

}  // namespace cdp
