// Front angles (paper section 5: "we compute this front angle using the adjacent points in
// the front"), measured in the tangent plane of the point so that they stay meaningful on a
// curved front.
#include "tracker.h"

#include <cmath>
#include <numbers>

namespace cdp::adaptive {

double Tracker::sector_position(int node, const Vec3& x) const {
  const FrontNode& n = fs_.nodes[node];
  const Vec3& p = mesh_.positions[n.vertex];
  const Vec3& N = mesh_.normals[n.vertex];
  Vec3 d0 = mesh_.positions[fs_.nodes[n.next].vertex] - p;
  d0 -= N * N.dot(d0);
  Vec3 d1 = x - p;
  d1 -= N * N.dot(d1);
  // The unmeshed region lies to the left of next -> ... seen from outside, i.e. counter-clockwise
  // from the direction of next around the outward normal.
  double t = std::atan2(N.dot(d0.cross(d1)), d0.dot(d1));
  if (t < 0) t += 2 * std::numbers::pi;
  return t;
}

double Tracker::front_angle(int node) const {
  return sector_position(node, mesh_.positions[fs_.nodes[fs_.nodes[node].prev].vertex]);
}

bool Tracker::in_sector(int node, const Vec3& x, double margin) const {
  const double t = sector_position(node, x);
  return t > margin && t < fs_.nodes[node].angle - margin;
}

}  // namespace cdp::adaptive
