// What one field evaluation of each kind costs at the points of a mesh: the price list that turns
// a polygonizer's evaluation counts (stats "field_evaluations") into the time it spent in the
// field, so that the time outside the field (the polygonizer's own bookkeeping) can be told
// apart. An estimate: the points are the mesh's vertices (the algorithms also evaluate off the
// surface, and in another order), and a shared machine adds noise, which the minimum over
// repetitions damps.
#pragma once

#include <cdp/core/field.h>
#include <cdp/core/mesh.h>

#include <cstddef>

namespace cdp {

struct FieldCost {
  double value_seconds = 0;            // per evaluation
  double value_gradient_seconds = 0;
  double gradient_hessian_seconds = 0;
  std::size_t points = 0;              // evaluated per kind and repetition
};

struct FieldCostOptions {
  // Vertices evaluated (evenly strided over the mesh's): enough for a stable mean on any model,
  // few enough to cost well under a second on the most expensive one (VIS-4004, about 20 us for
  // a Hessian).
  std::size_t max_points = 1000;
  // Each kind is timed this many times over the same points; the fastest pass counts.
  int repetitions = 3;
};

// Times single-point evaluations (as the polygonizers make them) at the mesh's vertices. Points
// where the field throws are skipped. Zero cost for a mesh without vertices.
// \return the seconds per evaluation of each kind in the fastest pass, over every
//         ceil(n / max_points)-th of the n vertices; zero also for max_points 0.
FieldCost measure_field_cost(const Field& field, const Mesh& mesh, const FieldCostOptions& options = {});

}  // namespace cdp
