// Checks <cdp/raytrace/camera.h>: ray counts, unit directions, eyes outside the box, determinism.
#include <cdp/raytrace/camera.h>

#include <cdp/core/errors.h>

#include <gtest/gtest.h>

#include <cmath>

namespace cdp {
namespace {

const Box kBox{{-1, -2, -0.5}, {2, 1, 0.5}};

TEST(Camera, PerspectiveRaysStartOutsideTheBoxAndAimAtTheBoundingSphere) {
  CameraOptions o;
  o.views = 5;
  o.resolution = 7;
  const auto rays = make_camera_rays(kBox, o);
  ASSERT_EQ(rays.size(), 5u * 7 * 7);
  const double radius = 0.5 * kBox.diagonal();
  for (const Ray& r : rays) {
    EXPECT_NEAR(r.direction.norm(), 1.0, 1e-14);
    EXPECT_FALSE(kBox.contains(r.origin));
    EXPECT_NEAR((r.origin - kBox.center()).norm(), o.distance * radius, 1e-12);
  }
  // The centre pixel of an odd resolution looks straight at the box centre.
  const Ray& centre = rays[3 * 7 + 3];
  EXPECT_NEAR((centre.origin + o.distance * radius * centre.direction - kBox.center()).norm(), 0.0, 1e-12);
  // The image covers the box: every corner lies within a pixel of some ray of every view, and
  // it fits the box closely: most rays of a view meet the box.
  for (int v = 0; v < o.views; ++v) {
    const Vec3 eye = rays[v * 49].origin;
    std::size_t meet = 0;
    for (int k = 0; k < 8; ++k) {
      const Vec3 corner((k & 1) ? kBox.max.x() : kBox.min.x(), (k & 2) ? kBox.max.y() : kBox.min.y(),
                        (k & 4) ? kBox.max.z() : kBox.min.z());
      double best = 1e9;
      for (int i = 0; i < 49; ++i)
        best = std::min(best, std::acos(std::min(1.0, rays[v * 49 + i].direction.dot((corner - eye).normalized()))));
      EXPECT_LT(best, 0.1) << "view " << v << " corner " << k;  // a pixel spans about 0.1 rad here
    }
    for (int i = 0; i < 49; ++i) {
      const Ray& r = rays[v * 49 + i];
      // Distance from the box centre to the ray's line against the box's bounding radius.
      const Vec3 q = kBox.center() - r.origin;
      meet += (q - q.dot(r.direction) * r.direction).norm() < radius;
    }
    EXPECT_GT(meet, 20u);
  }
}

TEST(Camera, OrthographicRaysOfOneViewAreParallel) {
  CameraOptions o;
  o.projection = Projection::Orthographic;
  o.directions = {Vec3(0, 0, -2)};
  o.resolution = 4;
  const auto rays = make_camera_rays(kBox, o);
  ASSERT_EQ(rays.size(), 16u);
  for (const Ray& r : rays) {
    EXPECT_EQ(r.direction, Vec3(0, 0, -1));
    EXPECT_GT(r.origin.z(), kBox.max.z());
  }
  EXPECT_NE(rays[0].origin, rays[1].origin);
}

TEST(Camera, ViewDirectionsAreDistinctUnitVectorsAndDeterministic) {
  CameraOptions o;
  o.views = 12;
  const auto d = view_directions(o);
  ASSERT_EQ(d.size(), 12u);
  Vec3 sum = Vec3::Zero();
  for (std::size_t i = 0; i < d.size(); ++i) {
    EXPECT_NEAR(d[i].norm(), 1.0, 1e-14);
    sum += d[i];
    for (std::size_t j = 0; j < i; ++j) EXPECT_GT((d[i] - d[j]).norm(), 0.3);
  }
  // A Fibonacci spiral spreads the directions: their mean is near zero.
  EXPECT_LT(sum.norm() / 12.0, 0.1);
  const auto again = make_camera_rays(kBox, o);
  const auto first = make_camera_rays(kBox, o);
  ASSERT_EQ(again.size(), first.size());
  for (std::size_t i = 0; i < first.size(); ++i) {
    EXPECT_EQ(first[i].origin, again[i].origin);
    EXPECT_EQ(first[i].direction, again[i].direction);
  }
}

TEST(Camera, RejectsBadOptions) {
  CameraOptions o;
  o.resolution = 0;
  EXPECT_THROW(make_camera_rays(kBox, o), InvalidInputError);
  o = {};
  o.distance = 0.5;
  EXPECT_THROW(make_camera_rays(kBox, o), InvalidInputError);
  o = {};
  o.directions = {Vec3::Zero()};
  EXPECT_THROW(make_camera_rays(kBox, o), InvalidInputError);
  EXPECT_THROW(make_camera_rays(Box{}, CameraOptions{}), InvalidInputError);
  // A finite box whose diagonal overflows (a sphere of radius 1e160) once gave NaN rays.
  EXPECT_THROW(make_camera_rays(Box{Vec3::Constant(-1e160), Vec3::Constant(1e160)}, CameraOptions{}),
               InvalidInputError);
  EXPECT_THROW(parse_projection("fisheye"), InvalidInputError);
  EXPECT_EQ(parse_projection("orthographic"), Projection::Orthographic);
}

}  // namespace
}  // namespace cdp
