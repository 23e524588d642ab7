#include <cdp/raytrace/phong_normal.h>

#include <cmath>

#include <cdp/core/errors.h>

namespace cdp {

Vec3 phong_normal(const Mesh& mesh, int triangle, double u, double v) {
  if (mesh.normals.size() != mesh.positions.size())
    throw InvalidInputError("phong_normal: the mesh has no normal per vertex");
  const auto& t = mesh.triangles.at(static_cast<std::size_t>(triangle));
  const Vec3 n = (1.0 - u - v) * mesh.normals[t[0]] + u * mesh.normals[t[1]] + v * mesh.normals[t[2]];
  const double len = n.norm();
  return len > 0.0 ? Vec3(n / len) : Vec3::Zero();
}

std::vector<Vec3> area_weighted_normals(const Mesh& mesh) {
  std::vector<Vec3> normals(mesh.positions.size(), Vec3::Zero());
  for (const auto& t : mesh.triangles) {
    // The cross product's length is twice the area: summing it weights by area.
    const Vec3 n = (mesh.positions[t[1]] - mesh.positions[t[0]]).cross(mesh.positions[t[2]] - mesh.positions[t[0]]);
    for (int i : t) normals[i] += n;
  }
  for (Vec3& n : normals) {
    const double len = n.norm();
    n = len > 0.0 ? Vec3(n / len) : Vec3::Zero();
  }
  return normals;
}

std::vector<Vec3> field_normals(const Field& field, const Mesh& mesh) {
  std::vector<Vec3> normals(mesh.positions.size(), Vec3::Zero());
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    Vec3 g;
    field.value_gradient(mesh.positions[i], g);
    const double len = g.norm();
    if (len > 0.0 && std::isfinite(len)) normals[i] = g / len;
  }
  return normals;
}

}  // namespace cdp
