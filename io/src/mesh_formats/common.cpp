#include "mesh_formats/mesh_formats.h"

#include <cdp/core/errors.h>

#include <charconv>
#include <cmath>

namespace cdp::formats {

std::string shortest_decimal(double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, r.ptr);
}

void check_mesh(const Mesh& mesh, const std::string& name) {
  for (std::size_t i = 0; i < mesh.positions.size(); ++i)
    if (!mesh.positions[i].allFinite())
      throw InvalidInputError(name + ": vertex " + std::to_string(i) + " has a coordinate that is not a finite number");
  // Normals feed the Phong error and the shading: a NaN there would score or draw as nonsense.
  for (std::size_t i = 0; i < mesh.normals.size(); ++i)
    if (!mesh.normals[i].allFinite())
      throw InvalidInputError(name + ": vertex " + std::to_string(i) + " has a normal that is not a finite number");
  const auto nv = static_cast<long long>(mesh.positions.size());
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
    for (int k = 0; k < 3; ++k)
      if (mesh.triangles[f][k] < 0 || mesh.triangles[f][k] >= nv)
        throw InvalidInputError(name + ": face " + std::to_string(f) + " refers to vertex " +
                                std::to_string(mesh.triangles[f][k]) + " of " + std::to_string(nv));
  // Every use of a mesh file here (evaluation, pictures, oriented points for MPU) needs faces; a
  // file without any is an error rather than an empty result that scores as perfect.
  if (mesh.triangles.empty()) throw InvalidInputError(name + ": the mesh has no triangles");
}

}  // namespace cdp::formats
