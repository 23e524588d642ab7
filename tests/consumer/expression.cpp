// The README's C++ example, built against the installed package: an expression meshed and
// written to a file (cdp::core and cdp::io). Exit 0 and one line on success.
#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/models/expression.h>
#include <cdp/io/mesh_io.h>

#include <cstdio>

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  // --- README: begin ---
  const cdp::Expression torus("(sqrt(x^2 + y^2) - 1)^2 + z^2 - 0.3^2", cdp::Box{{-1.5, -1.5, -0.5}, {1.5, 1.5, 0.5}});
  cdp::AdaptiveOptions options;  // every field documented in adaptive_polygonizer.h
  options.factor = 3;            // edge = smallest radius of curvature / 3
  const cdp::PolygonizeResult result = cdp::polygonize_adaptive(torus, options);
  cdp::write_mesh(result.mesh, argv[1]);  // .ply, .obj, .off or .stl
  // --- README: end ---
  std::printf("consumer: torus expression meshed, %zu triangles, written\n", result.mesh.num_triangles());
  return result.mesh.num_triangles() > 100 ? 0 : 1;
}
