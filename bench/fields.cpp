// Field evaluation cost per model, by kind of evaluation, and curvature at a point.
//
// Names (bench/README.md): BM_Field/<field>/<kind> with kind one of value, value_gradient,
// gradient_hessian, values_batched (Field::values over the whole point set in one call) and
// values_scalar (a loop of Field::value over the same points); BM_Curvature/<field>
// (curvature_at: one gradient_hessian evaluation and the tangent-plane eigen-decomposition).
// Counter: evaluations_per_second (curvatures per second for BM_Curvature). The dashboard
// divides values_batched by values_scalar of the same field: the vectorization gain, a ratio
// measured in one run that does not drift between machines.
//
// Points: a cell-centred 16^3 lattice over the field's bounds (deterministic, and it avoids the
// centres of symmetric boxes where a distance field's gradient is undefined).
//   build/bin/bench_fields --benchmark_min_time=0.05
#include <cdp/core/curvature.h>
#include <cdp/core/errors.h>
#include <cdp/core/models/analytic.h>
#include <cdp/core/models/blobs.h>
#include <cdp/core/models/expression.h>
#include <cdp/io/field_factory.h>

#include <benchmark/benchmark.h>

#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace {

using namespace cdp;

constexpr int kLattice = 16;

std::vector<Vec3> lattice(const Box& box) {
  std::vector<Vec3> points;
  points.reserve(kLattice * kLattice * kLattice);
  for (int i = 0; i < kLattice; ++i)
    for (int j = 0; j < kLattice; ++j)
      for (int k = 0; k < kLattice; ++k) {
        const Vec3 t = (Vec3(i, j, k).array() + 0.5) / kLattice;
        points.push_back(box.min + t.cwiseProduct(box.size()));
      }
  return points;
}

// A ring of 24 boxes about the z axis, each turned to face it, as SDF code writes a union of
// many primitives: IQ's exact box, min of all, 24 x 31 instructions.
std::string ring_of_boxes() {
  std::string f = "min(";
  for (int i = 0; i < 24; ++i) {
    const double a = 2 * 3.14159265358979 * i / 24, c = std::cos(a), s = std::sin(a);
    const std::string u = "abs(" + std::to_string(c) + "*x + " + std::to_string(s) + "*y - 1.2) - 0.15";
    const std::string v = "abs(" + std::to_string(-s) + "*x + " + std::to_string(c) + "*y) - 0.1";
    const std::string w = "abs(z) - 1";
    f += (i ? ", " : "") + std::string("hypot(max(") + u + ", 0), max(" + v + ", 0), max(" + w + ", 0)) + min(max(" +
         u + ", " + v + ", " + w + "), 0)";
  }
  return f + ")";
}

struct Model {
  std::string name;
  std::shared_ptr<Field> field;
  Box points;  // the lattice's box
};

// The models, each under the name the dashboard and README use. The expression is the
// tanglecube written as a formula, so expression vs compiled tanglecube shows the interpreter's cost.
// The ring of boxes is evaluated twice on the same points: as usual (each cell of its box runs
// the formula without the min and max that cannot switch there, once evaluated often enough: the
// benchmark's repetitions see them made) and with its box elsewhere (`_whole`: the whole formula
// everywhere); the two are the same bits.
std::vector<Model> models() {
  std::vector<std::pair<std::string, std::shared_ptr<Field>>> m;
  m.emplace_back("sphere", std::make_shared<Sphere>(Vec3(0.1, -0.05, 0.02), 1.0));
  m.emplace_back("torus", std::make_shared<Torus>(Vec3(0.01, 0.02, -0.015), 1.0, 0.4));
  m.emplace_back("ellipsoid", std::make_shared<Ellipsoid>(Vec3::Zero(), Vec3(1.0, 0.7, 0.4)));
  std::vector<Blob> blobs;
  for (int i = 0; i < 8; ++i) {  // a ring of overlapping blobs: several kernels contribute at most points
    const double a = 2 * 3.14159265358979 * i / 8;
    blobs.push_back({Vec3(std::cos(a), std::sin(a), 0.2 * (i % 2)), 0.9, 1.0});
  }
  m.emplace_back("blobs", std::make_shared<Blobs>(BlobKernel::Wyvill, 0.3, blobs));
  m.emplace_back("expression_tanglecube",
                 std::make_shared<Expression>("x^4 - 5*x^2 + y^4 - 5*y^2 + z^4 - 5*z^2 + 11.8",
                                              std::map<std::string, double>{}, Box{{-3, -3, -3}, {3, 3, 3}}));
  for (const char* compiled : {"tanglecube", "double_torus"})
    m.emplace_back(std::string("compiled_") + compiled,
                   std::shared_ptr<Field>(make_field(nlohmann::json{{"type", compiled}}, "bench_fields")));
  const Box ring{{-1.6, -1.6, -1.2}, {1.6, 1.6, 1.2}}, elsewhere{{10, 10, 10}, {11, 11, 11}};
  m.emplace_back("expression_ring_of_boxes", std::make_shared<Expression>(ring_of_boxes(), ring));
  std::vector<Model> out;
  for (auto& [name, field] : m) out.push_back({name, field, field->bounds()});
  out.push_back({"expression_ring_of_boxes_whole", std::make_shared<Expression>(ring_of_boxes(), elsewhere), ring});
  return out;
}

