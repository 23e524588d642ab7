// Seeds on every component of the surface inside the field's box, from sign changes of F on a
// coarse grid. A component that fits between grid points (smaller than about one cell) can be
// missed; raise `resolution` to catch smaller ones.
#pragma once

#include <polygonizer/field.h>

#include <vector>

namespace cdp {

struct SeedOptions {
  int resolution = 32;  // grid cells along the longest side of the box
  // Reject fields whose surface leaves the box (F < 0 on the box's boundary).
  bool require_closed_in_box = true;
};

struct SurfaceSeed {
  Vec3 point;      // on the surface (bisected along a grid edge, then Newton-projected)
  int cluster;     // seeds of one connected group of crossed cells share a cluster id
};

// Seeds in a deterministic order, clusters numbered from 0. Throws NoSurfaceError when the field
// is NaN on the grid, has no zero crossing, or (with require_closed_in_box) leaves the box.
std::vector<SurfaceSeed> find_surface_seeds(const Field& field, const SeedOptions& options = {});

}  // namespace cdp
