// Everything the evaluation measures about one mesh of one field, as one JSON object (the schema
// is documented in raytrace/README.md).
#pragma once

#include <cdp/raytrace/accuracy.h>
#include <cdp/raytrace/camera.h>
#include <cdp/raytrace/implicit_raycast.h>
#include <cdp/raytrace/mesh_quality.h>
#include <cdp/raytrace/self_intersection.h>
#include <cdp/raytrace/surface_distance.h>

#include <cdp/core/field.h>
#include <cdp/core/mesh.h>

#include <nlohmann/json.hpp>

#include <string>

namespace cdp {

inline constexpr const char* kMetricsSchema = "cdp-metrics/1";

struct EvaluateOptions {
  CameraOptions camera;
  RaycastOptions raycast;
  MeshQualityOptions quality;
  SurfaceSamplingOptions sampling;
};

// `truth` must have been cast with options.camera and options.raycast for this field. The mesh
// needs normals (see phong_normal.h for meshes without). `normals_source` and `cache_key` are
// recorded as given.
// \pre `truth` was cast with options.camera and options.raycast for this field; the field can be
//      evaluated from several threads at once (Field::thread_safe is not consulted).
// \return the metrics object, "schema" kMetricsSchema.
// \throw InvalidInputError for a mesh without one normal per vertex or without triangles, when no ray
//        hits the mesh, and as EmbreeScene, compute_accuracy, compute_mesh_quality and
//        find_self_intersections.
// \throw NoSurfaceError and LimitExceededError as crease_distance.
// \throw what the field's evaluations throw, unchanged.
nlohmann::json evaluate_mesh(const Field& field, const Mesh& mesh, const GroundTruth& truth,
                             const EvaluateOptions& options, const std::string& normals_source = "file",
                             const std::string& cache_key = "");

// \return the object's part of the metrics JSON; a statistic that is NaN or infinite becomes null.
nlohmann::json to_json(const SampleStats& stats);
nlohmann::json to_json(const MeshQuality& quality);
nlohmann::json to_json(const AccuracyMetrics& accuracy);
nlohmann::json to_json(const SelfIntersectionReport& report);

}  // namespace cdp
