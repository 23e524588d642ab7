// The smallest angle of each triangle, summarised: what decides whether a mesh suits finite
// elements or parametrization (one 2-degree sliver spoils it, whatever the mean).
#pragma once

#include <cdp/core/mesh.h>

#include <array>
#include <cstddef>
#include <vector>

namespace cdp {

struct AngleStatistics {
  std::size_t triangles = 0;       // non-degenerate ones (zero-area triangles have no angles)
  std::size_t degenerate = 0;
  double min_degrees = 0;          // smallest angle of any triangle (0 for an empty mesh)
  double mean_min_degrees = 0;     // mean over triangles of their smallest angle
  double mean_edge_ratio = 0;      // mean over triangles of longest / shortest edge
  // Shares of triangles whose smallest angle is under 10, 20 and 30 degrees.
  double share_under_10 = 0, share_under_20 = 0, share_under_30 = 0;
  // Cumulative histogram: below[k] triangles have their smallest angle under k + 1 degrees,
  // k = 0 .. 59 (every smallest angle is at most 60 degrees; an exact 60 counts in the last).
  std::vector<long long> below;
};

// \pre every triangle index is in [0, mesh.num_vertices()).
// \return the statistics of the triangles with a positive area and shortest edge; the others are
//         counted in `degenerate`.
AngleStatistics angle_statistics(const Mesh& mesh);

struct PolygonizeStats;

// Sets stats.angles to angle_statistics(mesh) (STATS.json's "angles" object), as the polygonize
// program and the Python module report it for every method.
// \pre as angle_statistics.
void add_angle_statistics(const Mesh& mesh, PolygonizeStats& stats);

}  // namespace cdp
