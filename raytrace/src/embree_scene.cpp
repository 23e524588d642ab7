// With box_overlaps.cpp, the only file of the project that calls Embree (version 3).
#include <cdp/raytrace/embree_scene.h>

#include <cdp/core/errors.h>

#include "embree_error.h"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <string>

namespace cdp {

namespace {

constexpr unsigned kRayBlock = 256;
// Embree works in float and takes nothing farther than FLT_LARGE (about 1.8e18) from the scene's
// centre, in its own units: it aborts on such a ray (an assertion). The scene is scaled so that
// the mesh fits in about [-1, 1]^3 (below), so this bounds how far, in half-diagonals of the
// mesh, a ray may start.
constexpr double kMaxReach = 1e18;
constexpr const char* kMaxReachText = "1e18";

// The power of two at or above half the box's diagonal. Embree's float arithmetic multiplies
// coordinates (cross products, then dot products: cubes of them), which overflows float for a
// mesh 1e13 across (and underflows for a tiny one): a sphere of radius 1e14 got a Phong error of
// 73 degrees and a relative depth error of 0.28 where its scaled copy gets 0.6 degrees and
// 0.0035. Dividing by a power of two is exact in float, so a mesh of ordinary size gets the same
// arithmetic as without the scale, only with exponents shifted.
double scene_scale(const Box& box) {
  const double half = 0.5 * box.diagonal();
  if (!(half > 0) || !std::isfinite(half)) return 1.0;
  return std::ldexp(1.0, std::ilogb(half) + 1);
}

}  // namespace

struct EmbreeScene::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::string error;
  Vec3 center = Vec3::Zero();  // subtracted before the float conversion
  double scale = 1.0;          // then divided by (scene_scale), Embree's unit of length
  double query_margin = 0.0;   // float rounding of the scene, added to point-query radii
  std::vector<Vec3> positions;
  std::vector<std::array<int, 3>> triangles;

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
  void check(const char* what) const {
    if (!error.empty()) throw InvalidInputError(std::string("EmbreeScene: ") + what + ": " + error);
  }
};

EmbreeScene::EmbreeScene(const Mesh& mesh) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.positions = mesh.positions;
  m.triangles = mesh.triangles;
  const auto nv = static_cast<long long>(mesh.positions.size());
  Box box{Vec3::Constant(std::numeric_limits<double>::infinity()), Vec3::Constant(-std::numeric_limits<double>::infinity())};
  for (const Vec3& p : mesh.positions) {
    if (!p.allFinite()) throw InvalidInputError("EmbreeScene: a vertex position is not finite");
    box.min = box.min.cwiseMin(p);
    box.max = box.max.cwiseMax(p);
  }
  for (const auto& t : mesh.triangles)
    for (int i : t)
      if (i < 0 || i >= nv) throw InvalidInputError("EmbreeScene: a triangle index is out of range");
  if (nv > 0) {
    if (!std::isfinite(box.diagonal()))
      throw InvalidInputError("EmbreeScene: the mesh is too large for double precision (its box's diagonal overflows)");
    m.center = box.center();
    m.scale = scene_scale(box);
    m.query_margin = 1e-6 * (box.diagonal() + box.max.cwiseAbs().maxCoeff());
  }

  m.device = rtcNewDevice(nullptr);
  if (!m.device) throw InvalidInputError("EmbreeScene: cannot create an Embree device");
  rtcSetDeviceErrorFunction(m.device, embree::record_first_error, &m.error);
  m.scene = rtcNewScene(m.device);
  rtcSetSceneFlags(m.scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(m.scene, RTC_BUILD_QUALITY_HIGH);
  if (!mesh.triangles.empty()) {
    RTCGeometry geom = rtcNewGeometry(m.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    // rtcSetNewGeometryBuffer allocates with the padding Embree's vector loads need.
    auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                           3 * sizeof(float), mesh.positions.size()));
    auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                              3 * sizeof(unsigned), mesh.triangles.size()));
    m.check("allocating buffers");
    if (!vb || !ib) throw InvalidInputError("EmbreeScene: cannot allocate the geometry buffers");
    for (std::size_t i = 0; i < mesh.positions.size(); ++i)
      for (int a = 0; a < 3; ++a) vb[3 * i + a] = static_cast<float>((mesh.positions[i][a] - m.center[a]) / m.scale);
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
      for (int a = 0; a < 3; ++a) ib[3 * i + a] = static_cast<unsigned>(mesh.triangles[i][a]);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(m.scene, geom);
    rtcReleaseGeometry(geom);
  }
  rtcCommitScene(m.scene);
  m.check("building the scene");
}

EmbreeScene::~EmbreeScene() = default;

