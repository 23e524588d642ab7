// The adaptive polygonizer: torus and tanglecube at several factors, the bunny VIS-800 of the
// paper's Table 1 beside Marching Tetrahedra and Marching Cubes at the paper's precision, and a
// scaling series from 10^4 to 10^6 triangles on the torus, where bookkeeping that grows faster
// than linearly would show as a rising time per triangle; and two CSG shapes meshed along their
// creases. Times are the polygonizers' own
// stats.seconds (manual time), as in STATS.json.
#include <cdp/baselines/marching_cubes.h>
#include <cdp/baselines/marching_tetrahedra.h>
#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/block_tasks.h>
#include <cdp/core/models/analytic.h>
#include <cdp/core/models/expression.h>
#include <cdp/core/mesh_topology.h>
#include <cdp/core/surface_seeds.h>
#include <cdp/core/triangle_intersection.h>
#include <cdp/io/field_factory.h>
#include <cdp/raytrace/field_cost.h>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <map>
#include <memory>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include <spawn.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;  // POSIX: declared by no header without _GNU_SOURCE

namespace {

using namespace cdp;

enum Shape { kTorus, kTanglecube };

std::unique_ptr<Field> make_shape(Shape shape) {
  if (shape == kTorus) return std::make_unique<Torus>(Vec3(0.01, 0.02, -0.015), 1.0, 0.4);
  return std::make_unique<Expression>("x^4 - 5*x^2 + y^4 - 5*y^2 + z^4 - 5*z^2 + 11.8",
                                      std::map<std::string, double>{}, Box{{-3, -3, -3}, {3, 3, 3}});
}

// Counters common to every polygonizer benchmark here. "tracking" evaluations leave out the
// fixed cost of the seed grid, which small meshes do not amortize.
void report(benchmark::State& state, double triangles, double vertices, double evaluations, double seed_evaluations) {
  state.counters["triangles_per_second"] = benchmark::Counter(triangles, benchmark::Counter::kIsRate);
  state.counters["triangles"] = triangles / static_cast<double>(state.iterations());
  state.counters["evals_per_vertex"] = evaluations / vertices;
  state.counters["evaluations_per_triangle"] = evaluations / triangles;
  if (seed_evaluations >= 0) state.counters["tracking_evals_per_vertex"] = (evaluations - seed_evaluations) / vertices;
}

// Value evaluations of the sign-change grid that seeds every component, measured.
double seed_grid_evaluations(const Field& field, int resolution) {
  SeedOptions o;
  o.resolution = resolution;
  const EvaluationCounts before = field.counts();
  find_surface_crossings(field, o);
  return static_cast<double>((field.counts() - before).total());
}

// Returns the total polygonization time.
double run_adaptive(benchmark::State& state, const Field& field, const AdaptiveOptions& options) {
  double triangles = 0, vertices = 0, evaluations = 0, seeds = 0, seconds = 0, grid_seconds = 0;
  const double seed_cost = seed_grid_evaluations(field, options.seed_resolution);
  for (auto _ : state) {
    const PolygonizeResult r = polygonize_adaptive(field, options);
    triangles += static_cast<double>(r.stats.triangles);
    vertices += static_cast<double>(r.stats.vertices);
    evaluations += static_cast<double>(r.stats.field_evaluations.total());
    seeds += seed_cost;
    benchmark::DoNotOptimize(r.mesh.positions.data());
    state.SetIterationTime(r.stats.seconds);
    seconds += r.stats.seconds;
    grid_seconds += r.stats.adaptive->seed_grid_seconds;
  }
  report(state, triangles, vertices, evaluations, seeds);
  // The share of the time spent before the first triangle: the seed grid (issue 14: at most 5%
  // on the bunny at factor 3).
  state.counters["seed_grid_share"] = grid_seconds / seconds;
  return seconds / triangles;
}

void BM_Adaptive(benchmark::State& state) {
  const auto shape = static_cast<Shape>(state.range(0));
  const double factor = static_cast<double>(state.range(1));
  const auto field = make_shape(shape);
  AdaptiveOptions o;
  o.factor = factor;
  run_adaptive(state, *field, o);
  state.SetLabel(std::string(shape == kTorus ? "torus" : "tanglecube") + "/adaptive/factor" +
                 std::to_string(state.range(1)));
}
BENCHMARK(BM_Adaptive)
    ->ArgNames({"shape", "factor"})
    ->ArgsProduct({{kTorus, kTanglecube}, {2, 3, 5}})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

// CSG shapes meshed along their creases (AdaptiveOptions::creases, crease_patches.h): the
// tracing, the layout and one tracker per piece against the plain tracker. The capped cylinder
// both ways (the ratio is the crease handling's cost there); the box minus a ball only along its
// creases (across them it stalls at its holes' acute rims).
void BM_AdaptiveCreases(benchmark::State& state) {
  const bool box = state.range(0) == 1;
  const bool follow = state.range(1) == 1;
  const Expression field(box ? "max(max(abs(x),max(abs(y),abs(z)))-1, 1.2-sqrt(x^2+y^2+z^2))"
                             : "max(sqrt(x^2+y^2)-1, abs(z)-1)",
                         {}, Box{Vec3::Constant(-1.5137), Vec3::Constant(1.5)});
  AdaptiveOptions o;
  o.sizing = SizingMode::Tolerance;
  o.tolerance = 1e-3;
  o.creases = follow ? CreaseHandling::Follow : CreaseHandling::Ignore;
  run_adaptive(state, field, o);
  state.SetLabel(std::string(box ? "box_minus_ball" : "capped_cylinder") + "/adaptive/creases_" +
                 (follow ? "follow" : "ignore"));
}
BENCHMARK(BM_AdaptiveCreases)
    ->ArgNames({"shape", "follow"})
    ->Args({0, 0})
    ->Args({0, 1})
    ->Args({1, 1})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

// Time per triangle from 10^4 to 10^6 triangles: the factor grows so that the triangle count
// (about proportional to factor^2) grows tenfold per step; clamps out of the way.
void BM_AdaptiveScaling(benchmark::State& state) {
  const auto field = make_shape(kTorus);
  AdaptiveOptions o;
  o.factor = static_cast<double>(state.range(0)) / 10;
  o.min_edge = 1e-5;
  state.counters["ns_per_triangle"] = 1e9 * run_adaptive(state, *field, o);
  state.SetLabel("torus/adaptive/scaling");
}
// Factors 6.3, 20, 63 give about 10^4, 10^5, 10^6 triangles on this torus.
BENCHMARK(BM_AdaptiveScaling)->ArgName("factor_x10")->Arg(63)->Arg(200)->Arg(630)->UseManualTime()->Unit(benchmark::kMillisecond);

// The torus of experiments/fields/torus.json (the field files' torus, not make_shape's), built once.
const Field& torus_field() {
  static const std::unique_ptr<Field> torus = load_field(std::string(CDP_SOURCE_DIR) + "/experiments/fields/torus.json");
  return *torus;
}

// Table 1 at the paper's middle setting: bunny VIS-800, adaptive factor 3 against MT and MC at
// precision 3 (comparable triangle counts). The model is built once.
const Field& bunny() {
  static const std::unique_ptr<Field> field =
      load_field(std::string(CDP_SOURCE_DIR) + "/experiments/fields/bunny_vis800.json");
  return *field;
}

void BM_PaperBunny(benchmark::State& state) {
  const int method = static_cast<int>(state.range(0));  // 0 adaptive, 1 mt, 2 mc
  const Field& field = bunny();
  if (method == 0) {
    AdaptiveOptions o;
    o.factor = 3;
    run_adaptive(state, field, o);
  } else {
    MarchingOptions o;
    o.precision = 3;
    double triangles = 0, vertices = 0, evaluations = 0;
    for (auto _ : state) {
      const PolygonizeResult r = method == 1 ? marching_tetrahedra(field, o) : marching_cubes(field, o);
      triangles += static_cast<double>(r.stats.triangles);
      vertices += static_cast<double>(r.stats.vertices);
      evaluations += static_cast<double>(r.stats.field_evaluations.total());
      benchmark::DoNotOptimize(r.mesh.positions.data());
      state.SetIterationTime(r.stats.seconds);
    }
    report(state, triangles, vertices, evaluations, -1);
  }
  state.SetLabel(std::string("bunny_vis800/") + (method == 0 ? "adaptive" : method == 1 ? "mt" : "mc"));
}
BENCHMARK(BM_PaperBunny)->ArgName("method")->DenseRange(0, 2)->UseManualTime()->Unit(benchmark::kMillisecond);

// Shape 0: the torus (made into `holder`), 1: the bunny VIS-800 (built once).
const Field& torus_or_bunny(int shape, std::unique_ptr<Field>& holder) {
  if (shape != 0) return bunny();
  holder = make_shape(kTorus);
  return *holder;
}

// Tolerance mode's field evaluations a vertex, by kind (issue 57: at most one Hessian and 2.5
// values and gradients a vertex in tracking, repair and checks together), and its time a
// triangle: the torus at 1e-4 (a cheap field: its estimates are measured) and the bunny VIS-800 at
// 3e-4 (a costly one: its estimates are predicted from the vertices' Hessians, repair_context.h).
void BM_ToleranceEvaluations(benchmark::State& state) {
  const int shape = static_cast<int>(state.range(0));  // 0 torus, 1 bunny VIS-800
  std::unique_ptr<Field> torus;
  const Field& field = torus_or_bunny(shape, torus);
  AdaptiveOptions o;
  o.sizing = SizingMode::Tolerance;
  o.tolerance = shape == 0 ? 1e-4 : 3e-4;
  o.threads = 1;
  double vertices = 0, value_gradient = 0, gradient_hessian = 0, triangles = 0, seconds = 0;
  for (auto _ : state) {
    const PolygonizeResult r = polygonize_adaptive(field, o);
    vertices += static_cast<double>(r.stats.vertices);
    value_gradient += static_cast<double>(r.stats.field_evaluations.value_gradient);
    gradient_hessian += static_cast<double>(r.stats.field_evaluations.gradient_hessian);
    triangles += static_cast<double>(r.stats.triangles);
    seconds += r.stats.seconds;
    state.SetIterationTime(r.stats.seconds);
  }
  state.counters["triangles"] = triangles / static_cast<double>(state.iterations());
  state.counters["ns_per_triangle"] = 1e9 * seconds / triangles;
  state.counters["value_gradient_per_vertex"] = value_gradient / vertices;
  state.counters["gradient_hessian_per_vertex"] = gradient_hessian / vertices;
  state.SetLabel(std::string(shape == 0 ? "torus" : "bunny_vis800") + "/adaptive_tolerance");
}
BENCHMARK(BM_ToleranceEvaluations)->ArgName("shape")->DenseRange(0, 1)->UseManualTime()->Unit(benchmark::kMillisecond);

// Tolerance mode against factor mode at about the same triangle count, one thread, the two in
// turn in every iteration (issue 57: tolerance mode at most 1.3 times factor mode's time a
// triangle). Shapes: 0 the torus of experiments/fields/torus.json at 1e-4 against factor 27
// (1.86 and 1.73 * 10^5 triangles), 1 the random blobs at 1e-3 against factor 11 (20,352 and
// 19,932). BM_ToleranceVsFactorSlow: the torus at 1e-5 against factor 88 with min_edge 4e-4
// (1.85 and 1.84 * 10^6 triangles, the size: the default min_edge, 2e-3 of the diagonal,
// stops factor 88 at 5.4 * 10^5; tolerance 1e-5 reaches 4.1e-4), about 20 s an iteration, not in
// bench-short. Counters:
// tolerance_vs_factor (the ratio of their times a triangle), each one's microseconds a
// triangle and triangles. Manual time: tolerance mode's.
void measure_tolerance_vs_factor(benchmark::State& state, const Field& field, double tolerance, double factor,
                                 double min_edge = 0) {
  AdaptiveOptions by_tolerance;
  by_tolerance.sizing = SizingMode::Tolerance;
  by_tolerance.tolerance = tolerance;
  by_tolerance.threads = 1;
  AdaptiveOptions by_factor;
  by_factor.factor = factor;
  by_factor.min_edge = min_edge;
  by_factor.threads = 1;
  std::array<double, 2> seconds{}, triangles{};
  for (auto _ : state) {
    for (int k = 0; k < 2; ++k) {
      const PolygonizeResult r = polygonize_adaptive(field, k == 0 ? by_tolerance : by_factor);
      seconds[k] += r.stats.seconds;
      triangles[k] += static_cast<double>(r.stats.triangles);
      if (k == 0) state.SetIterationTime(r.stats.seconds);
    }
  }
  const auto us_per_triangle = [&](int k) { return 1e6 * seconds[k] / triangles[k]; };
  const auto n = static_cast<double>(state.iterations());
  state.counters["tolerance_us_per_triangle"] = us_per_triangle(0);
  state.counters["factor_us_per_triangle"] = us_per_triangle(1);
  state.counters["tolerance_vs_factor"] = us_per_triangle(0) / us_per_triangle(1);
  state.counters["tolerance_triangles"] = triangles[0] / n;
  state.counters["factor_triangles"] = triangles[1] / n;
}

void BM_ToleranceVsFactor(benchmark::State& state) {
  const int shape = static_cast<int>(state.range(0));
  static const std::unique_ptr<Field> blobs = load_field(std::string(CDP_SOURCE_DIR) + "/experiments/fields/random_blobs.json");
  if (shape == 0) measure_tolerance_vs_factor(state, torus_field(), 1e-4, 27);
  else measure_tolerance_vs_factor(state, *blobs, 1e-3, 11);
  state.SetLabel(shape == 0 ? "torus/tol1e-4_vs_factor27/threads1" : "random_blobs/tol1e-3_vs_factor11/threads1");
}
BENCHMARK(BM_ToleranceVsFactor)->ArgName("shape")->DenseRange(0, 1)->UseManualTime()->Unit(benchmark::kMillisecond);

void BM_ToleranceVsFactorSlow(benchmark::State& state) {
  measure_tolerance_vs_factor(state, torus_field(), 1e-5, 88, 4e-4);
  state.SetLabel("torus/tol1e-5_vs_factor88/threads1");
}
BENCHMARK(BM_ToleranceVsFactorSlow)->Iterations(1)->UseManualTime()->Unit(benchmark::kMillisecond);

// The paper's algorithm as printed (Variant::Paper: no grading, repair, relaxation or tolerance
// refinement), with the robustness of the tracker and the seeding and the final
// self-intersection check: the torus at the factors of BM_Adaptive and the bunny VIS-800 at
// factor 3. What the robustness costs, apart from the quality additions BM_Adaptive includes.
void BM_AdaptivePaperVariant(benchmark::State& state) {
  const int shape = static_cast<int>(state.range(0));  // 0 torus, 1 bunny VIS-800
  std::unique_ptr<Field> torus;
  const Field& field = torus_or_bunny(shape, torus);
  AdaptiveOptions o;
  o.factor = static_cast<double>(state.range(1));
  o.variant = Variant::Paper;
  run_adaptive(state, field, o);
  state.SetLabel(std::string(shape == 0 ? "torus" : "bunny_vis800") + "/adaptive_paper/factor" +
                 std::to_string(state.range(1)));
}
BENCHMARK(BM_AdaptivePaperVariant)
    ->ArgNames({"shape", "factor"})
    ->Args({0, 2})
    ->Args({0, 3})
    ->Args({0, 5})
    ->Args({1, 3})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

// Speed per core: the torus of experiments/fields/torus.json on one thread, meshed at factor 40
// by the adaptive method (the default, then Variant::Paper) and by marching cubes at cell 0.004
// (about seven times the triangles), the three in turn in every iteration so that their ratios
// come from the same moments of a shared machine. Counters: the default's triangles per second
// over marching cubes' (aim: at least 1), the default's time over the paper variant's (aim: at
// most 1.2), and each one's microseconds a triangle. Manual time: the default's. About 9 s an
// iteration, so not in bench-short.
void BM_SpeedPerCoreSlow(benchmark::State& state) {
  const Field& torus = torus_field();
  AdaptiveOptions improved;
  improved.factor = 40;
  improved.threads = 1;
  AdaptiveOptions paper = improved;
  paper.variant = Variant::Paper;
  MarchingOptions mc;
  mc.cell_size = 0.004;
  mc.threads = 1;
  std::array<double, 3> seconds{}, triangles{};
  for (auto _ : state) {
    for (int k = 0; k < 3; ++k) {
      const PolygonizeResult r =
          k == 2 ? marching_cubes(torus, mc) : polygonize_adaptive(torus, k == 0 ? improved : paper);
      seconds[k] += r.stats.seconds;
      triangles[k] += static_cast<double>(r.stats.triangles);
      if (k == 0) state.SetIterationTime(r.stats.seconds);
    }
  }
  const auto us_per_triangle = [&](int k) { return 1e6 * seconds[k] / triangles[k]; };
  state.counters["default_us_per_triangle"] = us_per_triangle(0);
  state.counters["paper_us_per_triangle"] = us_per_triangle(1);
  state.counters["mc_us_per_triangle"] = us_per_triangle(2);
  state.counters["triangle_rate_vs_mc"] = us_per_triangle(2) / us_per_triangle(0);
  state.counters["time_vs_paper"] = seconds[0] / seconds[1];
  state.SetLabel("torus/adaptive_vs_mc/factor40_cell0.004/threads1");
}
BENCHMARK(BM_SpeedPerCoreSlow)->UseManualTime()->Unit(benchmark::kMillisecond);

// The adaptive polygonizer's own time outside the field (issue 14's "bookkeeping"): the run's
// time less its evaluation counts priced by measure_field_cost at the mesh's vertices (single
// calls, the fastest of three passes). The manual time is that remainder, so the dashboard
// tracks it and flags its regressions like any time; us_per_vertex divides it by the vertices,
// and PHASE_us_per_vertex is the same for each phase of the run's stats "phases"
// (kAdaptivePhases; the profile of where the bookkeeping goes). Each phase's remainder is
// clamped at 0 like the whole's, so they need not add up to us_per_vertex exactly: the seed
// grid's batched values cost less than single calls, and its remainder comes out about 0.
// An estimate: the tracker batches some of its calls, which may cost less than single ones.
void BM_AdaptiveBookkeeping(benchmark::State& state) {
  const int shape = static_cast<int>(state.range(0));  // 0 torus, 1 bunny VIS-800
  std::unique_ptr<Field> torus;
  const Field& field = torus_or_bunny(shape, torus);
  AdaptiveOptions o;
  o.factor = shape == 0 ? 6.3 : 3;  // about 10^4 triangles on both
  // On one thread: evaluations shared among threads (the seed grid, the relaxation's
  // projections) take less time than their count priced one by one, which would hide
  // bookkeeping in the estimate.
  o.threads = 1;
  const FieldCost cost = measure_field_cost(field, polygonize_adaptive(field, o).mesh);
  double vertices = 0, bookkeeping = 0, field_seconds = 0;
  const auto priced = [&](double value, double value_gradient, double gradient_hessian) {
    return value * cost.value_seconds + value_gradient * cost.value_gradient_seconds +
           gradient_hessian * cost.gradient_hessian_seconds;
  };
  std::array<double, kAdaptivePhases.size()> phase_outside{};
  for (auto _ : state) {
    const PolygonizeResult r = polygonize_adaptive(field, o);
    const EvaluationCounts& c = r.stats.field_evaluations;
    const double in_field = priced(static_cast<double>(c.value), static_cast<double>(c.value_gradient),
                                   static_cast<double>(c.gradient_hessian));
    const double outside = std::max(0.0, r.stats.seconds - in_field);
    for (std::size_t i = 0; i < kAdaptivePhases.size(); ++i) {
      const EvaluationCounts& n = r.stats.adaptive->phases[i].evaluations;
      const auto d = [](std::uint64_t x) { return static_cast<double>(x); };
      phase_outside[i] += std::max(0.0, r.stats.adaptive->phases[i].seconds -
                                            priced(d(n.value), d(n.value_gradient), d(n.gradient_hessian)));
    }
    state.SetIterationTime(outside);
    vertices += static_cast<double>(r.stats.vertices);
    bookkeeping += outside;
    field_seconds += in_field;
  }
  state.counters["us_per_vertex"] = 1e6 * bookkeeping / vertices;
  state.counters["field_us_per_vertex"] = 1e6 * field_seconds / vertices;
  for (std::size_t i = 0; i < kAdaptivePhases.size(); ++i)
    state.counters[std::string(kAdaptivePhases[i]) + "_us_per_vertex"] = 1e6 * phase_outside[i] / vertices;
  state.SetLabel(shape == 0 ? "torus/adaptive/bookkeeping" : "bunny_vis800/adaptive/bookkeeping");
}
BENCHMARK(BM_AdaptiveBookkeeping)->ArgName("shape")->DenseRange(0, 1)->UseManualTime()->Unit(benchmark::kMillisecond);

// Issue 14's "all cores": each iteration meshes the field on one thread and on two
// (AdaptiveOptions::threads: the seed grid, the relaxation's targets, projections and
// intersection tests, the final checks share them, and the tracking splits the evaluations of a
// large VIS with a helper thread) and requires the two meshes to be the same bit for bit; it
// reports both times and their ratio, speedup_1_to_2. The manual time is the two-thread run's.
// Tanglecube (a cheap field: the serial tracking dominates), the bunny VIS-800 (a dear one,
// too small to split) and the Igea VIS-4004 (which splits), at factor 3, and the gyroid clipped by
// a ball of the hard-surface suite at factor 3 (issue 58's surface with creases: meshed along
// them, not in blocks: its two groups of patches meshed and repaired side by side), and
// fogleman/sdf's README model at tolerance 1e-4 (about 85,000 triangles in ten groups of
// patches). On a machine with one core the second run has nothing to share and the ratio is
// about 1.
const Field& igea() {
  static const std::unique_ptr<Field> field =
      load_field(std::string(CDP_SOURCE_DIR) + "/experiments/fields/igea_vis4004.json");
  return *field;
}

void BM_AdaptiveThreads(benchmark::State& state) {
  // 0 tanglecube, 1 bunny VIS-800, 2 Igea VIS-4004, 3 the gyroid ball, 4 fogleman/sdf's README model
  const int shape = static_cast<int>(state.range(0));
  std::unique_ptr<Field> own;
  if (shape == 0) own = make_shape(kTanglecube);
  if (shape == 3)
    own = std::make_unique<Expression>("max(sin(4*x)*cos(4*y)+sin(4*y)*cos(4*z)+sin(4*z)*cos(4*x), x^2+y^2+z^2-4)",
                                       std::map<std::string, double>{}, Box{{-2.2, -2.2, -2.2}, {2.2, 2.2, 2.2}});
  if (shape == 4)
    own = std::make_unique<Expression>(
        "max(max(sqrt(x^2+y^2+z^2)-1, max(max(abs(x),abs(y)),abs(z))-0.75), "
        "-min(min(sqrt(y^2+z^2)-0.5, sqrt(x^2+z^2)-0.5), sqrt(x^2+y^2)-0.5))",
        std::map<std::string, double>{}, Box{{-1.2, -1.2, -1.2}, {1.2, 1.2, 1.2}});
  const Field& field = shape == 1 ? bunny() : shape == 2 ? igea() : *own;
  AdaptiveOptions o;
  o.factor = 3;
  if (shape == 4) o.sizing = SizingMode::Tolerance, o.tolerance = 1e-4;
  double one = 0, two = 0;
  for (auto _ : state) {
    o.threads = 1;
    const PolygonizeResult r1 = polygonize_adaptive(field, o);
    o.threads = 2;
    const PolygonizeResult r2 = polygonize_adaptive(field, o);
    if (r1.mesh.positions != r2.mesh.positions || r1.mesh.normals != r2.mesh.normals ||
        r1.mesh.triangles != r2.mesh.triangles) {
      state.SkipWithError("the meshes on one and two threads differ");
      return;
    }
    state.SetIterationTime(r2.stats.seconds);
    one += r1.stats.seconds;
    two += r2.stats.seconds;
  }
  const auto n = static_cast<double>(state.iterations());
  state.counters["seconds_1_thread"] = one / n;
  state.counters["seconds_2_threads"] = two / n;
  state.counters["speedup_1_to_2"] = one / two;
  state.SetLabel(shape == 0   ? "tanglecube/adaptive/threads"
                 : shape == 1 ? "bunny_vis800/adaptive/threads"
                 : shape == 2 ? "igea_vis4004/adaptive/threads"
                 : shape == 3 ? "gyroid_ball/adaptive/threads"
                              : "fogleman_readme_tol1e-4/adaptive/threads");
}
BENCHMARK(BM_AdaptiveThreads)->ArgName("shape")->DenseRange(0, 4)->UseManualTime()->Unit(benchmark::kMillisecond);

// Issue 58's blocks (AdaptiveOptions::blocks): each iteration meshes the field by tracking alone
// on one thread, then with blocks on one thread and on two, in turn, and requires the two block
// meshes to be the same bit for bit. Counters: speedup_1_to_2 (blocks, one thread over two; aim
// 1.8), blocks_over_serial (blocks on one thread over tracking alone; aim at most 1.1),
// cpu_2_over_1 (process CPU time per triangle, two threads over one; aim at most 1.15), and the
// speedups the measured block times project at 8 and 16 threads: the one-thread run's time
// outside its blocks taken as serial (the parallel passes' share of it counted as serial too),
// plus the blocks scheduled greedily, longest first, onto that many threads (aim 6 and 10 on the
// torus at 2 * 10^6 triangles and the bunny at factor 5). projected_speedup_8_passes and _16_passes
// take the run's data-parallel passes outside the blocks (BlocksReport::pass_seconds: the seed
// grid, the cut planes, the final checks, ...) as Amdahl's law fitted to what they measured from
// one thread to two in the same iteration (pass_speedup_1_to_2 = s: a share f = 2 (1 - 1/s) of
// their time divides among the threads, the rest does not), and the rest of the time outside the
// blocks as serial. Shapes: 0 the torus of
// experiments/fields/torus.json at factor 40 (4 * 10^5 triangles), 1 tanglecube at factor 12,
// 2 the bunny VIS-800 at factor 5, 3 the random blobs at tolerance 1e-3, 4 the bunny VIS-800 at
// factor 3. BM_AdaptiveBlocksLargeSlow: the same torus at tolerance 1e-5 (about 1.9 * 10^6
// triangles, issue 58's large run; about 30 s an iteration, not in bench-short).
double greedy_makespan(std::vector<double> times, int threads) {
  std::sort(times.rbegin(), times.rend());
  std::vector<double> load(static_cast<std::size_t>(threads), 0.0);
  for (const double t : times) *std::min_element(load.begin(), load.end()) += t;
  return *std::max_element(load.begin(), load.end());
}

double cpu_seconds() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

// The measures above of `field` meshed with `serial` (tracking alone on one thread), then in
// blocks on one thread and on two.
void measure_blocks(benchmark::State& state, const Field& field, const AdaptiveOptions& serial) {
  AdaptiveOptions blocks1 = serial;
  blocks1.blocks = true;
  AdaptiveOptions blocks2 = blocks1;
  blocks2.threads = 2;
  double t_serial = 0, t1 = 0, t2 = 0, cpu1 = 0, cpu2 = 0, p8 = 0, p16 = 0, q8 = 0, q16 = 0, passes1 = 0, passes2 = 0,
         triangles = 0, nblocks = 0;
  for (auto _ : state) {
    const PolygonizeResult rs = polygonize_adaptive(field, serial);
    double c0 = cpu_seconds();
    const PolygonizeResult r1 = polygonize_adaptive(field, blocks1);
    cpu1 += cpu_seconds() - c0;
    c0 = cpu_seconds();
    const PolygonizeResult r2 = polygonize_adaptive(field, blocks2);
    cpu2 += cpu_seconds() - c0;
    const BlocksReport& b = r1.stats.adaptive->blocks;
    if (!b.used) {
      state.SkipWithError(("no blocks: " + b.fallback).c_str());
      return;
    }
    if (r1.mesh.positions != r2.mesh.positions || r1.mesh.triangles != r2.mesh.triangles) {
      state.SkipWithError("the block meshes on one and two threads differ");
      return;
    }
    state.SetIterationTime(r2.stats.seconds);
    t_serial += rs.stats.seconds;
    t1 += r1.stats.seconds;
    t2 += r2.stats.seconds;
    double in_blocks = 0;
    for (const double t : b.block_seconds) in_blocks += t;
    const double outside = r1.stats.seconds - in_blocks;
    p8 += r1.stats.seconds / (outside + greedy_makespan(b.block_seconds, 8));
    p16 += r1.stats.seconds / (outside + greedy_makespan(b.block_seconds, 16));
    // The passes as fitted from one thread to two, the rest outside the blocks serial.
    const auto sum = [](const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0); };
    const double one = sum(b.pass_seconds), two = sum(r2.stats.adaptive->blocks.pass_seconds);
    const double shared = two > 0 ? std::clamp(2 * (1 - two / one), 0.0, 1.0) : 0.0;
    const auto in_passes = [&](double threads) { return one * ((1 - shared) + shared / threads); };
    const double serial_outside = std::max(0.0, outside - one);
    q8 += r1.stats.seconds / (serial_outside + in_passes(8) + greedy_makespan(b.block_seconds, 8));
    q16 += r1.stats.seconds / (serial_outside + in_passes(16) + greedy_makespan(b.block_seconds, 16));
    passes1 += one;
    passes2 += two;
    triangles = static_cast<double>(r1.stats.triangles);
    nblocks = static_cast<double>(b.meshed_blocks);
  }
  const auto n = static_cast<double>(state.iterations());
  state.counters["seconds_serial"] = t_serial / n;
  state.counters["seconds_1_thread"] = t1 / n;  // with blocks, as the dashboard's table of speedups reads them
  state.counters["seconds_2_threads"] = t2 / n;
  state.counters["speedup_1_to_2"] = t1 / t2;
  state.counters["blocks_over_serial"] = t1 / t_serial;
  state.counters["cpu_2_over_1"] = cpu2 / cpu1;
  state.counters["projected_speedup_8"] = p8 / n;
  state.counters["projected_speedup_16"] = p16 / n;
  state.counters["projected_speedup_8_passes"] = q8 / n;
  state.counters["projected_speedup_16_passes"] = q16 / n;
  state.counters["pass_seconds_1_thread"] = passes1 / n;
  state.counters["pass_speedup_1_to_2"] = passes2 > 0 ? passes1 / passes2 : 0.0;
  state.counters["triangles"] = triangles;
  state.counters["meshed_blocks"] = nblocks;
}

