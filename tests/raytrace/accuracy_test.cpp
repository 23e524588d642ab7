// Checks <cdp/raytrace/accuracy.h>: depth and Phong errors of an icosphere shrink as h^2, a mesh
// shifted along the view direction has exactly that depth error, flipped normals give 180 deg.
#include <cdp/raytrace/accuracy.h>
#include "common/reference_meshes.h"

#include <cdp/core/models/analytic.h>
#include <cdp/core/models/expression.h>

#include <gtest/gtest.h>

#include <cmath>

namespace cdp {
namespace {

AccuracyMetrics measure(const Field& field, const Mesh& mesh, const CameraOptions& camera) {
  const GroundTruth gt = compute_ground_truth(field, make_camera_rays(field.bounds(), camera));
  const EmbreeScene scene(mesh);
  return compute_accuracy(gt, scene.intersect(gt.rays), mesh);
}

TEST(Accuracy, SampleStatsArePopulationStatistics) {
  const SampleStats s = sample_stats({1.0, 2.0, 3.0, 6.0});
  EXPECT_EQ(s.count, 4u);
  EXPECT_DOUBLE_EQ(s.mean, 3.0);
  EXPECT_DOUBLE_EQ(s.std, std::sqrt((4.0 + 1.0 + 0.0 + 9.0) / 4.0));
  EXPECT_EQ(s.max, 6.0);
  EXPECT_EQ(s.min, 1.0);
  // No samples is no measurement: NaN (null in the metrics JSON), never a perfect zero.
  const SampleStats none = sample_stats({});
  EXPECT_EQ(none.count, 0u);
  EXPECT_TRUE(std::isnan(none.mean) && std::isnan(none.std) && std::isnan(none.min) && std::isnan(none.max));
}

TEST(Accuracy, IcosphereErrorsConvergeQuadratically) {
  const Sphere sphere(Vec3(0.1, 0.2, -0.1), 1.0);
  CameraOptions camera;
  camera.views = 4;
  camera.resolution = 32;
  const AccuracyMetrics coarse = measure(sphere, icosphere(3, Vec3(0.1, 0.2, -0.1)), camera);
  const AccuracyMetrics fine = measure(sphere, icosphere(4, Vec3(0.1, 0.2, -0.1)), camera);
  ASSERT_GT(fine.both_hit, 500u);
  EXPECT_EQ(coarse.compared, coarse.rays);
  // Halving the edge length divides both errors by about four.
  const double depth_ratio = coarse.depth.mean / fine.depth.mean;
  const double phong_ratio = coarse.phong_deg.mean / fine.phong_deg.mean;
  EXPECT_GT(depth_ratio, 3.3);
  EXPECT_LT(depth_ratio, 4.7);
  EXPECT_GT(phong_ratio, 3.3);
  EXPECT_LT(phong_ratio, 4.7);
  EXPECT_LT(fine.depth.mean, 2e-3);
  EXPECT_LT(fine.phong_deg.mean, 0.2);
  EXPECT_GE(fine.depth.max, fine.depth.mean);
  // The inscribed mesh loses a thin rim of the silhouette: rays hitting only the sphere.
  EXPECT_EQ(fine.mesh_only, 0u);
  EXPECT_LE(fine.surface_only, coarse.surface_only);
  EXPECT_LT(fine.silhouette_disagreement, 0.01);
}

// The plane z = 0 seen from above by an orthographic camera, and a square mesh at z = shift.
struct PlaneCase {
  Expression field{"z", {}, Box{{-1, -1, -1}, {1, 1, 1}}};
  CameraOptions camera;
  Mesh square(double shift, const Vec3& normal) const {
    Mesh m;
    m.positions = {Vec3(-1, -1, shift), Vec3(1, -1, shift), Vec3(1, 1, shift), Vec3(-1, 1, shift)};
    m.triangles = {{0, 1, 2}, {0, 2, 3}};
    m.normals.assign(4, normal);
    return m;
  }
  PlaneCase() {
    camera.projection = Projection::Orthographic;
    camera.directions = {Vec3(0, 0, -1)};
    camera.resolution = 15;
  }
};

TEST(Accuracy, MeshShiftedAlongTheViewDirectionHasThatDepthError) {
  const PlaneCase pc;
  for (double shift : {0.01, -0.03}) {
    const AccuracyMetrics a = measure(pc.field, pc.square(shift, Vec3::UnitZ()), pc.camera);
    ASSERT_GT(a.both_hit, 50u);
    EXPECT_NEAR(a.depth.mean, std::abs(shift), 1e-12);
    EXPECT_NEAR(a.depth.max, std::abs(shift), 1e-12);
    EXPECT_LT(a.depth.std, 1e-12);
    EXPECT_NEAR(a.depth_relative_mean, std::abs(shift) / (2.0 * std::sqrt(3.0)), 1e-12);
    EXPECT_LT(a.phong_deg.max, 1e-12);
    EXPECT_EQ(a.surface_only + a.mesh_only, 0u);
  }
}

TEST(Accuracy, FlippedNormalsGivePhongErrorsNear180Degrees) {
  const PlaneCase pc;
  const AccuracyMetrics plane = measure(pc.field, pc.square(0.0, -Vec3::UnitZ()), pc.camera);
  EXPECT_NEAR(plane.phong_deg.mean, 180.0, 1e-12);

  Mesh sphere_mesh = icosphere(3);
  for (Vec3& n : sphere_mesh.normals) n = -n;
  CameraOptions camera;
  camera.views = 2;
  camera.resolution = 16;
  const AccuracyMetrics a = measure(Sphere(Vec3::Zero(), 1.0), sphere_mesh, camera);
  ASSERT_GT(a.both_hit, 50u);
  EXPECT_GT(a.phong_deg.mean, 178.0);
  EXPECT_GT(a.phong_deg.min, 170.0);
  EXPECT_EQ(a.phong_undefined, 0u);
}

TEST(Accuracy, CancellingVertexNormalsLeaveThePhongErrorUndefinedAndCounted) {
  const PlaneCase pc;
  Mesh m = pc.square(0.0, Vec3::UnitZ());
  m.normals[2] = -Vec3::UnitZ();  // opposite ends of the diagonal 0-2: its midpoint blends to zero
  const GroundTruth gt = compute_ground_truth(
      pc.field, {Ray{Vec3(0, 0, 2), -Vec3::UnitZ()}, Ray{Vec3(0.5, -0.5, 2), -Vec3::UnitZ()}});
  const EmbreeScene scene(m);
  const AccuracyMetrics a = compute_accuracy(gt, scene.intersect(gt.rays), m);
  EXPECT_EQ(a.both_hit, 2u);
  EXPECT_EQ(a.phong_undefined, 1u);
  EXPECT_EQ(a.phong_deg.count, 1u);
}

TEST(Accuracy, SilhouetteCountsRaysHittingOnlyOneSide) {
  const PlaneCase pc;
  // Half the square is gone: rays over x < 0 hit only the plane.
  Mesh half;
  half.positions = {Vec3(0, -1, 0), Vec3(1, -1, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)};
  half.triangles = {{0, 1, 2}, {0, 2, 3}};
  half.normals.assign(4, Vec3::UnitZ());
  const AccuracyMetrics a = measure(pc.field, half, pc.camera);
  EXPECT_GT(a.surface_only, 0u);
  EXPECT_EQ(a.mesh_only, 0u);
  EXPECT_EQ(a.surface_only + a.both_hit + a.neither, a.compared);
  EXPECT_DOUBLE_EQ(a.silhouette_disagreement, static_cast<double>(a.surface_only) / a.compared);
  EXPECT_NEAR(static_cast<double>(a.surface_only), static_cast<double>(a.both_hit), 15.0);
}

TEST(Accuracy, RaysHittingOnlyTheMeshLeaveTheErrorsUndefinedNotZero) {
  // A square in a corner of the box, off the sphere: every ray hitting it misses the surface.
  const Sphere sphere(Vec3::Zero(), 1.0);
  Mesh corner;
  corner.positions = {Vec3(0.8, 0.8, 0), Vec3(1.1, 0.8, 0), Vec3(1.1, 1.1, 0), Vec3(0.8, 1.1, 0)};
  corner.triangles = {{0, 1, 2}, {0, 2, 3}};
  corner.normals.assign(4, Vec3::UnitZ());
  const PlaneCase pc;
  const AccuracyMetrics a = measure(sphere, corner, pc.camera);
  ASSERT_GT(a.mesh_only, 0u);
  EXPECT_EQ(a.both_hit, 0u);
  EXPECT_GT(a.surface_only, 0u);
  EXPECT_TRUE(std::isnan(a.depth.mean) && std::isnan(a.depth_relative_mean) && std::isnan(a.phong_deg.mean));
  EXPECT_DOUBLE_EQ(a.silhouette_disagreement, 1.0 - static_cast<double>(a.neither) / a.compared);
}

}  // namespace
}  // namespace cdp
