// search_position_codec.hpp (internal to findmug_io) — one search_position_t <->
// SearchPosition conversion for every message that carries search positions
// (tables_t's tables, find_result_t's "stand here"), so the checks on the way in
// cannot drift apart between them.
#pragma once

#include <string>

#include "findmug/tables/tables.hpp"
#include "findmug_lcm/search_position_t.hpp"

namespace findmug::io::detail {

findmug_lcm::search_position_t searchPositionToLcm(const SearchPosition& position);

// Throws findmug::Error, prefixed with `where` (channel: type.field), when the position
// is not a finite place on a map (a coordinate beyond 1e6 m included).
SearchPosition searchPositionFromLcm(const findmug_lcm::search_position_t& position,
                                     const std::string& where);

}  // namespace findmug::io::detail