void BM_AdaptiveBlocks(benchmark::State& state) {
  const int shape = static_cast<int>(state.range(0));
  static const std::unique_ptr<Field> tangle = load_field(std::string(CDP_SOURCE_DIR) + "/experiments/fields/tanglecube.json");
  static const std::unique_ptr<Field> blobs = load_field(std::string(CDP_SOURCE_DIR) + "/experiments/fields/random_blobs.json");
  const Field& field = shape == 0 ? torus_field() : shape == 1 ? *tangle : shape == 3 ? *blobs : bunny();
  AdaptiveOptions serial;
  serial.threads = 1;
  serial.blocks = false;
  if (shape == 3) serial.sizing = SizingMode::Tolerance, serial.tolerance = 1e-3;
  else serial.factor = shape == 0 ? 40 : shape == 1 ? 12 : shape == 2 ? 5 : 3;
  measure_blocks(state, field, serial);
  state.SetLabel(shape == 0   ? "torus_f40/adaptive/blocks"
                 : shape == 1 ? "tanglecube_f12/adaptive/blocks"
                 : shape == 2 ? "bunny_vis800_f5/adaptive/blocks"
                 : shape == 3 ? "random_blobs_tol1e-3/adaptive/blocks"
                              : "bunny_vis800_f3/adaptive/blocks");
}
BENCHMARK(BM_AdaptiveBlocks)->ArgName("shape")->DenseRange(0, 4)->UseManualTime()->Unit(benchmark::kMillisecond);

