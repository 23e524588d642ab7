// Triangle shape measures of a mesh: the paper's "Average Ratio L/s" (longest over shortest edge)
// and its deviation, a near-equilateral share, angles and radius ratios, plus its topology.
#pragma once

#include <cdp/raytrace/accuracy.h>

#include <cdp/core/mesh.h>
#include <cdp/core/mesh_angles.h>
#include <cdp/core/mesh_topology.h>

#include <vector>

namespace cdp {

struct MeshQualityOptions {
  // A triangle is near-equilateral when longest / shortest edge <= this.
  double near_equilateral_ratio = 1.1;
  // Histogram of edge ratios: bins [edges[i], edges[i+1]); larger ratios go to `overflow`.
  // Default: 1.0, 1.1, ..., 3.0.
  std::vector<double> histogram_edges;
  // Shares of triangles with longest / shortest edge at or below each of these: the paper's
  // "about 50% equilateral" is undefined, and its own means and deviations are consistent with
  // some thresholds only (scripts/table1.py judges the claim at those).
  std::vector<double> share_thresholds = {1.1, 1.2, 1.25, 1.3};
};

struct MeshQuality {
  std::size_t triangles = 0, vertices = 0;
  std::size_t degenerate = 0;   // a zero-length edge or zero area: left out of the shape measures
  SampleStats edge_ratio;       // longest / shortest edge
  double near_equilateral_fraction = 0.0;  // of the non-degenerate triangles
  double near_equilateral_ratio = 1.1;
  std::vector<double> histogram_edges;
  std::vector<std::size_t> histogram_counts;
  std::size_t histogram_overflow = 0;
  std::vector<double> share_thresholds;   // as in the options
  std::vector<double> shares_at_most;     // of the non-degenerate triangles, one per threshold
  SampleStats min_angle_deg;    // smallest angle of each triangle
  AngleStatistics angles;       // the same angles: shares under 10, 20, 30 degrees, cumulative histogram
  SampleStats radius_ratio;     // 2 r_in / r_circ: 1 equilateral, 0 degenerate
  SampleStats edge_length;      // over triangle sides (each shared edge counted per triangle)
  MeshTopology topology;
};

// \throw InvalidInputError for histogram_edges given with fewer than two values or out of order, or
//        a triangle index out of range.
MeshQuality compute_mesh_quality(const Mesh& mesh, const MeshQualityOptions& options = {});

}  // namespace cdp
