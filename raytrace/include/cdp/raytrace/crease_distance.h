// How well a mesh follows the creases of a CSG field (the sharp-features measures): the exact
// creases traced on the field (<cdp/core/crease_curves.h>) against the mesh's edges.
//   crease -> mesh edges: from every point of the exact creases to the nearest mesh edge (any
//     edge); small when edges run along the creases (the Hausdorff distance is its max);
//   crease -> sharp edges and sharp edges -> crease: the same against the mesh's sharp edges
//     (dihedral angle over `sharp_angle_degrees`), and from points along those edges back to the
//     creases; the edge-Chamfer distance is the mean of the two means.
#pragma once

#include <cdp/raytrace/accuracy.h>

#include <cdp/core/crease_curves.h>
#include <cdp/core/field.h>
#include <cdp/core/mesh.h>

namespace cdp {

struct CreaseDistanceOptions {
  // An edge is sharp when its two triangles' normals differ by more than this.
  double sharp_angle_degrees = 30;
  // Points along the sharp edges: at most this far apart. Non-positive: 0.002 of the diagonal.
  double edge_spacing = 0;
  // The exact creases: dense polylines (0.002 of the diagonal, tangent turning at most 0.02 rad
  // a step), so that a chord is within about 5e-6 of the diagonal of the crease.
  CreaseTracingOptions tracing = dense_tracing();

  static CreaseTracingOptions dense_tracing() {
    CreaseTracingOptions t;
    t.max_turn = 0.02;
    return t;
  }
};

struct CreaseDistance {
  std::size_t crease_curves = 0, crease_points = 0, corners = 0;
  std::size_t sharp_edges = 0, edge_points = 0;
  SampleStats crease_to_mesh_edges;   // over crease_points
  SampleStats crease_to_sharp_edges;  // over crease_points; empty without sharp edges
  SampleStats sharp_edges_to_crease;  // over edge_points; empty without creases
  double edge_chamfer = SampleStats::kNone;  // mean of the two means above, when both exist
};

// Throws what trace_creases throws. The mesh must be a triangle mesh (any topology).
// \pre every triangle index is in [0, mesh.num_vertices()) and every position is finite.
// \return the counts and distances; no crease points and no distances (count 0) for a field without
//         creases (Field::has_pieces false).
// \throw InvalidInputError for a tracing resolution below 2 or a seed grid of too many nodes.
// \throw NoSurfaceError for a field whose box is not valid, or that is NaN next to the inside on
//        the seed grid.
// \throw LimitExceededError past options.tracing.max_points.
// \throw what the field's evaluations throw, unchanged.
CreaseDistance crease_distance(const Field& field, const Mesh& mesh, const CreaseDistanceOptions& options = {});

}  // namespace cdp
