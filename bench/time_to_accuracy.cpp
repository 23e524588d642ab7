// Time to accuracy: how long each method needs to reach a given accuracy, rather than how fast it
// makes triangles. For four fields (bunny VIS-800, Igea VIS-4004, tanglecube, random blobs) and
// five method families (adaptive by factor, by tolerance and by chord deviation, Marching
// Tetrahedra, Marching Cubes) it finds the fastest run that reaches
//   phong: a mean Phong error <= 0.5 degrees (AccuracyMetrics::phong_deg.mean), and
//   depth: a mean depth error <= 1e-4 of the box diagonal (AccuracyMetrics::depth_relative_mean),
// measured as `evaluate` measures them with Table 1's camera (experiments/table1.json: 6 views,
// 200 x 200 rays, perspective) and the mesh's own vertex normals (every method writes the
// field's normalized gradient). The ground truth has evaluate's cache key, so the cache of
// `make reproduce` in results/cache is reused; a missing one is computed and saved there.
//
// Design. Each family walks a parameter ladder in growing triangle count, and stops one step
// after both targets are reached (none when the step reaching them took over
// half the time bound). The ladders step by about sqrt(2) in triangles (kRungsPerDoubling), so
// that the run chosen overshoots a target by about as much whatever the method:
//   adaptive_factor     factor 2^(j/4) from 1 to 19 (triangles go as the factor squared; default
//                       clamps: min_edge 2e-3 and max_edge 0.1 of the diagonal, as in the
//                       experiments)
//   adaptive_tolerance  SizingMode::Tolerance, eps = diagonal x 3e-3 / 2^(j/2) down to 8e-6
//                       (triangles go as 1 / eps)
//   adaptive_chord      SizingMode::Chord (the tolerance's sizing without its bound), the same eps
//   mt, mc              the paper's precisions 0..5 on the variational fields (cell = constraint
//                       spacing x 1, 0.7, 0.6, 0.5, 0.4, 0.3: 1.4-2 times the triangles a step,
//                       kept as the paper's), then cells diagonal / N for N = 16 x 2^(k/4) up to
//                       4096, those finer than the last precision's cell
// With the ladders of before (factors 1, 1.5, 2, 3, 4, 5, 6, 8, 10, 13, 16, 20; eps 3e-3, 1e-3,
// 3e-4 ...; N = 16 x sqrt(2)^k) one rung was 1.4-2.3, 3.3 and 2 times the triangles of the one
// before, and a method's ratio to another moved by up to that much with where its rungs fell.
// Bounds: a family stops after a run slower than kMaxRunSeconds or larger
// than kMaxTriangles (the polygonizers' own max_triangles is set a little above, so a runaway run
// throws instead of going on). A run that throws (the adaptive method does on some surfaces)
// counts as not reaching and the walk goes on. A run whose silhouette disagrees with the
// surface's on more than 1% of the rays does not count either: the Phong and depth means are
// over the rays that hit both, so a mesh missing a part would look accurate (Marching Cubes
// loses parts of the tanglecube at cell diagonal/16).
// Each run of the ladder is timed once. Of the runs that reach a target, the first two and any
// other within 1.5 times the fastest single run are timed again as the median of 3 runs, and
// the fastest is chosen, a later step only when at least 20% faster (single runs are noisy on a
// shared machine, and the configuration a benchmark times should not change with the noise).
// Times are the polygonizer's own stats.seconds (manual time, wall clock). The adaptive runs
// keep their defaults (check_self_intersections on, about 1 us per triangle), as `polygonize`
// and the experiments run them.
//
// Benchmarks: BM_SlowTimeToAccuracy/<field>/<family>/<phong|depth>, registered at start-up. The
// sweep of a field runs once, on the first of its benchmarks that runs (a static cache); each
// invocation then re-runs only the chosen configuration and reports that run's time, so the
// runner's repetitions are real samples. Counters: triangles, the parameter (factor, tolerance
// as a fraction of the diagonal, or cell as a fraction of it), the error reached, and on the
// adaptive entries vs_mt / vs_mc = adaptive time / that method's time for the same field and
// target (medians of 3 measured in this process), and the same goal as time per vertex
// (report_overhead). A target that the ladder does not reach is
// SkipWithError("... not reached up to ..."): missing, never a made-up number. "Slow" in the
// name keeps it out of the CI short mode: the whole sweep takes minutes. The sweep's table is
// printed to stderr.
#include <cdp/baselines/marching_cubes.h>
#include <cdp/baselines/marching_options.h>
#include <cdp/baselines/marching_tetrahedra.h>
#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/errors.h>
#include <cdp/io/field_factory.h>
#include <cdp/raytrace/accuracy.h>
#include <cdp/raytrace/camera.h>
#include <cdp/raytrace/embree_scene.h>
#include <cdp/raytrace/field_cost.h>
#include <cdp/raytrace/ground_truth_cache.h>
#include <cdp/raytrace/implicit_raycast.h>
#include <cdp/raytrace/phong_normal.h>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace {

