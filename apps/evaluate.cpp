// build/bin/evaluate FIELD.json MESH.ply [--rays N] [--views V] [--projection perspective|orthographic]
//                    [--samples N] [--cache DIR] -o METRICS.json
// Measures one mesh of one field: depth and Phong errors against exact ray casting (the ground
// truth, cached in DIR when given), silhouette disagreement, triangle quality, topology,
// self-intersections and distances between mesh and surface. Writes METRICS.json (schema in
// raytrace/README.md) and prints a short summary.
#include "support/app_support.h"
#include "support/command_line.h"

#include <cdp/raytrace/evaluate.h>
#include <cdp/raytrace/ground_truth_cache.h>
#include <cdp/raytrace/phong_normal.h>

#include <cdp/core/errors.h>
#include <cdp/io/atomic_write.h>
#include <cdp/io/field_factory.h>
#include <cdp/io/mesh_io.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace {

std::string read_text(const fs::path& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw cdp::InvalidInputError(path.string() + ": is a folder, not a field file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw cdp::InvalidInputError(path.string() + ": cannot open");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

int main(int argc, char** argv) {
  cdp::app::install_signal_handling();
  cdp::app::keep_freed_memory();
  try {
    CLI::App app{"Measures MESH.ply against the implicit surface of FIELD.json (exact ray casting): depth and\n"
                 "Phong errors, silhouettes, triangle quality, topology, self-intersections, distances.\n"
                 "Writes METRICS.json (schema in raytrace/README.md) and prints a summary.\n",
                 "evaluate"};
    cdp::app::configure(app);
    std::string field_path, mesh_path, out_path, cache_dir, projection = "perspective", normals_choice;
    bool quiet = false, progress_lines = false;
    cdp::EvaluateOptions options;
    app.add_option("FIELD.json", field_path, "the field file")->required()->type_name("")->check(cdp::app::path_name());
    app.add_option("MESH.ply", mesh_path, "the mesh: .ply, .obj, .off or .stl")->required()->type_name("")->check(cdp::app::path_name());
    app.add_option("-o", out_path, "the metrics file")->required()->type_name("METRICS.json")->check(cdp::app::path_name());
    app.add_option("--rays", options.camera.resolution, "N x N rays per view, N in [1, 8192]")
        ->capture_default_str()
        ->type_name("N")
        ->transform(cdp::app::integer_in(1, 8192));
    app.add_option("--views", options.camera.views, "viewing directions, in [1, 10000]")
        ->capture_default_str()
        ->type_name("V")
        ->transform(cdp::app::integer_in(1, 10000));
    app.add_option("--projection", projection, "perspective or orthographic")
        ->capture_default_str()
        ->type_name("NAME")
        ->check(CLI::IsMember({"perspective", "orthographic"}));
    app.add_option("--samples", options.sampling.samples, "points of the mesh measured against the surface, in [1, 1e8]")
        ->capture_default_str()
        ->type_name("N")
        ->transform(cdp::app::integer_in(1, 100000000));
    app.add_option("--cache", cache_dir, "keep the ground truth in DIR and reuse it")->type_name("DIR")->check(cdp::app::path_name());
    app.add_option("--normals", normals_choice,
                   "vertex normals of the Phong error: field (the gradient at the vertices; each side's at the "
                   "vertices on creases of a min/max/abs field), file or mesh "
                   "(area-weighted); default: file when the mesh has them, else field")
        ->type_name("NAME")
        ->check(CLI::IsMember({"field", "file", "mesh"}));
    CLI::Option* quiet_flag = app.add_flag("--quiet", quiet, "no progress bar");
    app.add_flag("--progress", progress_lines, "progress as lines, one per phase and one every 5 s (for logs)")
        ->excludes(quiet_flag);
    if (const auto status = cdp::app::parse(app, argc, argv)) return *status;
    options.camera.projection = cdp::parse_projection(projection);
    cdp::app::check_output_paths({{"-o", out_path}}, {field_path, mesh_path});
    cdp::app::ProgressReporter reporter("evaluate", fs::path(mesh_path).filename().string(),
                                        cdp::app::progress_mode(quiet, progress_lines));

    reporter.phase("reading the field and the mesh");
    const std::string field_text = read_text(field_path);
    const auto field = cdp::load_field(field_path);
    cdp::Mesh mesh = cdp::read_mesh(mesh_path);
    // Which vertex normals the Phong error uses: the file's, the field's gradient at the vertices
    // (the exact normal, as the adaptive method writes them) or the mesh's own area-weighted
    // ones. Default: the file's when it has them, else the field's, so that a mesh from another
    // tool is not judged on how it estimates normals.
    if (normals_choice.empty()) normals_choice = mesh.normals.size() == mesh.positions.size() ? "file" : "field";
    std::string normals_source = normals_choice;
    if (normals_choice == "file") {
      if (mesh.normals.size() != mesh.positions.size())
        throw cdp::InvalidInputError(mesh_path + ": --normals file, but the mesh file has no vertex normals");
    } else if (normals_choice == "field") {
      mesh.normals = cdp::field_normals(*field, mesh);
      mesh.corner_normals = cdp::field_corner_normals(*field, mesh, mesh.normals);
      normals_source = mesh.corner_normals.empty()
                           ? "field (normalized gradient at the vertices)"
                           : "field (normalized gradient at the vertices, each side's at creases)";
    } else {
      mesh.normals = cdp::area_weighted_normals(mesh);
      normals_source = "mesh (area-weighted face normals)";
    }

    const auto start = std::chrono::steady_clock::now();
    std::vector<cdp::Ray> rays;
    try {
      rays = cdp::make_camera_rays(field->bounds(), options.camera);
    } catch (const cdp::InvalidInputError& e) {
      throw cdp::InvalidInputError(field_path + ": " + e.what());  // the rays are fitted to the field's box
    }
    const std::string key = cdp::ground_truth_key(field_text, options.camera, options.raycast);
    bool cached = false;
    const cdp::GroundTruth truth = cdp::cached_ground_truth(
        *field, std::move(rays), options.raycast, cache_dir, key, &cached,
        [&] { reporter.phase("casting rays at the implicit surface"); });
    const double gt_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    reporter.phase("measuring the mesh");
    nlohmann::json metrics;
    try {
      metrics = cdp::evaluate_mesh(*field, mesh, truth, options, normals_source, key);
    } catch (const cdp::InvalidInputError& e) {
      throw cdp::InvalidInputError(mesh_path + ": " + e.what());  // what is wrong is the mesh
    }
    metrics["files"] = {{"field", field_path}, {"mesh", mesh_path}};
    metrics["rays"]["ground_truth_cached"] = cached;
    metrics["rays"]["ground_truth_seconds"] = gt_seconds;
    reporter.phase("writing " + out_path);
    cdp::write_file_atomically(out_path, metrics.dump(2) + "\n", "metrics");

    const auto& r = metrics["rays"];
    std::printf("%s: %zu triangles, %zu rays (%s), %zu surface hits\n", mesh_path.c_str(), mesh.num_triangles(),
                r["count"].get<std::size_t>(), cached ? "cached ground truth" : "ground truth computed",
                r["surface_hits"].get<std::size_t>());
    auto num = [](const nlohmann::json& v) { return v.is_number() ? v.get<double>() : std::nan(""); };
    std::printf("depth error mean %.4g (relative %.3g)  Phong error mean %.4g deg std %.4g  silhouette %.4g\n",
                num(metrics["depth_error"]["mean"]), num(metrics["depth_error"]["relative_mean"]),
                num(metrics["phong_error_deg"]["mean"]), num(metrics["phong_error_deg"]["std"]),
                num(metrics["silhouette_disagreement"]));
    std::printf("edge ratio mean %.4g std %.4g  near-equilateral %.3f  min angle %.3g deg  genus %d  "
                "self-intersecting pairs %zu\n",
                num(metrics["edge_ratio"]["mean"]), num(metrics["edge_ratio"]["std"]),
                num(metrics["near_equilateral_fraction"]), num(metrics["min_angle_deg"]["min"]),
                metrics["topology"]["genus"].get<int>(),
                metrics["topology"]["self_intersections"]["pairs"].get<std::size_t>());
    const auto& under = metrics["min_angle_deg"]["share_under"];
    std::printf("smallest angles under 10/20/30 deg: %.4f %.4f %.4f  mesh-surface distance max %.4g\n",
                num(under["10"]), num(under["20"]), num(under["30"]), num(metrics["hausdorff_estimate"]));
    if (const auto& c = metrics["creases"]; c["curves"].get<std::size_t>() > 0)
      std::printf("creases: %zu curves, %zu corners  crease-to-edge distance mean %.4g max %.4g  edge-Chamfer %.4g "
                  "(%zu sharp edges)\n",
                  c["curves"].get<std::size_t>(), c["corners"].get<std::size_t>(),
                  num(c["crease_to_mesh_edges"]["mean"]), num(c["crease_to_mesh_edges"]["max"]), num(c["edge_chamfer"]),
                  c["sharp_edges"].get<std::size_t>());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "evaluate: %s\n", e.what());
    return 1;
  }
}
