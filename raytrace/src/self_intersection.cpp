// Self-intersections: candidate pairs from overlapping_box_pairs (Embree, in box_overlaps.cpp),
// each decided by the core's exact triangle-triangle test (<cdp/core/triangle_intersection.h>).
#include <cdp/raytrace/self_intersection.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace cdp {

SelfIntersectionReport find_self_intersections(const Mesh& mesh, std::size_t max_examples) {
  SelfIntersectionReport report;
  // Degenerate triangles get an empty box, so they take part in no candidate pair; triangles
  // with a common point have overlapping boxes (closed, in double), so no pair is lost.
  const std::vector<Box> boxes = triangle_boxes_for_intersection(mesh, &report.degenerate_triangles);
  const std::vector<std::pair<int, int>> candidates = overlapping_box_pairs(boxes);
  report.candidate_pairs = candidates.size();
  const auto corners = [&](int f) -> std::array<Vec3, 3> {
    const auto& t = mesh.triangles[static_cast<std::size_t>(f)];
    return {mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]};
  };
  std::vector<unsigned char> hit(candidates.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, candidates.size(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                        hit[i] = nondegenerate_triangles_intersect(corners(candidates[i].first),
                                                                   corners(candidates[i].second));
                    });
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    if (!hit[i]) continue;
    ++report.pairs;
    if (report.examples.size() < max_examples) report.examples.push_back(candidates[i]);
  }
  return report;
}

}  // namespace cdp