void BM_AdaptiveBlocksLargeSlow(benchmark::State& state) {
  AdaptiveOptions serial;
  serial.threads = 1;
  serial.blocks = false;
  serial.sizing = SizingMode::Tolerance;
  serial.tolerance = 1e-5;
  measure_blocks(state, torus_field(), serial);
  state.SetLabel("torus_tol1e-5/adaptive/blocks");
}
BENCHMARK(BM_AdaptiveBlocksLargeSlow)->Iterations(1)->UseManualTime()->Unit(benchmark::kMillisecond);

// Issue 60's scale on paper: the blocks of a run handed to a cluster (AdaptiveOptions::block_runner,
// python/cdp/distributed.py), projected to a run of 10^9 triangles on 64 workers from what one
// run measures here. Each iteration meshes the torus of experiments/fields/torus.json at factor 40
// (4 * 10^5 triangles, 112 blocks) on one thread with a runner that runs every task from its bytes
// (run_block_task: the workers' whole work, their bytes' reading and writing included), timing
// each, and requires the mesh of the run without a runner. Measured: the client's time outside the
// tasks (layout, assembly, the band's repair, the seeding, the checks), the tasks' times, and the
// bytes of tasks and pieces. Projected to kClusterTriangles on kClusterWorkers:
//   blocks: the blocks grow to kClusterBlocks (16^3, blocks.cpp's largest layout), each the
//     measured blocks' times cycled and scaled by the triangles per block, scheduled greedily
//     onto the workers; largest_block: the largest of those (no run ends before it);
//   client: the time outside the tasks per triangle times 10^9 (taken as linear: the layout grows
//     more slowly, the assembly and checks linearly), plus kDaskTaskSeconds per task (Dask's
//     documented scheduler overhead, about a millisecond a task);
//   transfer: the pieces' bytes per triangle times 10^9 over kClientBytesPerSecond (every piece
//     ends at the client);
//   projected_seconds: client + max(blocks, transfer) (the pieces arrive while blocks run);
//   client_mesh_gb: the assembled mesh the client holds (positions, normals, triangles) at 10^9
//     triangles, the least memory it needs without streaming (issue 58's item 5).
constexpr double kClusterTriangles = 1e9;
constexpr int kClusterWorkers = 64;
constexpr int kClusterBlocks = 16 * 16 * 16;
constexpr double kDaskTaskSeconds = 1e-3;
constexpr double kClientBytesPerSecond = 1.25e9;  // 10 Gb/s Ethernet

