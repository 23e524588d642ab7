// The data-driven models of the paper's experiments (bunny VIS with 800 constraints, horse MPU,
// Igea VIS with 4004 constraints) polygonize into closed meshes of one component and genus 0 (the
// scans' topology; the bunny's holes close) with every method, at a coarse resolution: no stray
// sheets inside their boxes, no surface leaving them. The adaptive polygonizer on the horse MPU at
// factor 1 stalls in its first run and meshes in the second, with rollbacks (see Known limits in
// docs/adaptive_polygonizer.md): the test checks that this path is the one taken.
#include <gtest/gtest.h>

#include <cdp/baselines/marching_cubes.h>
#include <cdp/baselines/marching_tetrahedra.h>
#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/mesh_topology.h>
#include <cdp/io/field_factory.h>

#include <map>
#include <memory>
#include <vector>

namespace cdp {
namespace {

struct DataCase {
  std::string file;
  std::string method;
};

std::ostream& operator<<(std::ostream& os, const DataCase& c) { return os << c.file << "/" << c.method; }

// One field per file for the whole suite: the Igea solve takes seconds.
const Field& field_of(const std::string& file) {
  static std::map<std::string, std::unique_ptr<Field>> cache;
  auto& f = cache[file];
  if (!f) f = load_field(std::string(CDP_SOURCE_DIR) + "/experiments/fields/" + file);
  return *f;
}

class DataDrivenMeshes : public ::testing::TestWithParam<DataCase> {};

TEST_P(DataDrivenMeshes, ClosedOneComponentGenusZero) {
  const Field& field = field_of(GetParam().file);
  PolygonizeResult r;
  if (GetParam().method == "adaptive") {
    AdaptiveOptions o;
    o.factor = 1;
    r = polygonize_adaptive(field, o);
  } else {
    MarchingOptions o;
    o.cell_size = field.bounds().size().maxCoeff() / 48;  // coarse
    r = GetParam().method == "mc" ? marching_cubes(field, o) : marching_tetrahedra(field, o);
  }
  const MeshTopology t = analyze_topology(r.mesh);
  RecordProperty("triangles", std::to_string(t.triangles));
  EXPECT_TRUE(t.closed()) << t.boundary_edges << " boundary edges";
  EXPECT_TRUE(t.edge_manifold());
  EXPECT_TRUE(t.oriented());
  EXPECT_GT(t.signed_volume, 0.0);
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.genus, 0);
}

// The rollbacks (rollback.cpp) undo a region where a front ran over finished mesh and mesh it
// again. The horse MPU at factor 1 needed them until expansions that fold across the surface
// were placed again (Tracker::folds_across), the bunny MPU at factor 3 until the grading
// became gentler (growth 1.25 per edge instead of 1.5), and the horse MPU at factor 5 until the
// side points (expand_point.cpp); the bunny MPU at tolerance 3e-3 still does: its first run
// stalls, the second undoes two regions.
TEST(DataDrivenRollbacks, TheBunnyMpuAtToleranceThreeThousandthsMeshesWithRollbacks) {
  AdaptiveOptions o;
  o.sizing = SizingMode::Tolerance;
  o.tolerance = 3e-3;
  // The mesh the rollbacks make has a mean longest/shortest edge of 1.2517, over issue 18's
  // 1.25, so by default it is made again with the front look-ahead, which meshes it without
  // rollbacks (1.2417, kept). A caller's bound on the triangles keeps the first mesh.
  o.max_triangles = 10'000'000;
  const PolygonizeResult r = polygonize_adaptive(field_of("bunny_mpu.json"), o);
  EXPECT_FALSE(r.stats.adaptive->recoveries.quality_rerun);
  EXPECT_TRUE(r.stats.adaptive->recoveries.remeshed_with_rollbacks);
  EXPECT_GT(r.stats.adaptive->tracker.rollbacks, 0u);
  const MeshTopology t = analyze_topology(r.mesh);
  EXPECT_TRUE(t.closed()) << t.boundary_edges << " boundary edges";
  EXPECT_TRUE(t.edge_manifold());
  EXPECT_TRUE(t.oriented());
  EXPECT_GT(t.signed_volume, 0.0);
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.genus, 0);
}

std::vector<DataCase> data_cases() {
  std::vector<DataCase> out;
  for (const char* file : {"bunny_vis800.json", "horse_mpu.json", "igea_vis4004.json"})
    for (const char* method : {"mc", "mt", "adaptive"}) out.push_back({file, method});
  // The Igea VIS-4004's cases carry the ctest label slow_under_sanitizers (tests/CMakeLists.txt):
  // they run the bunny VIS-800's code on five times the constraints (126 s of the sanitizer run
  // for the three).
  return out;
}

INSTANTIATE_TEST_SUITE_P(Models, DataDrivenMeshes, ::testing::ValuesIn(data_cases()),
                         [](const auto& info) {
                           std::string name = info.param.file.substr(0, info.param.file.find('.')) + "_" + info.param.method;
                           return name;
                         });

}  // namespace
}  // namespace cdp
