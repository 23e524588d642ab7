#include <cdp/core/mesh.h>

namespace cdp {

void compute_field_normals(const Field& field, Mesh& mesh) {
  mesh.normals.resize(mesh.positions.size());
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    const Vec3 g = field.gradient(mesh.positions[i]);
    const double n = g.norm();
    mesh.normals[i] = n > 0 ? Vec3(g / n) : Vec3::Zero();
  }
}

}  // namespace cdp
