#include <cdp/raytrace/crease_distance.h>
#include <cdp/raytrace/embree_scene.h>
#include <cdp/raytrace/evaluate.h>
#include <cdp/raytrace/field_cost.h>
#include <cdp/raytrace/self_intersection.h>

#include <cdp/core/errors.h>

#include <cmath>

namespace cdp {

namespace {
// JSON has no infinity or NaN: such values become null.
nlohmann::json number(double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr); }
}  // namespace

nlohmann::json to_json(const SampleStats& s) {
  return {{"count", s.count}, {"mean", number(s.mean)}, {"std", number(s.std)}, {"min", number(s.min)},
          {"max", number(s.max)}};
}

nlohmann::json to_json(const MeshQuality& q) {
  nlohmann::json j;
  j["triangles"] = q.triangles;
  j["vertices"] = q.vertices;
  j["degenerate_triangles"] = q.degenerate;
  j["edge_ratio"] = to_json(q.edge_ratio);
  j["edge_ratio"]["histogram"] = {{"edges", q.histogram_edges}, {"counts", q.histogram_counts},
                                  {"overflow", q.histogram_overflow}};
  // Keys are the thresholds as written ("1.25"), so that scripts read them without rounding.
  for (std::size_t i = 0; i < q.share_thresholds.size(); ++i)
    j["edge_ratio"]["share_at_most"][nlohmann::json(q.share_thresholds[i]).dump()] = q.shares_at_most[i];
  j["near_equilateral_fraction"] = q.near_equilateral_fraction;
  j["near_equilateral_definition"] = "longest / shortest edge <= " + nlohmann::json(q.near_equilateral_ratio).dump();
  j["min_angle_deg"] = to_json(q.min_angle_deg);
  j["min_angle_deg"]["share_under"] = {{"10", q.angles.share_under_10}, {"20", q.angles.share_under_20},
                                       {"30", q.angles.share_under_30}};
  j["min_angle_deg"]["cumulative_below_degrees"] = q.angles.below;
  j["radius_ratio"] = to_json(q.radius_ratio);
  j["edge_length"] = to_json(q.edge_length);
  const MeshTopology& t = q.topology;
  j["topology"] = {{"closed", t.closed()},
                   {"manifold", t.edge_manifold() && t.vertex_manifold()},
                   {"oriented", t.oriented()},
                   {"watertight", t.watertight()},
                   {"components", t.components},
                   {"genus", t.genus},
                   {"euler_characteristic", t.euler_characteristic},
                   {"boundary_edges", t.boundary_edges},
                   {"nonmanifold_edges", t.nonmanifold_edges},
                   {"nonmanifold_vertices", t.nonmanifold_vertices},
                   {"misoriented_edges", t.misoriented_edges},
                   {"degenerate_triangles", t.degenerate_triangles},
                   {"duplicate_triangles", t.duplicate_triangles},
                   {"area", t.area},
                   {"signed_volume", t.signed_volume}};
  return j;
}

nlohmann::json to_json(const SelfIntersectionReport& r) {
  nlohmann::json examples = nlohmann::json::array();
  for (const auto& [f, g] : r.examples) examples.push_back({f, g});
  return {{"pairs", r.pairs},
          {"examples", examples},
          {"degenerate_triangles_skipped", r.degenerate_triangles},
          {"candidate_pairs", r.candidate_pairs}};
}

nlohmann::json to_json(const AccuracyMetrics& a) {
  nlohmann::json j;
  j["depth_error"] = to_json(a.depth);
  j["depth_error"]["relative_mean"] = number(a.depth_relative_mean);
  j["phong_error_deg"] = to_json(a.phong_deg);
  j["phong_error_deg"]["undefined"] = a.phong_undefined;
  j["silhouette_disagreement"] = number(a.silhouette_disagreement);
  j["silhouette_counts"] = {{"compared", a.compared}, {"surface_only", a.surface_only}, {"mesh_only", a.mesh_only},
                            {"both_hit", a.both_hit}, {"neither", a.neither}, {"excluded", a.excluded}};
  return j;
}

