// tables_t <-> TablesMessage: the per-frame tables and the table map (findmug/io/lcm_codec.hpp).
#include <cmath>
#include <string>

#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "lcm_codec_checks.hpp"
#include "search_position_codec.hpp"

namespace findmug::io {

using detail::checkArraySize;
using detail::checkDimensions;
using detail::checkFinite;
using detail::field;
using detail::finite;

// ---- tables ------------------------------------------------------------------------------------

namespace {

findmug_lcm::search_position_t toLcmMap(const SearchPosition& p, const RobotPose& pose) {
  findmug_lcm::search_position_t out = detail::searchPositionToLcm(p);
  const Eigen::Vector2d m = transformPointD(pose.pose, p.xy.cast<double>());
  out.x = m.x();
  out.y = m.y();
  out.yaw = wrapAngle(p.yaw + pose.pose.yaw);
  return out;
}

}  // namespace

findmug_lcm::tables_t encodeTables(const TablesMessage& in) {
  return encodeTables(in.utime, in.seq, in.content, in.tables, in.map_pose, in.map_info);
}

findmug_lcm::tables_t encodeTables(std::uint64_t utime, std::int64_t seq, TablesContent content,
                                   std::span<const TableCluster> tables,
                                   const std::optional<RobotPose>& map_pose,
                                   std::span<const TableMapInfo> map_info) {
  if (!map_info.empty() && map_info.size() != tables.size()) {
    throw Error("encodeTables: " + std::to_string(map_info.size()) + " map entries for " +
                std::to_string(tables.size()) + " tables");
  }
  if (content == TablesContent::Map) {
    if (!map_pose) throw Error("encodeTables: a table map message needs the robot's map pose");
    for (std::size_t k = 0; k < tables.size(); ++k) {
      if (map_info.empty() || map_info[k].map_id <= 0 || map_info[k].map_id != tables[k].id) {
        throw Error("encodeTables: table map entry " + std::to_string(k) +
                    " needs id == map_id > 0");
      }
    }
  }
  findmug_lcm::tables_t msg;
  msg.utime = static_cast<std::int64_t>(utime);
  msg.seq = seq;
  msg.content = static_cast<std::int8_t>(content);
  msg.has_map_pose = map_pose.has_value();
  if (map_pose)
    msg.map_pose = encodeRobotPose(*map_pose);
  else
    msg.map_pose = encodeRobotPose(RobotPose{});
  msg.num_tables = static_cast<std::int32_t>(tables.size());
  for (std::size_t k = 0; k < tables.size(); ++k) {
    const TableCluster& t = tables[k];
    findmug_lcm::table_t out;
    out.id = t.id;
    const TableMapInfo info = map_info.empty() ? TableMapInfo{} : map_info[k];
    out.map_id = info.map_id;
    out.confirmed = info.confirmed;
    out.sightings = info.sightings;
    out.viewpoints = info.viewpoints;
    out.center[0] = t.center.x();
    out.center[1] = t.center.y();
    for (int i = 0; i < 3; ++i) out.centroid[i] = t.centroid[i];
    out.top_height = t.top_height;
    for (int i = 0; i < 2; ++i) {
      out.major_axis[i] = t.major_axis[i];
      out.minor_axis[i] = t.minor_axis[i];
      out.extents[i] = t.extents[i];
    }
    out.hull_size = static_cast<std::int32_t>(t.hull.size());
    for (const auto& p : t.hull) out.hull.push_back({p.x(), p.y()});
    out.point_count = t.point_count;
    out.mean_confidence = t.mean_confidence;
    out.num_search_positions = static_cast<std::int32_t>(t.search_positions.size());
    for (const auto& p : t.search_positions)
      out.search_positions.push_back(detail::searchPositionToLcm(p));
    if (map_pose) {
      const Eigen::Vector2d c =
          transformPointD(map_pose->pose, t.centroid.head<2>().cast<double>());
      out.map_centroid[0] = c.x();
      out.map_centroid[1] = c.y();
      out.map_centroid[2] = t.centroid.z();
      const Eigen::Vector2d center = transformPointD(map_pose->pose, t.center.cast<double>());
      out.map_center[0] = center.x();
      out.map_center[1] = center.y();
      for (const auto& p : t.hull) {
        const Eigen::Vector2d m = transformPointD(map_pose->pose, p.cast<double>());
        out.map_hull.push_back({m.x(), m.y()});
      }
      for (const auto& p : t.search_positions) {
        out.map_search_positions.push_back(toLcmMap(p, *map_pose));
      }
    } else {
      // The arrays share their length fields with the base-frame ones.
      for (int i = 0; i < 3; ++i) out.map_centroid[i] = 0.0;
      out.map_center[0] = out.map_center[1] = 0.0;
      out.map_hull.assign(t.hull.size(), std::vector<double>(2, 0.0));
      out.map_search_positions.assign(t.search_positions.size(),
                                      detail::searchPositionToLcm(SearchPosition{}));
    }
    msg.tables.push_back(std::move(out));
  }
  return msg;
}

TablesMessage decodeTables(const findmug_lcm::tables_t& msg, std::string_view channel) {
  constexpr std::string_view type = "tables_t";
  checkArraySize(msg.num_tables, msg.tables.size(), channel, type, "num_tables");
  if (msg.utime < 0) {
    throw Error(field(channel, type, "utime") + ": negative time " + std::to_string(msg.utime));
  }
  if (msg.content != findmug_lcm::tables_t::CONTENT_FRAME &&
      msg.content != findmug_lcm::tables_t::CONTENT_MAP) {
    throw Error(field(channel, type, "content") + ": unknown content id " +
                std::to_string(static_cast<int>(msg.content)) + " (expected " +
                std::to_string(static_cast<int>(findmug_lcm::tables_t::CONTENT_FRAME)) + " or " +
                std::to_string(static_cast<int>(findmug_lcm::tables_t::CONTENT_MAP)) + ")");
  }
  const bool map_content = msg.content == findmug_lcm::tables_t::CONTENT_MAP;
  if (map_content && !msg.has_map_pose) {
    throw Error(field(channel, type, "has_map_pose") +
                ": a table map message (CONTENT_MAP) must carry the robot's map pose");
  }
  TablesMessage out;
  out.utime = static_cast<std::uint64_t>(msg.utime);
  out.seq = msg.seq;
  out.content = map_content ? TablesContent::Map : TablesContent::Frame;
  if (msg.has_map_pose) {
    const auto& p = msg.map_pose;
    checkFinite({p.x, p.y, p.yaw}, field(channel, type, "map_pose"));
    if (p.utime < 0) {
      throw Error(field(channel, type, "map_pose.utime") + ": negative time " +
                  std::to_string(p.utime));
    }
    out.map_pose = RobotPose{static_cast<std::uint64_t>(p.utime), {p.x, p.y, p.yaw}};
  }
  for (std::size_t k = 0; k < msg.tables.size(); ++k) {
    const findmug_lcm::table_t& t = msg.tables[k];
    const std::string where = field(channel, type, "tables[" + std::to_string(k) + "]");
    checkArraySize(t.hull_size, t.hull.size(), channel, type,
                   "tables[" + std::to_string(k) + "].hull_size");
    checkArraySize(t.hull_size, t.map_hull.size(), channel, type,
                   "tables[" + std::to_string(k) + "].map_hull");
    checkArraySize(t.num_search_positions, t.search_positions.size(), channel, type,
                   "tables[" + std::to_string(k) + "].num_search_positions");
    checkArraySize(t.num_search_positions, t.map_search_positions.size(), channel, type,
                   "tables[" + std::to_string(k) + "].map_search_positions");
    checkFinite({t.centroid[0], t.centroid[1], t.centroid[2], t.top_height, t.major_axis[0],
                 t.major_axis[1], t.minor_axis[0], t.minor_axis[1], t.extents[0], t.extents[1]},
                where + ".centroid/top_height/axes/extents");
    const double major_norm = std::hypot(t.major_axis[0], t.major_axis[1]);
    const double minor_norm = std::hypot(t.minor_axis[0], t.minor_axis[1]);
    if (std::abs(major_norm - 1.0) > 1e-3 || std::abs(minor_norm - 1.0) > 1e-3) {
      throw Error(where + ": principal axes are not unit vectors (|major| " +
                  std::to_string(major_norm) + ", |minor| " + std::to_string(minor_norm) + ")");
    }
    if (t.extents[0] < 0 || t.extents[1] < 0) throw Error(where + ".extents: negative extent");
    if (t.point_count < 0) {
      throw Error(where + ".point_count: negative (" + std::to_string(t.point_count) + ")");
    }
    if (!(t.mean_confidence >= 0.0f && t.mean_confidence <= 1.0f)) {
      throw Error(where + ".mean_confidence: " + std::to_string(t.mean_confidence) +
                  " outside [0, 1]");
    }
    checkFinite({t.center[0], t.center[1]}, where + ".center");
    if (t.map_id < 0 || t.sightings < 0) {
      throw Error(where + ".map_id/sightings: negative (" + std::to_string(t.map_id) + ", " +
                  std::to_string(t.sightings) + ")");
    }
    if (t.viewpoints < 0 || t.viewpoints > t.sightings) {
      throw Error(where + ".viewpoints: " + std::to_string(t.viewpoints) +
                  " outside [0, sightings " + std::to_string(t.sightings) + "]");
    }
    if (t.confirmed && t.map_id == 0) {
      throw Error(where + ".confirmed: set for a table that is not in the map (map_id 0)");
    }
    if (map_content && (t.map_id == 0 || t.id != t.map_id)) {
      throw Error(where + ".map_id: a table map entry needs id == map_id > 0 (id " +
                  std::to_string(t.id) + ", map_id " + std::to_string(t.map_id) + ")");
    }
    out.map_info.push_back({t.map_id, t.confirmed != 0, t.sightings, t.viewpoints});
    TableCluster c;
    c.id = t.id;
    c.center = Eigen::Vector2f(static_cast<float>(t.center[0]), static_cast<float>(t.center[1]));
    c.centroid =
        Eigen::Vector3f(static_cast<float>(t.centroid[0]), static_cast<float>(t.centroid[1]),
                        static_cast<float>(t.centroid[2]));
    c.top_height = static_cast<float>(t.top_height);
    c.major_axis =
        Eigen::Vector2f(static_cast<float>(t.major_axis[0]), static_cast<float>(t.major_axis[1]));
    c.minor_axis =
        Eigen::Vector2f(static_cast<float>(t.minor_axis[0]), static_cast<float>(t.minor_axis[1]));
    c.extents = Eigen::Vector2f(static_cast<float>(t.extents[0]), static_cast<float>(t.extents[1]));
    for (const auto& p : t.hull) {
      checkFinite({p[0], p[1]}, where + ".hull");
      c.hull.emplace_back(static_cast<float>(p[0]), static_cast<float>(p[1]));
    }
    c.point_count = t.point_count;
    c.mean_confidence = t.mean_confidence;
    for (const auto& p : t.search_positions) {
      c.search_positions.push_back(detail::searchPositionFromLcm(p, where + ".search_positions"));
    }
    if (msg.has_map_pose) {
      MapFrameTable m;
      checkFinite({t.map_centroid[0], t.map_centroid[1], t.map_centroid[2]},
                  where + ".map_centroid");
      m.centroid = Eigen::Vector3d(t.map_centroid[0], t.map_centroid[1], t.map_centroid[2]);
      checkFinite({t.map_center[0], t.map_center[1]}, where + ".map_center");
      m.center = Eigen::Vector2d(t.map_center[0], t.map_center[1]);
      for (const auto& p : t.map_hull) {
        checkFinite({p[0], p[1]}, where + ".map_hull");
        m.hull.emplace_back(p[0], p[1]);
      }
      for (const auto& p : t.map_search_positions) {
        m.search_positions.push_back(
            detail::searchPositionFromLcm(p, where + ".map_search_positions"));
      }
      out.map_tables.push_back(std::move(m));
    }
    out.tables.push_back(std::move(c));
  }
  return out;
}

TablesMessage decodeTables(const void* data, std::size_t size, std::string_view channel) {
  return decodeTables(decodeMessage<findmug_lcm::tables_t>(data, size, channel), channel);
}

}  // namespace findmug::io
