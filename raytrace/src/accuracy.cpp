#include <cdp/raytrace/accuracy.h>
#include <cdp/raytrace/phong_normal.h>

#include <cdp/core/errors.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace cdp {

SampleStats sample_stats(const std::vector<double>& values) {
  SampleStats s;
  s.count = values.size();
  if (values.empty()) return s;
  double sum = 0.0;
  s.max = -std::numeric_limits<double>::infinity();
  s.min = std::numeric_limits<double>::infinity();
  for (double x : values) {
    sum += x;
    s.max = std::max(s.max, x);
    s.min = std::min(s.min, x);
  }
  s.mean = sum / static_cast<double>(values.size());
  double sq = 0.0;
  for (double x : values) sq += (x - s.mean) * (x - s.mean);
  s.std = std::sqrt(sq / static_cast<double>(values.size()));
  return s;
}

AccuracyMetrics compute_accuracy(const GroundTruth& truth, const std::vector<MeshHit>& mesh_hits, const Mesh& mesh) {
  if (truth.hits.size() != truth.rays.size() || mesh_hits.size() != truth.rays.size())
    throw InvalidInputError("compute_accuracy: ground truth and mesh hits differ in number of rays");
  AccuracyMetrics a;
  a.rays = truth.rays.size();
  std::vector<double> depth, phong;
  for (std::size_t i = 0; i < truth.hits.size(); ++i) {
    const SurfaceHit& s = truth.hits[i];
    const MeshHit& m = mesh_hits[i];
    if (s.status != RayStatus::Hit && s.status != RayStatus::Miss) {
      ++a.excluded;
      continue;
    }
    ++a.compared;
    if (!s.hit()) {
      ++(m.hit() ? a.mesh_only : a.neither);
      continue;
    }
    if (!m.hit()) {
      ++a.surface_only;
      continue;
    }
    ++a.both_hit;
    depth.push_back(std::abs(m.t - s.t));
    const Vec3 pn = phong_normal(mesh, m.triangle, m.u, m.v);
    if (pn == Vec3::Zero() || s.normal == Vec3::Zero()) {
      ++a.phong_undefined;
      continue;
    }
    // atan2 of sine and cosine stays accurate at small angles, where acos loses half the digits.
    phong.push_back(std::atan2(s.normal.cross(pn).norm(), s.normal.dot(pn)) * 180.0 / std::numbers::pi);
  }
  a.depth = sample_stats(depth);
  a.phong_deg = sample_stats(phong);
  a.depth_relative_mean = a.depth.mean / truth.setup.box.diagonal();
  a.silhouette_disagreement = a.compared ? static_cast<double>(a.surface_only + a.mesh_only) /
                                               static_cast<double>(a.compared)
                                         : SampleStats::kNone;
  return a;
}

}  // namespace cdp