nlohmann::json evaluate_mesh(const Field& field, const Mesh& mesh, const GroundTruth& truth,
                             const EvaluateOptions& options, const std::string& normals_source,
                             const std::string& cache_key) {
  if (mesh.normals.size() != mesh.positions.size())
    throw InvalidInputError("evaluate: the mesh needs one normal per vertex");
  if (mesh.triangles.empty()) throw InvalidInputError("the mesh has no triangles");
  const EmbreeScene scene(mesh);
  const std::vector<MeshHit> mesh_hits = scene.intersect(truth.rays);
  const GroundTruthCounts c = truth.counts();
  std::size_t mesh_hit_count = 0;
  for (const MeshHit& h : mesh_hits) mesh_hit_count += h.hit();
  // Every accuracy measure would be over zero samples: a mesh nowhere near the field's surface.
  if (mesh_hit_count == 0)
    throw InvalidInputError("no ray hits the mesh (" + std::to_string(c.hits) + " of " +
                            std::to_string(truth.rays.size()) + " rays hit the surface)");
  const AccuracyMetrics accuracy = compute_accuracy(truth, mesh_hits, mesh);
  const MeshQuality quality = compute_mesh_quality(mesh, options.quality);

  nlohmann::json j{{"schema", kMetricsSchema}};
  j.update(to_json(accuracy));
  j.update(to_json(quality));
  j["topology"]["self_intersections"] = to_json(find_self_intersections(mesh));
  j["normals"] = normals_source;

  nlohmann::json rays = to_json(options.camera);
  rays["count"] = truth.rays.size();
  rays["cache_key"] = cache_key;
  rays["lipschitz"] = truth.setup.lipschitz;
  rays["lipschitz_source"] = truth.setup.lipschitz_from_model ? "model" : "estimate or option";
  rays["min_step"] = truth.setup.min_step;
  rays["surface_hits"] = c.hits;
  rays["mesh_hits"] = mesh_hit_count;
  rays["misses"] = c.misses;
  rays["starts_inside"] = c.starts_inside;
  rays["step_limit"] = c.step_limit;
  rays["not_finite"] = c.not_finite;
  rays["grazing"] = c.grazing;
  rays["tangent"] = c.tangent;
  rays["near_miss"] = c.near_miss;
  j["rays"] = rays;

  const SampleStats vd = vertex_distance(field, mesh);
  j["vertex_distance"] = {{"mean", number(vd.mean)}, {"max", number(vd.max)}, {"count", vd.count},
                          {"method", "|F|/|grad F| at every vertex"}};
  const SampleStats ms = mesh_to_surface_distance(field, mesh, options.sampling);
  j["mesh_to_surface"] = {{"mean", number(ms.mean)}, {"max", number(ms.max)}, {"samples", ms.count},
                          {"seed", options.sampling.seed},
                          {"method", "|F|/|grad F| at area-weighted random points of the triangles"}};
  const SampleStats sm = surface_to_mesh_distance(truth, scene);
  j["surface_to_mesh"] = {{"mean", number(sm.mean)}, {"max", number(sm.max)}, {"points", sm.count},
                          {"method", "distance from every ground-truth ray hit to the nearest mesh point"}};
  // fmax: a side without samples (--samples 0) leaves the other side's maximum.
  j["hausdorff_estimate"] = number(std::fmax(ms.max, sm.max));
  // The sharp-feature measures, for fields that report their pieces (CSG expressions).
  const CreaseDistance creases = crease_distance(field, mesh);
  const auto stats = [&](const SampleStats& s) {
    return nlohmann::json{{"mean", number(s.mean)}, {"max", number(s.max)}, {"count", s.count}};
  };
  j["creases"] = {{"curves", creases.crease_curves},
                  {"corners", creases.corners},
                  {"points", creases.crease_points},
                  {"sharp_edges", creases.sharp_edges},
                  {"crease_to_mesh_edges", stats(creases.crease_to_mesh_edges)},
                  {"crease_to_sharp_edges", stats(creases.crease_to_sharp_edges)},
                  {"sharp_edges_to_crease", stats(creases.sharp_edges_to_crease)},
                  {"edge_chamfer", number(creases.edge_chamfer)},
                  {"method", "exact creases traced on the field's min/max/abs pieces against the mesh's edges; "
                             "sharp: dihedral angle over 30 degrees"}};
  const FieldCost cost = measure_field_cost(field, mesh);
  j["field_cost"] = {{"value_us", 1e6 * cost.value_seconds},
                     {"value_gradient_us", 1e6 * cost.value_gradient_seconds},
                     {"gradient_hessian_us", 1e6 * cost.gradient_hessian_seconds},
                     {"points", cost.points},
                     {"method", "fastest of 3 passes of single-point evaluations at up to 1000 vertices"}};
  return j;
}

}  // namespace cdp
