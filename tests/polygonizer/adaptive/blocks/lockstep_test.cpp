// Tasks in lockstep (polygonizer/src/adaptive/lockstep.h): every evaluation answered as the field
// answers it alone, the batches the same on every run, a failing call failing its batch's tasks,
// and blocks of a field whose calls are costly meshed in lockstep into one sound mesh, the same in
// any block order.
#include <gtest/gtest.h>

#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/mesh_topology.h>

#include "common/same_bits.h"
#include "common/same_mesh.h"
#include "common/test_fields.h"
#include "src/adaptive/blocks.h"
#include "src/adaptive/lockstep.h"
#include "src/adaptive/resolve_settings.h"
#include "src/adaptive/stage_checks.h"
#include "src/adaptive/stage_seed_grid.h"

#include <cmath>
#include <iostream>
#include <mutex>
#include <stdexcept>
#include <vector>

namespace cdp::adaptive {
namespace {

// A field that stands for another through its public calls, says its calls are costly, and
// records every batch it is asked for (the points, in order), as a Python function would see them.
class RecordingCostlyField final : public Field {
 public:
  explicit RecordingCostlyField(const Field& f) : f_(f) { set_bounds(f.bounds()); }
  std::string type_name() const override { return f_.type_name(); }
  // True, or the answers of `script` in turn (the last one repeated) while it has any.
  bool costly_calls() const override {
    if (script.empty()) return true;
    return script[std::min(asked++, script.size() - 1)];
  }
  std::vector<bool> script;
  mutable std::size_t asked = 0;
  std::optional<double> lipschitz_bound() const override { return f_.lipschitz_bound(); }
  std::vector<std::vector<Vec3>> batches() const {
    std::lock_guard lock(mutex_);
    return batches_;
  }
  // A call with this point among its points throws.
  std::optional<Vec3> poison;

 protected:
  double eval_value(const Vec3& p) const override {
    double v;
    eval_values(&p, &v, 1);
    return v;
  }
  double eval_value_gradient(const Vec3& p, Vec3& g) const override {
    double v;
    eval_values_gradients(&p, &v, &g, 1);
    return v;
  }
  double eval_gradient_hessian(const Vec3& p, Vec3& g, Mat3& h) const override {
    double v;
    eval_gradients_hessians(&p, &v, &g, &h, 1);
    return v;
  }
  void eval_values(const Vec3* p, double* out, std::size_t n) const override {
    record(p, n);
    f_.values(p, out, n);
  }
  void eval_values_gradients(const Vec3* p, double* v, Vec3* g, std::size_t n) const override {
    record(p, n);
    f_.values_gradients(p, v, g, n);
  }
  void eval_gradients_hessians(const Vec3* p, double* v, Vec3* g, Mat3* h, std::size_t n) const override {
    record(p, n);
    f_.gradients_hessians(p, v, g, h, n);
  }
  // One call for the three kinds, as a Python function makes it: one batch, recorded once.
  void eval_together(const Batch& plain, const Batch& with_gradients, const Batch& with_hessians) const override {
    std::vector<Vec3> all(plain.points, plain.points + plain.n);
    all.insert(all.end(), with_gradients.points, with_gradients.points + with_gradients.n);
    all.insert(all.end(), with_hessians.points, with_hessians.points + with_hessians.n);
    record(all.data(), all.size());
    if (plain.n > 0) f_.values(plain.points, plain.values, plain.n);
    if (with_gradients.n > 0)
      f_.values_gradients(with_gradients.points, with_gradients.values, with_gradients.gradients, with_gradients.n);
    if (with_hessians.n > 0)
      f_.gradients_hessians(with_hessians.points, with_hessians.values, with_hessians.gradients,
                            with_hessians.hessians, with_hessians.n);
  }

