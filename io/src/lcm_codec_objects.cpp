// The table-top objects message (lcm_codec_objects.hpp): TableObjectDetection
// -> objects_t for findmugd, and the checked way back for every listener.
// One file per message (lcm_codec_*.cpp); the wire walk is in
// lcm_wire.cpp with the other types'.
#include "findmug/io/lcm_codec_objects.hpp"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <string>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/common/pose2d.hpp"
#include "findmug/objects/object_model.hpp"
#include "lcm_codec_checks.hpp"

namespace findmug::io {

using detail::checkFinite;

namespace {

constexpr std::string_view kType = "objects_t";
constexpr int kTruncationBits = findmug_lcm::table_object_t::TRUNCATED_OUTLINE |
                                findmug_lcm::table_object_t::TRUNCATED_BORDER |
                                findmug_lcm::table_object_t::TRUNCATED_DEPTH_HOLE;
// A histogram normalised in float sums to 1 within a few ulps per bin; a
// larger gap is a corrupt or foreign message.
constexpr double kHistogramSumTolerance = 1e-3;
constexpr double kUnitTolerance = 1e-3;  // as the tables' axes

std::string field(std::string_view channel, std::string_view name) {
  return std::string(channel) + ": " + std::string(kType) + "." + std::string(name);
}

// The map-frame centroid: x, y through the pose, z unchanged (the map floor is the base floor),
// as encodeTables does for the tables' map_centroid.
Eigen::Vector3d mapCentroid(const Eigen::Vector3f& centroid, const RobotPose& pose) {
  const Eigen::Vector2d xy = transformPointD(pose.pose, centroid.head<2>().cast<double>());
  return {xy.x(), xy.y(), static_cast<double>(centroid.z())};
}

// `o.table` is the index of its table in the frame's tables_t: that table's frame id.
findmug_lcm::table_object_t toLcm(const TableObject& o, int table_map_id,
                                  const std::optional<RobotPose>& map_pose) {
  findmug_lcm::table_object_t out{};
  out.id = o.id;
  out.table_id = o.table;
  out.table_map_id = table_map_id;
  const Eigen::Vector3d map_centroid =
      map_pose ? mapCentroid(o.centroid, *map_pose) : Eigen::Vector3d::Zero();
  for (int i = 0; i < 3; ++i) {
    out.centroid[i] = o.centroid[i];
    out.map_centroid[i] = map_centroid[i];
    out.mean_rgb[i] = o.mean_rgb[i];
  }
  out.height_above_top = o.height_above_top;
  for (int i = 0; i < 2; ++i) {
    out.major_axis[i] = o.major_axis[i];
    out.extents[i] = o.extents[i];
    out.center[i] = o.center[i];
  }
  out.point_count = o.point_count;
  for (int b = 0; b < kObjectColourBins; ++b) out.colour_histogram[b] = o.colour_histogram[b];
  out.truncation = static_cast<std::int8_t>(o.truncation);
  out.map_id = 0;  // frame content: no object map fields
  out.sightings = 0;
  out.last_seen_utime = 0;
  out.name_score = 0.0f;
  return out;
}

// One object of the object map: map-frame fields from the map, the others relative to
// the robot at `map_pose` (`map_to_base`).
findmug_lcm::table_object_t mapObjectToLcm(const MappedObject& o, int table_index,
                                           const Pose2D& map_to_base) {
  findmug_lcm::table_object_t out{};
  out.id = o.id;
  out.table_id = table_index;
  out.table_map_id = o.table_id;
  const Eigen::Vector2d base_xy =
      transformPointD(map_to_base, o.centroid.head<2>().cast<double>());
  const double c = std::cos(map_to_base.yaw), s = std::sin(map_to_base.yaw);
  const Eigen::Vector2d axis(c * o.major_axis.x() - s * o.major_axis.y(),
                             s * o.major_axis.x() + c * o.major_axis.y());
  for (int i = 0; i < 3; ++i) {
    out.map_centroid[i] = o.centroid[i];
    out.mean_rgb[i] = std::clamp(o.mean_rgb[i], 0.0f, 255.0f);
  }
  out.centroid[0] = base_xy.x();
  out.centroid[1] = base_xy.y();
  out.centroid[2] = o.centroid.z();
  out.height_above_top = std::max(o.height_above_top, 0.0f);
  const double norm = axis.norm();
  out.major_axis[0] = norm > 0 ? axis.x() / norm : 1.0;
  out.major_axis[1] = norm > 0 ? axis.y() / norm : 0.0;
  out.extents[0] = o.extents.x();
  out.extents[1] = o.extents.y();
  // The map keeps no footprint box centre apart from the centroid.
  out.center[0] = base_xy.x();
  out.center[1] = base_xy.y();
  out.point_count = std::max(o.point_count, 1);
  // The running mean of normalised histograms sums to 1 up to rounding: renormalised.
  double sum = 0.0;
  for (int b = 0; b < kObjectColourBins; ++b) sum += std::max(o.colour_histogram[b], 0.0f);
  for (int b = 0; b < kObjectColourBins; ++b) {
    out.colour_histogram[b] =
        sum > 0 ? static_cast<float>(std::max(o.colour_histogram[b], 0.0f) / sum)
                : (b == kObjectColourBins - 1 ? 1.0f : 0.0f);
  }
  out.truncation = 0;
  out.map_id = o.id;
  out.sightings = o.sightings;
  out.last_seen_utime = static_cast<std::int64_t>(o.last_seen_utime);
  out.name = o.name;
  out.name_score = o.name.empty() ? 0.0f : o.name_score;
  return out;
}

void checkHeader(const findmug_lcm::objects_t& msg, std::string_view channel) {
  if (msg.num_objects < 0 || static_cast<std::size_t>(msg.num_objects) != msg.objects.size()) {
    throw Error(field(channel, "num_objects") + ": size field says " +
                std::to_string(msg.num_objects) + " but the array holds " +
                std::to_string(msg.objects.size()));
  }
  if (msg.utime < 0) {
    throw Error(field(channel, "utime") + ": negative time " + std::to_string(msg.utime));
  }
  if (msg.content != findmug_lcm::objects_t::CONTENT_FRAME &&
      msg.content != findmug_lcm::objects_t::CONTENT_MAP) {
    throw Error(field(channel, "content") + ": unknown content id " +
                std::to_string(static_cast<int>(msg.content)) + " (expected 0 or 1)");
  }
  if (msg.content == findmug_lcm::objects_t::CONTENT_MAP && !msg.has_map_pose) {
    throw Error(field(channel, "has_map_pose") +
                ": an object map message (CONTENT_MAP) must carry the robot's map pose");
  }
  if (msg.num_tables < 0) {
    throw Error(field(channel, "num_tables") + ": negative (" + std::to_string(msg.num_tables) +
                ")");
  }
}

std::optional<RobotPose> decodeMapPose(const findmug_lcm::objects_t& msg,
                                       std::string_view channel) {
  if (!msg.has_map_pose) return std::nullopt;
  const auto& p = msg.map_pose;
  checkFinite({p.x, p.y, p.yaw}, field(channel, "map_pose"));
  if (p.utime < 0) {
    throw Error(field(channel, "map_pose.utime") + ": negative time " + std::to_string(p.utime));
  }
  return RobotPose{static_cast<std::uint64_t>(p.utime), {p.x, p.y, p.yaw}};
}

// The ids: unique within the message, frame ids 0..n-1, the table within the frame's tables.
void checkIds(const findmug_lcm::table_object_t& o, const findmug_lcm::objects_t& msg,
              std::vector<bool>& id_seen, const std::string& where) {
  const bool map_content = msg.content == findmug_lcm::objects_t::CONTENT_MAP;
  if (!map_content) {
    if (o.id < 0 || o.id >= msg.num_objects) {
      throw Error(where + ".id: " + std::to_string(o.id) + " outside [0, num_objects " +
                  std::to_string(msg.num_objects) + ")");
    }
    if (id_seen[static_cast<std::size_t>(o.id)]) {
      throw Error(where + ".id: " + std::to_string(o.id) + " appears twice");
    }
    id_seen[static_cast<std::size_t>(o.id)] = true;
  }
  // An object map entry whose table is not among the table map's confirmed tables: -1.
  const bool no_table = map_content && o.table_id == -1;
  if (!no_table && (o.table_id < 0 || o.table_id >= msg.num_tables)) {
    throw Error(where + ".table_id: " + std::to_string(o.table_id) + " outside [" +
                (map_content ? "-1" : "0") + ", num_tables " + std::to_string(msg.num_tables) +
                ")");
  }
  if (o.table_map_id < 0) {
    throw Error(where + ".table_map_id: negative (" + std::to_string(o.table_map_id) + ")");
  }
}

void checkGeometry(const findmug_lcm::table_object_t& o, const std::string& where) {
  checkFinite({o.centroid[0], o.centroid[1], o.centroid[2]}, where + ".centroid");
  checkFinite({o.height_above_top}, where + ".height_above_top");
  if (o.height_above_top < 0) {
    throw Error(where + ".height_above_top: negative (" + std::to_string(o.height_above_top) + ")");
  }
  checkFinite({o.major_axis[0], o.major_axis[1]}, where + ".major_axis");
  const double norm = std::hypot(o.major_axis[0], o.major_axis[1]);
  if (std::abs(norm - 1.0) > kUnitTolerance) {
    throw Error(where + ".major_axis: not a unit vector (length " + std::to_string(norm) + ")");
  }
  checkFinite({o.extents[0], o.extents[1]}, where + ".extents");
  if (o.extents[0] < 0 || o.extents[1] < 0) throw Error(where + ".extents: negative extent");
  checkFinite({o.center[0], o.center[1]}, where + ".center");
  if (o.point_count < 1) {
    throw Error(where + ".point_count: " + std::to_string(o.point_count) +
                " (a candidate has at least one point)");
  }
}

void checkColour(const findmug_lcm::table_object_t& o, const std::string& where) {
  for (float c : o.mean_rgb) {
    if (!(c >= 0.0f && c <= 255.0f)) {
      throw Error(where + ".mean_rgb: " + std::to_string(c) + " outside [0, 255]");
    }
  }
  double sum = 0.0;
  for (int b = 0; b < kObjectColourBins; ++b) {
    const float v = o.colour_histogram[b];
    if (!(v >= 0.0f && v <= 1.0f)) {
      throw Error(where + ".colour_histogram[" + std::to_string(b) + "]: " + std::to_string(v) +
                  " outside [0, 1]");
    }
    sum += v;
  }
  if (std::abs(sum - 1.0) > kHistogramSumTolerance) {
    throw Error(where + ".colour_histogram: sums to " + std::to_string(sum) + ", not 1");
  }
  if ((o.truncation & ~kTruncationBits) != 0) {
    throw Error(where + ".truncation: unknown bits in " +
                std::to_string(static_cast<int>(static_cast<std::uint8_t>(o.truncation))) +
                " (known: 1, 2, 4)");
  }
}

// Frame content carries no object-map fields; map content needs them.
void checkMapEntry(const findmug_lcm::table_object_t& o, bool map_content,
                   const std::string& where) {
  if (!map_content) {
    if (o.map_id != 0 || o.sightings != 0 || o.last_seen_utime != 0) {
      throw Error(where + ".map_id/sightings/last_seen_utime: must be 0 in a frame message (" +
                  std::to_string(o.map_id) + ", " + std::to_string(o.sightings) + ", " +
                  std::to_string(o.last_seen_utime) + ")");
    }
    if (!o.name.empty() || o.name_score != 0.0f) {
      throw Error(where + ".name/name_score: must be \"\" and 0 in a frame message");
    }
    return;
  }
  if (!o.name.empty()) {
    try {
      validateObjectModelName(o.name);
    } catch (const Error& e) {
      throw Error(where + ".name: " + e.what());
    }
  }
  if (!(o.name_score >= 0.0f && o.name_score <= 1.0f) || (o.name.empty() && o.name_score != 0.0f)) {
    throw Error(where + ".name_score: " + std::to_string(o.name_score) +
                " (in [0, 1] for a named object, 0 for one never named)");
  }
  if (o.map_id <= 0 || o.id != o.map_id) {
    throw Error(where + ".map_id: an object map entry needs id == map_id > 0 (id " +
                std::to_string(o.id) + ", map_id " + std::to_string(o.map_id) + ")");
  }
  if (o.sightings < 1 || o.last_seen_utime < 0) {
    throw Error(where + ".sightings/last_seen_utime: an object map entry needs sightings >= 1 " +
                "and a time >= 0 (" + std::to_string(o.sightings) + ", " +
                std::to_string(o.last_seen_utime) + ")");
  }
}

TableObject fromLcm(const findmug_lcm::table_object_t& o) {
  TableObject out;
  out.id = o.id;
  out.table = o.table_id;
  out.centroid =
      Eigen::Vector3f(static_cast<float>(o.centroid[0]), static_cast<float>(o.centroid[1]),
                      static_cast<float>(o.centroid[2]));
  out.height_above_top = static_cast<float>(o.height_above_top);
  out.major_axis =
      Eigen::Vector2f(static_cast<float>(o.major_axis[0]), static_cast<float>(o.major_axis[1]));
  out.extents = Eigen::Vector2f(static_cast<float>(o.extents[0]), static_cast<float>(o.extents[1]));
  out.center = Eigen::Vector2f(static_cast<float>(o.center[0]), static_cast<float>(o.center[1]));
  out.point_count = o.point_count;
  out.mean_rgb = Eigen::Vector3f(o.mean_rgb[0], o.mean_rgb[1], o.mean_rgb[2]);
  for (int b = 0; b < kObjectColourBins; ++b) out.colour_histogram[b] = o.colour_histogram[b];
  out.truncation = static_cast<std::uint8_t>(o.truncation);
  return out;
}

ObjectMapInfo mapInfoFromLcm(const findmug_lcm::table_object_t& o, bool has_map_pose,
                             const std::string& where) {
  ObjectMapInfo info;
  info.table_map_id = o.table_map_id;
  if (has_map_pose) {
    checkFinite({o.map_centroid[0], o.map_centroid[1], o.map_centroid[2]}, where + ".map_centroid");
    info.map_centroid = Eigen::Vector3d(o.map_centroid[0], o.map_centroid[1], o.map_centroid[2]);
  }
  info.map_id = o.map_id;
  info.sightings = o.sightings;
  info.last_seen_utime = static_cast<std::uint64_t>(o.last_seen_utime);
  info.name = o.name;
  info.name_score = o.name_score;
  return info;
}

}  // namespace

findmug_lcm::objects_t encodeObjects(std::uint64_t utime, std::int64_t seq,
                                     const TableObjectDetection& detection,
                                     std::span<const TableCluster> tables,
                                     const std::optional<RobotPose>& map_pose,
                                     std::span<const TableMapInfo> table_map_info) {
  if (!table_map_info.empty() && table_map_info.size() != tables.size()) {
    throw Error("encodeObjects: " + std::to_string(table_map_info.size()) +
                " table map entries for " + std::to_string(tables.size()) + " tables");
  }
  findmug_lcm::objects_t msg{};
  msg.utime = static_cast<std::int64_t>(utime);
  msg.seq = seq;
  msg.content = findmug_lcm::objects_t::CONTENT_FRAME;
  msg.num_tables = static_cast<std::int32_t>(tables.size());
  msg.has_map_pose = map_pose.has_value();
  msg.map_pose = encodeRobotPose(map_pose.value_or(RobotPose{}));
  msg.objects.reserve(detection.objects.size());
  for (const TableObject& o : detection.objects) {
    if (o.table < 0 || static_cast<std::size_t>(o.table) >= tables.size()) {
      throw Error("encodeObjects: object " + std::to_string(o.id) + " stands on table " +
                  std::to_string(o.table) + " of " + std::to_string(tables.size()));
    }
    const auto k = static_cast<std::size_t>(o.table);
    const int table_map_id = table_map_info.empty() ? 0 : table_map_info[k].map_id;
    msg.objects.push_back(toLcm(o, table_map_id, map_pose));
  }
  msg.num_objects = static_cast<std::int32_t>(msg.objects.size());
  // What every listener would refuse is refused here, naming the field: a candidate the
  // object stage got wrong fails the frame's publish (reported and counted by findmugd)
  // rather than going out as a message each client drops. A few objects: cheap.
  (void)decodeObjects(msg, "encodeObjects");
  return msg;
}

findmug_lcm::objects_t encodeObjectMap(std::uint64_t utime, std::int64_t seq,
                                       std::span<const MappedObject> objects,
                                       std::span<const TableCluster> map_tables,
                                       const RobotPose& map_pose) {
  findmug_lcm::objects_t msg{};
  msg.utime = static_cast<std::int64_t>(utime);
  msg.seq = seq;
  msg.content = findmug_lcm::objects_t::CONTENT_MAP;
  msg.num_tables = static_cast<std::int32_t>(map_tables.size());
  msg.has_map_pose = true;
  msg.map_pose = encodeRobotPose(map_pose);
  const Pose2D map_to_base = inversePose(map_pose.pose);
  msg.objects.reserve(objects.size());
  for (const MappedObject& o : objects) {
    int index = -1;
    for (std::size_t k = 0; k < map_tables.size(); ++k) {
      if (o.table_id != 0 && map_tables[k].id == o.table_id) index = static_cast<int>(k);
    }
    msg.objects.push_back(mapObjectToLcm(o, index, map_to_base));
  }
  msg.num_objects = static_cast<std::int32_t>(msg.objects.size());
  (void)decodeObjects(msg, "encodeObjectMap");  // what a listener refuses is refused here
  return msg;
}

ObjectsMessage decodeObjects(const findmug_lcm::objects_t& msg, std::string_view channel) {
  checkHeader(msg, channel);
  const bool map_content = msg.content == findmug_lcm::objects_t::CONTENT_MAP;
  ObjectsMessage out;
  out.utime = static_cast<std::uint64_t>(msg.utime);
  out.seq = msg.seq;
  out.content = map_content ? TablesContent::Map : TablesContent::Frame;
  out.num_tables = msg.num_tables;
  out.map_pose = decodeMapPose(msg, channel);
  std::vector<bool> id_seen(msg.objects.size(), false);
  for (std::size_t k = 0; k < msg.objects.size(); ++k) {
    const findmug_lcm::table_object_t& o = msg.objects[k];
    const std::string where = field(channel, "objects[" + std::to_string(k) + "]");
    checkIds(o, msg, id_seen, where);
    checkGeometry(o, where);
    checkColour(o, where);
    checkMapEntry(o, map_content, where);
    out.map_info.push_back(mapInfoFromLcm(o, msg.has_map_pose, where));
    out.objects.push_back(fromLcm(o));
  }
  return out;
}

ObjectsMessage decodeObjects(const void* data, std::size_t size, std::string_view channel) {
  return decodeObjects(decodeMessage<findmug_lcm::objects_t>(data, size, channel), channel);
}

}  // namespace findmug::io
