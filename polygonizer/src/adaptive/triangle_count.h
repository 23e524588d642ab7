// How many triangles the expansion of a front point produces (paper section 5).
#pragma once

#include <cdp/core/adaptive_polygonizer.h>

namespace cdp::adaptive {

// theta: front angle in radians; neighbour_distance: distance between the point's two front
// neighbours; delta: edge length. A result of 0 or 1 means: close the angle with the single
// triangle (prev, point, next), creating no new point.
int triangle_count(TriangleCountRule rule, double theta, double neighbour_distance, double delta);

}  // namespace cdp::adaptive
