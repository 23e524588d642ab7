// Whether the surface F = 0 passes through a point of the zero set, or F only touches zero there.
// Where two solids touch (a box standing flush on another, a table's leg under its top), their
// union's F is zero on the common face and negative on either side of it: part of the zero set,
// no surface. Shared by the crease tracer (a crease's faces), the crease layout (a patch's side)
// and the adaptive polygonizer's seeding (a sign change's point).
#pragma once

#include <cdp/core/field.h>

namespace cdp {

// Whether F changes sign between p - depth n and p + depth n (n: a unit normal at p). `depth`
// must stay far below any wedge of solid or air at p (a sharp crease nearby) and far above the
// tolerance p was found to.
inline bool surface_passes(const Field& field, const Vec3& p, const Vec3& n, double depth) {
  return (field.value(p + depth * n) > 0) != (field.value(p - depth * n) > 0);
}

}  // namespace cdp
