// The smallest angle of each triangle, summarised: what decides whether a mesh suits finite
// elements or parametrization (one 2-degree sliver spoils it, whatever the mean).
#pragma once

#include <cdp/core/field.h>
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

// The smallest angles at a field's creases and away from them, judged from the field rather than
// from a mesher's record of its crease vertices: a vertex is on a crease when two pieces of the
// field meet within `near` of it (Field::pieces), and a triangle is at a crease when a corner is.
// The adaptive method's bounds: 20 degrees away from creases, 5 at them (issue 55).
struct CreaseAngles {
  std::size_t crease_vertices = 0;
  std::size_t triangles_at_creases = 0, triangles_away = 0;
  double min_degrees_at_creases = 180, min_degrees_away = 180;  // 180: no such triangle
  Vec3 worst_away = Vec3::Zero();  // the centroid of the triangle of min_degrees_away
};

// \pre every triangle index is in [0, mesh.num_vertices()).
// \param near  how close two pieces must meet to a vertex; non-positive: 1e-6 of the field's box
//              diagonal.
// \return the angles; a field that reports no pieces (a black box) has every triangle away from
//         creases.
// \throw what the field's evaluations throw.
CreaseAngles crease_angles(const Field& field, const Mesh& mesh, double near = 0);

struct PolygonizeStats;

// Sets stats.angles to angle_statistics(mesh) (STATS.json's "angles" object), as the polygonize
// program and the Python module report it for every method.
// \pre as angle_statistics.
void add_angle_statistics(const Mesh& mesh, PolygonizeStats& stats);

}  // namespace cdp
