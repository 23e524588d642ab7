// Checks <cdp/raytrace/surface_distance.h>: deterministic area-weighted sampling, vertex and sampled
// distances of an icosphere against the sphere, surface-to-mesh distance of a shifted plane.
#include <cdp/raytrace/surface_distance.h>
#include "common/reference_meshes.h"

#include <cdp/core/models/analytic.h>
#include <cdp/core/models/expression.h>

#include <gtest/gtest.h>

#include <cmath>

namespace cdp {
namespace {

TEST(SurfaceDistance, SamplingIsDeterministicAreaWeightedAndOnTheMesh) {
  Mesh m;  // areas 0.5 and 1.5: a quarter and three quarters of the samples
  m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(-3, 0, 0), Vec3(0, -1, 0)};
  m.triangles = {{0, 1, 2}, {0, 4, 3}};
  SurfaceSamplingOptions o;
  o.samples = 4000;
  const auto p = sample_mesh_surface(m, o);
  ASSERT_EQ(p.size(), 4000u);
  EXPECT_EQ(p, sample_mesh_surface(m, o));
  o.seed = 2;
  EXPECT_NE(p, sample_mesh_surface(m, o));
  std::size_t first = 0;
  for (const Vec3& x : p) {
    EXPECT_EQ(x.z(), 0.0);
    if (x.x() >= 0 && x.y() >= 0) {
      EXPECT_LE(x.x() + x.y(), 1.0 + 1e-15);
      ++first;
    } else {
      EXPECT_LE(x.x(), 0.0);
      EXPECT_LE(x.y(), 0.0);
      EXPECT_GE(x.x() / 3.0 + x.y(), -1.0 - 1e-15);
    }
  }
  EXPECT_NEAR(first / 4000.0, 0.25, 0.03);
  EXPECT_TRUE(sample_mesh_surface(Mesh{}, o).empty());
}

TEST(SurfaceDistance, IcosphereAgainstItsSphere) {
  const Sphere sphere(Vec3::Zero(), 1.0);
  const Mesh mesh = icosphere(3);
  const SampleStats v = vertex_distance(sphere, mesh);
  EXPECT_EQ(v.count, mesh.num_vertices());
  EXPECT_LT(v.max, 1e-15);
  // For a signed distance field |F| is the exact distance; the deepest mesh point is a face
  // centre, at 1 - (inscribed radius) below the sphere.
  double deepest = 0;
  for (const auto& t : mesh.triangles) {
    const Vec3 c = (mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3.0;
    deepest = std::max(deepest, 1.0 - c.norm());
  }
  SurfaceSamplingOptions o;
  o.samples = 3000;
  const SampleStats s = mesh_to_surface_distance(sphere, mesh, o);
  EXPECT_EQ(s.count, 3000u);
  EXPECT_LE(s.max, deepest + 1e-15);
  EXPECT_GT(s.max, 0.5 * deepest);
  EXPECT_GT(s.mean, 0.2 * deepest);
  EXPECT_LT(s.mean, 0.8 * deepest);
}

TEST(SurfaceDistance, SurfaceToMeshOfAShiftedPlane) {
  const Expression plane("z", {}, Box{{-1, -1, -1}, {1, 1, 1}});
  CameraOptions camera;
  camera.projection = Projection::Orthographic;
  camera.directions = {Vec3(0.1, 0.2, -1)};
  camera.resolution = 10;
  const GroundTruth gt = compute_ground_truth(plane, make_camera_rays(plane.bounds(), camera));
  Mesh m;  // a larger square, so that every true hit projects inside it
  m.positions = {Vec3(-3, -3, 0.05), Vec3(3, -3, 0.05), Vec3(3, 3, 0.05), Vec3(-3, 3, 0.05)};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  const EmbreeScene scene(m);
  const SampleStats d = surface_to_mesh_distance(gt, scene);
  EXPECT_EQ(d.count, gt.counts().hits);
  EXPECT_GT(d.count, 30u);
  EXPECT_NEAR(d.mean, 0.05, 1e-12);
  EXPECT_NEAR(d.max, 0.05, 1e-12);
}

}  // namespace
}  // namespace cdp
