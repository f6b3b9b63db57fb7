// findmug/map/visiting_order.hpp — the order in which to visit search
// positions: a short open tour from the robot's position. The daemon's answer
// to a "find" request lists the places to look in this order, and
// findmug-nav-client and the table-map picture show the same tour.
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
