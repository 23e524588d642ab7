// Checks <cdp/raytrace/embree_scene.h>: hits agree with the triangle they name, misses, closest points
// against brute force, and the closest point on a triangle in each of its regions.
#include <cdp/raytrace/embree_scene.h>
#include "common/reference_meshes.h"

#include <cdp/core/errors.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace cdp {
namespace {

TEST(EmbreeScene, HitsLieOnTheTriangleTheyNameAndAreFirstHits) {
  const Mesh mesh = icosphere(3, Vec3(10.0, -5.0, 2.0), 2.0);  // away from the origin on purpose
  const EmbreeScene scene(mesh);
  CameraOptions camera;
  camera.views = 3;
  camera.resolution = 16;
  const Box box{Vec3(8, -7, 0), Vec3(12, -3, 4)};
  const auto rays = make_camera_rays(box, camera);
  const auto hits = scene.intersect(rays);
  ASSERT_EQ(hits.size(), rays.size());
  std::size_t n_hits = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const Ray& r = rays[i];
    // The exact sphere bounds the inscribed polyhedron: a ray missing the sphere misses the mesh.
    const Vec3 q = r.origin - Vec3(10.0, -5.0, 2.0);
    const double b = q.dot(r.direction), disc = b * b - (q.squaredNorm() - 4.0);
    if (disc < 0) {
      EXPECT_FALSE(hits[i].hit());
    }
    if (!hits[i].hit()) continue;
    ++n_hits;
    const auto& t = mesh.triangles[hits[i].triangle];
    const Vec3 p = (1 - hits[i].u - hits[i].v) * mesh.positions[t[0]] + hits[i].u * mesh.positions[t[1]] +
                   hits[i].v * mesh.positions[t[2]];
    EXPECT_NEAR((r.origin + hits[i].t * r.direction - p).norm(), 0.0, 1e-11);
    EXPECT_GE(hits[i].u, 0.0);
    EXPECT_GE(hits[i].v, 0.0);
    EXPECT_LE(hits[i].u + hits[i].v, 1.0);
    // First hit: the front face, whose outward normal faces the ray; t lies before the far root.
    const Vec3 n = (mesh.positions[t[1]] - mesh.positions[t[0]]).cross(mesh.positions[t[2]] - mesh.positions[t[0]]);
    EXPECT_LT(n.dot(r.direction), 0.0);
    EXPECT_LE(hits[i].t, -b + 1e-9);
  }
  EXPECT_GT(n_hits, 100u);
}

TEST(EmbreeScene, ClosestPointsMatchBruteForce) {
  const Mesh mesh = icosphere(2);
  const EmbreeScene scene(mesh);
  std::mt19937_64 rng(7);
  std::vector<Vec3> points;
  for (int i = 0; i < 200; ++i) {
    Vec3 p;
    for (int a = 0; a < 3; ++a) p[a] = static_cast<double>(rng() >> 11) * 0x1.0p-53 * 4.0 - 2.0;
    points.push_back(p);
  }
  const auto closest = scene.closest_points(points);
  for (std::size_t i = 0; i < points.size(); ++i) {
    double best = 1e300;
    for (const auto& t : mesh.triangles)
      best = std::min(best, (closest_point_on_triangle(points[i], mesh.positions[t[0]], mesh.positions[t[1]],
                                                       mesh.positions[t[2]]) -
                             points[i]).norm());
    EXPECT_NEAR(closest[i].distance, best, 1e-12) << i;
    EXPECT_NEAR((closest[i].point - points[i]).norm(), closest[i].distance, 1e-12);
    EXPECT_GE(closest[i].triangle, 0);
  }
}

TEST(EmbreeScene, ClosestPointOnTriangleRegions) {
  const Vec3 a(0, 0, 0), b(2, 0, 0), c(0, 2, 0);
  EXPECT_EQ(closest_point_on_triangle(Vec3(0.5, 0.5, 3), a, b, c), Vec3(0.5, 0.5, 0));  // interior
  EXPECT_EQ(closest_point_on_triangle(Vec3(-1, -1, 1), a, b, c), a);                     // vertex
  EXPECT_EQ(closest_point_on_triangle(Vec3(3, -1, 0), a, b, c), b);
  EXPECT_EQ(closest_point_on_triangle(Vec3(1, -1, 0), a, b, c), Vec3(1, 0, 0));          // edge ab
  EXPECT_TRUE(closest_point_on_triangle(Vec3(2, 2, 0), a, b, c).isApprox(Vec3(1, 1, 0)));  // edge bc
  EXPECT_EQ(closest_point_on_triangle(Vec3(-1, 1, 0), a, b, c), Vec3(0, 1, 0));          // edge ca
}

