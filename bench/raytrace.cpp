// Rays per second of the exact implicit ray caster (torus: model Lipschitz bound; tanglecube:
// estimated bound) and of the Embree mesh intersection, single-threaded and with TBB.
//   build/bin/bench_raytrace --benchmark_min_time=0.05
#include <cdp/raytrace/embree_scene.h>
#include <cdp/raytrace/implicit_raycast.h>
#include "common/reference_meshes.h"

#include <cdp/core/models/analytic.h>
#include <cdp/core/models/expression.h>

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <memory>

namespace {

std::vector<cdp::Ray> rays_for(const cdp::Box& box, int resolution) {
  cdp::CameraOptions camera;
  camera.views = 4;
  camera.resolution = resolution;
  return cdp::make_camera_rays(box, camera);
}

std::unique_ptr<cdp::Field> make_field(int which) {
  if (which == 0) return std::make_unique<cdp::Torus>(cdp::Vec3::Zero(), 1.0, 0.35);
  return std::make_unique<cdp::Expression>("x^4 - 5*x^2 + y^4 - 5*y^2 + z^4 - 5*z^2 + 11.8",
                                           std::map<std::string, double>{}, cdp::Box{{-3, -3, -3}, {3, 3, 3}});
}

// Arguments: field (0 torus, 1 tanglecube), threads (0 = all).
void BM_ExactRaycast(benchmark::State& state) {
  const auto field = make_field(static_cast<int>(state.range(0)));
  const auto rays = rays_for(field->bounds(), 32);
  const int threads = static_cast<int>(state.range(1));
  std::unique_ptr<tbb::global_control> limit;
  if (threads > 0) limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
  const cdp::RaycastOptions options;
  cdp::GroundTruth gt;
  for (auto _ : state) {
    gt = cdp::compute_ground_truth(*field, rays, options);  // includes the Lipschitz estimate
    benchmark::DoNotOptimize(gt.hits.data());
  }
  const auto c = gt.counts();
  state.counters["rays_per_s"] = benchmark::Counter(static_cast<double>(rays.size()), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["hit_fraction"] = static_cast<double>(c.hits) / static_cast<double>(rays.size());
  std::uint64_t steps = 0;
  for (const auto& h : gt.hits) steps += static_cast<std::uint64_t>(h.steps);
  state.counters["steps_per_ray"] = static_cast<double>(steps) / static_cast<double>(rays.size());
  state.SetLabel(field->type_name());
}
BENCHMARK(BM_ExactRaycast)->Args({0, 1})->Args({1, 1})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ExactRaycast)->Args({0, 0})->Args({1, 0})->Unit(benchmark::kMillisecond)->UseRealTime();

// Arguments: icosphere subdivisions, threads (0 = all).
void BM_EmbreeIntersect(benchmark::State& state) {
  const cdp::Mesh mesh = cdp::icosphere(static_cast<int>(state.range(0)));
  const cdp::EmbreeScene scene(mesh);
  const auto rays = rays_for(cdp::Box{cdp::Vec3::Constant(-1.1), cdp::Vec3::Constant(1.1)}, 128);
  const int threads = static_cast<int>(state.range(1));
  std::unique_ptr<tbb::global_control> limit;
  if (threads > 0) limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
  for (auto _ : state) {
    auto hits = scene.intersect(rays);
    benchmark::DoNotOptimize(hits.data());
  }
  state.counters["rays_per_s"] = benchmark::Counter(static_cast<double>(rays.size()), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["triangles"] = static_cast<double>(mesh.num_triangles());
}
BENCHMARK(BM_EmbreeIntersect)->Args({5, 1})->Args({7, 1})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EmbreeIntersect)->Args({5, 0})->Args({7, 0})->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_EmbreeBuild(benchmark::State& state) {
  const cdp::Mesh mesh = cdp::icosphere(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    cdp::EmbreeScene scene(mesh);
    benchmark::ClobberMemory();
  }
  state.counters["triangles_per_s"] =
      benchmark::Counter(static_cast<double>(mesh.num_triangles()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_EmbreeBuild)->Arg(5)->Arg(7)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
