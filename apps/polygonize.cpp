// build/bin/polygonize FIELD.json -o OUT.ply [--method adaptive|mc|mt] [options] [--stats STATS.json]
// One front end for the adaptive polygonizer and the two baselines: the same field file, the
// same mesh output (PLY, OBJ or OFF by extension, vertex normals from the field gradient) and
// the same STATS.json, so that experiments compare like with like.
#include <baselines/marching_cubes.h>
#include <baselines/marching_tetrahedra.h>
#include <polygonizer/atomic_write.h>
#include <polygonizer/adaptive_polygonizer.h>
#include <polygonizer/errors.h>
#include <polygonizer/field_factory.h>
#include <polygonizer/mesh_io.h>
#include <polygonizer/progress.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <string>

namespace {

constexpr const char* kUsage =
    "usage: polygonize FIELD.json -o OUT.ply|obj|off [--method adaptive|mc|mt] [--stats STATS.json] [--quiet]\n"
    "  adaptive: [--factor K | --tolerance EPS] [--min-edge L] [--max-edge L] [--curvature]\n"
    "            [--triangle-count hartmann|paper] [--seed-resolution N] [--max-triangles N]\n"
    "  mc, mt:   [--cell H | --precision P] [--traversal continuation|grid] [--seed-resolution N]\n"
    "            [--max-triangles N]";

double parse_number(const std::string& flag, const std::string& text) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !std::isfinite(v))
    throw cdp::InvalidInputError(flag + " expects a number, found \"" + text + "\"");
  return v;
}

long parse_integer(const std::string& flag, const std::string& text) {
  const double v = parse_number(flag, text);
  if (v != std::floor(v) || std::abs(v) > 1e15)
    throw cdp::InvalidInputError(flag + " expects an integer, found \"" + text + "\"");
  return static_cast<long>(v);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    std::string field_path, out_path, stats_path, method = "adaptive";
    bool quiet = false;
    // Flags are collected first and checked against the method, so that a flag the chosen
    // method would ignore is an error rather than a silent no-op.
    std::map<std::string, std::string> flags;
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      const auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw cdp::InvalidInputError(arg + " needs a value; " + kUsage);
        return argv[++i];
      };
      if (arg == "-o" || arg == "--output") out_path = value();
      else if (arg == "--method") method = value();
      else if (arg == "--stats") stats_path = value();
      else if (arg == "--quiet") quiet = true;
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
      else throw cdp::InvalidInputError("unexpected argument \"" + arg + "\"\n" + kUsage);
    }
    if (field_path.empty() || out_path.empty()) throw cdp::InvalidInputError(std::string("missing FIELD.json or -o OUT\n") + kUsage);
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

    const auto field = cdp::load_field(field_path);
    cdp::ProgressBar bar(method + " " + std::filesystem::path(field_path).filename().string());
    cdp::ProgressCallback progress;
    if (!quiet) progress = bar.callback();

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
      if (auto v = get("--seed-resolution")) o.seed_resolution = static_cast<int>(parse_integer("--seed-resolution", *v));
      if (auto v = get("--max-triangles")) {
        const long n = parse_integer("--max-triangles", *v);
        if (n <= 0) throw cdp::InvalidInputError("--max-triangles must be positive");
        o.max_triangles = static_cast<std::size_t>(n);
      }
      o.curvature_properties = get("--curvature").has_value();
      o.progress = progress;
      result = cdp::polygonize_adaptive(*field, o);
    } else {
      cdp::MarchingOptions o;
      if (auto v = get("--cell")) o.cell_size = parse_number("--cell", *v);
      if (auto v = get("--precision")) o.precision = static_cast<int>(parse_integer("--precision", *v));
      if (auto v = get("--traversal")) {
        if (*v == "continuation") o.traversal = cdp::Traversal::Continuation;
        else if (*v == "grid") o.traversal = cdp::Traversal::Grid;
        else throw cdp::InvalidInputError("--traversal must be continuation or grid, not \"" + *v + "\"");
      }
      if (auto v = get("--seed-resolution")) o.seed_resolution = static_cast<int>(parse_integer("--seed-resolution", *v));
      if (auto v = get("--max-triangles")) {
        const long n = parse_integer("--max-triangles", *v);
        if (n <= 0) throw cdp::InvalidInputError("--max-triangles must be positive");
        o.max_triangles = static_cast<std::size_t>(n);
      }
      o.progress = progress;
      result = method == "mc" ? cdp::marching_cubes(*field, o) : cdp::marching_tetrahedra(*field, o);
    }

    cdp::write_mesh(result.mesh, out_path);
    if (!stats_path.empty()) {
      nlohmann::json j = cdp::to_json(result.stats);
      j["field"] = field_path;
      cdp::write_file_atomically(stats_path, j.dump(2) + "\n");
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "polygonize: %s\n", e.what());
    return 1;
  }
}