using namespace cdp;

constexpr double kPhongTargetDeg = 0.5;
constexpr double kDepthTargetRelative = 1e-4;
constexpr double kMaxRunSeconds = 5.0;
constexpr std::size_t kMaxTriangles = 2'000'000;
// Rungs of each ladder per doubling of the triangle count (see Design).
constexpr int kRungsPerDoubling = 2;
// The ladders' ends: the adaptive factors up to this, the tolerances (of the diagonal) from the
// first down to the last; the marching cells go from diagonal / 16 to diagonal / 4096.
constexpr double kLastFactor = 20;
constexpr double kFirstTolerance = 3e-3, kLastTolerance = 8e-6;
constexpr int kTimingRuns = 3;
// Runs whose silhouette disagrees with the surface's on more than this share of the rays miss or
// add a part of the surface and do not count (their Phong and depth means leave that part out).
constexpr double kMaxSilhouette = 0.01;
// Beyond the first two steps reaching a target, candidates slower than this times the fastest
// single run reaching it are not timed again.
constexpr double kCandidateSlack = 1.5;
// A candidate later on the ladder than the current choice replaces it only below this share of its time.
constexpr double kLaterStepMargin = 0.8;

const char* const kFields[][2] = {{"bunny_vis800", "experiments/fields/bunny_vis800.json"},
                                  {"igea_vis4004", "experiments/fields/igea_vis4004.json"},
                                  {"tanglecube", "experiments/fields/tanglecube.json"},
                                  {"random_blobs", "experiments/fields/random_blobs.json"}};
const char* const kFamilies[] = {"adaptive_factor", "adaptive_tolerance", "adaptive_chord", "mt", "mc"};
const char* const kTargets[] = {"phong", "depth"};

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// One rung of a ladder: a parameter value and the run it stands for.
struct Step {
  std::string param;  // "factor", "tolerance/diag", "chord/diag", "precision", "cell/diag"
  double value = 0;
  std::function<PolygonizeResult(const Field&)> run;
};

// What a step gave: ok = false when it threw or hit a bound.
struct Outcome {
  Step step;
  bool ok = false;
  std::string error;
  bool bound = false;  // a LimitExceededError
  std::size_t triangles = 0;
  double seconds = 0;     // the sweep's single run
  double phong = NAN, depth = NAN;
  double silhouette = NAN;  // AccuracyMetrics::silhouette_disagreement
  std::optional<double> median_seconds;  // when timed as a candidate
};

struct Choice {
  bool reached = false;
  Outcome outcome;
  double seconds = 0;  // median of kTimingRuns
  std::string why;     // when not reached
};

struct FieldSweep {
  std::unique_ptr<Field> field;
  std::map<std::string, std::vector<Outcome>> outcomes;  // by family
  std::map<std::string, Choice> choices;                 // by "<family>/<target>"
};

