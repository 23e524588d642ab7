// Helpers shared by the Marching Cubes and Marching Tetrahedra tests: a random field that
// exercises every cube case, and comparisons of meshes by geometry rather than by index.
#pragma once

#include <cdp/core/field.h>
#include <cdp/core/mesh.h>
#include <cdp/core/mesh_topology.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace cdp::test {

// Trilinear interpolation of random values in [-1, 1] on the integer lattice of spacing 1
// starting at `origin`, forced positive outside the ball of radius `radius` around the box
// centre so that the surface is closed inside the box. On a polygonizer lattice with the same
// origin and cell 1, every corner sign pattern and face ambiguity occurs, and the field is
// linear along edges and bilinear on faces, as the asymptotic decider assumes.
class NoiseField : public Field {
 public:
  NoiseField(int n, unsigned seed) : n_(n), values_((n + 1) * (n + 1) * (n + 1)) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1);
    const double c = n / 2.0, radius = n / 2.0 - 1;
    for (int k = 0; k <= n; ++k)
      for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
          const double v = u(rng);
          const bool outside = Vec3(i - c, j - c, k - c).norm() > radius;
          values_[index(i, j, k)] = outside ? 1.0 : (v == 0 ? 0.5 : v);
        }
    set_bounds({Vec3::Zero(), Vec3::Constant(n)});
  }
  std::string type_name() const override { return "noise"; }

 protected:
  double eval_value(const Vec3& p) const override {
    Vec3 g;
    return eval_value_gradient(p, g);
  }
  double eval_value_gradient(const Vec3& p, Vec3& gradient) const override {
    int cell[3];
    double t[3];
    for (int a = 0; a < 3; ++a) {
      const double x = std::clamp(p[a], 0.0, static_cast<double>(n_));
      cell[a] = std::min(n_ - 1, static_cast<int>(std::floor(x)));
      t[a] = x - cell[a];
    }
    double value = 0;
    gradient.setZero();
    for (int c = 0; c < 8; ++c) {
      const int o[3] = {c & 1, (c >> 1) & 1, (c >> 2) & 1};
      const double v = values_[index(cell[0] + o[0], cell[1] + o[1], cell[2] + o[2])];
      double w[3], dw[3];
      for (int a = 0; a < 3; ++a) {
        w[a] = o[a] ? t[a] : 1 - t[a];
        dw[a] = o[a] ? 1 : -1;
      }
      value += v * w[0] * w[1] * w[2];
      gradient += v * Vec3(dw[0] * w[1] * w[2], w[0] * dw[1] * w[2], w[0] * w[1] * dw[2]);
    }
    return value;
  }
  double eval_gradient_hessian(const Vec3& p, Vec3& gradient, Mat3& hessian) const override {
    hessian.setZero();  // not used by the polygonizers under test
    return eval_value_gradient(p, gradient);
  }

 private:
  std::size_t index(int i, int j, int k) const { return (static_cast<std::size_t>(k) * (n_ + 1) + j) * (n_ + 1) + i; }
  int n_;
  std::vector<double> values_;
};

// A mesh's triangles as position triples, each rotated to start at its smallest vertex
// (keeping orientation), sorted: equal for meshes that differ only in vertex numbering.
inline std::vector<std::array<std::array<double, 3>, 3>> triangle_set(const Mesh& mesh) {
  std::vector<std::array<std::array<double, 3>, 3>> out;
  for (const auto& t : mesh.triangles) {
    std::array<std::array<double, 3>, 3> tri;
    for (int q = 0; q < 3; ++q) {
      const Vec3& p = mesh.positions[t[q]];
      tri[q] = {p.x(), p.y(), p.z()};
    }
    std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end()), tri.end());
    out.push_back(tri);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Closed, oriented outward, edge- and vertex-manifold, no duplicate triangles.
inline void expect_closed_manifold(const MeshTopology& t) {
  EXPECT_EQ(t.boundary_edges, 0u);
  EXPECT_EQ(t.nonmanifold_edges, 0u);
  EXPECT_EQ(t.misoriented_edges, 0u);
  EXPECT_EQ(t.nonmanifold_vertices, 0u);
  EXPECT_EQ(t.duplicate_triangles, 0u);
  EXPECT_EQ(t.unreferenced_vertices, 0u);
  EXPECT_GT(t.signed_volume, 0);
}

}  // namespace cdp::test