void BM_BlocksClusterProjectionSlow(benchmark::State& state) {
  const Field& torus = torus_field();
  AdaptiveOptions o;
  o.factor = 40;
  o.threads = 1;
  o.blocks = true;
  const PolygonizeResult local = polygonize_adaptive(torus, o);
  std::vector<double> task_seconds;
  o.block_runner = [&](const std::vector<std::string>& tasks) {
    std::vector<std::string> pieces;
    for (const std::string& t : tasks) {
      const auto t0 = std::chrono::steady_clock::now();
      pieces.push_back(run_block_task(torus, t));
      task_seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    return pieces;
  };
  double client = 0, in_tasks = 0, largest = 0, task_bytes = 0, piece_bytes = 0, triangles = 0, tasks = 0, mesh_bytes = 0;
  for (auto _ : state) {
    task_seconds.clear();  // every layout's tasks (a run that meshes again lays out again)
    const PolygonizeResult r = polygonize_adaptive(torus, o);
    const BlocksReport& b = r.stats.adaptive->blocks;
    if (!b.used || r.mesh.positions != local.mesh.positions || r.mesh.triangles != local.mesh.triangles) {
      state.SkipWithError(b.used ? "the mesh of the tasks run from their bytes differs" : b.fallback.c_str());
      return;
    }
    state.SetIterationTime(r.stats.seconds);
    double sum = 0;
    for (const double t : task_seconds) sum += t;
    in_tasks += sum;
    client += r.stats.seconds - sum;
    largest += *std::max_element(task_seconds.begin(), task_seconds.end());
    task_bytes += static_cast<double>(b.task_bytes);
    piece_bytes += static_cast<double>(b.piece_bytes);
    triangles = static_cast<double>(r.mesh.triangles.size());
    tasks = static_cast<double>(task_seconds.size());
    mesh_bytes = static_cast<double>(r.mesh.positions.size() * 2 * sizeof(Vec3) + r.mesh.triangles.size() * 3 * sizeof(int));
  }
  const auto n = static_cast<double>(state.iterations());
  // The measured blocks' times (the last iteration's distribution) cycled to kClusterBlocks
  // blocks, scaled so that they sum to the measured block time per triangle times
  // kClusterTriangles.
  std::vector<double> grown(kClusterBlocks);
  for (std::size_t i = 0; i < grown.size(); ++i) grown[i] = task_seconds[i % task_seconds.size()];
  const double scale = in_tasks / n / triangles * kClusterTriangles / std::accumulate(grown.begin(), grown.end(), 0.0);
  for (double& t : grown) t *= scale;
  const double blocks_seconds = greedy_makespan(grown, kClusterWorkers);
  const double client_seconds = client / n / triangles * kClusterTriangles + kDaskTaskSeconds * kClusterBlocks;
  const double transfer_seconds = piece_bytes / n / triangles * kClusterTriangles / kClientBytesPerSecond;
  state.counters["triangles"] = triangles;
  state.counters["tasks"] = tasks;
  state.counters["client_seconds_per_triangle"] = client / n / triangles;
  state.counters["block_seconds_per_triangle"] = in_tasks / n / triangles;
  state.counters["largest_task_share"] = largest / in_tasks;  // of the tasks' sum
  state.counters["task_bytes_per_triangle"] = task_bytes / n / triangles;
  state.counters["piece_bytes_per_triangle"] = piece_bytes / n / triangles;
  state.counters["projected_blocks_seconds"] = blocks_seconds;
  state.counters["projected_largest_block_seconds"] = *std::max_element(grown.begin(), grown.end());
  state.counters["projected_client_seconds"] = client_seconds;
  state.counters["projected_transfer_seconds"] = transfer_seconds;
  state.counters["projected_seconds"] = client_seconds + std::max(blocks_seconds, transfer_seconds);
  state.counters["projected_one_worker_seconds"] = client_seconds + in_tasks / n / triangles * kClusterTriangles;
  state.counters["client_mesh_gb"] = mesh_bytes / triangles * kClusterTriangles / 1e9;
  state.SetLabel("torus_f40/adaptive/blocks_on_64_workers_at_1e9");
}
BENCHMARK(BM_BlocksClusterProjectionSlow)->Iterations(2)->UseManualTime()->Unit(benchmark::kMillisecond);

// Issue 58's item 5, measured as users meet it: the peak resident memory of the `polygonize`
// program (a process of its own, its stats' peak_resident_bytes: its VmHWM once the mesh file is
// written; not wait4's maximum, which on Linux carries a vfork parent's peak into the child)
// meshing the torus of experiments/fields/torus.json with the defaults at tolerance 1e-5 (about
// 1.9 * 10^6 triangles) and 1e-6 (about 1.8 * 10^7), each written to a PLY file. `peak_ratio` is
// the large run's peak over the small one's: with streaming, at most 1.3; holding the mesh until
// it is written, about the ratio of the triangles (`triangle_ratio`) at most. One iteration, one
// repetition: the large run takes about a minute and 3 GB.
struct ProgramRun {
  double peak_bytes = 0, triangles = 0, seconds = 0;
};

std::string program_path(const std::string& name) {
  std::vector<char> self(4096);
  const ssize_t n = readlink("/proc/self/exe", self.data(), self.size() - 1);
  if (n <= 0) return name;
  const std::string path(self.data(), static_cast<std::size_t>(n));
  return path.substr(0, path.rfind('/') + 1) + name;
}

// Runs `polygonize FIELD -o DIR/mesh.ply --quiet --stats DIR/stats.json ARGS`.
std::optional<ProgramRun> run_polygonize(const std::string& field, const std::vector<std::string>& args,
                                         const std::string& dir, std::string& error) {
  const std::string program = program_path("polygonize"), out = dir + "/mesh.ply", stats = dir + "/stats.json";
  std::vector<std::string> words{program, field, "-o", out, "--quiet", "--stats", stats};
  words.insert(words.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  const auto t0 = std::chrono::steady_clock::now();
  pid_t pid = 0;
  if (posix_spawn(&pid, program.c_str(), nullptr, nullptr, argv.data(), environ) != 0) {
    error = "cannot start " + program;
    return std::nullopt;
  }
  int status = 0;
  if (waitpid(pid, &status, 0) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    error = program + " failed";
    return std::nullopt;
  }
  ProgramRun r;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  try {
    std::ifstream in(stats);
    const nlohmann::json j = nlohmann::json::parse(in);
    r.triangles = j.at("triangles").get<double>();
    r.peak_bytes = j.at("peak_resident_bytes").get<double>();
  } catch (const std::exception& e) {
    error = stats + ": " + e.what();
  }
  std::remove(out.c_str());
  std::remove(stats.c_str());
  if (!error.empty()) return std::nullopt;
  return r;
}

void BM_PeakMemorySlow(benchmark::State& state) {
  const std::string field = std::string(CDP_SOURCE_DIR) + "/experiments/fields/torus.json";
  char dir_template[] = "/tmp/cdp_bench_memory_XXXXXX";
  const char* dir = mkdtemp(dir_template);
  if (!dir) {
    state.SkipWithError("cannot make a temporary directory");
    return;
  }
  ProgramRun small, large;
  for (auto _ : state) {
    std::string error;
    const auto a = run_polygonize(field, {"--tolerance", "1e-5"}, dir, error);
    const auto b = a ? run_polygonize(field, {"--tolerance", "1e-6"}, dir, error) : std::nullopt;
    if (!b) {
      rmdir(dir);
      state.SkipWithError(error.c_str());
      return;
    }
    small = *a, large = *b;
    state.SetIterationTime(large.seconds);
  }
  rmdir(dir);
  state.counters["triangles_small"] = small.triangles;
  state.counters["triangles_large"] = large.triangles;
  state.counters["peak_mb_small"] = small.peak_bytes / 1e6;
  state.counters["peak_mb_large"] = large.peak_bytes / 1e6;
  state.counters["bytes_per_triangle_small"] = small.peak_bytes / small.triangles;
  state.counters["bytes_per_triangle_large"] = large.peak_bytes / large.triangles;
  state.counters["peak_ratio"] = large.peak_bytes / small.peak_bytes;
  state.counters["triangle_ratio"] = large.triangles / small.triangles;
  state.counters["seconds_small"] = small.seconds;
  state.SetLabel("torus/adaptive/polygonize_1e-5_and_1e-6");
}
BENCHMARK(BM_PeakMemorySlow)->Iterations(1)->Repetitions(1)->UseManualTime()->Unit(benchmark::kMillisecond);

// One SDF model at factor 3, for BM_AdaptiveSdf and BM_AdaptiveSdfCrowdSlow: each iteration
// meshes it with its creases followed (the defaults), then ignored, then a smooth sphere (an
// expression of its own): `creases_cost_ratio` is the first time over the second (not reported
// where the second fails, nor where `compare_ignored` is false), and
// `per_triangle_vs_sphere` the time per triangle over the sphere's (the SDF-models issue: at
// most 1.5 where the model is C1, and at most 2); manual time = the default run's.
void sdf_model_costs(benchmark::State& state, const Field& field, const std::string& name, bool compare_ignored = true) {
  const Box box{Vec3::Constant(-1.2), Vec3::Constant(1.2)};
  const Expression sphere("sqrt(x^2+y^2+z^2)-1", {}, box);
  AdaptiveOptions o;
  o.factor = 3;
  double follow = 0, ignore = 0, follow_per_triangle = 0, sphere_per_triangle = 0, triangles = 0;
  // The run with creases ignored meshed (a Menger sponge's do not: no ratio then).
  bool ignored = compare_ignored;
  for (auto _ : state) {
    o.creases = CreaseHandling::Follow;
    const PolygonizeResult f = polygonize_adaptive(field, o);
    o.creases = CreaseHandling::Ignore;
    // Once the run with creases ignored has failed (the Menger sponge's, after about 4 s), it is
    // not made again: it would fail the same way, and made at every iteration it was most of
    // bench-short's time for this benchmark.
    if (ignored) {
      try {
        ignore += polygonize_adaptive(field, o).stats.seconds;
      } catch (const LimitExceededError&) {
        ignored = false;
      } catch (const NoSurfaceError&) {
        ignored = false;
      }
    }
    o.creases = CreaseHandling::Follow;
    const PolygonizeResult s = polygonize_adaptive(sphere, o);
    state.SetIterationTime(f.stats.seconds);
    follow += f.stats.seconds;
    triangles += static_cast<double>(f.stats.triangles);
    follow_per_triangle += f.stats.seconds / static_cast<double>(f.stats.triangles);
    sphere_per_triangle += s.stats.seconds / static_cast<double>(s.stats.triangles);
  }
  state.counters["triangles"] = triangles / static_cast<double>(state.iterations());
  if (ignored) state.counters["creases_cost_ratio"] = follow / ignore;
  state.counters["per_triangle_vs_sphere"] = follow_per_triangle / sphere_per_triangle;
  state.SetLabel(name + "/adaptive/factor3");
}

// Models written as SDF code writes them, at factor 3: a rounded box, a smooth union of it with a
// sphere (both C1 where their max and clamps switch: no crease), the union minus a cylinder (C1
// seams and two sharp rims), fogleman/sdf's README model (sharp creases only), a Menger sponge of
// level 1 (creases meeting six at a corner), two equal pipes crossing in a box (creases that
// cross where their pieces are tangent), a box with a ball blended onto an edge (a crease that
// fades out into a seam), cdp.sdf's rounded block with a ball blended on and a hole through
// both (its rounded box written as Inigo Quilez's exact distance) and fogleman/sdf's README model
// with its holes cut by a smooth difference (k = 0.1: each face, its fillet and its hole's wall
// one smooth region, coded differently along its boundaries); sdf_model_costs times each.
void BM_AdaptiveSdf(benchmark::State& state) {
  static const char* kRoundedBox = "sqrt(max(abs(x)-0.6,0)^2+max(abs(y)-0.4,0)^2+max(abs(z)-0.3,0)^2)-0.15";
  const std::map<std::string, std::string> blend = {
      {"a", kRoundedBox},
      {"b", "sqrt((x-0.5)^2+(y-0.3)^2+z^2)-0.45"},
      {"h", "clamp(0.5+0.5*(b-a)/0.2,0,1)"},
      {"u", "b+h*(a-b)-0.2*h*(1-h)"}};
  const Box box{Vec3::Constant(-1.2), Vec3::Constant(1.2)};
  const int which = static_cast<int>(state.range(0));
  static const char* kNames[] = {"rounded_box",   "smooth_union",  "smooth_union_minus_cylinder",
                                 "fogleman_readme", "menger_level1", "crossed_pipes",
                                 "box_blended_ball", "blended_block", "fogleman_filleted_holes"};
  // cdp.sdf's rounded_box((1.6, 1, 0.8), 0.1) | sphere(0.55, center=(0.6, 0.3, 0.3)).k(0.2).
  const std::map<std::string, std::string> block = {
      {"q0", "abs(x)-0.7"},
      {"q1", "abs(y)-0.4"},
      {"q2", "abs(z)-0.3"},
      {"m", "min(max(q0,q1,q2),0)"},
      {"a", "hypot(max(q0,0),max(q1,0),max(q2,0),m)+2*m-0.1"},
      {"b", "hypot(x-0.6,y-0.3,z-0.3)-0.55"},
      {"h", "clamp(0.5+0.5*(b-a)/0.2,0,1)"},
      {"u", "b+h*(a-b)-0.2*h*(1-h)"}};
  const Expression field =
      which == 0   ? Expression(kRoundedBox, {}, box)
      : which == 1 ? Expression("u", {}, box, blend)
      : which == 2 ? Expression("max(u, 0.2-sqrt(x^2+y^2))", {}, box, blend)
      : which == 3 ? Expression("max(max(sqrt(x^2+y^2+z^2)-1, max(abs(x),abs(y),abs(z))-0.75), "
                                "-min(hypot(y,z)-0.5, hypot(x,z)-0.5, hypot(x,y)-0.5))",
                                {}, box)
      : which == 4 ? Expression("max(max(abs(x),abs(y),abs(z))-1, -min(max(abs(x),abs(y))-0.4, "
                                "max(abs(y),abs(z))-0.4, max(abs(x),abs(z))-0.4))",
                                {}, Box{Vec3::Constant(-1.3), Vec3::Constant(1.3)})
      : which == 5 ? Expression("max(min(hypot(y,z)-0.5, hypot(x,z)-0.5), max(abs(x),abs(y),abs(z))-1)", {}, box)
      : which == 6 ? Expression("b+h*(a-b)-0.25*h*(1-h)", {}, Box{Vec3::Constant(-1.4), Vec3::Constant(1.4)},
                                {{"a", "max(abs(x),abs(y),abs(z))-0.75"},
                                 {"b", "hypot(x-0.75,y-0.75,z)-0.5"},
                                 {"h", "clamp(0.5+0.5*(b-a)/0.25,0,1)"}})
      : which == 7 ? Expression("max(u, 0.2-hypot(x,y))", {}, Box{Vec3::Constant(-1.3), Vec3::Constant(1.3)}, block)
                   : Expression("d0-(d1+d0)*h+0.1*h*(1-h)", {}, Box{Vec3::Constant(-0.9), Vec3::Constant(0.9)},
                                {{"d0", "max(hypot(x,y,z)-1, max(abs(x),abs(y),abs(z))-0.75)"},
                                 {"d1", "min(hypot(y,z)-0.5, hypot(x,z)-0.5, hypot(x,y)-0.5)"},
                                 {"h", "clamp(0.5-(d1+d0)*5,0,1)"}});
  sdf_model_costs(state, field, kNames[which]);
}
BENCHMARK(BM_AdaptiveSdf)->ArgName("model")->DenseRange(0, 8)->UseManualTime()->Unit(benchmark::kMillisecond);

// The crowd of 200 Wyvill blobs (tests/polygonizer/fields), two of them joined by a neck
// narrower than min_edge: the run as given fails and the run with min_edge lowered meshes it
// (about 155k triangles and 4 s at factor 3; not in bench-short).
void BM_AdaptiveSdfCrowdSlow(benchmark::State& state) {
  static const std::unique_ptr<Field> crowd =
      load_field(std::string(CDP_SOURCE_DIR) + "/tests/polygonizer/fields/crowd_200_wyvill_blobs.json");
  // A sum of blobs has no min, max or abs: ignoring creases would mesh it the same way again.
  sdf_model_costs(state, *crowd, "crowd_200_blobs", false);
}
BENCHMARK(BM_AdaptiveSdfCrowdSlow)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(1);

// Components of very different scales: a torus tube of radius 0.003 beside a sphere of radius
// 1.2 at factor 1, min_edge 1e-4 (the hashes sized by the tube's edges hold the sphere's
// triangles; the run took 330 s before coarser levels for wide boxes, 0.43 s after).
void BM_AdaptiveMixedScales(benchmark::State& state) {
  const Expression field("min(sqrt((x-2.8)^2+y^2+z^2)-1.2, sqrt((sqrt(x^2+y^2)-1)^2+z^2)-0.003)", {},
                         Box{Vec3::Constant(-4), Vec3::Constant(4)});
  AdaptiveOptions o;
  o.factor = 1;
  o.min_edge = 1e-4;
  run_adaptive(state, field, o);
  state.SetLabel("sphere_and_thin_torus/adaptive/factor1");
}
BENCHMARK(BM_AdaptiveMixedScales)->UseManualTime()->Unit(benchmark::kMillisecond);

// The two final checks of every adaptive run, timed on one finished mesh of the torus at
// factor state.range(0) / 10: `check` returns whether the mesh passed (it must).
template <class Check>
void time_final_check(benchmark::State& state, const char* label, const char* failure, Check check) {
  const auto field = make_shape(kTorus);
  AdaptiveOptions o;
  o.factor = static_cast<double>(state.range(0)) / 10;
  o.check_self_intersections = false;
  const Mesh mesh = polygonize_adaptive(*field, o).mesh;
  double seconds = 0, checks = 0;
  bool passed = true;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    passed = check(mesh) && passed;
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ++checks;
  }
  if (!passed) state.SkipWithError(failure);
  state.counters["ns_per_triangle"] = 1e9 * seconds / (checks * static_cast<double>(mesh.num_triangles()));
  state.SetLabel(label);
}

// AdaptiveOptions::check_self_intersections: all intersecting pairs of a finished mesh, on one
// thread. The torus at factor 6.3 (about 10^4 triangles, one thread below the check's parallel
// threshold in a real run) and at 20 (10^5).
void BM_SelfIntersectionCheck(benchmark::State& state) {
  time_final_check(state, "torus/self_intersection_check", "the torus mesh intersects itself",
                   [](const Mesh& mesh) { return count_self_intersecting_pairs(mesh, 1) == 0; });
}
BENCHMARK(BM_SelfIntersectionCheck)->ArgName("factor_x10")->Arg(63)->Arg(200)->Unit(benchmark::kMillisecond);

// Closed, oriented, manifold, components (analyze_topology), at factors 5 and 20.
void BM_MeshTopology(benchmark::State& state) {
  time_final_check(state, "torus/mesh_topology", "the torus mesh is not watertight",
                   [](const Mesh& mesh) { return analyze_topology(mesh).watertight(); });
}
BENCHMARK(BM_MeshTopology)->ArgName("factor_x10")->Arg(50)->Arg(200)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

// How soon a cancelled run stops (AdaptiveOptions::cancel, cdp/core/cancel.h): the run is
// made once uncancelled, then cancelled from another thread at each tenth of its time (the
// seed grid, the tracking, the repair, the checks); the latency is the time from cancel() to
// CancelledError reaching the caller. Counters: the largest and the median latency in
// seconds, the tenth of the run where the largest was met, and the uncancelled run's time.
// Manual time = the largest latency.
void measure_cancel_latency(benchmark::State& state, const Field& field, AdaptiveOptions o, const char* label) {
  const double seconds = polygonize_adaptive(field, o).stats.seconds;
  std::vector<double> latencies;
  int worst_at = 0;  // the tenth of the run at which the largest latency was met
  for (auto _ : state) {
    double worst = 0;
    for (int k = 1; k <= 9; ++k) {
      o.cancel.reset();
      const auto clock = [] { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); };
      std::atomic<double> cancelled_at{0};
      std::thread canceller([&] {
        std::this_thread::sleep_for(std::chrono::duration<double>(k * seconds / 10));
        cancelled_at.store(clock());
        o.cancel.cancel();
      });
      try {
        polygonize_adaptive(field, o);
      } catch (const CancelledError&) {
      }
      const double now = clock();
      canceller.join();
      // A run that ended before its token was cancelled: no latency (0).
      const double latency = cancelled_at.load() > 0 ? std::max(0.0, now - cancelled_at.load()) : 0;
      latencies.push_back(latency);
      if (latency > worst) worst = latency, worst_at = k;
    }
    state.SetIterationTime(worst);
  }
  std::sort(latencies.begin(), latencies.end());
  state.counters["latency_max_seconds"] = latencies.back();
  state.counters["latency_median_seconds"] = latencies[latencies.size() / 2];
  state.counters["run_seconds"] = seconds;
  state.counters["latency_max_at_tenth"] = worst_at;
  state.SetLabel(label);
}

