// overlapping_box_pairs (self_intersection.h): Embree's rtcCollide as a broad phase. With
// embree_scene.cpp, the only file of the project that calls Embree (version 3).
#include <cdp/raytrace/self_intersection.h>

#include <cdp/core/errors.h>

#include "embree_error.h"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <climits>
#include <cstddef>
#include <cmath>
#include <cstdint>
#include <limits>
#include <new>
#include <string>

namespace cdp {

namespace {

// A device and a scene, released on every path out; the first Embree error is kept.
struct EmbreeHandles {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::string error;
  ~EmbreeHandles() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
  void check(const char* what) const {
    if (!error.empty()) throw InvalidInputError(std::string("overlapping_box_pairs: ") + what + ": " + error);
  }
};

// Boxes as Embree sees them: lower x, y, z, upper x, y, z.
using FloatBox = std::array<float, 6>;

struct CollideData {
  const std::vector<FloatBox>* boxes = nullptr;
  tbb::enumerable_thread_specific<std::vector<std::uint64_t>> pairs;
  std::atomic<bool> failed{false};
};

void box_bounds(const RTCBoundsFunctionArguments* args) {
  const FloatBox& b = static_cast<const FloatBox*>(args->geometryUserPtr)[args->primID];
  RTCBounds* o = args->bounds_o;
  o->lower_x = b[0];
  o->lower_y = b[1];
  o->lower_z = b[2];
  o->upper_x = b[3];
  o->upper_y = b[4];
  o->upper_z = b[5];
}

// The user geometry is only collided, never ray traced.
void no_intersection(const RTCIntersectFunctionNArguments*) {}
void no_occlusion(const RTCOccludedFunctionNArguments*) {}

// rtcCollide reports every pair of primitives of two leaves whose bounds overlap (not checking
// the primitives' own bounds), from several threads, in both orders: keep (i < j) when the
// float boxes overlap.
void collect_pairs(void* user, RTCCollision* collisions, unsigned int count) {
  auto* data = static_cast<CollideData*>(user);
  try {
    const std::vector<FloatBox>& b = *data->boxes;
    std::vector<std::uint64_t>& out = data->pairs.local();
    for (unsigned int k = 0; k < count; ++k) {
      std::uint32_t i = collisions[k].primID0, j = collisions[k].primID1;
      if (i == j) continue;
      if (i > j) std::swap(i, j);
      const FloatBox &p = b[i], &q = b[j];
      if (p[0] <= q[3] && q[0] <= p[3] && p[1] <= q[4] && q[1] <= p[4] && p[2] <= q[5] && q[2] <= p[5])
        out.push_back((static_cast<std::uint64_t>(i) << 32) | j);
    }
  } catch (...) {
    data->failed = true;
  }
}

// The largest float not above x, and the smallest not below.
float float_below(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}
float float_above(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

bool is_empty(const Box& b) { return (b.min.array() > b.max.array()).any(); }

}  // namespace

std::vector<std::pair<int, int>> overlapping_box_pairs(const std::vector<Box>& boxes) {
  if (boxes.size() > static_cast<std::size_t>(INT_MAX)) throw InvalidInputError("overlapping_box_pairs: too many boxes");
  Box scene_box{Vec3::Constant(std::numeric_limits<double>::infinity()),
                Vec3::Constant(-std::numeric_limits<double>::infinity())};
  std::size_t live = 0;
  for (const Box& b : boxes) {
    if (!b.min.allFinite() || !b.max.allFinite()) throw InvalidInputError("overlapping_box_pairs: a box is not finite");
    if (is_empty(b)) continue;
    ++live;
    scene_box.min = scene_box.min.cwiseMin(b.min);
    scene_box.max = scene_box.max.cwiseMax(b.max);
  }
  if (live < 2) return {};

  // Embree works in float: map the scene into [-1, 1]^3, then round every box outwards and
  // inflate it by 2^-20 (the double rounding of the map is far below that). The map is
  // monotone, so boxes that overlap in double still overlap in float.
  const Vec3 center = scene_box.center();
  double half = 0.5 * scene_box.size().maxCoeff();
  if (!(half > 0.0) || !std::isfinite(half)) half = std::max(1.0, center.cwiseAbs().maxCoeff());
  constexpr double kMargin = 0x1p-20;
  std::vector<FloatBox> fboxes(boxes.size());
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    if (is_empty(boxes[i])) {
      fboxes[i] = {2.0f, 2.0f, 2.0f, -2.0f, -2.0f, -2.0f};  // invalid bounds: Embree leaves it out
      continue;
    }
    for (int a = 0; a < 3; ++a) {
      fboxes[i][a] = float_below((boxes[i].min[a] - center[a]) / half - kMargin);
      fboxes[i][a + 3] = float_above((boxes[i].max[a] - center[a]) / half + kMargin);
      if (!std::isfinite(fboxes[i][a]) || !std::isfinite(fboxes[i][a + 3]))
        throw InvalidInputError("overlapping_box_pairs: coordinates too large");
    }
  }

