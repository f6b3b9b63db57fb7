// Tests of visitingOrder (findmug/map/visiting_order.hpp): the tour a navigation
// client takes over search positions. Exact on small sets (against brute
// force over every order), no worse than greedy nearest neighbour on large
// ones, and the obvious order on a line.
#include "findmug/map/visiting_order.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <vector>

namespace findmug {
namespace {

float pathLength(const Eigen::Vector2f& start, const std::vector<Eigen::Vector2f>& pts,
                 const std::vector<int>& order) {
  float length = 0.0f;
  Eigen::Vector2f at = start;
  for (int i : order) {
    length += (pts[i] - at).norm();
    at = pts[i];
  }
  return length;
}

TEST(VisitingOrder, IsAPermutationAndOptimalOnSmallSets) {
  EXPECT_TRUE(visitingOrder({0, 0}, {}).empty());
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> coord(-4.0f, 4.0f);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Eigen::Vector2f> pts;
    for (int i = 0; i < 7; ++i) pts.emplace_back(coord(rng), coord(rng));
    const Eigen::Vector2f start(coord(rng), coord(rng));
    const auto order = visitingOrder(start, pts);
    std::vector<int> sorted = order;
    std::sort(sorted.begin(), sorted.end());
    ASSERT_EQ(sorted, (std::vector<int>{0, 1, 2, 3, 4, 5, 6}));
    // Brute force over all 5040 orders: the shortest path.
    std::vector<int> perm = sorted;
    float best = std::numeric_limits<float>::max();
    do {
      best = std::min(best, pathLength(start, pts, perm));
    } while (std::next_permutation(perm.begin(), perm.end()));
    EXPECT_NEAR(pathLength(start, pts, order), best, 1e-4f) << "trial " << trial;
  }
  // Many points (heuristic): a permutation, and no longer than the greedy
  // nearest-neighbour tour it starts from.
  std::vector<Eigen::Vector2f> many;
  for (int i = 0; i < 40; ++i) many.emplace_back(coord(rng), coord(rng));
  const auto order = visitingOrder({0, 0}, many);
  std::vector<int> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (int i = 0; i < 40; ++i) ASSERT_EQ(sorted[i], i);
  std::vector<int> greedy;
  std::vector<bool> used(many.size(), false);
  Eigen::Vector2f at(0, 0);
  for (int step = 0; step < 40; ++step) {
    int best = -1;
    for (int i = 0; i < 40; ++i) {
      if (!used[i] && (best < 0 || (many[i] - at).norm() < (many[best] - at).norm())) best = i;
    }
    used[best] = true;
    greedy.push_back(best);
    at = many[best];
  }
  EXPECT_LE(pathLength({0, 0}, many, order), pathLength({0, 0}, many, greedy) + 1e-4f);
  // Points on a line, robot at one end: visited in line order.
  const std::vector<Eigen::Vector2f> line = {{3, 0}, {1, 0}, {4, 0}, {2, 0}};
  EXPECT_EQ(visitingOrder({0, 0}, line), (std::vector<int>{1, 3, 0, 2}));
}

}  // namespace
}  // namespace findmug
