// The data-driven fields of the paper's experiments: evaluation rates and build times.
//
// Names (bench/README.md):
//   BM_Vis/<field>/<kind>/vectorized and BM_Vis/<field>/<kind>/scalar, kind one of value,
//     value_gradient, gradient_hessian: the SIMD kernel (Field interface) against the plain
//     one-centre-at-a-time loop (Vis::*_scalar), in the same run; the dashboard divides the pair.
//   BM_Vis/<field>/values_batched: Field::values over the whole point set in one call.
//   BM_Vis/<field>/<kind>/helper, kind value_gradient or gradient_hessian: the vectorized kernel
//     with a helper thread lent (polygonizer/src/helper_thread.h), which sums half the lanes of
//     a model from Vis::kSplit*Centres centres; counter split_share, the share of evaluations
//     split (0 on one processor, or below the threshold). Back to back, as here, a hand-over
//     costs less than between the tracker's evaluations.
//   BM_Mpu/<field>/<kind>: the MPU models (bunny_mpu, horse_mpu, igea_mpu), same kinds.
//   BM_VisSolve/<field>: the VIS system (assembly, null-space Cholesky, residual check) for the
//     400, 1000 or 2002 points drawn from the scan; BM_VisSolveSlow/igea_vis4004 (seconds).
//   BM_MpuBuild/<field>: the MPU octree and fits over all the scan's points (file read excluded).
// Counters: evaluations_per_second; for the builds, constraints or points, and leaves.
//
// Fields: experiments/fields/<field>.json, built once per process. Points: 4096 near the surface
// (scan vertices moved along their normals by -0.5, 0 or +0.5 % of the box diagonal), the region
// the polygonizers evaluate; deterministic.
//   build/bin/bench_fields_data --benchmark_min_time=0.05
#include <cdp/core/models/mpu.h>
#include <cdp/core/models/vis.h>
#include <cdp/core/oriented_points.h>
#include <cdp/io/field_factory.h>
#include <cdp/io/mesh_io.h>

#include <benchmark/benchmark.h>