// The checks both methods must pass, written once.
#include <cdp/baselines/marching_options.h>
#include <cdp/core/polygonize_result.h>

namespace cdp::test {

using MarchingMethod = PolygonizeResult (*)(const Field&, const MarchingOptions&);

inline MarchingOptions marching_options(double cell, Traversal traversal) {
  MarchingOptions o;
  o.cell_size = cell;
  o.traversal = traversal;
  return o;
}

// Both traversals: closed, manifold, outward, with the expected components and genus, and the
// same triangles (the continuation visits exactly the crossed cubes of a connected lattice).
inline void expect_topology_both_traversals(MarchingMethod method, const Field& field, double cell,
                                            std::size_t components, int genus) {
  const PolygonizeResult cont = method(field, marching_options(cell, Traversal::Continuation));
  const PolygonizeResult grid = method(field, marching_options(cell, Traversal::Grid));
  for (const PolygonizeResult* r : {&cont, &grid}) {
    SCOPED_TRACE(r == &cont ? "continuation" : "grid");
    const MeshTopology t = analyze_topology(r->mesh);
    expect_closed_manifold(t);
    EXPECT_TRUE(t.watertight());  // also no degenerate triangles on these smooth fields
    EXPECT_EQ(t.components, components);
    EXPECT_EQ(t.genus, genus);
    EXPECT_EQ(r->stats.components, components);
    EXPECT_EQ(r->stats.triangles, r->mesh.num_triangles());
    EXPECT_EQ(r->stats.vertices, r->mesh.num_vertices());
    ASSERT_EQ(r->mesh.normals.size(), r->mesh.num_vertices());
    for (const Vec3& n : r->mesh.normals) EXPECT_NEAR(n.norm(), 1.0, 1e-9);
  }
  EXPECT_EQ(triangle_set(cont.mesh), triangle_set(grid.mesh));
  // One seed per component, each found by the seeds alone; every grid sign change reached.
  EXPECT_EQ(cont.stats.lattice->seeding->completion_starts, 0u);
  EXPECT_EQ(cont.stats.lattice->seeding->unreached_sign_changes, 0u);
  EXPECT_GT(cont.stats.lattice->seeding->sign_changes, 0u);
}

// A spherical shell 0.2 thick: two sheets, 0.2 apart, inside one cluster of seed-grid cells.
inline constexpr const char* kThinShell =
    R"({"type": "expression", "value": "abs(sqrt(x^2+y^2+z^2)-1)-0.1", "bounds": [[-1.5,-1.5,-1.5],[1.5,1.5,1.5]]})";

// Random Wyvill blobs (the hard-surface suite's random_blobs_16 and _12, rounded) with three and
// two components, two of which come within a seed cell of each other.
inline constexpr const char* kCloseBlobs3 =
    R"({"type": "blobs", "kernel": "wyvill", "threshold": 0.3, "blobs": [)"
    R"({"center": [0.02232, 1.571, 0.246], "radius": 0.9511}, {"center": [-1.315, 0.3848, -0.3526], "radius": 0.7637},)"
    R"( {"center": [0.8625, 0.7516, 0.8446], "radius": 0.7065}]})";
inline constexpr const char* kCloseBlobs2 =
    R"({"type": "blobs", "kernel": "wyvill", "threshold": 0.3, "blobs": [)"
    R"({"center": [1.12, -0.5955, 0.6642], "radius": 0.9859}, {"center": [1.415, -0.7914, 0.3487], "radius": 0.9835},)"
    R"( {"center": [0.8659, 0.02968, -1.011], "radius": 1.163}, {"center": [0.4053, 1.269, -1.216], "radius": 1.044}]})";

// Three tori (R 1, r 0.3) side by side in the plane z = 0, each overlapping the next, joined by
// min: genus 3, with crease curves where they meet, and lattice corners of cell 0.05 exactly on
// the surface (F = 0), which used to give triangles of area 2e-13 h^2.
inline constexpr const char* kThreeTori =
    R"json({"type": "expression", "value": "min(min(sqrt((sqrt((x+2.2)^2+y^2)-1)^2+z^2)-0.3, )json"
    R"json(sqrt((sqrt(x^2+y^2)-1)^2+z^2)-0.3), sqrt((sqrt((x-2.2)^2+y^2)-1)^2+z^2)-0.3)", )json"
    R"json("bounds": [[-3.6, -1.5, -0.5], [3.6, 1.5, 0.5]]})json";

// The smallest triangle area and the largest longest-to-shortest edge ratio of a mesh.
struct TriangleShapes {
  double min_area = std::numeric_limits<double>::infinity();
  double max_edge_ratio = 0;
};
inline TriangleShapes triangle_shapes(const Mesh& mesh) {
  TriangleShapes s;
  for (const auto& t : mesh.triangles) {
    const Vec3 &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
    s.min_area = std::min(s.min_area, 0.5 * (b - a).cross(c - a).norm());
    const double l[3] = {(b - a).norm(), (c - b).norm(), (a - c).norm()};
    s.max_edge_ratio = std::max(s.max_edge_ratio, *std::max_element(l, l + 3) / *std::min_element(l, l + 3));
  }
  return s;
}

// Where the surface passes through lattice corners, both traversals give a closed, oriented,
// manifold mesh of the right topology with no degenerate triangle. The collapse leaves no edge
// under h/100 and none over the cube diagonal sqrt(3) h (plus h/100), so the edge ratio stays
// under 175. Areas have no such bound (three vertices far apart can be nearly collinear); the
// threshold 1e-5 h^2 is a quarter of an equilateral triangle of side h/100, the smallest
// well-shaped triangle the collapse length allows, so a triangle below it is either a sliver
// from a root a hair from a corner or a collapse that did not happen. Measured on the tori:
// 1e-3 h^2 in Marching Cubes, 6e-5 h^2 in Marching Tetrahedra (before: 2e-13 h^2, ratios 10^6).
inline void expect_no_degenerate_triangles(MarchingMethod method, const Field& field, double cell,
                                           std::size_t components, int genus) {
  constexpr double kMinArea = 1e-5, kMaxEdgeRatio = 175;
  for (Traversal tr : {Traversal::Continuation, Traversal::Grid}) {
    SCOPED_TRACE(to_string(tr));
    const PolygonizeResult r = method(field, marching_options(cell, tr));
    const MeshTopology t = analyze_topology(r.mesh);
    expect_closed_manifold(t);
    EXPECT_TRUE(t.watertight());
    EXPECT_EQ(t.components, components);
    EXPECT_EQ(t.genus, genus);
    const TriangleShapes s = triangle_shapes(r.mesh);
    EXPECT_GT(s.min_area, kMinArea * cell * cell);
    EXPECT_LT(s.max_edge_ratio, kMaxEdgeRatio);
    EXPECT_GT(r.stats.lattice->collapsed_edges, 0u);
    EXPECT_EQ(r.stats.lattice->short_edges_left, 0u);
    EXPECT_EQ(r.stats.lattice->dropped_components, 0u);
  }
}

// A field whose seeds miss components (one seed per cluster of crossed seed-grid cells, and a
// cluster can hold several): the continuation still meshes them all, as the grid traversal does.
inline void expect_continuation_finds_what_the_seeds_miss(MarchingMethod method, const Field& field, double cell,
                                                          std::size_t components) {
  const PolygonizeResult cont = method(field, marching_options(cell, Traversal::Continuation));
  const PolygonizeResult grid = method(field, marching_options(cell, Traversal::Grid));
  EXPECT_EQ(analyze_topology(cont.mesh).components, components);
  EXPECT_EQ(cont.stats.components, components);
  EXPECT_TRUE(triangle_set(cont.mesh) == triangle_set(grid.mesh))
      << cont.mesh.num_triangles() << " triangles from the continuation, " << grid.mesh.num_triangles() << " from the grid";
  EXPECT_LT(cont.stats.lattice->seeding->seeds, components);  // the case is what it claims
  EXPECT_EQ(cont.stats.lattice->seeding->starts, components);
  EXPECT_EQ(cont.stats.lattice->seeding->completion_starts,
            components - cont.stats.lattice->seeding->seeds);
  EXPECT_EQ(cont.stats.lattice->seeding->unreached_sign_changes, 0u);
}

// Relative area errors at the given cells (continuation), for checking convergence.
inline std::vector<double> area_errors(MarchingMethod method, const Field& field, double exact,
                                       const std::vector<double>& cells) {
  std::vector<double> errors;
  for (double cell : cells) {
    const PolygonizeResult r = method(field, marching_options(cell, Traversal::Continuation));
    errors.push_back(std::abs(analyze_topology(r.mesh).area - exact) / exact);
  }
  return errors;
}

}  // namespace cdp::test
