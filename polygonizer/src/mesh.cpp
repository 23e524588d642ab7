#include <cdp/core/mesh.h>

#include <algorithm>

namespace cdp {

namespace {

// Normals are evaluated this many vertices per batched call: one call per batch for a field whose
// calls cost more than their arithmetic (a Python function), with its buffers (a difference
// stencil of 7 points a vertex there) near 3 MB.
constexpr std::size_t kNormalBatch = 16384;

}  // namespace

void compute_field_normals(const Field& field, Mesh& mesh) {
  const std::size_t n = mesh.positions.size();
  mesh.normals.resize(n);
  std::vector<double> values(std::min(n, kNormalBatch));
  std::vector<Vec3> gradients(values.size());
  for (std::size_t first = 0; first < n; first += kNormalBatch) {
    const std::size_t count = std::min(kNormalBatch, n - first);
    field.values_gradients(mesh.positions.data() + first, values.data(), gradients.data(), count);
    for (std::size_t i = 0; i < count; ++i) {
      const Vec3& g = gradients[i];
      const double norm = g.norm();
      mesh.normals[first + i] = norm > 0 ? Vec3(g / norm) : Vec3::Zero();
    }
  }
}

}  // namespace cdp