 private:
  void record(const Vec3* p, std::size_t n) const {
    std::lock_guard lock(mutex_);
    batches_.emplace_back(p, p + n);
    for (std::size_t i = 0; i < n; ++i)
      if (poison && p[i] == *poison) throw std::runtime_error("the poisoned point");
  }
  const Field& f_;
  mutable std::mutex mutex_;
  mutable std::vector<std::vector<Vec3>> batches_;
};

// Task i's k-th evaluation: its kind and points depend on i and k only, and so many of them
// (1 + i % 7) that the tasks end at different times.
Vec3 task_point(std::size_t i, std::size_t k, std::size_t j) {
  return Vec3(0.1 * static_cast<double>(i % 11) - 0.5, 0.07 * static_cast<double>(k) - 0.3,
              0.05 * static_cast<double>(j) + 0.01 * static_cast<double>(i));
}
std::size_t task_evaluations(std::size_t i) { return 1 + i % 7; }

// Every answer of task i, checked against the field's own.
void lockstep_task(const Field& view, const Field& direct, std::size_t i, std::vector<int>& wrong) {
  for (std::size_t k = 0; k < task_evaluations(i); ++k) {
    std::vector<Vec3> p;
    for (std::size_t j = 0; j < 1 + (i + k) % 3; ++j) p.push_back(task_point(i, k, j));
    const std::size_t n = p.size();
    // Zero where a kind leaves them: the comparison below covers every output.
    std::vector<double> v(n, 0.0), w(n, 0.0);
    std::vector<Vec3> g(n, Vec3::Zero()), gw(n, Vec3::Zero());
    std::vector<Mat3> h(n, Mat3::Zero()), hw(n, Mat3::Zero());
    switch ((i + k) % 4) {
      case 0:
        v.assign(1, view.value(p[0]));
        w.assign(1, direct.value(p[0]));
        break;
      case 1:
        view.values(p.data(), v.data(), n);
        direct.values(p.data(), w.data(), n);
        break;
      case 2:
        view.values_gradients(p.data(), v.data(), g.data(), n);
        direct.values_gradients(p.data(), w.data(), gw.data(), n);
        break;
      default:
        view.gradients_hessians(p.data(), v.data(), g.data(), h.data(), n);
        direct.gradients_hessians(p.data(), w.data(), gw.data(), hw.data(), n);
    }
    for (std::size_t j = 0; j < v.size(); ++j)
      if (!test::same_bits(v[j], w[j]) || !test::same_bits(g[j], gw[j]) || !test::same_bits(h[j], hw[j])) ++wrong[i];
  }
}

TEST(Lockstep, EveryTaskGetsTheFieldsOwnAnswersInTheSameBatchesOnEveryRun) {
  const auto torus = test::field_from_json(R"({"type": "torus", "major_radius": 1, "minor_radius": 0.4})");
  // More tasks than carriers, so that carriers run several one after another.
  const std::size_t n = kLockstepTasks + 37;
  std::vector<std::vector<std::vector<Vec3>>> runs;
  // Twice: the same batches.
  for (int run = 0; run < 2; ++run) {
    const RecordingCostlyField costly(*torus);
    std::vector<int> wrong(n, 0);
    const LockstepReport report = run_in_lockstep(
        costly, n, [&](const Field& view, std::size_t i) { lockstep_task(view, *torus, i, wrong); });
    for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(wrong[i], 0) << "task " << i;
    EXPECT_EQ(report.carriers, kLockstepTasks);
    const auto batches = costly.batches();
    EXPECT_EQ(report.batches, batches.size());
    // Carrier c runs tasks c and c + 64: at most 7 + 7 evaluations each, one call each round for
    // every kind asked (Field::evaluate_together), against one a task's evaluation one task at a
    // time.
    std::size_t evaluations = 0;
    for (std::size_t i = 0; i < n; ++i) evaluations += task_evaluations(i);
    EXPECT_LE(batches.size(), 14u);
    EXPECT_LT(batches.size() * 25, evaluations);
    runs.push_back(batches);
  }
  ASSERT_EQ(runs[0].size(), runs[1].size());
  for (std::size_t b = 0; b < runs[0].size(); ++b) {
    ASSERT_EQ(runs[0][b].size(), runs[1][b].size()) << "batch " << b;
    for (std::size_t j = 0; j < runs[0][b].size(); ++j) ASSERT_TRUE(test::same_bits(runs[0][b][j], runs[1][b][j]));
  }
}

TEST(Lockstep, AFailingCallFailsItsRoundsRequestsOnlyAndTheLowestTasksErrorIsThrown) {
  const auto sphere = test::field_from_json(R"({"type": "sphere", "radius": 1})");
  RecordingCostlyField costly(*sphere);
  costly.poison = Vec3(0.5, 0.5, 0.5);
  std::vector<int> failed(10, 0), finished(10, 0);
  // The even tasks make one evaluation. At their second, tasks 3 and 7 ask for values at the
  // poisoned point, the other odd tasks for gradients: another kind, in the same call.
  try {
    run_in_lockstep(costly, 10, [&](const Field& view, std::size_t i) {
      try {
        view.value(Vec3(0.1 * static_cast<double>(i), 0, 0));
        if (i % 2 == 1) {
          if (i == 3 || i == 7) view.value(*costly.poison);
          else view.gradient(Vec3(0, 0.1, 0));
          view.value(Vec3(0, 0, 0.1));
        }
        ++finished[i];
      } catch (const std::runtime_error&) {
        ++failed[i];
        if (i >= 3) throw std::runtime_error("task " + std::to_string(i));  // escapes
      }
    });
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "task 3");  // the lowest of those that threw, not the first in time
  }
  // The second round's call failed for every odd task; the even ones had ended before it.
  for (std::size_t i = 0; i < 10; ++i) {
    EXPECT_EQ(failed[i], i % 2) << "task " << i;
    EXPECT_EQ(finished[i], 1 - i % 2) << "task " << i;
  }
}

// The torus of python/README.md's example, as a costly field (a Python function's stand-in).
const char* const kReadmeTorus = R"({"type": "expression", "value": "(sqrt(x^2+y^2)-1)^2 + z^2 - 0.09",
                                     "bounds": [[-1.5, -1.5, -0.5], [1.5, 1.5, 0.5]]})";

