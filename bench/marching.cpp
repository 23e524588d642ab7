// Marching Cubes and Marching Tetrahedra on the torus and the tanglecube, with both traversals.
// Counters: triangles per second (rate) and field evaluations (all kinds, normals included)
// per triangle; also evaluations at lattice corners and in root searches per triangle. Times
// are the polygonizer's own stats.seconds (manual time), as in STATS.json: the topology count
// the statistics also make is not polygonization.
#include <cdp/baselines/marching_cubes.h>
#include <cdp/baselines/marching_tetrahedra.h>

#include <cdp/core/models/analytic.h>
#include <cdp/core/models/expression.h>

#include <benchmark/benchmark.h>

#include <memory>

namespace {

using namespace cdp;

enum Shape { kTorus, kTanglecube };
enum Method { kMC, kMT };

std::unique_ptr<Field> make_shape(Shape shape) {
  if (shape == kTorus) return std::make_unique<Torus>(Vec3(0.01, 0.02, -0.015), 1.0, 0.4);
  return std::make_unique<Expression>("x^4 - 5*x^2 + y^4 - 5*y^2 + z^4 - 5*z^2 + 11.8",
                                      std::map<std::string, double>{}, Box{{-3, -3, -3}, {3, 3, 3}});
}

// Cells giving meshes of some 10^5 triangles, small enough to repeat.
double cell_for(Shape shape) { return shape == kTorus ? 0.02 : 0.05; }

void BM_Marching(benchmark::State& state) {
  const auto shape = static_cast<Shape>(state.range(0));
  const auto method = static_cast<Method>(state.range(1));
  const auto traversal = static_cast<Traversal>(state.range(2));
  const std::unique_ptr<Field> field = make_shape(shape);
  MarchingOptions options;
  options.cell_size = cell_for(shape);
  options.traversal = traversal;
  double triangles = 0, evaluations = 0, corners = 0, roots = 0;
  for (auto _ : state) {
    const PolygonizeResult r = method == kMC ? marching_cubes(*field, options) : marching_tetrahedra(*field, options);
    triangles += static_cast<double>(r.stats.triangles);
    evaluations += static_cast<double>(r.stats.field_evaluations.total());
    corners += static_cast<double>(r.stats.lattice->corner_evaluations);
    roots += static_cast<double>(r.stats.lattice->root_evaluations);
    benchmark::DoNotOptimize(r.mesh.positions.data());
    state.SetIterationTime(r.stats.seconds);
  }
  state.counters["triangles_per_second"] = benchmark::Counter(triangles, benchmark::Counter::kIsRate);
  state.counters["triangles"] = triangles / static_cast<double>(state.iterations());
  state.counters["evaluations_per_triangle"] = evaluations / triangles;
  state.counters["evaluations"] = evaluations / static_cast<double>(state.iterations());
  state.counters["corner_evaluations_per_triangle"] = corners / triangles;
  state.counters["root_evaluations_per_triangle"] = roots / triangles;
  state.SetLabel(std::string(shape == kTorus ? "torus" : "tanglecube") + "/" + (method == kMC ? "mc" : "mt") + "/" +
                 to_string(traversal));
}

BENCHMARK(BM_Marching)
    ->ArgNames({"shape", "method", "traversal"})
    ->ArgsProduct({{kTorus, kTanglecube},
                   {kMC, kMT},
                   {static_cast<long>(Traversal::Continuation), static_cast<long>(Traversal::Grid)}})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
