// build/bin/polygonize FIELD.json -o OUT.ply [--method adaptive|mc|mt] [options] [--stats STATS.json]
// One front end for the adaptive polygonizer and the two baselines: the same field file, the
// same mesh output (PLY, OBJ or OFF by extension, vertex normals from the field gradient) and
// the same STATS.json, so that experiments compare like with like.
#include "support/app_support.h"

#include <baselines/marching_cubes.h>
#include <baselines/marching_tetrahedra.h>
#include <polygonizer/atomic_write.h>
#include <polygonizer/adaptive_polygonizer.h>
#include <polygonizer/errors.h>
#include <polygonizer/field_factory.h>
#include <polygonizer/mesh_io.h>
#include <polygonizer/polygonize_stats_json.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <string>

namespace {

constexpr const char* kUsage =
    "usage: polygonize FIELD.json -o OUT.ply|obj|off [--method adaptive|mc|mt] [--stats STATS.json] [--quiet|--progress]\n"
    "  adaptive: [--factor K | --tolerance EPS] [--min-edge L] [--max-edge L] [--curvature]\n"
    "            [--triangle-count hartmann|paper] [--seed-resolution N] [--max-triangles N]\n"
    "  mc, mt:   [--cell H | --precision P] [--traversal continuation|grid] [--seed-resolution N]\n"
    "            [--max-triangles N]";

using cdp::app::parse_integer;
using cdp::app::parse_number;

// Integer options are ints in the libraries; larger values are refused here with their range
// rather than wrapping around.
constexpr long long kIntMax = 2147483647;

// Runs an algorithm on the field of `path`; its errors (no surface, a bound reached, bad
// options) are about that field, so their messages get its name in front, as every other
// message about a file has.
template <class F>
cdp::PolygonizeResult name_field(const std::string& path, F&& run) {
  try {
    return run();
  } catch (const cdp::NoSurfaceError& e) {
    throw cdp::NoSurfaceError(path + ": " + e.what());
  } catch (const cdp::LimitExceededError& e) {
    throw cdp::LimitExceededError(path + ": " + e.what());
  } catch (const cdp::InvalidInputError& e) {
    throw cdp::InvalidInputError(path + ": " + e.what());
  }
}

}  // namespace