using Kernel = std::function<double(const Field&, const std::vector<Vec3>&, std::vector<double>&)>;

void run(benchmark::State& state, const Field& field, const std::vector<Vec3>& points, const Kernel& kernel,
         const char* counter) {
  std::vector<double> out(points.size());
  double sink = 0;
  for (auto _ : state) {
    sink += kernel(field, points, out);
    benchmark::DoNotOptimize(sink);
    benchmark::ClobberMemory();
  }
  state.counters[counter] =
      benchmark::Counter(static_cast<double>(points.size()), benchmark::Counter::kIsIterationInvariantRate);
}

double eval_value(const Field& f, const std::vector<Vec3>& pts, std::vector<double>&) {
  double s = 0;
  for (const Vec3& p : pts) s += f.value(p);
  return s;
}

double eval_value_gradient(const Field& f, const std::vector<Vec3>& pts, std::vector<double>&) {
  double s = 0;
  Vec3 g;
  for (const Vec3& p : pts) s += f.value_gradient(p, g) + g.x();
  return s;
}

double eval_gradient_hessian(const Field& f, const std::vector<Vec3>& pts, std::vector<double>&) {
  double s = 0;
  Vec3 g;
  Mat3 h;
  for (const Vec3& p : pts) s += f.gradient_hessian(p, g, h) + h(0, 1);
  return s;
}

double eval_values_batched(const Field& f, const std::vector<Vec3>& pts, std::vector<double>& out) {
  f.values(pts.data(), out.data(), pts.size());
  return out.back();
}

double eval_values_scalar(const Field& f, const std::vector<Vec3>& pts, std::vector<double>& out) {
  for (std::size_t i = 0; i < pts.size(); ++i) out[i] = f.value(pts[i]);
  return out.back();
}

double eval_curvature(const Field& f, const std::vector<Vec3>& pts, std::vector<double>&) {
  double s = 0;
  for (const Vec3& p : pts) s += curvature_at(f, p).mean;
  return s;
}

void register_all() {
  const std::pair<const char*, Kernel> kinds[] = {
      {"value", eval_value},
      {"value_gradient", eval_value_gradient},
      {"gradient_hessian", eval_gradient_hessian},
      {"values_batched", eval_values_batched},
      {"values_scalar", eval_values_scalar},
  };
  for (const auto& [name, field, box] : models()) {
    auto points = std::make_shared<std::vector<Vec3>>(lattice(box));
    // An expression's cells are specialized once evaluated often enough (about 64 times, one
    // point each here): measured after, as in a run, where most evaluations come near the surface.
    for (int k = 0; k < 100 && field->type_name() == "expression"; ++k)
      for (const Vec3& p : *points) field->value(p);
    for (const auto& [kind, kernel] : kinds) {
      benchmark::RegisterBenchmark(("BM_Field/" + name + "/" + kind).c_str(),
                                   [field, points, kernel = kernel](benchmark::State& st) {
                                     run(st, *field, *points, kernel, "evaluations_per_second");
                                   })
          ->Unit(benchmark::kMicrosecond);
    }
    // Curvature needs a non-vanishing gradient; keep the lattice points where it is defined
    // (all of them for these models, but a model added later may have critical points).
    auto regular = std::make_shared<std::vector<Vec3>>();
    for (const Vec3& p : *points) {
      try {
        curvature_at(*field, p);
        regular->push_back(p);
      } catch (const NoSurfaceError&) {
      }
    }
    benchmark::RegisterBenchmark(("BM_Curvature/" + name).c_str(),
                                 [field, regular](benchmark::State& st) {
                                   run(st, *field, *regular, eval_curvature, "curvatures_per_second");
                                 })
        ->Unit(benchmark::kMicrosecond);
  }
}

}  // namespace

int main(int argc, char** argv) {
  register_all();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
