// Ray-mesh intersection and closest-point queries through Embree. Every Embree call of the
// project is in embree_scene.cpp and box_overlaps.cpp (rtcCollide, for self_intersection.h), so
// moving to another Embree version touches those two files.
#pragma once

#include <cdp/raytrace/camera.h>

#include <cdp/core/mesh.h>
#include <cdp/core/triangle_geometry.h>  // closest_point_on_triangle, used with the queries below

#include <limits>
#include <memory>
#include <vector>

namespace cdp {

// Embree's conventions: the hit point is (1-u-v) p0 + u p1 + v p2 of triangle `triangle`.
struct MeshHit {
  int triangle = -1;
  double u = 0.0, v = 0.0;
  double t = std::numeric_limits<double>::infinity();
  bool hit() const { return triangle >= 0; }
};

struct ClosestPoint {
  Vec3 point = Vec3::Zero();
  double distance = std::numeric_limits<double>::infinity();
  int triangle = -1;
};

// An Embree scene of one mesh (robust build flag, float vertices relative to the mesh's centre,
// in units of a power of two near its half-diagonal, so that meshes of any size work).
// Embree finds the triangle; t, u and v are then recomputed in double on that triangle, so that
// depth errors are not floored by float rounding (about 1e-7 of the distance).
class EmbreeScene {
 public:
  // Throws InvalidInputError on out-of-range indices, non-finite positions or a mesh whose box's
  // diagonal overflows double.
  // \throw InvalidInputError for an out-of-range index, a non-finite position, a box whose diagonal
  //        overflows, or when Embree fails (no device, no buffers, an error building the scene).
  explicit EmbreeScene(const Mesh& mesh);
  ~EmbreeScene();
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  // The first hit of every ray (t >= 0), in parallel over blocks of rays. Throws InvalidInputError
  // (where Embree would abort) on a non-finite ray or one starting beyond its float range (1e18
  // half-diagonals of the mesh from its centre).
  // \pre every ray's direction has unit length (so that t is a distance).
  // \return one hit per ray, in order; triangle -1 where the ray misses.
  // \throw InvalidInputError for a ray whose direction is not finite, or whose origin is not finite
  //        or lies beyond that range.
  std::vector<MeshHit> intersect(const std::vector<Ray>& rays) const;
  // The nearest point of the mesh to every point (rtcPointQuery), in parallel.
  // \pre the points are finite.
  // \return one per point, in order; distance infinity and triangle -1 for a mesh without triangles.
  std::vector<ClosestPoint> closest_points(const std::vector<Vec3>& points) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cdp