  EmbreeHandles e;
  e.device = rtcNewDevice(nullptr);
  if (!e.device) throw InvalidInputError("overlapping_box_pairs: cannot create an Embree device");
  rtcSetDeviceErrorFunction(e.device, embree::record_first_error, &e.error);
  e.scene = rtcNewScene(e.device);
  // rtcCollide works on scenes made of user geometries only: one primitive per box.
  RTCGeometry geom = rtcNewGeometry(e.device, RTC_GEOMETRY_TYPE_USER);
  rtcSetGeometryUserPrimitiveCount(geom, static_cast<unsigned int>(boxes.size()));
  rtcSetGeometryUserData(geom, fboxes.data());
  rtcSetGeometryBoundsFunction(geom, box_bounds, nullptr);
  rtcSetGeometryIntersectFunction(geom, no_intersection);
  rtcSetGeometryOccludedFunction(geom, no_occlusion);
  rtcCommitGeometry(geom);
  rtcAttachGeometry(e.scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(e.scene);
  e.check("building the scene");

  CollideData data;
  data.boxes = &fboxes;
  rtcCollide(e.scene, e.scene, collect_pairs, &data);
  e.check("rtcCollide");
  if (data.failed) throw std::bad_alloc();

  // Bucket the reported partners j by i, then sort and deduplicate each (short) bucket and keep
  // the pairs whose double boxes overlap (the float boxes are a little larger).
  const std::size_t n = boxes.size();
  std::vector<std::size_t> start(n + 1, 0);
  for (const auto& part : data.pairs)
    for (const std::uint64_t k : part) ++start[(k >> 32) + 1];
  for (std::size_t i = 0; i < n; ++i) start[i + 1] += start[i];
  std::vector<std::uint32_t> partners(start[n]);
  {
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (const auto& part : data.pairs)
      for (const std::uint64_t k : part) partners[fill[k >> 32]++] = static_cast<std::uint32_t>(k & 0xFFFFFFFFu);
  }
  constexpr std::uint32_t kDropped = 0xFFFFFFFFu;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const auto first = partners.begin() + static_cast<std::ptrdiff_t>(start[i]);
      const auto last = partners.begin() + static_cast<std::ptrdiff_t>(start[i + 1]);
      std::sort(first, last);
      std::uint32_t previous = kDropped;  // no box has this index (fewer than INT_MAX boxes)
      for (auto it = first; it != last; ++it) {
        const std::uint32_t j = *it;
        const Box &p = boxes[i], &q = boxes[j];
        if (j == previous || !((p.min.array() <= q.max.array()).all() && (q.min.array() <= p.max.array()).all()))
          *it = kDropped;
        previous = j;
      }
    }
  });
  std::vector<std::pair<int, int>> pairs;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t k = start[i]; k < start[i + 1]; ++k)
      if (partners[k] != kDropped) pairs.emplace_back(static_cast<int>(i), static_cast<int>(partners[k]));
  return pairs;
}

}  // namespace cdp
