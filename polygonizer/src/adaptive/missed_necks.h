// Necks and tunnels a finished mesh stepped over. Where the surface has a thin neck of solid or
// a narrow tunnel, the field has a saddle close to zero at its core: a critical point (grad F = 0)
// with |F| small. A front whose edges are longer than the neck is wide can pass over it without
// placing a vertex there, and the mesh comes out closed, manifold and free of intersections but
// with a handle too few (five runs of blobs30 in results/topology_sweep.md, exit 0). The core of
// the neck then lies on the wrong side of the mesh: outside it where F < 0 (a cut neck), inside
// where F > 0 (a closed tunnel). A mesh with the neck has its core inside the tube it makes, so
// the test below does not fire on a correct mesh whose distance to the surface is below the
// neck's radius. A front that capped the neck at its waist leaves the core on the cap, its side
// decided by rounding; there the mesh crosses the neck's axis twice (a cap on each side) where
// the field says the solid (or the tunnel's void) runs on, which a correct mesh never does: the
// axis lies inside the tube its vertices ring. A distance field's thin neck or tunnel has no
// saddle: its core lies on the medial axis, where F has a kink and grad F does not vanish, so no
// walk settles there. A front that capped such a tube left triangles across it, whose normal
// turns from their corners' normals by nearly a right angle; along them the mesh's side of space
// disagrees with F's sign over a stretch the surface rings (find_missed_necks, kCapTurn).
#pragma once

#include <cdp/core/field.h>
#include <cdp/core/mesh.h>

#include "spatial_hash.h"

#include <cstddef>
#include <optional>
#include <span>
#include <vector>

namespace cdp::adaptive {

// A vertex starts a walk when the Newton step from it is at most this many of its edges: the
// saddle of blobs30's lost neck (results/topology_sweep.md) was found from vertices 1-3 edges
// away, the nearest ones the front placed before it stepped over the neck.
inline constexpr double kCriticalReach = 3;

// Where to look for a critical point: a mesh vertex, the Newton step toward grad F = 0 from it
// (-H^-1 grad F, with the derivatives the tracker evaluated there for the curvature) and the
// length of the edges meant there.
struct CriticalStart {
  Vec3 point;
  Vec3 step;
  double edge = 0;
};

// The Newton step toward a critical point from derivatives at a point, or nothing where the
// Hessian is singular (the flat outside of a blob's support) or the step is not finite.
std::optional<Vec3> step_to_critical_point(const Vec3& gradient, const Mat3& hessian);

// A critical point of F whose side of the mesh disagrees with its sign.
struct MissedNeck {
  Vec3 point;
  double value = 0;  // F there: negative for a neck of solid the mesh cuts, positive for a tunnel it closes
  double width = 0;  // twice the radius at which the quadratic model of F there reaches zero
  double edge = 0;   // the edge length meant at the vertex that found it (a cap's longest edge)
  bool kinked = false;  // found along a cap (no saddle: a kink of F, a distance field's medial axis)
};

struct NeckSearch {
  std::vector<MissedNeck> missed;   // every tested critical point on the wrong side, thinnest first
  std::size_t walks = 0;            // Newton walks started (bounded: missed_necks.cpp)
  std::size_t critical_points = 0;  // distinct critical points they reached
  std::size_t tested = 0;           // thin enough to test against the mesh
  std::size_t capped = 0;           // of missed: the core's side right or undecided, two sheets across its axis
  std::size_t caps = 0;             // triangles turned past kCapTurn from a corner's normal, looked along
  // Starts left unwalked once the walks reached their bound (their predicted critical point not
  // claimed by a walk before them): necks there, if any, were not looked for.
  std::size_t unwalked = 0;
};

// Walks Newton from the starts (the tracker keeps only those whose step is at most kCriticalReach
// of their edge; in order, skipping one whose predicted critical point is already claimed, at
// most max(4096, a quarter of the mesh's vertices) walks), keeps the critical points whose
// quadratic model reaches zero within kThinWaist edges (the thin ones, which fronts can step
// over), and tests each, thinnest first, for the side of the mesh it lies on (MeshSides) and, when
// that side is right or undecided, for two sheets of the mesh across its axis (missed_necks.cpp,
// kAxisReach). Then looks along the triangles whose normal turns more than kCapTurn from one of
// their corners' normals (caps across a tube; at most as many as the walks' bound) for a stretch
// where the mesh's side disagrees with F's sign and the surface rings it. The mesh must be closed
// (the tracker's checks come first).
NeckSearch find_missed_necks(const Field& field, const Mesh& mesh, std::span<const CriticalStart> starts);

// Which side of a closed mesh points lie on: the parity of the triangles a ray from the point
// along +z crosses, the triangles hashed by their boxes once so that a query looks only at the
// column above the point.
class MeshSides {
 public:
  explicit MeshSides(const Mesh& mesh);
  // Whether p is inside; nothing when the ray passes through an edge or a vertex of the mesh in
  // the projection, or p lies on a triangle (decided neither way).
  std::optional<bool> inside(const Vec3& p) const;
  // The parameters in [0, 1] at which the segment from a to b crosses the mesh's triangles (a
  // segment in a triangle's plane crosses it nowhere), in no set order.
  void crossings(const Vec3& a, const Vec3& b, std::vector<double>& at) const;

 private:
  const Mesh& mesh_;
  SpatialHash hash_;
  double top_ = 0;
  mutable std::vector<int> seen_;
  mutable int stamp_ = 0;
};

}  // namespace cdp::adaptive
