// The paper's accuracy measures: depth error and Phong error along the ground-truth rays, and
// how often the mesh and the surface disagree on whether a ray hits at all.
#pragma once

#include <cdp/raytrace/embree_scene.h>
#include <cdp/raytrace/implicit_raycast.h>

#include <cdp/core/mesh.h>

#include <limits>

namespace cdp {

// Mean, population standard deviation (divide by n) and maximum of n values. NaN when n = 0
// (null in JSON): no samples is no measurement, and a zero would read as a perfect score.
struct SampleStats {
  std::size_t count = 0;
  static constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
  double mean = kNone, std = kNone, max = kNone, min = kNone;
};
// \return the count, mean, population standard deviation, minimum and maximum of `values`; the
//         statistics NaN for no values.
SampleStats sample_stats(const std::vector<double>& values);

struct AccuracyMetrics {
  std::size_t rays = 0;
  std::size_t compared = 0;      // rays whose ground truth is Hit or Miss
  std::size_t both_hit = 0, surface_only = 0, mesh_only = 0, neither = 0;
  std::size_t excluded = 0;      // StartsInside, StepLimit or NotFinite ground truth
  SampleStats depth;             // |t_mesh - t_surface| over rays hitting both
  double depth_relative_mean = 0.0;  // depth.mean / diagonal of the field's box
  SampleStats phong_deg;         // angle between field normal at the true hit and Phong normal
  // Rays hitting both where the angle is undefined (a zero field gradient, or vertex normals that
  // cancel in the blend): left out of phong_deg and counted here.
  std::size_t phong_undefined = 0;
  double silhouette_disagreement = 0.0;  // (surface_only + mesh_only) / compared; NaN when none is
};

// `mesh` must have normals (the ones the Phong normals blend). Throws InvalidInputError when the
// sizes do not match.
// \pre mesh_hits were cast on `mesh` along truth.rays, and every triangle index is in range.
// \throw InvalidInputError when truth.hits or mesh_hits differ from truth.rays in number, or (where a
//        ray hits both) the mesh has no normal per vertex.
// \throw std::out_of_range for a hit triangle that is not in the mesh.
AccuracyMetrics compute_accuracy(const GroundTruth& truth, const std::vector<MeshHit>& mesh_hits, const Mesh& mesh);

}  // namespace cdp
