// build/bin/polygonize FIELD.json -o OUT.ply [--method adaptive|mc|mt] [options] [--stats STATS.json] [--repeat N]
// One front end for the adaptive polygonizer and the two baselines: the same field file, the
// same mesh output (PLY, OBJ or OFF by extension, vertex normals from the field gradient) and
// the same STATS.json, so that experiments compare like with like.
#include "support/app_support.h"
#include "support/command_line.h"
#include "support/polygonize_flags.h"

#include <cdp/baselines/marching_cubes.h>
#include <cdp/baselines/marching_tetrahedra.h>
#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/errors.h>
#include <cdp/core/mesh_angles.h>
#include <cdp/core/models/level_shift.h>
#include <cdp/io/atomic_write.h>
#include <cdp/io/field_factory.h>
#include <cdp/io/mesh_io.h>
#include <cdp/io/polygonize_options.h>
#include <cdp/io/polygonize_stats_json.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

// --repeat is for timing a run, not for a benchmark loop (bench/ has those).
constexpr long long kMaxRepeat = 100;

bool same_mesh(const cdp::Mesh& a, const cdp::Mesh& b) {
  return a.positions == b.positions && a.normals == b.normals && a.triangles == b.triangles &&
         a.corner_normals == b.corner_normals && a.vertex_scalars == b.vertex_scalars;
}

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

// VmHWM of /proc/self/status in bytes; none where it cannot be read (not Linux).
std::optional<double> peak_resident_bytes() {
  std::FILE* f = std::fopen("/proc/self/status", "r");
  if (!f) return std::nullopt;
  char line[256];
  std::optional<double> kb;
  while (std::fgets(line, sizeof line, f))
    if (std::strncmp(line, "VmHWM:", 6) == 0) {
      kb = std::strtod(line + 6, nullptr);
      break;
    }
  std::fclose(f);
  if (!kb || !(*kb > 0)) return std::nullopt;
  return *kb * 1024;
}

}  // namespace