std::vector<Step> ladder(const Field& field, const std::string& family) {
  const double diag = field.bounds().diagonal();
  std::vector<Step> steps;
  if (family == "adaptive_factor") {
    // Triangles go as the factor squared: a doubling is sqrt(2) in the factor.
    for (int j = 0;; ++j) {
      const double k = std::pow(2.0, j / (2.0 * kRungsPerDoubling));
      if (k > kLastFactor) break;
      steps.push_back({"factor", k, [k](const Field& f) {
                         AdaptiveOptions o;
                         o.factor = k;
                         o.max_triangles = kMaxTriangles + kMaxTriangles / 4;
                         return polygonize_adaptive(f, o);
                       }});
    }
  } else if (family == "adaptive_tolerance" || family == "adaptive_chord") {
    // Triangles go as 1 / eps.
    const SizingMode mode = family == "adaptive_chord" ? SizingMode::Chord : SizingMode::Tolerance;
    for (int j = 0;; ++j) {
      const double t = kFirstTolerance * std::pow(2.0, -j / static_cast<double>(kRungsPerDoubling));
      if (t < kLastTolerance) break;
      steps.push_back({mode == SizingMode::Chord ? "chord/diag" : "tolerance/diag", t, [t, diag, mode](const Field& f) {
                         AdaptiveOptions o;
                         o.sizing = mode;
                         o.tolerance = t * diag;
                         o.max_triangles = kMaxTriangles + kMaxTriangles / 4;
                         return polygonize_adaptive(f, o);
                       }});
    }
  } else {
    const bool mc = family == "mc";
    auto run = [mc](const MarchingOptions& o) {
      return [mc, o](const Field& f) { return mc ? marching_cubes(f, o) : marching_tetrahedra(f, o); };
    };
    double finest = INFINITY;
    if (const auto spacing = field.constraint_spacing()) {
      for (int p = 0; p <= 5; ++p) {
        MarchingOptions o;
        o.precision = p;
        o.max_triangles = kMaxTriangles + kMaxTriangles / 4;
        steps.push_back({"precision", static_cast<double>(p), run(o)});
        finest = *spacing * precision_scale(p);
      }
    }
    // Triangles go as N squared.
    for (int k = 0; k <= 16 * kRungsPerDoubling; ++k) {
      const double n = 16 * std::pow(2.0, k / (2.0 * kRungsPerDoubling));
      if (diag / n >= finest * 0.999) continue;
      MarchingOptions o;
      o.cell_size = diag / n;
      o.max_triangles = kMaxTriangles + kMaxTriangles / 4;
      steps.push_back({"cell/diag", 1 / n, run(o)});
    }
  }
  return steps;
}

bool reaches(const Outcome& o, const std::string& target) {
  if (!o.ok) return false;
  return target == "phong" ? o.phong <= kPhongTargetDeg : o.depth <= kDepthTargetRelative;
}

std::string format_step(const Step& s) {
  char buf[64];
  if (s.param == "precision") std::snprintf(buf, sizeof buf, "P%g", s.value);
  else if (s.param == "factor") std::snprintf(buf, sizeof buf, "k=%.3g", s.value);
  else if (s.param == "tolerance/diag" || s.param == "chord/diag") std::snprintf(buf, sizeof buf, "eps=%.3g d", s.value);
  else std::snprintf(buf, sizeof buf, "h=d/%.0f", 1 / s.value);
  return buf;
}

