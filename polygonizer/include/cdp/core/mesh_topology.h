// What a user relies on in a mesh: closed, oriented, manifold, components, genus.
// Works on the raw index arrays, so it also detects what OpenMesh would refuse to load.
#pragma once

#include <cdp/core/cancel.h>
#include <cdp/core/mesh.h>

namespace cdp {

struct MeshTopology {
  std::size_t vertices = 0;            // referenced by at least one triangle
  std::size_t unreferenced_vertices = 0;
  std::size_t triangles = 0;
  std::size_t edges = 0;
  std::size_t boundary_edges = 0;      // used by one triangle
  std::size_t nonmanifold_edges = 0;   // used by three or more triangles
  std::size_t misoriented_edges = 0;   // two triangles traverse the edge in the same direction
  std::size_t nonmanifold_vertices = 0;  // one-ring is not a single fan
  std::size_t degenerate_triangles = 0;  // repeated index, or twice its area at most 1e-12 of its longest edge squared
  std::size_t duplicate_triangles = 0;   // same vertex set as another triangle
  std::size_t components = 0;            // connected through shared edges
  int euler_characteristic = 0;          // V - E + F
  int genus = -1;                        // total genus when closed, oriented and manifold; -1 otherwise
  double signed_volume = 0;              // positive when oriented outward
  double area = 0;

  bool closed() const { return boundary_edges == 0; }
  bool edge_manifold() const { return nonmanifold_edges == 0; }
  bool vertex_manifold() const { return nonmanifold_vertices == 0; }
  bool oriented() const { return misoriented_edges == 0; }
  // Closed, oriented, edge- and vertex-manifold, no degenerate or duplicate triangles, outward.
  bool watertight() const {
    return closed() && edge_manifold() && vertex_manifold() && oriented() && degenerate_triangles == 0 &&
           duplicate_triangles == 0 && signed_volume > 0;
  }
};

// Whether triangle f is one MeshTopology::degenerate_triangles counts.
// \pre f < mesh.triangles.size() and its indices are in [0, mesh.num_vertices()).
bool triangle_is_zero_area(const Mesh& mesh, std::size_t f);

// \pre every triangle index is in [0, mesh.num_vertices()).
// \return the counts above; genus -1 unless the mesh has triangles and is closed, oriented and
//         manifold.
MeshTopology analyze_topology(const Mesh& mesh);
// The same, polling `cancel` every few thousand triangles and vertices.
// \throw CancelledError once cancel is cancelled.
MeshTopology analyze_topology(const Mesh& mesh, const CancelToken& cancel);

}  // namespace cdp
