#include <cdp/core/errors.h>
#include <cdp/core/oriented_points.h>

#include <cmath>
#include <limits>
#include <tuple>

namespace cdp {

OrientedPoints oriented_points_from_mesh(const Mesh& mesh, const std::string& source) {
  const std::size_t nv = mesh.positions.size();
  std::vector<Vec3> sum(nv, Vec3::Zero());
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const auto& t = mesh.triangles[f];
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || static_cast<std::size_t>(t[k]) >= nv)
        throw InvalidInputError(source + ": triangle " + std::to_string(f) + " has an out-of-range vertex index");
    const Vec3& a = mesh.positions[t[0]];
    const Vec3& b = mesh.positions[t[1]];
    const Vec3& c = mesh.positions[t[2]];
    // |(b - a) x (c - a)| is twice the area: summing these weights each face by its area.
    const Vec3 n = (b - a).cross(c - a);
    for (int k = 0; k < 3; ++k) sum[t[k]] += n;
  }
  OrientedPoints out;
  out.positions.reserve(nv);
  out.normals.reserve(nv);
  for (std::size_t i = 0; i < nv; ++i) {
    const double len = sum[i].norm();
    if (!(len > 0) || !std::isfinite(len) || !mesh.positions[i].allFinite()) continue;
    out.positions.push_back(mesh.positions[i]);
    out.normals.push_back(sum[i] / len);
  }
  if (out.positions.empty()) throw InvalidInputError(source + ": no vertex with a defined normal (no triangles?)");
  return out;
}

std::vector<std::size_t> farthest_point_subset(const std::vector<Vec3>& positions, std::size_t n) {
  const std::size_t size = positions.size();
  if (n > size)
    throw InvalidInputError("farthest-point subset: asked for " + std::to_string(n) + " points of " +
                            std::to_string(size));
  std::vector<std::size_t> chosen;
  if (n == 0) return chosen;
  chosen.reserve(n);
  std::size_t first = 0;
  for (std::size_t i = 1; i < size; ++i) {
    const Vec3& p = positions[i];
    const Vec3& q = positions[first];
    if (std::tie(p.x(), p.y(), p.z()) < std::tie(q.x(), q.y(), q.z())) first = i;
  }
  // Squared distance of every point to the chosen set, updated after each choice.
  std::vector<double> d2(size, std::numeric_limits<double>::infinity());
  std::size_t next = first;
  for (std::size_t k = 0; k < n; ++k) {
    chosen.push_back(next);
    const Vec3 c = positions[next];
    double best = -1;
    std::size_t best_i = 0;
    for (std::size_t i = 0; i < size; ++i) {
      const double d = (positions[i] - c).squaredNorm();
      if (d < d2[i]) d2[i] = d;
      if (d2[i] > best) {  // strict: ties keep the lowest index
        best = d2[i];
        best_i = i;
      }
    }
    next = best_i;
  }
  return chosen;
}

OrientedPoints select_points(const OrientedPoints& points, const std::vector<std::size_t>& indices) {
  OrientedPoints out;
  out.positions.reserve(indices.size());
  out.normals.reserve(indices.size());
  for (std::size_t i : indices) {
    out.positions.push_back(points.positions.at(i));
    out.normals.push_back(points.normals.at(i));
  }
  return out;
}

Box bounding_box(const std::vector<Vec3>& positions) {
  Box box{Vec3::Constant(std::numeric_limits<double>::infinity()), Vec3::Constant(-std::numeric_limits<double>::infinity())};
  for (const Vec3& p : positions) {
    box.min = box.min.cwiseMin(p);
    box.max = box.max.cwiseMax(p);
  }
  return box;
}

}  // namespace cdp