TEST(EmbreeScene, EmptyMeshMissesAndBadIndicesThrow) {
  const EmbreeScene empty{Mesh{}};
  const auto hits = empty.intersect({Ray{Vec3(0, 0, -5), Vec3::UnitZ()}});
  EXPECT_FALSE(hits[0].hit());
  Mesh bad = icosphere(0);
  bad.triangles[0][1] = 99;
  EXPECT_THROW(EmbreeScene{bad}, InvalidInputError);
}

// Embree aborts (an assertion) on such rays and silently drops such triangles: errors instead.
TEST(EmbreeScene, RaysAndMeshesBeyondEmbreesFloatRangeAreErrors) {
  const EmbreeScene scene(icosphere(1));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const Ray& ray : {Ray{Vec3(0, 0, -1e19), Vec3::UnitZ()}, Ray{Vec3(nan, 0, -5), Vec3::UnitZ()},
                         Ray{Vec3(0, 0, -5), Vec3(0, 0, nan)}}) {
    try {
      (void)scene.intersect({Ray{Vec3(0, 0, -5), Vec3::UnitZ()}, ray});
      ADD_FAILURE() << ray.origin.transpose();
    } catch (const InvalidInputError& e) {
      EXPECT_EQ(std::string(e.what()),
                "EmbreeScene: ray 1 is not finite or starts more than 1e18 half-diagonals of the mesh from its "
                "centre, out of Embree's float range");
    }
  }
  EXPECT_NO_THROW((void)scene.intersect({Ray{Vec3(0, 0, -9e17), Vec3::UnitZ()}})) << "within the range";
  EXPECT_NO_THROW(EmbreeScene{icosphere(1, Vec3(1e30, 0, 0), 1.0)}) << "far from the origin is fine: it is shifted";
  EXPECT_THROW(EmbreeScene{icosphere(1, Vec3::Zero(), 1e300)}, InvalidInputError) << "the diagonal overflows double";
}

// Embree's float products of coordinates overflowed for a mesh 1e13 across (a sphere of radius
// 1e14 got a Phong error of 73 degrees) and underflow for a tiny one: the scene is scaled, so
// the same rays, scaled with the mesh, hit the same triangles at the same scaled distances.
TEST(EmbreeScene, MeshesOfAnySizeGiveTheSameHits) {
  const Mesh unit = icosphere(3);
  const EmbreeScene reference(unit);
  std::vector<Ray> rays;
  for (int i = 0; i < 200; ++i) {
    const double a = 0.1 * i, b = 0.037 * i;
    const Vec3 target(0.6 * std::cos(a) * std::cos(b), 0.6 * std::sin(a) * std::cos(b), 0.6 * std::sin(b));
    const Vec3 origin(3 * std::cos(1.7 * i), 3 * std::sin(1.7 * i), 0.5);
    rays.push_back({origin, (target - origin).normalized()});
  }
  const std::vector<MeshHit> expected = reference.intersect(rays);
  for (const double size : {1e-20, 1e14, 1e30}) {
    Mesh scaled = unit;
    for (Vec3& p : scaled.positions) p *= size;
    std::vector<Ray> scaled_rays = rays;
    for (Ray& r : scaled_rays) r.origin *= size;
    const std::vector<MeshHit> hits = EmbreeScene(scaled).intersect(scaled_rays);
    for (std::size_t i = 0; i < rays.size(); ++i) {
      ASSERT_GE(expected[i].triangle, 0) << i;
      EXPECT_EQ(hits[i].triangle, expected[i].triangle) << "size " << size << ", ray " << i;
      EXPECT_NEAR(hits[i].t / size, expected[i].t, 1e-12) << "size " << size << ", ray " << i;
    }
  }
}

}  // namespace
}  // namespace cdp