int main(int argc, char** argv) {
  cdp::app::install_signal_handling();
  try {
    std::string field_path, out_path, stats_path, method;
    bool quiet = false, progress_lines = false;
    // Flags are collected first and checked against the method, so that a flag the chosen
    // method would ignore is an error rather than a silent no-op.
    std::map<std::string, std::string> flags;
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      const auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw cdp::InvalidInputError(arg + " needs a value; " + kUsage);
        return argv[++i];
      };
      // Each option once: a second value would silently replace the first.
      const auto once = [&](std::string& slot) {
        if (!slot.empty()) throw cdp::InvalidInputError(arg + " given twice");
        slot = value();
        if (slot.empty()) throw cdp::InvalidInputError(arg + " needs a non-empty value");
      };
      if (arg == "-o" || arg == "--output") once(out_path);
      else if (arg == "--method") once(method);
      else if (arg == "--stats") once(stats_path);
      else if (arg == "--quiet") quiet = true;
      else if (arg == "--progress") progress_lines = true;
      else if (arg == "--curvature") flags[arg] = "1";
      else if (arg == "-h" || arg == "--help") {
        std::cout << kUsage << "\n";
        return 0;
      } else if (arg == "--factor" || arg == "--tolerance" || arg == "--min-edge" || arg == "--max-edge" ||
                 arg == "--triangle-count" || arg == "--seed-resolution" || arg == "--max-triangles" ||
                 arg == "--cell" || arg == "--precision" || arg == "--traversal") {
        if (flags.count(arg)) throw cdp::InvalidInputError(arg + " given twice");
        flags[arg] = value();
      } else if (!arg.empty() && arg[0] != '-' && field_path.empty()) field_path = arg;
      else if (!arg.empty() && arg[0] != '-') throw cdp::InvalidInputError("a second field file \"" + arg + "\"; " + kUsage);
      else throw cdp::InvalidInputError("unexpected argument \"" + arg + "\"\n" + kUsage);
    }
    if (field_path.empty() || out_path.empty()) throw cdp::InvalidInputError(std::string("missing FIELD.json or -o OUT\n") + kUsage);
    if (method.empty()) method = "adaptive";
    if (quiet && progress_lines) throw cdp::InvalidInputError("give either --quiet or --progress, not both");
    if (method != "adaptive" && method != "mc" && method != "mt")
      throw cdp::InvalidInputError("--method must be adaptive, mc or mt, not \"" + method + "\"");
    const std::string ext = std::filesystem::path(out_path).extension().string();
    if (ext != ".ply" && ext != ".obj" && ext != ".off")
      throw cdp::InvalidInputError("output " + out_path + ": the extension must be .ply, .obj or .off");

    const bool adaptive = method == "adaptive";
    for (const auto& [flag, v] : flags) {
      const bool adaptive_only = flag == "--factor" || flag == "--tolerance" || flag == "--min-edge" ||
                                 flag == "--max-edge" || flag == "--triangle-count" || flag == "--curvature";
      const bool marching_only = flag == "--cell" || flag == "--precision" || flag == "--traversal";
      if ((adaptive_only && !adaptive) || (marching_only && adaptive))
        throw cdp::InvalidInputError(flag + " does not apply to --method " + method);
    }
    const auto get = [&](const char* flag) -> std::optional<std::string> {
      auto it = flags.find(flag);
      if (it == flags.end()) return std::nullopt;
      return it->second;
    };

    // Every output is checked before the work starts: an unwritable --stats is found before
    // minutes of meshing, and no output may replace another output or the field file.
    std::vector<std::pair<std::string, std::filesystem::path>> outputs{{"-o", out_path}};
    if (!stats_path.empty()) outputs.push_back({"--stats", stats_path});
    cdp::app::check_output_paths(outputs, {field_path});

    cdp::app::ProgressReporter reporter("polygonize", method + " " + std::filesystem::path(field_path).filename().string(),
                                        cdp::app::progress_mode(quiet, progress_lines));
    reporter.phase("reading the field");
    const auto field = cdp::load_field(field_path);
    const cdp::ProgressCallback progress = reporter.callback();

    cdp::PolygonizeResult result;
    if (adaptive) {
      cdp::AdaptiveOptions o;
      if (get("--factor") && get("--tolerance"))
        throw cdp::InvalidInputError("give either --factor or --tolerance, not both");
      if (auto v = get("--factor")) {
        o.factor = parse_number("--factor", *v);
        if (!(o.factor > 0)) throw cdp::InvalidInputError("--factor must be positive");
      }
      if (auto v = get("--tolerance")) {
        o.sizing = cdp::SizingMode::Tolerance;
        o.tolerance = parse_number("--tolerance", *v);
        if (!(o.tolerance > 0)) throw cdp::InvalidInputError("--tolerance must be positive");
      }
      if (auto v = get("--min-edge")) {
        o.min_edge = parse_number("--min-edge", *v);
        if (!(o.min_edge > 0)) throw cdp::InvalidInputError("--min-edge must be positive");
      }
      if (auto v = get("--max-edge")) {
        o.max_edge = parse_number("--max-edge", *v);
        if (!(o.max_edge > 0)) throw cdp::InvalidInputError("--max-edge must be positive");
      }
      if (auto v = get("--triangle-count")) {
        if (*v == "hartmann") o.triangle_count = cdp::TriangleCountRule::Hartmann;
        else if (*v == "paper") o.triangle_count = cdp::TriangleCountRule::PaperFloor;
        else throw cdp::InvalidInputError("--triangle-count must be hartmann or paper, not \"" + *v + "\"");
      }
      if (auto v = get("--seed-resolution")) o.seed_resolution = static_cast<int>(parse_integer("--seed-resolution", *v, 2, kIntMax));
      if (auto v = get("--max-triangles")) o.max_triangles = static_cast<std::size_t>(parse_integer("--max-triangles", *v, 1, kIntMax));
      o.curvature_properties = get("--curvature").has_value();
      o.progress = progress;
      o.phase = reporter.phase_callback();
      result = name_field(field_path, [&] { return cdp::polygonize_adaptive(*field, o); });
    } else {
      cdp::MarchingOptions o;
      if (get("--cell") && get("--precision")) throw cdp::InvalidInputError("give either --cell or --precision, not both");
      if (auto v = get("--cell")) {
        o.cell_size = parse_number("--cell", *v);
        // 0 means "the default" inside the library; on the command line it is a mistake.
        if (!(o.cell_size > 0)) throw cdp::InvalidInputError("--cell must be positive, not " + *v);
      }
      if (auto v = get("--precision")) o.precision = static_cast<int>(parse_integer("--precision", *v, 0, 5));
      if (auto v = get("--traversal")) {
        if (*v == "continuation") o.traversal = cdp::Traversal::Continuation;
        else if (*v == "grid") o.traversal = cdp::Traversal::Grid;
        else throw cdp::InvalidInputError("--traversal must be continuation or grid, not \"" + *v + "\"");
      }
      if (auto v = get("--seed-resolution")) o.seed_resolution = static_cast<int>(parse_integer("--seed-resolution", *v, 2, kIntMax));
      if (auto v = get("--max-triangles")) o.max_triangles = static_cast<std::size_t>(parse_integer("--max-triangles", *v, 1, kIntMax));
      reporter.phase("meshing");
      o.progress = progress;
      result = name_field(field_path, [&] { return method == "mc" ? cdp::marching_cubes(*field, o) : cdp::marching_tetrahedra(*field, o); });
    }

    reporter.phase("writing " + out_path);
    cdp::write_mesh(result.mesh, out_path);
    if (!stats_path.empty()) {
      nlohmann::json j = cdp::to_json(result.stats);
      j["field"] = field_path;
      cdp::write_file_atomically(stats_path, j.dump(2) + "\n", "statistics");
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "polygonize: %s\n", e.what());
    return 1;
  }
}
