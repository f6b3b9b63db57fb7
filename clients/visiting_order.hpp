// visiting_order.hpp — the order in which a navigation client visits search
// positions: a short open tour from the robot's position. Used by
// findmug-nav-client (and the table-map picture that shows the tour); the
// core library does not need it, so it lives with the clients.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace findmug {

// Order in which to visit `points` starting from `start` (an open path, any
// end): the shortest one for up to 12 points (dynamic programme), else
// nearest neighbour improved by 2-opt until no reversal shortens it.
// Returns indices into `points`.
std::vector<int> visitingOrder(const Eigen::Vector2f& start,
                               const std::vector<Eigen::Vector2f>& points);

}  // namespace findmug
