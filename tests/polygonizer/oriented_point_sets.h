// Oriented points sampled from closed-form surfaces, for the data-driven model tests.
#pragma once

#include <cdp/core/oriented_points.h>

#include <cmath>

namespace cdp::test {

// n points of the sphere of radius r about c, spread by the Fibonacci spiral; outward normals.
inline OrientedPoints sphere_points(int n, double r = 1.0, const Vec3& c = Vec3::Zero()) {
  OrientedPoints pts;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / n;
    const double rho = std::sqrt(1.0 - z * z);
    const Vec3 u(rho * std::cos(golden * i), rho * std::sin(golden * i), z);
    pts.positions.push_back(c + r * u);
    pts.normals.push_back(u);
  }
  return pts;
}

// The torus of radii R > r about the z axis on an nu x nv grid of its angles; outward normals.
inline OrientedPoints torus_points(int nu, int nv, double R = 1.0, double r = 0.4) {
  OrientedPoints pts;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * M_PI * (i + 0.5 * (j % 2)) / nu, v = 2 * M_PI * j / nv;
      const Vec3 n(std::cos(v) * std::cos(u), std::cos(v) * std::sin(u), std::sin(v));
      pts.positions.push_back(Vec3(R * std::cos(u), R * std::sin(u), 0.0) + r * n);
      pts.normals.push_back(n);
    }
  return pts;
}

// Distance of p from the torus of radii R, r about the z axis (signed, positive outside).
inline double torus_distance(const Vec3& p, double R = 1.0, double r = 0.4) {
  return std::hypot(std::hypot(p.x(), p.y()) - R, p.z()) - r;
}

}  // namespace cdp::test