// Shape 0: the torus at factor 20 (100k triangles), 1: the bunny VIS-800 at factor 5 (sizes
// bench-short can afford).
void BM_CancelLatency(benchmark::State& state) {
  const int shape = static_cast<int>(state.range(0));
  const auto torus = make_shape(kTorus);
  AdaptiveOptions o;
  o.factor = shape == 0 ? 20 : 5;
  measure_cancel_latency(state, shape == 0 ? *torus : bunny(), o,
                         shape == 0 ? "torus/adaptive/factor20/cancel" : "bunny_vis800/adaptive/factor5/cancel");
}
BENCHMARK(BM_CancelLatency)->ArgName("shape")->DenseRange(0, 1)->Iterations(1)->UseManualTime()->Unit(benchmark::kMillisecond);

// The torus at 2*10^6 triangles (factor 89, as BM_AdaptiveScaling's series: about factor^2), the
// size the cancellation's 0.1 s is promised at; ten runs of about 15 s each, so not in bench-short.
void BM_CancelLatencySlow(benchmark::State& state) {
  const auto torus = make_shape(kTorus);
  AdaptiveOptions o;
  o.factor = 89;
  o.min_edge = 1e-5;
  measure_cancel_latency(state, *torus, o, "torus/adaptive/2e6/cancel");
}
BENCHMARK(BM_CancelLatencySlow)->Iterations(1)->UseManualTime()->Unit(benchmark::kMillisecond);
