// Distances between a mesh and the implicit surface, both ways.
//   vertex distance and mesh -> surface: |F| / |grad F| (the first-order distance; exact for
//   signed distance fields) at the vertices and at points sampled on the triangles;
//   surface -> mesh: from the ground-truth ray hits to the nearest mesh point (Embree point query).
#pragma once

#include <cdp/raytrace/accuracy.h>
#include <cdp/raytrace/embree_scene.h>
#include <cdp/raytrace/implicit_raycast.h>

#include <cdp/core/field.h>
#include <cdp/core/mesh.h>

#include <cstdint>
#include <vector>

namespace cdp {

struct SurfaceSamplingOptions {
  // Points sampled on the mesh, area-weighted: triangle by the inverse area CDF, point uniform in
  // the triangle, both from a mt19937_64 stream with this seed (deterministic on every platform).
  std::size_t samples = 20000;
  std::uint64_t seed = 1;
};

// \return options.samples points (none when the mesh's area is zero).
// \throw std::out_of_range for a triangle index out of range.
std::vector<Vec3> sample_mesh_surface(const Mesh& mesh, const SurfaceSamplingOptions& options = {});

// |F| / |grad F| at every point, in parallel; a vanishing gradient gives infinity.
// \pre the field can be evaluated from several threads at once (Field::thread_safe is not consulted).
// \throw what the field's evaluations throw, unchanged.
std::vector<double> first_order_distances(const Field& field, const std::vector<Vec3>& points);

// \pre as first_order_distances.
// \return the statistics of first_order_distances at the vertices.
// \throw as first_order_distances.
SampleStats vertex_distance(const Field& field, const Mesh& mesh);
// \pre as first_order_distances.
// \return the statistics of first_order_distances at sample_mesh_surface's points.
// \throw as sample_mesh_surface and first_order_distances.
SampleStats mesh_to_surface_distance(const Field& field, const Mesh& mesh, const SurfaceSamplingOptions& options = {});
// Over the ground-truth hits (status Hit).
// \pre truth.hits has no more entries than truth.rays.
// \return the statistics of the distances from every hit point to the nearest point of the scene's
//         mesh (infinity for a mesh without triangles).
SampleStats surface_to_mesh_distance(const GroundTruth& truth, const EmbreeScene& scene);

}  // namespace cdp
