// search_position_t <-> SearchPosition (search_position_codec.hpp).
#include "search_position_codec.hpp"

#include <cmath>

#include "findmug/common/error.hpp"

namespace findmug::io::detail {

findmug_lcm::search_position_t searchPositionToLcm(const SearchPosition& position) {
  findmug_lcm::search_position_t out;
  out.x = position.xy.x();
  out.y = position.xy.y();
  out.yaw = position.yaw;
  out.reachable = position.reachable;
  out.reason = position.reason;
  return out;
}

SearchPosition searchPositionFromLcm(const findmug_lcm::search_position_t& position,
                                     const std::string& where) {
  // A place a robot can drive to: finite, and within 1000 km of the map's origin (a larger
  // value can only come from a corrupt message and would lose all precision as a float).
  constexpr double kMaxCoordinate = 1e6;
  if (!std::isfinite(position.x) || !std::isfinite(position.y) || !std::isfinite(position.yaw) ||
      std::abs(position.x) > kMaxCoordinate || std::abs(position.y) > kMaxCoordinate) {
    throw Error(where + ": search position (" + std::to_string(position.x) + ", " +
                std::to_string(position.y) + ", yaw " + std::to_string(position.yaw) +
                ") is not a finite place on a map");
  }
  SearchPosition out;
  out.xy = Eigen::Vector2f(static_cast<float>(position.x), static_cast<float>(position.y));
  out.yaw = static_cast<float>(position.yaw);
  out.reachable = position.reachable;
  out.reason = position.reason;
  return out;
}

}  // namespace findmug::io::detail