int main(int argc, char** argv) {
  cdp::app::install_signal_handling();
  cdp::app::keep_freed_memory();
  try {
    CLI::App app{"Meshes the implicit surface of FIELD.json with the adaptive polygonizer (the default) or a\n"
                 "baseline, Marching Cubes (mc) or Marching Tetrahedra (mt).\n",
                 "polygonize"};
    cdp::app::configure(app);
    std::string field_path, out_path, stats_path, method = "adaptive";
    bool quiet = false, progress_lines = false;
    app.add_option("FIELD.json", field_path, "the field file")->required()->type_name("")->check(cdp::app::path_name());
    app.add_option("-o,--output", out_path, "the mesh file: .ply, .obj, .off or .stl")
        ->required()
        ->type_name("OUT")
        ->check(cdp::app::path_name());
    app.add_option("--method", method, "adaptive, mc or mt")
        ->capture_default_str()
        ->type_name("NAME")
        ->check(CLI::IsMember({"adaptive", "mc", "mt"}));
    app.add_option("--stats", stats_path, "also write the run's statistics as JSON")
        ->type_name("STATS.json")
        ->check(cdp::app::path_name());
    CLI::Option* quiet_flag = app.add_flag("--quiet", quiet, "no progress bar");
    app.add_flag("--progress", progress_lines, "progress as lines, one per phase and one every 5 s (for logs)")
        ->excludes(quiet_flag);
    int repeat = 1;
    app.add_option("--repeat", repeat,
                   "run the method N times (1-100) for a steadier time: STATS.json gives the run of median time "
                   "(the lower middle one for an even N) "
                   "and every run's time (repeat_seconds); the meshes must agree bit for bit")
        ->capture_default_str()
        ->type_name("N")
        ->transform(cdp::app::integer_in(1, kMaxRepeat));
    // The methods' options, from the table Python's keywords and the experiment keys share.
    const cdp::app::PolygonizeFlags flags(app);

    if (const auto status = cdp::app::parse(app, argc, argv)) return *status;

    const bool adaptive = method == "adaptive";
    if (const std::string flag = flags.not_applying(method); !flag.empty())
      throw cdp::InvalidInputError(flag + " does not apply to --method " + method);
    const std::string ext = std::filesystem::path(out_path).extension().string();
    if (ext != ".ply" && ext != ".obj" && ext != ".off" && ext != ".stl")
      throw cdp::InvalidInputError("output " + out_path + ": the extension must be .ply, .obj, .off or .stl");

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

    // The options once; each repetition (--repeat) then runs the method again with them.
    cdp::PolygonizeRequest request = cdp::polygonize_request(method, flags.given());
    std::optional<cdp::LevelShift> shifted;
    const cdp::Field& surface = request.level != 0 ? shifted.emplace(*field, request.level) : *field;
    cdp::AdaptiveOptions& adaptive_options = request.adaptive;
    cdp::MarchingOptions& marching_options = request.marching;
    adaptive_options.progress = marching_options.progress = progress;
    // A signal during a run cancels it (app_support.h): it ends within the polls' bound, and the
    // program then by that signal.
    adaptive_options.cancel = marching_options.cancel = cdp::app::run_token();
    adaptive_options.phase = reporter.phase_callback();
    const auto run_once = [&]() -> cdp::PolygonizeResult {
      const cdp::app::CancellableRun cancellable;
      if (adaptive) return name_field(field_path, [&] { return cdp::polygonize_adaptive(surface, adaptive_options); });
      reporter.phase("meshing");
      return name_field(field_path, [&] {
        return method == "mc" ? cdp::marching_cubes(surface, marching_options) : cdp::marching_tetrahedra(surface, marching_options);
      });
    };

    // With --repeat the method runs again on the same field; every run must make the same mesh
    // (the library promises it), and the statistics are those of the run of median time (for an
    // even N the lower of the two middle ones), so that a run slowed by the machine's other work
    // does not decide a comparison of times.
    cdp::PolygonizeResult result = run_once();
    std::vector<cdp::PolygonizeStats> runs{result.stats};
    for (int i = 1; i < repeat; ++i) {
      cdp::PolygonizeResult again = run_once();
      if (!same_mesh(again.mesh, result.mesh))
        throw std::runtime_error(field_path + ": repetition " + std::to_string(i + 1) +
                                 " made a different mesh from the first (the method should be deterministic: "
                                 "please report this)");
      runs.push_back(std::move(again.stats));
    }
    std::vector<std::size_t> by_time(runs.size());
    std::iota(by_time.begin(), by_time.end(), std::size_t{0});
    std::stable_sort(by_time.begin(), by_time.end(),
                     [&](std::size_t a, std::size_t b) { return runs[a].seconds < runs[b].seconds; });
    result.stats = runs[by_time[(runs.size() - 1) / 2]];

    reporter.phase("writing " + out_path);
    cdp::write_mesh(result.mesh, out_path);
    // The program's own high-water mark, the mesh's writing included (a parent's wait4 can report
    // the parent's: Linux carries a vfork parent's peak into its child's exec).
    const std::optional<double> peak = peak_resident_bytes();
    if (!stats_path.empty()) {
      // Every method's triangles by their smallest angle and the mesh's topology: the summary.
      cdp::add_mesh_summary(result.mesh, result.stats);
      nlohmann::json j = cdp::to_json(result.stats);
      j["field"] = field_path;
      if (peak) j["peak_resident_bytes"] = *peak;
      if (repeat > 1) {
        j["repeat_seconds"] = nlohmann::json::array();
        for (const auto& r : runs) j["repeat_seconds"].push_back(r.seconds);
      }
      cdp::write_file_atomically(stats_path, j.dump(2) + "\n", "statistics");
    }
    // The tolerance is a promise: triangles the refinement could not bring under it (detail
    // finer than min_edge) are named here, not only counted in the statistics. The mesh is still
    // written: it is closed and valid, and the rest of it keeps the bound.
    if (adaptive && adaptive_options.sizing == cdp::SizingMode::Tolerance) {
      const cdp::QualityReport& q = result.stats.adaptive->quality;
      if (q.over_tolerance > 0) {
        std::fprintf(stderr,
                     "polygonize: %s: warning: %zu triangles lie farther from the surface than the tolerance %g (up to "
                     "%g, near (%g, %g, %g)); the refinement could not split them further (edges too short to halve, "
                     "or splits that would fold)\n",
                     field_path.c_str(), q.over_tolerance, adaptive_options.tolerance, q.over_tolerance_worst,
                     q.over_tolerance_near.x(), q.over_tolerance_near.y(), q.over_tolerance_near.z());
      }
    }
    // So are creases asked for and not followed: the surface was meshed across them as smooth,
    // its sharp edges cut by chords, where the layout or a patch failed (creases.fallback says why).
    if (adaptive) {
      const cdp::CreaseReport& c = result.stats.adaptive->creases;
      if (c.handling == cdp::CreaseHandling::Follow && !c.followed && !c.fallback.empty())
        std::fprintf(stderr, "polygonize: %s: warning: the creases are not followed, the surface is meshed across them as smooth (%s)\n",
                     field_path.c_str(), c.fallback.c_str());
    }
    return 0;
  } catch (const cdp::CancelledError& e) {
    cdp::app::end_if_interrupted();
    std::fprintf(stderr, "polygonize: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "polygonize: %s\n", e.what());
    return 1;
  }
}
