// Meshes a sphere through the installed library and checks the mesh: what a user's first
// program does. Exit 0 and one line on success.
#include <cdp/core/adaptive_polygonizer.h>
#include <cdp/core/mesh_topology.h>
#include <cdp/core/models/analytic.h>

#include <cstdio>

int main() {
  const cdp::Sphere sphere(cdp::Vec3::Zero(), 1.0);
  cdp::AdaptiveOptions options;
  options.factor = 2;
  const cdp::PolygonizeResult r = cdp::polygonize_adaptive(sphere, options);
  const cdp::MeshTopology t = cdp::analyze_topology(r.mesh);
  if (!t.closed() || t.genus != 0 || r.mesh.num_triangles() < 100) {
    std::printf("consumer: bad sphere mesh (%zu triangles)\n", r.mesh.num_triangles());
    return 1;
  }
  std::printf("consumer: sphere meshed, %zu triangles, closed, genus 0\n", r.mesh.num_triangles());
  return 0;
}