TEST(Lockstep, TheSeamsAndBlocksOfALockstepRunAreThoseMadeOneAfterAnother) {
  const auto torus = test::field_from_json(kReadmeTorus);
  RecordingCostlyField costly(*torus);
  AdaptiveOptions o;
  o.factor = 8;
  o.blocks = true;
  o.threads = 2;
  Settings settings = resolve_settings(costly, o);
  const SeedGridStage seeds = sample_seed_grid_stage(costly, o, settings);
  settings.hash_cell = seeds.hash_cell;
  const BlockMeshing together = mesh_blocks(costly, o, settings, seeds);
  ASSERT_TRUE(together.mesh) << together.report.fallback;
  EXPECT_GT(together.report.lockstep_tasks, 16u);
  // A costly field's layout (mesh_blocks asks first), then its faces and blocks one after another.
  costly.script = {true, false, false};
  const BlockMeshing alone = mesh_blocks(costly, o, settings, seeds);
  ASSERT_EQ(costly.asked, 3u);
  ASSERT_TRUE(alone.mesh) << alone.report.fallback;
  EXPECT_EQ(alone.report.lockstep_tasks, 0u);
  EXPECT_EQ(alone.report.blocks, together.report.blocks);
  EXPECT_EQ(alone.report.seam_vertices, together.report.seam_vertices);
  test::expect_same_mesh(together.mesh->mesh, alone.mesh->mesh);
}

TEST(Lockstep, ACostlyFieldIsMeshedInBlocksUnlessTrackingAloneIsAskedFor) {
  // Blocks in lockstep make a sixth to a twentieth of a Python function's calls (python/README.md):
  // the default (AdaptiveOptions::blocks unset), as for any other field. Until December 2026 a
  // black box with C1 seams (a rounded box) took far longer in blocks, and the caller chose.
  const auto torus = test::field_from_json(kReadmeTorus);
  const RecordingCostlyField costly(*torus);
  AdaptiveOptions o;
  o.factor = 8;
  const PolygonizeResult r = polygonize_adaptive(costly, o);
  EXPECT_TRUE(r.stats.adaptive->blocks.requested);
  EXPECT_TRUE(r.stats.adaptive->blocks.used) << r.stats.adaptive->blocks.fallback;
  EXPECT_GT(r.stats.adaptive->blocks.lockstep_batches, 0u);
  o.blocks = false;
  const PolygonizeResult alone = polygonize_adaptive(costly, o);
  EXPECT_FALSE(alone.stats.adaptive->blocks.requested);
  EXPECT_FALSE(alone.stats.adaptive->blocks.used);
  EXPECT_EQ(alone.stats.adaptive->blocks.lockstep_batches, 0u);
}