std::vector<MeshHit> EmbreeScene::intersect(const std::vector<Ray>& rays) const {
  const Impl& m = *impl_;
  for (std::size_t i = 0; i < rays.size(); ++i)
    if (!rays[i].direction.allFinite() || !((rays[i].origin - m.center).norm() / m.scale <= kMaxReach))
      throw InvalidInputError("EmbreeScene: ray " + std::to_string(i) + " is not finite or starts more than " +
                              kMaxReachText + " half-diagonals of the mesh from its centre, out of Embree's float range");
  std::vector<MeshHit> hits(rays.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), kRayBlock), [&](const tbb::blocked_range<std::size_t>& r) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const Ray& ray = rays[i];
      const Vec3 o = (ray.origin - m.center) / m.scale;
      RTCRayHit rh{};
      rh.ray.org_x = static_cast<float>(o.x());
      rh.ray.org_y = static_cast<float>(o.y());
      rh.ray.org_z = static_cast<float>(o.z());
      rh.ray.dir_x = static_cast<float>(ray.direction.x());
      rh.ray.dir_y = static_cast<float>(ray.direction.y());
      rh.ray.dir_z = static_cast<float>(ray.direction.z());
      rh.ray.tnear = 0.0f;
      rh.ray.tfar = std::numeric_limits<float>::infinity();
      rh.ray.mask = 0xFFFFFFFFu;
      rh.ray.flags = 0;
      rh.ray.time = 0.0f;
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(m.scene, &context, &rh);
      if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
      MeshHit& h = hits[i];
      h.triangle = static_cast<int>(rh.hit.primID);
      h.u = rh.hit.u;
      h.v = rh.hit.v;
      h.t = rh.ray.tfar * m.scale;
      // Recompute t, u, v in double on the triangle Embree found.
      const auto& tri = m.triangles[rh.hit.primID];
      const Vec3& p0 = m.positions[tri[0]];
      const Vec3 e1 = m.positions[tri[1]] - p0, e2 = m.positions[tri[2]] - p0;
      const Vec3 n = e1.cross(e2);
      const double denom = n.dot(ray.direction);
      if (std::abs(denom) > 1e-12 * n.norm()) {
        const double t = n.dot(p0 - ray.origin) / denom;
        const Vec3 q = ray.origin + t * ray.direction - p0;
        const double d00 = e1.dot(e1), d01 = e1.dot(e2), d11 = e2.dot(e2), d20 = q.dot(e1), d21 = q.dot(e2);
        const double den = d00 * d11 - d01 * d01;
        if (den > 0.0 && std::isfinite(t)) {
          double u = (d11 * d20 - d01 * d21) / den, v = (d00 * d21 - d01 * d20) / den;
          // The double triangle differs from Embree's float one by rounding: keep the blend inside.
          u = std::clamp(u, 0.0, 1.0);
          v = std::clamp(v, 0.0, 1.0);
          if (u + v > 1.0) {
            const double s = u + v;
            u /= s;
            v /= s;
          }
          h.t = t;
          h.u = u;
          h.v = v;
        }
      }
    }
  });
  return hits;
}

std::vector<ClosestPoint> EmbreeScene::closest_points(const std::vector<Vec3>& points) const {
  const Impl& m = *impl_;
  std::vector<ClosestPoint> out(points.size());
  struct PointQueryData {
    const Impl* impl;
    Vec3 point;
    ClosestPoint best;
  };
  // Embree calls this for every triangle whose bounds meet the query sphere; it shrinks the sphere.
  const RTCPointQueryFunction callback = [](RTCPointQueryFunctionArguments* args) -> bool {
    auto* d = static_cast<PointQueryData*>(args->userPtr);
    const auto& tri = d->impl->triangles[args->primID];
    const auto& P = d->impl->positions;
    const Vec3 q = closest_point_on_triangle(d->point, P[tri[0]], P[tri[1]], P[tri[2]]);
    const double dist = (q - d->point).norm();
    if (dist < d->best.distance) {
      d->best = {q, dist, static_cast<int>(args->primID)};
      args->query->radius = static_cast<float>((dist + d->impl->query_margin) / d->impl->scale);
      return true;
    }
    return false;
  };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), kRayBlock), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      PointQueryData data{&m, points[i], {}};
      const Vec3 p = (points[i] - m.center) / m.scale;
      RTCPointQuery query;
      query.x = static_cast<float>(p.x());
      query.y = static_cast<float>(p.y());
      query.z = static_cast<float>(p.z());
      query.time = 0.0f;
      query.radius = std::numeric_limits<float>::infinity();
      RTCPointQueryContext context;
      rtcInitPointQueryContext(&context);
      rtcPointQuery(m.scene, &query, &context, callback, &data);
      out[i] = data.best;
    }
  });
  return out;
}

}  // namespace cdp
