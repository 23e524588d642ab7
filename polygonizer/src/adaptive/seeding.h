// The seeding guarantee of the adaptive polygonizer: every component of the surface inside the
// box is meshed once, and a run that cannot keep that promise says so.
//
//  1. Sign changes. F is sampled on the seed grid; every grid edge whose ends differ in sign is
//     a place the surface crosses. Coverage, not proximity, decides whether it is meshed: a sign
//     change that a mesh triangle crosses is meshed. One that no triangle crosses is meshed too
//     when the nearest triangle facing the same way within one of its own (longest) edges of the
//     surface point there is about as far from that point as from the surface (the mesh is a
//     chord of the surface and can pass a grid node on the other side of where the surface does;
//     a triangle of another sheet is farther from the point than from its own sheet), or when a walk along the surface in steps of
//     min_edge reaches such a triangle and the surface, followed the other way, ends (detail
//     finer than min_edge, a needle's tip, that the mesh stops short of: `below_resolution`;
//     where it runs onto another component instead, a thin bridge: `thin_bridges`, Bridges
//     below). Anything else starts a new component, from a point whose curvature min_edge
//     resolves first (seeds in unresolvable detail wait).
//     Opposite orientation is never "the same sheet": the inner sphere of a hollow ball, the
//     second of two spheres 1e-3 apart.
//  2. Small and thin components, which no grid edge sees. With a Lipschitz bound L (analytic
//     models, blobs) a grid cell without a sign change may hold surface only where
//     |F(centre)| <= L * half-diagonal (models that bound their values over a box, blobs, prove
//     more cells empty); such a cell, unless every point of it lies within one edge of a
//     triangle, is split into eight, down to min_edge, until a sign change is found or every
//     part is proved empty (`refined_cells`; cells still undecided at min_edge are
//     `unresolved_cells`, which includes the band next to the meshed surface; the splits are
//     bounded by the mesh already made, and the cells left past that bound are
//     `unsearched_cells`). Without a bound (expressions, VIS, MPU) Newton's method starts from
//     every grid node where |F| is a strict local minimum among its 26 neighbours of the same
//     sign (a component between grid nodes pulls |F| down around it); this finds isolated small
//     components but proves nothing. Newton also starts from the nodes of the band next to the
//     crossed cells where the level set through the node curls within about two cells, on the
//     grid and by F's own derivatives (a small component beside the surface, which no grid edge
//     crosses and leaves no strict local minimum beside the surface's sign change; any field but
//     a sampled volume). Sampled volumes, whose noise puts small components right beside the
//     surface, scan that band instead (scan_band): the cells near crossed ones that the volume
//     cannot prove free of critical points (Field::gradient_range) are sampled on a lattice of
//     step at most min_edge (not below a twelfth of a cell), and one sign change of each
//     connected set of crossed lattice cells is visited as a grid edge's (`band_cells`,
//     `band_components`).
//  3. After the run every sign change found is checked again; `uncovered` must be 0, else the
//     polygonization fails with an error naming the place.
#pragma once

#include "tracker.h"

#include <cdp/core/adaptive_report.h>
#include <cdp/core/surface_seeds.h>

#include <cstddef>
#include <vector>

namespace cdp::adaptive {

// Thin bridges: seeds on surface that components meshed before them closed over. A feature
// thinner than min_edge that runs from one component of the mesh to another (a rod between two
// balls, seeding.cpp's kTipFacing), and a component seeded late whose mesh runs into theirs (the
// rod when min_edge resolves it: the balls' long edges stepped over where it joins them). A
// component grown from there after the others were closed meets their meshes; an attempt made
// again with them seeded `first` grows from the bridge onto what it joins (Run::attempt).
struct Bridges {
  std::vector<Vec3> first;  // seeded before the grid's sign changes, in order
  std::vector<Vec3> found;  // appended as found (kept when the meshing throws)
};

// Meshes every component through `tracker` (which appends to `mesh`). `cell` sizes the index of
// triangles the coverage tests use: about a typical edge (never below the grid's cell). Deterministic.
SeedingReport seed_every_component(const Field& field, const SeedGrid& grid, double min_edge, double cell,
                                   Tracker& tracker, const Mesh& mesh, Bridges* bridges = nullptr);

}  // namespace cdp::adaptive
