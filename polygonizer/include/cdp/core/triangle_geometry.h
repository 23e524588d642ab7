// Small exact-as-double geometric queries on single triangles, shared by the polygonizer's
// seeding (coverage of sign changes by the mesh) and the metrics.
#pragma once

#include <cdp/core/field.h>

namespace cdp {

// The point of triangle (a, b, c) nearest to p (Ericson, Real-Time Collision Detection, 5.1.5).
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

// Whether segment p-q meets triangle (a, b, c), boundaries included (a segment through a shared
// edge or vertex meets both triangles there). A segment lying in the triangle's plane counts
// as missing it; degenerate triangles are missed.
bool segment_meets_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c);

// The length of the longest edge of triangle (a, b, c).
double longest_edge(const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace cdp