double timed_median(const Field& field, const Step& step) {
  std::vector<double> t;
  for (int i = 0; i < kTimingRuns; ++i) {
    const PolygonizeResult r = step.run(field);
    benchmark::DoNotOptimize(r.mesh.positions.data());
    t.push_back(r.stats.seconds);
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

GroundTruth ground_truth(const std::string& name, const std::string& path, const Field& field) {
  CameraOptions camera;  // Table 1's evaluation, as build/bin/experiment passes it to evaluate
  camera.views = 6;
  camera.resolution = 200;
  camera.projection = Projection::Perspective;
  const RaycastOptions raycast;
  const std::string key = ground_truth_key(read_text(path), camera, raycast);
  const std::string dir = std::string(CDP_SOURCE_DIR) + "/results/cache";
  std::vector<Ray> rays = make_camera_rays(field.bounds(), camera);
  const std::size_t n = rays.size();
  bool cached = false;
  GroundTruth truth = cached_ground_truth(field, std::move(rays), raycast, dir, key, &cached, [&] {
    std::fprintf(stderr, "[time to accuracy] %s: computing the ground truth (%zu rays), saved as %s/gt_%s.bin\n",
                 name.c_str(), n, dir.c_str(), key.c_str());
  });
  if (cached)
    std::fprintf(stderr, "[time to accuracy] %s: ground truth from %s/gt_%s.bin\n", name.c_str(), dir.c_str(), key.c_str());
  return truth;
}

// Runs one step and measures it as evaluate does (phong and depth only).
Outcome measure(const Field& field, const GroundTruth& truth, const Step& step) {
  Outcome out;
  out.step = step;
  const auto start = std::chrono::steady_clock::now();
  try {
    PolygonizeResult r = step.run(field);
    out.seconds = r.stats.seconds;
    out.triangles = r.stats.triangles;
    if (r.mesh.triangles.empty()) throw NoSurfaceError("no triangles");
    if (r.mesh.normals.size() != r.mesh.positions.size()) r.mesh.normals = field_normals(field, r.mesh);
    const EmbreeScene scene(r.mesh);
    const AccuracyMetrics a = compute_accuracy(truth, scene.intersect(truth.rays), r.mesh);
    out.phong = a.phong_deg.mean;
    out.depth = a.depth_relative_mean;
    out.silhouette = a.silhouette_disagreement;
    out.ok = std::isfinite(out.phong) && std::isfinite(out.depth);
    if (!out.ok) out.error = "no measurement";
    // Phong and depth errors are means over the rays that hit both: a mesh that misses a part of
    // the surface (a coarse lattice losing a small component) is not more accurate for it.
    if (out.ok && !(out.silhouette <= kMaxSilhouette)) {
      out.ok = false;
      out.error = "silhouette disagreement " + std::to_string(out.silhouette) + " > " + std::to_string(kMaxSilhouette);
    }
  } catch (const std::exception& e) {
    out.bound = dynamic_cast<const LimitExceededError*>(&e) != nullptr;
    // The time a failed run took before it threw (wall clock), for the bound on slow runs.
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    out.error = e.what();
    if (out.error.size() > 60) out.error = out.error.substr(0, 57) + "...";
  }
  return out;
}

void print_sweep(const std::string& name, const FieldSweep& s) {
  std::fprintf(stderr, "\n[time to accuracy] %s: the sweep (single runs; * = chosen, median of %d runs)\n", name.c_str(),
               kTimingRuns);
  std::fprintf(stderr, "  %-19s %-12s %10s %10s %10s %11s %10s  %s\n", "family", "step", "triangles", "ms",
               "phong deg", "depth/diag", "silhouette", "chosen for");
  for (const char* fam : kFamilies) {
    for (const Outcome& o : s.outcomes.at(fam)) {
      std::string chosen;
      for (const char* t : kTargets) {
        const Choice& c = s.choices.at(std::string(fam) + "/" + t);
        if (c.reached && c.outcome.step.param == o.step.param && c.outcome.step.value == o.step.value) {
          char buf[64];
          std::snprintf(buf, sizeof buf, "*%s (%.1f ms) ", t, 1e3 * c.seconds);
          chosen += buf;
        }
      }
      if (o.ok)
        std::fprintf(stderr, "  %-19s %-12s %10zu %10.1f %10.3f %11.3g %10.4f  %s\n", fam, format_step(o.step).c_str(),
                     o.triangles, 1e3 * o.seconds, o.phong, o.depth, o.silhouette, chosen.c_str());
      else
        std::fprintf(stderr, "  %-19s %-12s %10zu %10.1f %10s %11s %10s  not counted: %s\n", fam,
                     format_step(o.step).c_str(), o.triangles, 1e3 * o.seconds, "-", "-", "-", o.error.c_str());
    }
  }
  std::fflush(stderr);
}

const FieldSweep& sweep(int field_index) {
  static std::map<int, FieldSweep> cache;
  if (auto it = cache.find(field_index); it != cache.end()) return it->second;
  const std::string name = kFields[field_index][0];
  const std::string path = std::string(CDP_SOURCE_DIR) + "/" + kFields[field_index][1];
  FieldSweep s;
  s.field = load_field(path);
  const Field& field = *s.field;
  const GroundTruth truth = ground_truth(name, path, field);
  const auto start = std::chrono::steady_clock::now();
  for (const char* fam : kFamilies) {
    std::vector<Outcome>& outs = s.outcomes[fam];
    bool phong = false, depth = false;
    int after = -1;  // steps still to run once both targets are reached
    std::string stop;
    for (const Step& step : ladder(field, fam)) {
      if (after == 0) break;
      outs.push_back(measure(field, truth, step));
      const Outcome& o = outs.back();
      std::fprintf(stderr, "[time to accuracy] %s %s %s: %s\n", name.c_str(), fam, format_step(step).c_str(),
                   o.ok ? (std::to_string(o.triangles) + " triangles, " + std::to_string(1e3 * o.seconds) +
                           " ms, phong " + std::to_string(o.phong) + " deg, depth " + std::to_string(o.depth))
                              .c_str()
                        : ("failed: " + o.error).c_str());
      phong = phong || reaches(o, "phong");
      depth = depth || reaches(o, "depth");
      if (after > 0) --after;
      else if (phong && depth) after = o.seconds > kMaxRunSeconds / 2 ? 0 : 1;  // the extra step only when cheap
      if (o.seconds > kMaxRunSeconds || o.triangles > kMaxTriangles || o.bound) {
        stop = "bound reached at " + format_step(step);
        break;
      }
    }
    // The candidates of each target, timed as medians; the fastest wins.
    for (const char* t : kTargets) {
      Choice c;
      double fastest = INFINITY;
      for (const Outcome& o : outs)
        if (reaches(o, t)) fastest = std::min(fastest, o.seconds);
      int first = 0;  // the first two steps reaching the target are candidates whatever their time
      for (Outcome& o : outs) {
        if (!reaches(o, t)) continue;
        if (++first > 2 && o.seconds > kCandidateSlack * fastest) continue;
        if (!o.median_seconds) o.median_seconds = timed_median(field, o.step);
        // Ladders grow in triangles, so a later step wins only when clearly faster: noise alone
        // should not switch the configuration a benchmark times from one run to the next.
        if (!c.reached || *o.median_seconds < kLaterStepMargin * c.seconds) {
          c.reached = true;
          c.outcome = o;
          c.seconds = *o.median_seconds;
        }
      }
      if (!c.reached)
        c.why = std::string(t) + " target not reached up to " +
                (outs.empty() ? std::string("nothing run") : format_step(outs.back().step)) +
                (stop.empty() ? "" : " (" + stop + ")");
      s.choices[std::string(fam) + "/" + t] = c;
    }
  }
  print_sweep(name, s);
  std::fprintf(stderr, "[time to accuracy] %s: sweep took %.0f s\n\n", name.c_str(),
               std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return cache.emplace(field_index, std::move(s)).first->second;
}

// Issue 14's goal for an adaptive run (at most half of MT's and of MC's time), as time per vertex:
// field_floor_ms prices the floor of field calls, one Hessian and two value-and-gradient calls a
// vertex, by single calls at the mesh's vertices (measure_field_cost, one thread: a VIS that
// splits its calls with a helper thread pays less); seed_grid_ms is the run's own seed grid
// (stats phases.seed_grid, at the resolution the seeding guarantee uses). What the run spends
// beyond both, per vertex, is overhead_us_per_vertex: the tracker's, the relaxation's and the
// checks' own work and their calls beyond the floor. budget_us_per_vertex is what that may
// cost for the run to take half of the faster of MT's and MC's time (goal_ms) at this triangle
// count; negative where the floor alone is over the goal. Both are wall-clock shares of a run
// on all cores, so a budget is what a serial tracker has per vertex.
void report_overhead(benchmark::State& state, const Field& field, const PolygonizeResult& run, double seconds,
                     const Choice& mt, const Choice& mc) {
  const double vertices = static_cast<double>(run.stats.vertices);
  if (!(vertices > 0) || !run.stats.adaptive) return;
  const FieldCost cost = measure_field_cost(field, run.mesh);
  const double floor = vertices * (cost.gradient_hessian_seconds + 2 * cost.value_gradient_seconds);
  const double grid = run.stats.adaptive->phase("seed_grid").seconds;
  state.counters["field_floor_ms"] = 1e3 * floor;
  state.counters["seed_grid_ms"] = 1e3 * grid;
  state.counters["overhead_us_per_vertex"] = 1e6 * (seconds - floor - grid) / vertices;
  if (mt.reached && mc.reached) {
    const double goal = 0.5 * std::min(mt.seconds, mc.seconds);
    state.counters["goal_ms"] = 1e3 * goal;
    state.counters["budget_us_per_vertex"] = 1e6 * (goal - floor - grid) / vertices;
  }
}

void BM_SlowTimeToAccuracy(benchmark::State& state, int field_index, std::string family, std::string target) {
  const FieldSweep& s = sweep(field_index);
  const Choice& c = s.choices.at(family + "/" + target);
  if (!c.reached) {
    state.SkipWithError(c.why.c_str());
    for (auto _ : state) {
    }
    return;
  }
  std::optional<PolygonizeResult> last;
  for (auto _ : state) {
    last = c.outcome.step.run(*s.field);
    benchmark::DoNotOptimize(last->mesh.positions.data());
    state.SetIterationTime(last->stats.seconds);
  }
  const Outcome& o = c.outcome;
  state.counters["triangles"] = static_cast<double>(o.triangles);
  state.counters[o.step.param == "tolerance/diag" ? "tolerance_per_diag"
                 : o.step.param == "chord/diag"   ? "chord_per_diag"
                 : o.step.param == "cell/diag"    ? "cell_per_diag"
                                                  : o.step.param] = o.step.value;
  state.counters["phong_deg"] = o.phong;
  state.counters["depth_relative"] = o.depth;
  state.counters["sweep_median_ms"] = 1e3 * c.seconds;
  if (family.rfind("adaptive", 0) == 0) {
    for (const char* m : {"mt", "mc"}) {
      const Choice& other = s.choices.at(std::string(m) + "/" + target);
      if (other.reached && other.seconds > 0) state.counters[std::string("vs_") + m] = c.seconds / other.seconds;
    }
    if (last) report_overhead(state, *s.field, *last, c.seconds, s.choices.at("mt/" + target), s.choices.at("mc/" + target));
  }
  std::string label = format_step(o.step);  // no '/': the dashboard reads "<field>/<method>" labels
  std::replace(label.begin(), label.end(), '/', ':');
  state.SetLabel(label);
}

}  // namespace

int main(int argc, char** argv) {
  for (int f = 0; f < 4; ++f)
    for (const char* fam : kFamilies)
      for (const char* t : kTargets)
        benchmark::RegisterBenchmark(
            (std::string("BM_SlowTimeToAccuracy/") + kFields[f][0] + "/" + fam + "/" + t).c_str(),
            [f, fam = std::string(fam), t = std::string(t)](benchmark::State& st) {
              BM_SlowTimeToAccuracy(st, f, fam, t);
            })
            ->UseManualTime()
            ->Iterations(1)
            ->Unit(benchmark::kMillisecond);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