TEST(Lockstep, ACostlyFieldsBlocksMeshInLockstepSoundAndTheSameInAnyOrder) {
  const auto torus = test::field_from_json(kReadmeTorus);
  const RecordingCostlyField costly(*torus);
  AdaptiveOptions o;
  o.factor = 8;
  o.blocks = true;
  const PolygonizeResult r = polygonize_adaptive(costly, o);
  const BlocksReport& b = r.stats.adaptive->blocks;
  ASSERT_TRUE(b.used) << b.fallback;
  EXPECT_GE(b.blocks[0] * b.blocks[1] * b.blocks[2], 32);
  // The most carriers of either phase: the faces' (more than 64 here) and the blocks'.
  EXPECT_GE(b.meshed_blocks, 32u);
  EXPECT_EQ(b.lockstep_tasks, kLockstepTasks);
  EXPECT_GT(b.lockstep_batches, 0u);
  const MeshTopology t = analyze_topology(r.mesh);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.genus, 1);
  // Issue 58's bound on the calls of a costly field is 0.5 per vertex (a Python function at about
  // 5 tracked alone); with one call a round for every kind asked (Field::evaluate_together), 0.21
  // (0.38 with a call for each kind).
  const double calls_per_vertex = static_cast<double>(costly.batches().size()) / r.mesh.positions.size();
  std::cout << r.mesh.positions.size() << " vertices, " << costly.batches().size() << " calls ("
            << b.lockstep_batches << " gathered), " << calls_per_vertex << " per vertex\n";
  EXPECT_LE(calls_per_vertex, 0.3);
  // A seam's traced point looks across it (four Hessians) only where the point before it did not,
  // or found something there, or the curvature changed (SeamTracer::target): on this torus every
  // second point. Looking from every point made 3.8 Hessians a vertex; 2.7 now.
  const double hessians_per_vertex =
      static_cast<double>(r.stats.field_evaluations.gradient_hessian) / static_cast<double>(r.mesh.positions.size());
  EXPECT_LE(hessians_per_vertex, 3.2);

  // The blocks in other orders: other carriers, other batches, the same mesh.
  Settings settings = resolve_settings(costly, o);
  const SeedGridStage seeds = sample_seed_grid_stage(costly, o, settings);
  settings.hash_cell = seeds.hash_cell;
  const BlockMeshing first = mesh_blocks(costly, o, settings, seeds);
  ASSERT_TRUE(first.mesh) << first.report.fallback;
  for (const std::uint64_t shuffle : {1u, 2u}) {
    const BlockMeshing other = mesh_blocks(costly, o, settings, seeds, nullptr, shuffle);
    ASSERT_TRUE(other.mesh) << other.report.fallback;
    test::expect_same_mesh(first.mesh->mesh, other.mesh->mesh);
  }
}

TEST(Lockstep, ABlackBoxsRoundedEdgesAreSeenFromTheSeamsBesideThem) {
  // Quilez's rounded box as a costly black box (its branch data hidden, as a Python function's
  // is) at factor 5: 3 x 3 x 3 blocks, their cuts at +-0.378, one of them 0.022 from where a flat
  // face meets a rounded edge and along it. A seam on that strip took the flat face's long edges
  // from the curvature under it, the blocks' fronts from it met the rounded edge with slivers, and
  // the band's repair, one point a call, took 12 calls a vertex (a smallest angle of 20.4 degrees;
  // tracked alone 3.5 calls a vertex, 30 degrees). The seam tracer now looks across the seam
  // (SeamTracer::target, blocks.cpp).
  const auto box = test::field_from_json(
      R"({"type": "expression", "value": "sqrt(max(abs(x)-0.6,0)^2+max(abs(y)-0.4,0)^2+max(abs(z)-0.3,0)^2)+min(max(abs(x)-0.6,max(abs(y)-0.4,abs(z)-0.3)),0)-0.15",
          "bounds": [[-1.1, -1.1, -1.1], [1.1, 1.1, 1.1]]})");
  const test::Rewrapped black_box(*box, /*smooth=*/false, /*thread_safe=*/true);
  const RecordingCostlyField costly(black_box);
  AdaptiveOptions o;
  o.factor = 5;
  o.blocks = true;
  o.creases = CreaseHandling::Ignore;
  const PolygonizeResult r = polygonize_adaptive(costly, o);
  const BlocksReport& b = r.stats.adaptive->blocks;
  ASSERT_TRUE(b.used) << b.fallback;
  EXPECT_EQ(b.blocks, (std::array<int, 3>{3, 3, 3}));
  const MeshTopology t = analyze_topology(r.mesh);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.genus, 0);
  const double calls_per_vertex = static_cast<double>(costly.batches().size()) / r.mesh.positions.size();
  const double smallest = min_angle_degrees(r.mesh);
  std::cout << r.mesh.triangles.size() << " triangles, " << calls_per_vertex << " calls a vertex, smallest angle "
            << smallest << "\n";
  EXPECT_LE(calls_per_vertex, 1.5);
  EXPECT_GE(smallest, 28.0);
}

}  // namespace
}  // namespace cdp::adaptive
