#include <cdp/raytrace/phong_normal.h>

#include <cmath>

#include <cdp/core/errors.h>

namespace cdp {

Vec3 phong_normal(const Mesh& mesh, int triangle, double u, double v) {
  if (mesh.normals.size() != mesh.positions.size())
    throw InvalidInputError("phong_normal: the mesh has no normal per vertex");
  const auto& t = mesh.triangles.at(static_cast<std::size_t>(triangle));
  const bool corners = mesh.corner_normals.size() == mesh.triangles.size();
  const auto& c = corners ? mesh.corner_normals[static_cast<std::size_t>(triangle)]
                          : std::array<Vec3, 3>{mesh.normals[t[0]], mesh.normals[t[1]], mesh.normals[t[2]]};
  const Vec3 n = (1.0 - u - v) * c[0] + u * c[1] + v * c[2];
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

namespace {
// A vertex is on a crease when two pieces are taken within this share of the diagonal: the
// Newton tolerance of crease vertices (1e-10) times the margin trace_creases uses (20), and a
// few more for the rounding of a mesh file.
constexpr double kCornerPieceRadius = 1e-8;
// The side of a crease a triangle lies on is the piece the field takes at this fraction of the
// way from the corner to the triangle's centroid: far beyond kCornerPieceRadius, close enough
// that no other crease passes in between.
constexpr double kTowardCentroid = 1e-3;
}  // namespace

std::vector<std::array<Vec3, 3>> field_corner_normals(const Field& field, const Mesh& mesh,
                                                      const std::vector<Vec3>& vertex_normals) {
  if (!field.has_pieces()) return {};
  const double radius = kCornerPieceRadius * field.bounds().diagonal();
  // The pieces at each vertex on a crease (none elsewhere), evaluated there.
  std::vector<std::vector<FieldPiece>> pieces(mesh.positions.size());
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    auto p = field.pieces(mesh.positions[v], radius);
    if (p.size() >= 2) pieces[v] = std::move(p);
  }
  std::vector<std::array<Vec3, 3>> out(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const Vec3 centroid = (mesh.positions[tri[0]] + mesh.positions[tri[1]] + mesh.positions[tri[2]]) / 3;
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<std::size_t>(tri[k]);
      out[t][k] = vertex_normals.at(v);
      if (pieces[v].empty()) continue;
      const Vec3 q = mesh.positions[v] + kTowardCentroid * (centroid - mesh.positions[v]);
      Vec3 g;
      field.value_gradient(q, g);
      g.normalize();
      // The piece at the vertex whose gradient points as the field's does there.
      double best = -2;
      for (const FieldPiece& piece : pieces[v]) {
        const double len = piece.gradient.norm();
        if (!(len > 0) || !std::isfinite(len)) continue;
        const Vec3 n = piece.gradient / len;
        const double agree = n.dot(g);
        if (agree > best) best = agree, out[t][k] = n;
      }
    }
  }
  return out;
}

}  // namespace cdp
