// Blobby model: F(x) = T - sum_i s_i k(|x - c_i| / R_i), with Wyvill's compact polynomial kernel
// or Blinn's Gaussian. Both kernels are functions of a^2, so F is smooth everywhere.
#pragma once

#include <cdp/core/field.h>

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace cdp {

enum class BlobKernel { Wyvill, Blinn };

struct Blob {
  Vec3 center = Vec3::Zero();
  double radius = 1;
  double strength = 1;
};

class Blobs : public Field {
 public:
  // Throws InvalidInputError for an empty list, non-positive radii or a non-positive threshold.
  Blobs(BlobKernel kernel, double threshold, std::vector<Blob> blobs);
  std::string type_name() const override { return "blobs"; }
  bool thread_safe() const override { return true; }  // evaluation reads immutable data only
  bool smooth() const override { return true; }
  std::optional<double> lipschitz_bound() const override { return lipschitz_; }
  // Only blobs whose support reaches the region count (Wyvill kernels vanish beyond R).
  std::optional<double> lipschitz_bound(const Box& region) const override;
  // Both kernels decrease with distance, so each blob's term is bounded by its values at the
  // nearest and farthest points of the region.
  std::optional<std::pair<double, double>> value_range(const Box& region) const override;
  const std::vector<Blob>& blobs() const { return blobs_; }

 protected:
  double eval_value(const Vec3& p) const override;
  double eval_value_gradient(const Vec3& p, Vec3& gradient) const override;
  double eval_gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const override;

 private:
  // The blobs whose terms may not vanish at p (all of them for Blinn's kernel or a point outside
  // the support grid), in index order.
  std::span<const std::uint32_t> blobs_near(const Vec3& p) const;
  void build_support_grid(const Box& box);
  // Cell (x, y, z) of the support grid, in cell_start_.
  std::size_t cell_index(int x, int y, int z) const {
    return (static_cast<std::size_t>(z) * cells_[1] + y) * cells_[0] + x;
  }

  BlobKernel kernel_;
  double threshold_;
  std::vector<Blob> blobs_;
  double lipschitz_ = 0;
  // Wyvill's kernel vanishes beyond R, so a point's sum needs only the blobs whose support
  // reaches it: a uniform grid over the bounds lists, per cell, the blobs whose support box meets
  // the cell, in index order. The sums then add the same terms in the same order as a loop over
  // every blob (the others are skipped there too), bit for bit. Only from kGridBlobs blobs.
  std::vector<std::uint32_t> all_;         // 0 .. n-1: the full list
  std::vector<std::uint32_t> cell_start_;  // per cell, into cell_blobs_ (one past the last cell too)
  std::vector<std::uint32_t> cell_blobs_;
  std::array<int, 3> cells_{0, 0, 0};
  Vec3 grid_origin_ = Vec3::Zero();
  double inv_cell_ = 0;
};

}  // namespace cdp
