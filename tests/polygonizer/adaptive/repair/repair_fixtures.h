// What the tests of the repair's algorithms share (repair_*_test.cpp): the unit sphere, whose
// distances and normals are known in closed form, an icosphere on it as the mesh to repair,
// and a context over both.
#pragma once

#include "src/adaptive/repair_context.h"

#include <cdp/core/mesh_angles.h>
#include <cdp/core/mesh_topology.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>

#include "common/reference_meshes.h"
#include "common/test_fields.h"

namespace cdp::adaptive::repair::test_repair {

inline std::unique_ptr<Field> unit_sphere() { return test::field_from_json(R"({"type": "sphere", "radius": 1})"); }

inline QualityOptions sphere_options() {
  QualityOptions o;
  o.improve_below = 30 * std::numbers::pi / 180;
  o.diagonal = 2 * std::sqrt(3.0);
  o.min_edge = 1e-3;
  o.threads = 1;
  return o;
}

// v moved by `step` along the surface: onto the unit sphere, with its radial normal.
inline void move_on_sphere(Mesh& mesh, int v, const Vec3& step) {
  mesh.positions[v] = (mesh.positions[v] + step).normalized();
  mesh.normals[v] = mesh.positions[v];
}

// The largest distance of a vertex from the unit sphere.
inline double off_sphere(const Mesh& mesh) {
  double worst = 0;
  for (const Vec3& p : mesh.positions) worst = std::max(worst, std::abs(p.norm() - 1));
  return worst;
}

// Closed, oriented, manifold, outward, one sphere (genus 0, one component).
inline void expect_a_sphere(const Mesh& mesh) {
  const MeshTopology t = analyze_topology(mesh);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.genus, 0);
}

}  // namespace cdp::adaptive::repair::test_repair
