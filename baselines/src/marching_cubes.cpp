#include "lattice_mesher.h"

#include <cdp/baselines/cube_cases.h>
#include <cdp/baselines/marching_cubes.h>

namespace cdp {

namespace {

// Nielson & Hamann: on a face whose diagonals have opposite signs, the bilinear interpolant's
// saddle value (f00 f11 - f10 f01) / (f00 + f11 - f10 - f01) decides whether the inside corners
// connect. The face's corners are read in the order of kCubeFaces, which is the same from both
// cubes sharing it, so both compute the same bits and make the same decision.
bool saddle_inside(const std::array<double, 8>& f, int face) {
  const auto& c = kCubeFaces[face];
  const double f00 = f[c[0]], f10 = f[c[1]], f01 = f[c[2]], f11 = f[c[3]];
  const double saddle = (f00 * f11 - f10 * f01) / (f00 + f11 - f10 - f01);
  return saddle < 0;
}

std::uint8_t face_decisions(const std::array<double, 8>& f, std::uint8_t inside, FaceAmbiguity rule) {
  std::uint8_t join = 0;
  for (int face = 0; face < 6; ++face) {
    if (!face_is_ambiguous(inside, face)) continue;
    const bool joined = rule == FaceAmbiguity::JoinInside       ? true
                        : rule == FaceAmbiguity::SeparateInside ? false
                                                                : saddle_inside(f, face);
    if (joined) join |= 1 << face;
  }
  return join;
}

}  // namespace

PolygonizeResult marching_cubes(const Field& field, const MarchingOptions& options) {
  const FaceAmbiguity rule = options.face_ambiguity;
  cube_case(0, 0);  // generate the table before the clock of the polygonization matters
  const marching::CubeMesher mesher = [rule](const std::array<double, 8>& f, marching::CubeMesh& out) {
    std::uint8_t inside = 0;
    for (int c = 0; c < 8; ++c)
      if (f[c] < 0) inside |= 1 << c;
    if (inside == 0 || inside == 255) return;
    const CubeCase& cc = cube_case(inside, face_decisions(f, inside, rule));
    const auto local = [](int e) {
      return marching::LocalEdge{static_cast<std::uint8_t>(kCubeEdges[e][0]), static_cast<std::uint8_t>(kCubeEdges[e][1])};
    };
    // Centre vertices keep their polygon's number, so every polygon is listed (cheap: a few).
    bool any_centre = false;
    for (const auto& t : cc.triangles) {
      marching::CubeTriangle tri;
      for (int q = 0; q < 3; ++q) {
        if (t[q] >= kCubeCentreVertex) {
          tri[q] = {marching::kCentre, static_cast<std::uint8_t>(t[q] - kCubeCentreVertex)};
          any_centre = true;
        } else {
          tri[q] = local(t[q]);
        }
      }
      out.triangles.push_back(tri);
    }
    if (any_centre)
      for (const auto& poly : cc.polygons) {
        out.centres.emplace_back();
        for (int e : poly) out.centres.back().push_back(local(e));
      }
  };
  return marching::run_marching(field, options, "mc", mesher, to_string(rule));
}

}  // namespace cdp
