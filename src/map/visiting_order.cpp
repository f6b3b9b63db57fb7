// visiting_order.cpp — visitingOrder: exact (Held-Karp) for the few search
// positions of a frame, nearest neighbour + 2-opt for a whole map's worth.
#include "findmug/map/visiting_order.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>

namespace findmug {

namespace {

// Shortest open path from `start` through all points (Held-Karp dynamic
// programme, O(n^2 2^n)): exact, for the few positions of a frame.
std::vector<int> exactVisitingOrder(const Eigen::Vector2f& start,
                                    const std::vector<Eigen::Vector2f>& points) {
  const int n = static_cast<int>(points.size());
  const std::size_t subsets = std::size_t{1} << n;
  std::vector<float> cost(subsets * n, std::numeric_limits<float>::max());
  std::vector<std::int8_t> previous(subsets * n, -1);
  for (int i = 0; i < n; ++i) cost[(std::size_t{1} << i) * n + i] = (points[i] - start).norm();
  for (std::size_t mask = 1; mask < subsets; ++mask) {
    for (int last = 0; last < n; ++last) {
      const float c = cost[mask * n + last];
      if (!(mask & (std::size_t{1} << last)) || c == std::numeric_limits<float>::max()) continue;
      for (int next = 0; next < n; ++next) {
        if (mask & (std::size_t{1} << next)) continue;
        const std::size_t grown = mask | (std::size_t{1} << next);
        const float candidate = c + (points[next] - points[last]).norm();
        if (candidate < cost[grown * n + next]) {
          cost[grown * n + next] = candidate;
          previous[grown * n + next] = static_cast<std::int8_t>(last);
        }
      }
    }
  }
  std::size_t mask = subsets - 1;
  int last = 0;
  for (int i = 1; i < n; ++i) {
    if (cost[mask * n + i] < cost[mask * n + last]) last = i;
  }
  std::vector<int> order;
  while (last >= 0) {
    order.push_back(last);
    const int before = previous[mask * n + last];
    mask &= ~(std::size_t{1} << last);
    last = before;
  }
  std::reverse(order.begin(), order.end());
  return order;
}

constexpr int kExactVisitingOrderMax = 12;

}  // namespace

std::vector<int> visitingOrder(const Eigen::Vector2f& start,
                               const std::vector<Eigen::Vector2f>& points) {
  const int n = static_cast<int>(points.size());
  if (n == 0) return {};
  if (n <= kExactVisitingOrderMax) return exactVisitingOrder(start, points);
  std::vector<int> order;
  order.reserve(points.size());
  std::vector<bool> used(points.size(), false);
  Eigen::Vector2f at = start;
  for (int step = 0; step < n; ++step) {
    int best = -1;
    float best_d = std::numeric_limits<float>::max();
    for (int i = 0; i < n; ++i) {
      const float d = (points[i] - at).squaredNorm();
      if (!used[i] && d < best_d) {
        best = i;
        best_d = d;
      }
    }
    used[best] = true;
    order.push_back(best);
    at = points[best];
  }
  // 2-opt on the open path start -> order[0] -> ... -> order[n-1]: reversing
  // order[i..j] replaces edges (prev_i, i) and (j, next_j) by (prev_i, j) and
  // (i, next_j); the path has no edge after its last point.
  const auto pointAt = [&](int k) -> const Eigen::Vector2f& {
    return k < 0 ? start : points[order[k]];
  };
  bool improved = true;
  for (int pass = 0; improved && pass < 100; ++pass) {
    improved = false;
    for (int i = 0; i < n - 1; ++i) {
      for (int j = i + 1; j < n; ++j) {
        const float before = (pointAt(i - 1) - pointAt(i)).norm() +
                             (j + 1 < n ? (pointAt(j) - pointAt(j + 1)).norm() : 0.0f);
        const float after = (pointAt(i - 1) - pointAt(j)).norm() +
                            (j + 1 < n ? (pointAt(i) - pointAt(j + 1)).norm() : 0.0f);
        if (after < before - 1e-6f) {
          std::reverse(order.begin() + i, order.begin() + j + 1);
          improved = true;
        }
      }
    }
  }
  return order;
}

}  // namespace findmug
