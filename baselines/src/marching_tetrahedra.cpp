#include "lattice_mesher.h"

#include <cdp/baselines/marching_tetrahedra.h>

#include <vector>

namespace cdp {

namespace {

using marching::CubeTriangle;
using marching::LocalEdge;
using marching::corner_position;

LocalEdge local_edge(int a, int b) {
  // Freudenthal edges join corners whose offsets are ordered, so the smaller index is below.
  return a < b ? LocalEdge{static_cast<std::uint8_t>(a), static_cast<std::uint8_t>(b)}
               : LocalEdge{static_cast<std::uint8_t>(b), static_cast<std::uint8_t>(a)};
}

// Triangles of tetrahedron t for each set of inside corners (bit q: the tetrahedron's q-th
// corner is inside). A triangle is turned so that its normal points from the inside corners
// towards the outside ones; the crossing points on the edges only slide along the edges, which
// never flips a triangle whose vertices lie on three different edges of the tetrahedron, so
// deciding with edge midpoints is exact.
struct TetTable {
  std::array<std::array<std::vector<CubeTriangle>, 16>, 6> cases;
  TetTable() {
    for (int t = 0; t < 6; ++t)
      for (int mask = 1; mask < 15; ++mask) {
        std::vector<int> in, out;
        for (int q = 0; q < 4; ++q) ((mask >> q) & 1 ? in : out).push_back(kCubeTetrahedra[t][q]);
        Vec3 cin = Vec3::Zero(), cout = Vec3::Zero();
        for (int c : in) cin += corner_position(c) / static_cast<double>(in.size());
        for (int c : out) cout += corner_position(c) / static_cast<double>(out.size());
        const auto emit = [&](std::array<std::array<int, 2>, 3> e) {
          Vec3 mid[3];
          for (int q = 0; q < 3; ++q) mid[q] = 0.5 * (corner_position(e[q][0]) + corner_position(e[q][1]));
          if ((mid[1] - mid[0]).cross(mid[2] - mid[0]).dot(cout - cin) < 0) std::swap(e[1], e[2]);
          cases[t][mask].push_back({local_edge(e[0][0], e[0][1]), local_edge(e[1][0], e[1][1]),
                                    local_edge(e[2][0], e[2][1])});
        };
        if (in.size() == 1) {
          emit({{{in[0], out[0]}, {in[0], out[1]}, {in[0], out[2]}}});
        } else if (in.size() == 3) {
          emit({{{out[0], in[0]}, {out[0], in[1]}, {out[0], in[2]}}});
        } else {
          // The quad in0-out0, in0-out1, in1-out1, in1-out0; either diagonal joins two opposite
          // edges of the tetrahedron, so it is interior and no neighbour sees it.
          emit({{{in[0], out[0]}, {in[0], out[1]}, {in[1], out[1]}}});
          emit({{{in[0], out[0]}, {in[1], out[1]}, {in[1], out[0]}}});
        }
      }
  }
};

}  // namespace

PolygonizeResult marching_tetrahedra(const Field& field, const MarchingOptions& options) {
  static const TetTable table;
  const marching::CubeMesher mesher = [](const std::array<double, 8>& f, marching::CubeMesh& out) {
    for (int t = 0; t < 6; ++t) {
      int mask = 0;
      for (int q = 0; q < 4; ++q)
        if (f[kCubeTetrahedra[t][q]] < 0) mask |= 1 << q;
      for (const CubeTriangle& tri : table.cases[t][mask]) out.triangles.push_back(tri);
    }
  };
  return marching::run_marching(field, options, "mt", mesher, "");
}

}  // namespace cdp
