// A static k-d tree over points, for the ball and nearest-neighbour queries of the MPU fit.
// Private to the library. Deterministic: the same points give the same tree and the same answer
// order.
#pragma once

#include <cdp/core/field.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <queue>
#include <utility>
#include <vector>

namespace cdp {

class PointKdTree {
 public:
  explicit PointKdTree(const std::vector<Vec3>& points) : points_(points) {
    order_.resize(points.size());
    for (std::size_t i = 0; i < order_.size(); ++i) order_[i] = static_cast<std::uint32_t>(i);
    nodes_.reserve(2 * points.size() / kBucket + 2);
    if (!points.empty()) build(0, static_cast<std::uint32_t>(points.size()));
  }

  // Appends the indices of the points with |p - c| < r, in tree order.
  void ball(const Vec3& c, double r, std::vector<std::uint32_t>& out) const {
    if (nodes_.empty()) return;
    const double r2 = r * r;
    std::uint32_t stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes_[stack[--top]];
      if (box_distance2(n, c) >= r2) continue;
      if (n.left == kNone) {
        for (std::uint32_t k = n.lo; k < n.hi; ++k)
          if ((points_[order_[k]] - c).squaredNorm() < r2) out.push_back(order_[k]);
      } else {
        stack[top++] = n.right;
        stack[top++] = n.left;
      }
    }
  }

  // The k nearest points as (squared distance, index), nearest first, ties by index.
  std::vector<std::pair<double, std::uint32_t>> nearest(const Vec3& c, std::size_t k) const {
    std::priority_queue<std::pair<double, std::uint32_t>> heap;  // the worst on top
    k = std::min(k, points_.size());
    if (k == 0) return {};
    search(0, c, k, heap);
    std::vector<std::pair<double, std::uint32_t>> out(heap.size());
    for (std::size_t i = out.size(); i-- > 0;) {
      out[i] = heap.top();
      heap.pop();
    }
    return out;
  }

 private:
  static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  static constexpr std::uint32_t kBucket = 12;
  struct Node {
    Vec3 min, max;
    std::uint32_t lo, hi, left, right;
  };

  static double box_distance2(const Node& n, const Vec3& c) {
    return (n.min - c).cwiseMax(c - n.max).cwiseMax(0.0).squaredNorm();
  }

  std::uint32_t build(std::uint32_t lo, std::uint32_t hi) {
    const std::uint32_t id = static_cast<std::uint32_t>(nodes_.size());
    nodes_.push_back(Node{Vec3::Zero(), Vec3::Zero(), lo, hi, kNone, kNone});
    Vec3 mn = Vec3::Constant(std::numeric_limits<double>::infinity()), mx = -mn;
    for (std::uint32_t k = lo; k < hi; ++k) {
      mn = mn.cwiseMin(points_[order_[k]]);
      mx = mx.cwiseMax(points_[order_[k]]);
    }
    std::uint32_t left = kNone, right = kNone;
    if (hi - lo > kBucket) {
      int axis = 0;
      (mx - mn).maxCoeff(&axis);
      const std::uint32_t mid = lo + (hi - lo) / 2;
      std::nth_element(order_.begin() + lo, order_.begin() + mid, order_.begin() + hi,
                       [&](std::uint32_t a, std::uint32_t b) {
                         const double pa = points_[a][axis], pb = points_[b][axis];
                         return pa < pb || (pa == pb && a < b);
                       });
      left = build(lo, mid);
      right = build(mid, hi);
    }
    nodes_[id] = {mn, mx, lo, hi, left, right};
    return id;
  }

  void search(std::uint32_t id, const Vec3& c, std::size_t k,
              std::priority_queue<std::pair<double, std::uint32_t>>& heap) const {
    const Node& n = nodes_[id];
    if (heap.size() == k && box_distance2(n, c) > heap.top().first) return;
    if (n.left == kNone) {
      for (std::uint32_t j = n.lo; j < n.hi; ++j) {
        const std::pair<double, std::uint32_t> e{(points_[order_[j]] - c).squaredNorm(), order_[j]};
        if (heap.size() < k) {
          heap.push(e);
        } else if (e < heap.top()) {
          heap.pop();
          heap.push(e);
        }
      }
      return;
    }
    const bool left_first = box_distance2(nodes_[n.left], c) <= box_distance2(nodes_[n.right], c);
    search(left_first ? n.left : n.right, c, k, heap);
    search(left_first ? n.right : n.left, c, k, heap);
  }

  const std::vector<Vec3>& points_;
  std::vector<std::uint32_t> order_;
  std::vector<Node> nodes_;
};

}  // namespace cdp
