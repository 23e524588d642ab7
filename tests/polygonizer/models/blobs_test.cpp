// The blobby model (polygonizer/include/cdp/core/models/blobs.h): with many Wyvill blobs its
// evaluations visit only the blobs whose support reaches the point (a grid of supports), and give
// the numbers a loop over every blob gives, bit for bit.
#include <gtest/gtest.h>

#include <cdp/core/models/blobs.h>

#include <random>
#include <vector>

#include "common/same_bits.h"

namespace cdp {
namespace {

// Wyvill's kernel and its first two derivatives in s = |p - c|^2 / R^2, written out again.
struct BlobsTestKernel {
  double k, dk, d2k;
};
BlobsTestKernel blobs_test_wyvill(double s) {
  return {1.0 + s * (-22.0 / 9.0 + s * (17.0 / 9.0 - 4.0 / 9.0 * s)), -22.0 / 9.0 + s * (34.0 / 9.0 - 12.0 / 9.0 * s),
          34.0 / 9.0 - 24.0 / 9.0 * s};
}

TEST(BlobsSupportGrid, ManyWyvillBlobsGiveTheNumbersOfALoopOverEveryBlob) {
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> centre(-2, 2), radius(0.3, 0.8), strength(0.5, 1.5);
  std::vector<Blob> blobs(120);
  for (Blob& b : blobs) b = {Vec3(centre(rng), centre(rng), centre(rng)), radius(rng), strength(rng)};
  const double threshold = 0.3;
  const Blobs field(BlobKernel::Wyvill, threshold, blobs);
  // Points anywhere in the box and beyond it, and points on the spheres of radius R about the
  // centres (where a blob's term just vanishes), nudged by an ulp either way.
  std::vector<Vec3> points;
  std::uniform_real_distribution<double> anywhere(-3.5, 3.5);
  for (int i = 0; i < 3000; ++i) points.emplace_back(anywhere(rng), anywhere(rng), anywhere(rng));
  std::normal_distribution<double> gauss;
  for (const Blob& b : blobs)
    for (int i = 0; i < 10; ++i) {
      const Vec3 on = b.center + b.radius * Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
      for (const double dir : {-1.0, 1.0})
        points.emplace_back(std::nextafter(on.x(), on.x() + dir), std::nextafter(on.y(), on.y() + dir),
                            std::nextafter(on.z(), on.z() + dir));
    }
  std::size_t reached = 0;
  for (const Vec3& p : points) {
    double sum = 0;
    Vec3 g = Vec3::Zero();
    Mat3 h = Mat3::Zero();
    int terms = 0;
    for (const Blob& b : blobs) {
      const Vec3 d = p - b.center;
      const double inv_r2 = 1.0 / (b.radius * b.radius);
      const double s = d.squaredNorm() * inv_r2;
      if (s >= 1.0) continue;
      const BlobsTestKernel k = blobs_test_wyvill(s);
      sum += b.strength * k.k;
      g -= (b.strength * k.dk * 2.0 * inv_r2) * d;
      h -= b.strength * (k.d2k * 4.0 * inv_r2 * inv_r2 * (d * d.transpose()) + k.dk * 2.0 * inv_r2 * Mat3::Identity());
      ++terms;
    }
    reached += terms > 0;
    EXPECT_TRUE(test::same_bits(field.value(p), threshold - sum)) << p.transpose();
    Vec3 g1, g2;
    Mat3 h2;
    EXPECT_TRUE(test::same_bits(field.value_gradient(p, g1), threshold - sum)) << p.transpose();
    EXPECT_TRUE(test::same_bits(g1, g)) << p.transpose();
    EXPECT_TRUE(test::same_bits(field.gradient_hessian(p, g2, h2), threshold - sum)) << p.transpose();
    EXPECT_TRUE(test::same_bits(g2, g) && test::same_bits(h2, h)) << p.transpose();
  }
  EXPECT_GT(reached, points.size() / 3);  // a good share of the points lie within some blob's support
}

}  // namespace
}  // namespace cdp
