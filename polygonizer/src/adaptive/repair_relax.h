// The relaxation: the many mildly stretched triangles where the fronts' edge lengths change
// (most vertices of a graded mesh), made nearer equilateral by edge flips towards valence 6 and
// vertex moves along the surface; no vertex is added or removed. The angle repair
// (repair_angles.h) aims at the worst triangles; this at the mean edge ratio (the mean ratio
// 1.30 -> 1.20 on the bunny VIS-800 at factor 3).
#pragma once

#include "repair_context.h"

namespace cdp::adaptive::repair {

// Moves the vertices of the triangles whose longest edge exceeds kRelaxRatio times their
// shortest towards where their triangles would be equilateral (equilateral_step), projected
// back onto the surface: in kRelaxSweeps sweeps, each finding all its targets and projecting
// them first (on all cores where the field allows) and then taking them in index order, a
// move kept only if it lowers the mean edge ratio of v's star by kRelaxMinGain, keeps its
// smallest angle (or at least kRelaxKeepDegrees), its facing and the tolerance, and
// intersects nothing. Crease vertices stay. A target that does not lower the star's mean
// ratio in the tangent plane is not projected at all (no evaluation). Before the moves of
// each sweep, flips of the stretched triangles' edges towards valence 6 (try_flip's
// for_ratio). Where these sweeps leave the mesh's mean ratio over the aim
// (QualityOptions::aim_mean_edge_ratio), up to kRelaxSearchSweeps more whose moves are searched
// in the tangent plane (see repair_relax.cpp), judged and applied as above; a mesh they leave
// within the aim is not touched by them. The mesh and the evaluation counts are the same on
// any number of threads.
// \throw CancelledError (polled in every pass over the vertices).
void relax(RepairContext& ctx);

// The mean over live triangles of the longest edge over the shortest (1 for equilateral ones;
// 0 for no triangle).
double mean_edge_ratio(const RepairContext& ctx);

}  // namespace cdp::adaptive::repair
