// find_result_t <-> FindResultMessage (findmug/io/lcm_codec_find.hpp): the daemon's
// answer to "find NAME", checked field by field on the way in.
#include "findmug/io/lcm_codec_find.hpp"

#include <algorithm>
#include <cmath>

#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/objects/object_model.hpp"
#include "search_position_codec.hpp"

namespace findmug::io {
namespace {

constexpr std::string_view kType = "find_result_t";

std::string where(std::string_view channel, const std::string& field) {
  return std::string(channel) + ": " + std::string(kType) + "." + field;
}

// A name as taught objects have them (validateObjectModelName); "" allowed where `optional`.
void checkName(const std::string& name, const std::string& at, bool optional) {
  if (optional && name.empty()) return;
  try {
    validateObjectModelName(name);
  } catch (const Error& e) {
    throw Error(at + ": " + e.what());
  }
}

void checkSeenFieldsEmpty(const findmug_lcm::find_result_t& m, std::string_view channel) {
  const bool empty = m.seen_object_id == 0 && m.seen_table_id == 0 && m.seen_utime == 0 &&
                     m.seen_score == 0.0f && !m.has_stand_here && m.seen_position[0] == 0.0 &&
                     m.seen_position[1] == 0.0 && m.seen_position[2] == 0.0;
  if (!empty) throw Error(where(channel, "seen_*") + ": set although result is not RESULT_SEEN");
}

void decodeSeen(const findmug_lcm::find_result_t& m, std::string_view channel,
                FindResultMessage& out) {
  if (m.seen_object_id < 1) {
    throw Error(where(channel, "seen_object_id") + ": " + std::to_string(m.seen_object_id) +
                " is not a mapped object id (1, 2, ...)");
  }
  if (m.seen_table_id < 0) {
    throw Error(where(channel, "seen_table_id") + ": negative id " +
                std::to_string(m.seen_table_id));
  }
  if (m.seen_utime < 0) {
    throw Error(where(channel, "seen_utime") + ": negative time " + std::to_string(m.seen_utime));
  }
  if (!std::isfinite(m.seen_score) || m.seen_score < 0.0f || m.seen_score > 1.0f) {
    throw Error(where(channel, "seen_score") + ": " + std::to_string(m.seen_score) +
                " is not in [0, 1]");
  }
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(m.seen_position[i]) || std::abs(m.seen_position[i]) > 1e6) {
      throw Error(where(channel, "seen_position[" + std::to_string(i) + "]") + ": " +
                  std::to_string(m.seen_position[i]) + " is not a finite coordinate");
    }
  }
  out.seen_object_id = m.seen_object_id;
  out.seen_position = {m.seen_position[0], m.seen_position[1], m.seen_position[2]};
  out.seen_table_id = m.seen_table_id;
  out.seen_utime = static_cast<std::uint64_t>(m.seen_utime);
  out.seen_score = m.seen_score;
  if (m.has_stand_here) out.stand_here = detail::searchPositionFromLcm(m.stand_here, where(channel, "stand_here"));
}

void decodePlaces(const findmug_lcm::find_result_t& m, std::string_view channel,
                  FindResultMessage& out) {
  if (m.num_places < 0 || m.num_places > kMaxFindPlaces) {
    throw Error(where(channel, "num_places") + ": " + std::to_string(m.num_places) +
                " is not in [0, " + std::to_string(kMaxFindPlaces) + "]");
  }
  if (m.result != findmug_lcm::find_result_t::RESULT_LOOK_AT && m.num_places != 0) {
    throw Error(where(channel, "num_places") + ": " + std::to_string(m.num_places) +
                " places although result is not RESULT_LOOK_AT");
  }
  out.places.reserve(static_cast<std::size_t>(m.num_places));
  for (std::int32_t i = 0; i < m.num_places; ++i) {
    const std::string at = "places[" + std::to_string(i) + "]";
    PlaceToLook place;
    place.position = detail::searchPositionFromLcm(m.places[i], where(channel, at));
    if (!place.position.reachable) {
      throw Error(where(channel, at) + ": an unreachable place among the places to look");
    }
    if (m.place_table_ids[i] < 1) {
      throw Error(where(channel, "place_table_ids[" + std::to_string(i) + "]") + ": " +
                  std::to_string(m.place_table_ids[i]) + " is not a table map id (1, 2, ...)");
    }
    place.table_id = m.place_table_ids[i];
    place.seen_here_before = m.place_seen_before[i];
    place.searched = m.place_searched[i];
    place.look_closer = m.place_look_closer[i];
    out.places.push_back(place);
  }
}

}  // namespace

