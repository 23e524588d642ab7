// Blobby model: F(x) = T - sum_i s_i k(|x - c_i| / R_i), with Wyvill's compact polynomial kernel
// or Blinn's Gaussian. Both kernels are functions of a^2, so F is smooth everywhere.
#pragma once

#include <cdp/core/field.h>

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
  BlobKernel kernel_;
  double threshold_;
  std::vector<Blob> blobs_;
  double lipschitz_ = 0;
};

}  // namespace cdp
