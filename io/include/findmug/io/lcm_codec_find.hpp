// findmug/io/lcm_codec_find.hpp — the answer to a "find" request <-> find_result_t (LCM).
//
// findmugd answers command_t "find NAME" on FINDMUG_FIND_RESULT[_suffix]
// (lcmtypes/find_result_t.lcm): where the object was seen and where to stand,
// or the places to look in order, or why it cannot answer. The decoder trusts
// nothing, as those of lcm_codec.hpp: it walks the wire layout before LCM
// allocates, then checks every field (the result value, names, finite
// numbers, seen_ fields only with RESULT_SEEN, places only with
// RESULT_LOOK_AT, counts within bounds); any problem is a findmug::Error
// naming the channel and the field.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "findmug/io/lcm_codec.hpp"
#include "findmug/map/object_search.hpp"
#include "findmug_lcm/find_result_t.hpp"

namespace findmug::io {

// Walks the wire layout of a find_result_t, then lets LCM decode it (lcm_wire.cpp).
template <>
findmug_lcm::find_result_t decodeMessage<findmug_lcm::find_result_t>(const void*, std::size_t,
                                                                     std::string_view);

enum class FindResult : std::int8_t { Seen = 0, LookAt = 1, UnknownName = 2, Refused = 3 };

struct FindResultMessage {
  std::uint64_t utime = 0;
  std::int64_t request_id = 0;
  std::string name;
  FindResult result = FindResult::Refused;
  std::string summary;
  // FindResult::Seen only.
  int seen_object_id = 0;
  Eigen::Vector3d seen_position = Eigen::Vector3d::Zero();
  int seen_table_id = 0;
  std::uint64_t seen_utime = 0;
  float seen_score = 0.0f;
  std::optional<SearchPosition> stand_here;
  // FindResult::LookAt only, in the order to visit them.
  std::vector<PlaceToLook> places;
  std::vector<std::string> taught_names;
};

// Bounds the decoder holds a message to.
inline constexpr std::int32_t kMaxFindPlaces = 10000;
inline constexpr std::int32_t kMaxTaughtNames = 1000;
inline constexpr std::size_t kMaxFindSummaryBytes = 4096;

// The message for `answer` (ObjectSearch::answer) to request `request_id`.
FindResultMessage findResultMessage(const FindAnswer& answer, std::int64_t request_id,
                                    std::uint64_t utime,
                                    const std::vector<std::string>& taught_names);
// A refusal (no pose input, a bad name): result Refused with `why` as the summary.
FindResultMessage findRefusal(const std::string& name, std::int64_t request_id,
                              std::uint64_t utime, const std::string& why,
                              const std::vector<std::string>& taught_names);

findmug_lcm::find_result_t encodeFindResult(const FindResultMessage& message);
FindResultMessage decodeFindResult(const findmug_lcm::find_result_t& message,
                                   std::string_view channel);
// Walks the wire layout first (every length against the bytes really there).
FindResultMessage decodeFindResult(const void* data, std::size_t size, std::string_view channel);

}  // namespace findmug::io