FindResultMessage findResultMessage(const FindAnswer& answer, std::int64_t request_id,
                                    std::uint64_t utime,
                                    const std::vector<std::string>& taught_names) {
  FindResultMessage out;
  out.utime = utime;
  out.request_id = request_id;
  out.name = answer.name;
  out.summary = answer.summary.substr(0, kMaxFindSummaryBytes);
  out.taught_names = taught_names;
  switch (answer.kind) {
    case FindAnswer::Kind::UnknownName:
      out.result = FindResult::UnknownName;
      break;
    case FindAnswer::Kind::LookAt:
      out.result = FindResult::LookAt;
      out.places = answer.places;
      break;
    case FindAnswer::Kind::Seen:
      out.result = FindResult::Seen;
      out.seen_object_id = answer.object->id;
      out.seen_position = answer.object->centroid.cast<double>();
      out.seen_table_id = answer.object->table_id;
      out.seen_utime = answer.object->last_seen_utime;
      out.seen_score = std::clamp(answer.object->name_score, 0.0f, 1.0f);
      out.stand_here = answer.stand_here;
      break;
  }
  return out;
}

FindResultMessage findRefusal(const std::string& name, std::int64_t request_id,
                              std::uint64_t utime, const std::string& why,
                              const std::vector<std::string>& taught_names) {
  FindResultMessage out;
  out.utime = utime;
  out.request_id = request_id;
  out.name = name;
  out.result = FindResult::Refused;
  out.summary = why.substr(0, kMaxFindSummaryBytes);
  out.taught_names = taught_names;
  return out;
}

findmug_lcm::find_result_t encodeFindResult(const FindResultMessage& in) {
  findmug_lcm::find_result_t m{};
  m.utime = static_cast<std::int64_t>(in.utime);
  m.request_id = in.request_id;
  m.name = in.name;
  m.result = static_cast<std::int8_t>(in.result);
  m.summary = in.summary;
  m.seen_object_id = in.seen_object_id;
  for (int i = 0; i < 3; ++i) m.seen_position[i] = in.seen_position[i];
  m.seen_table_id = in.seen_table_id;
  m.seen_utime = static_cast<std::int64_t>(in.seen_utime);
  m.seen_score = in.seen_score;
  m.has_stand_here = in.stand_here.has_value();
  m.stand_here = detail::searchPositionToLcm(in.stand_here.value_or(SearchPosition{}));
  m.num_places = static_cast<std::int32_t>(in.places.size());
  for (const PlaceToLook& p : in.places) {
    m.places.push_back(detail::searchPositionToLcm(p.position));
    m.place_table_ids.push_back(p.table_id);
    m.place_seen_before.push_back(p.seen_here_before);
    m.place_searched.push_back(p.searched);
    m.place_look_closer.push_back(p.look_closer);
  }
  m.num_taught = static_cast<std::int32_t>(in.taught_names.size());
  m.taught_names = in.taught_names;
  return m;
}

FindResultMessage decodeFindResult(const findmug_lcm::find_result_t& m,
                                   std::string_view channel) {
  FindResultMessage out;
  if (m.utime < 0) throw Error(where(channel, "utime") + ": negative time " + std::to_string(m.utime));
  if (m.request_id < 0) {
    throw Error(where(channel, "request_id") + ": negative id " + std::to_string(m.request_id));
  }
  if (m.result < findmug_lcm::find_result_t::RESULT_SEEN ||
      m.result > findmug_lcm::find_result_t::RESULT_REFUSED) {
    throw Error(where(channel, "result") + ": unknown value " + std::to_string(m.result));
  }
  // A refusal may be about a name that is not one (the request's text, cut short).
  checkName(m.name, where(channel, "name"),
            /*optional=*/m.result == findmug_lcm::find_result_t::RESULT_REFUSED ||
                m.result == findmug_lcm::find_result_t::RESULT_UNKNOWN_NAME);
  if (m.name.size() > 1024) throw Error(where(channel, "name") + ": longer than 1024 bytes");
  if (m.summary.size() > kMaxFindSummaryBytes) {
    throw Error(where(channel, "summary") + ": " + std::to_string(m.summary.size()) +
                " bytes, more than " + std::to_string(kMaxFindSummaryBytes));
  }
  out.utime = static_cast<std::uint64_t>(m.utime);
  out.request_id = m.request_id;
  out.name = m.name;
  out.result = static_cast<FindResult>(m.result);
  out.summary = m.summary;
  if (m.result == findmug_lcm::find_result_t::RESULT_SEEN) {
    decodeSeen(m, channel, out);
  } else {
    checkSeenFieldsEmpty(m, channel);
  }
  decodePlaces(m, channel, out);
  if (m.num_taught < 0 || m.num_taught > kMaxTaughtNames) {
    throw Error(where(channel, "num_taught") + ": " + std::to_string(m.num_taught) +
                " is not in [0, " + std::to_string(kMaxTaughtNames) + "]");
  }
  for (std::int32_t i = 0; i < m.num_taught; ++i) {
    checkName(m.taught_names[i], where(channel, "taught_names[" + std::to_string(i) + "]"), false);
  }
  out.taught_names = m.taught_names;
  return out;
}

FindResultMessage decodeFindResult(const void* data, std::size_t size, std::string_view channel) {
  return decodeFindResult(decodeMessage<findmug_lcm::find_result_t>(data, size, channel),
                          channel);
}

}  // namespace findmug::io