#include "../polygonizer/src/helper_thread.h"

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace {

using namespace cdp;

const std::string kFieldsDir = std::string(CDP_SOURCE_DIR) + "/experiments/fields/";
const std::string kDataDir = std::string(CDP_SOURCE_DIR) + "/data/";

const Field& field(const std::string& name) {
  static std::map<std::string, std::unique_ptr<Field>> cache;
  auto& f = cache[name];
  if (!f) f = load_field(kFieldsDir + name + ".json");
  return *f;
}

const OrientedPoints& scan(const std::string& name) {
  static std::map<std::string, OrientedPoints> cache;
  auto it = cache.find(name);
  if (it == cache.end()) it = cache.emplace(name, read_oriented_points(kDataDir + name + ".ply")).first;
  return it->second;
}

std::string scan_of(const std::string& field_name) { return field_name.substr(0, field_name.find('_')); }

const std::vector<Vec3>& near_surface_points(const std::string& field_name) {
  static std::map<std::string, std::vector<Vec3>> cache;
  auto& pts = cache[field_name];
  if (pts.empty()) {
    const OrientedPoints& s = scan(scan_of(field_name));
    const double step = 0.005 * bounding_box(s.positions).diagonal();
    const std::size_t n = 4096, stride = s.size() / n;
    for (std::size_t i = 0; i < n; ++i)
      pts.push_back(s.positions[i * stride] + step * static_cast<double>(static_cast<int>(i % 3) - 1) * s.normals[i * stride]);
  }
  return pts;
}

enum Kind { kValue, kValueGradient, kGradientHessian, kBatched };

void evaluate(benchmark::State& state, const std::string& name, Kind kind, bool scalar, bool helper = false) {
  const Field& f = field(name);
  std::optional<detail::LendHelper> lend;
  if (helper) lend.emplace(2);
  const std::uint64_t split_before = detail::lent_helper() ? detail::lent_helper()->tasks_run() : 0;
  const auto* vis = dynamic_cast<const Vis*>(&f);
  const std::vector<Vec3>& pts = near_surface_points(name);
  std::vector<double> out(pts.size());
  double evaluations = 0;
  for (auto _ : state) {
    double sum = 0;
    Vec3 g;
    Mat3 H;
    if (kind == kBatched) {
      f.values(pts.data(), out.data(), pts.size());
      sum = out[0];
    } else {
      for (const Vec3& p : pts) {
        if (kind == kValue) {
          sum += scalar ? vis->value_scalar(p) : f.value(p);
        } else if (kind == kValueGradient) {
          sum += scalar ? vis->value_gradient_scalar(p, g) : f.value_gradient(p, g);
          sum += g.x();
        } else {
          sum += scalar ? vis->gradient_hessian_scalar(p, g, H) : f.gradient_hessian(p, g, H);
          sum += H(0, 1);
        }
      }
    }
    benchmark::DoNotOptimize(sum);
    evaluations += static_cast<double>(pts.size());
  }
  state.counters["evaluations_per_second"] = benchmark::Counter(evaluations, benchmark::Counter::kIsRate);
  if (helper) {
    const std::uint64_t split = detail::lent_helper() ? detail::lent_helper()->tasks_run() - split_before : 0;
    state.counters["split_share"] = evaluations > 0 ? static_cast<double>(split) / evaluations : 0.0;
  }
}

void vis_solve(benchmark::State& state, const std::string& name) {
  const auto& vis = dynamic_cast<const Vis&>(field(name));  // the points and offset it was built from
  const std::size_t n = vis.solve_info().constraints / 2;
  OrientedPoints pts;
  const double d = vis.solve_info().normal_offset;
  for (std::size_t i = 0; i < n; ++i) {
    pts.positions.push_back(vis.centres()[i]);
    pts.normals.push_back((vis.centres()[n + i] - vis.centres()[i]) / d);
  }
  for (Vec3& v : pts.normals) v.normalize();
  double residual = 0;
  for (auto _ : state) {
    const Vis solved(pts, d, name);
    // No DoNotOptimize(residual): with Debian's benchmark 1.7 and GCC 12 its "+m,r" asm can leave
    // a double holding garbage afterwards; the solve cannot be elided anyway (it allocates).
    residual = solved.solve_info().interpolation_residual;
  }
  state.counters["constraints"] = static_cast<double>(2 * n);
  state.counters["interpolation_residual"] = residual;
}

void mpu_build(benchmark::State& state, const std::string& name) {
  const OrientedPoints& pts = scan(scan_of(name));
  std::size_t leaves = 0;
  for (auto _ : state) {
    const Mpu mpu(pts, MpuOptions{}, name);
    leaves = mpu.stats().leaves;
    benchmark::DoNotOptimize(leaves);
  }
  state.counters["points"] = static_cast<double>(pts.size());
  state.counters["leaves"] = static_cast<double>(leaves);
}

const char* kind_name(Kind k) {
  switch (k) {
    case kValue: return "value";
    case kValueGradient: return "value_gradient";
    case kGradientHessian: return "gradient_hessian";
    default: return "values_batched";
  }
}

[[maybe_unused]] const bool registered = [] {
  for (const std::string name : {"bunny_vis800", "bunny_vis2000", "igea_vis4004"}) {
    for (Kind k : {kValue, kValueGradient, kGradientHessian})
      for (bool scalar : {false, true})
        benchmark::RegisterBenchmark(
            ("BM_Vis/" + name + "/" + kind_name(k) + (scalar ? "/scalar" : "/vectorized")).c_str(),
            [name, k, scalar](benchmark::State& s) { evaluate(s, name, k, scalar); })
            ->Unit(benchmark::kMicrosecond);
    for (Kind k : {kValueGradient, kGradientHessian})
      benchmark::RegisterBenchmark(("BM_Vis/" + name + "/" + kind_name(k) + "/helper").c_str(),
                                   [name, k](benchmark::State& s) { evaluate(s, name, k, false, true); })
          ->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark(("BM_Vis/" + name + "/values_batched").c_str(),
                                 [name](benchmark::State& s) { evaluate(s, name, kBatched, false); })
        ->Unit(benchmark::kMicrosecond);
  }
  for (const std::string name : {"bunny_mpu", "horse_mpu", "igea_mpu"})
    for (Kind k : {kValue, kValueGradient, kGradientHessian})
      benchmark::RegisterBenchmark(("BM_Mpu/" + name + "/" + kind_name(k)).c_str(),
                                   [name, k](benchmark::State& s) { evaluate(s, name, k, false); })
          ->Unit(benchmark::kMicrosecond);
  for (const std::string name : {"bunny_vis800", "bunny_vis2000"})
    benchmark::RegisterBenchmark(("BM_VisSolve/" + name).c_str(), [name](benchmark::State& s) { vis_solve(s, name); })
        ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("BM_VisSolveSlow/igea_vis4004",
                               [](benchmark::State& s) { vis_solve(s, "igea_vis4004"); })
      ->Unit(benchmark::kMillisecond);
  for (const std::string name : {"bunny_mpu", "horse_mpu", "igea_mpu"})
    benchmark::RegisterBenchmark(("BM_MpuBuild/" + name).c_str(), [name](benchmark::State& s) { mpu_build(s, name); })
        ->Unit(benchmark::kMillisecond);
  return true;
}();

}  // namespace

BENCHMARK_MAIN();
