// The object map (findmug/map/object_map.hpp): table-top candidates of many
// frames under stable ids, matched by place and colour, forgotten when their
// place is seen empty.
#include "findmug/map/object_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <tuple>

#include "findmug/common/error.hpp"

namespace findmug {
namespace {

[[noreturn]] void badObjectMapSetting(const std::string& key, double value,
                                      const std::string& rule) {
  std::ostringstream text;
  text << "object_map." << key << " = " << value << ": " << rule;
  throw Error(text.str());
}

// Signed distance of `p` inside a counter-clockwise convex polygon: the
// smallest distance to an edge's line, positive inside. -inf for fewer than
// three corners (nothing is inside a line).
float insideDistance(const std::vector<Eigen::Vector2f>& polygon, const Eigen::Vector2f& p) {
  if (polygon.size() < 3) return -std::numeric_limits<float>::infinity();
  float inside = std::numeric_limits<float>::infinity();
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2f& a = polygon[i];
    const Eigen::Vector2f& b = polygon[(i + 1) % polygon.size()];
    const Eigen::Vector2f edge = b - a;
    const float length = edge.norm();
    if (length <= 0.0f) continue;
    // Left of a CCW edge is inside.
    const float left = (edge.x() * (p.y() - a.y()) - edge.y() * (p.x() - a.x())) / length;
    inside = std::min(inside, left);
  }
  return inside;
}

Eigen::Vector2f rotate(const Eigen::Vector2f& v, double yaw) {
  const float c = static_cast<float>(std::cos(yaw));
  const float s = static_cast<float>(std::sin(yaw));
  return {c * v.x() - s * v.y(), s * v.x() + c * v.y()};
}

Eigen::Vector3f centroidInMap(const TableObject& seen, const Pose2D& base_in_map) {
  const Eigen::Vector2f xy = transformPoint(base_in_map, seen.centroid.head<2>());
  return {xy.x(), xy.y(), seen.centroid.z()};
}

// An axis and its opposite are one axis: turn `axis` to the half plane of `reference`.
Eigen::Vector2f alignedAxis(const Eigen::Vector2f& axis, const Eigen::Vector2f& reference) {
  return axis.dot(reference) < 0.0f ? Eigen::Vector2f(-axis) : axis;
}

void checkUpdateInputs(const std::vector<TableObject>& objects,
                       const std::vector<TableCluster>& tables,
                       const std::vector<int>& table_ids,
                       const std::vector<ObjectIdentity>& identities) {
  if (!identities.empty() && identities.size() != objects.size()) {
    throw Error("ObjectMap::update: " + std::to_string(identities.size()) + " identities for " +
                std::to_string(objects.size()) + " objects");
  }
  if (!table_ids.empty() && table_ids.size() != tables.size()) {
    throw Error("ObjectMap::update: " + std::to_string(table_ids.size()) + " table ids for " +
                std::to_string(tables.size()) + " tables");
  }
  for (const TableObject& object : objects) {
    if (object.table < 0 || object.table >= static_cast<int>(tables.size())) {
      throw Error("ObjectMap::update: object " + std::to_string(object.id) + " stands on table " +
                  std::to_string(object.table) + " of a frame with " +
                  std::to_string(tables.size()) + " tables");
    }
    if (!object.centroid.allFinite()) {
      throw Error("ObjectMap::update: object " + std::to_string(object.id) +
                  " has a non-finite centroid");
    }
  }
}

}  // namespace

void validateObjectMapConfig(const ObjectMapConfig& c) {
  if (!std::isfinite(c.match_distance_m) || c.match_distance_m <= 0.0f) {
    badObjectMapSetting("match_distance_m", c.match_distance_m, "must be a positive number");
  }
  if (!std::isfinite(c.match_height_m) || c.match_height_m <= 0.0f) {
    badObjectMapSetting("match_height_m", c.match_height_m, "must be a positive number");
  }
  if (!std::isfinite(c.match_colour_distance) || c.match_colour_distance < 0.0f ||
      c.match_colour_distance > 1.0f) {
    badObjectMapSetting("match_colour_distance", c.match_colour_distance, "must be in [0, 1]");
  }
  if (c.forget_misses < 1) badObjectMapSetting("forget_misses", c.forget_misses, "must be >= 1");
  if (!std::isfinite(c.seen_margin_m) || c.seen_margin_m < 0.0f) {
    badObjectMapSetting("seen_margin_m", c.seen_margin_m, "must be a number >= 0");
  }
  if (c.max_mean_sightings < 1) {
    badObjectMapSetting("max_mean_sightings", c.max_mean_sightings, "must be >= 1");
  }
  if (c.name_after_matches < 1) {
    badObjectMapSetting("name_after_matches", c.name_after_matches, "must be >= 1");
  }
  if (!std::isfinite(c.max_name_range_m) || c.max_name_range_m <= 0.0f) {
    badObjectMapSetting("max_name_range_m", c.max_name_range_m, "must be a positive number");
  }
}

const SettingsTable<ObjectMapConfig>& objectMapSettings() {
  using M = ObjectMapConfig;
  static const SettingsTable<M> table = [] {
    SettingsTable<M> t("object_map");
    t.add(numberSetting<M, float>(
        "object_map.match_distance_m", [](M& m) -> float& { return m.match_distance_m; }, 0, 5,
        "candidate centroids this close on the floor may be one mapped object"));
    t.add(numberSetting<M, float>(
        "object_map.match_height_m", [](M& m) -> float& { return m.match_height_m; }, 0, 2,
        "... when their heights differ by at most this"));
    t.add(numberSetting<M, float>(
        "object_map.match_colour_distance",
        [](M& m) -> float& { return m.match_colour_distance; }, 0, 1,
        "... and their colour histograms by at most this (1 - Bhattacharyya coefficient)"));
    t.add(integerSetting<M, int>(
        "object_map.forget_misses", [](M& m) -> int& { return m.forget_misses; }, 1, 1000,
        "consecutive frames an object's place was seen without it to forget it"));
    t.add(numberSetting<M, float>(
        "object_map.seen_margin_m", [](M& m) -> float& { return m.seen_margin_m; }, 0, 1,
        "a place counts as seen when this far inside a frame's visible table top"));
    t.add(integerSetting<M, int>(
        "object_map.max_mean_sightings", [](M& m) -> int& { return m.max_mean_sightings; }, 1,
        10000, "sightings the running mean of an object's position and colour weighs"));
    t.add(integerSetting<M, int>(
        "object_map.name_after_matches", [](M& m) -> int& { return m.name_after_matches; }, 1,
        1000, "matches (near enough) of a taught object before the object takes its name"));
    t.add(numberSetting<M, float>(
        "object_map.max_name_range_m", [](M& m) -> float& { return m.max_name_range_m; }, 0, 100,
        "a match farther than this from the robot (m) only makes the name pending: look closer"));
    return t;
  }();
  return table;
}

ObjectMap::ObjectMap(ObjectMapConfig config) : config_(config) {
  validateObjectMapConfig(config_);
}

void ObjectMap::clear() {
  objects_.clear();
  seen_on_tables_.clear();
  next_id_ = 1;
}

std::vector<int> ObjectMap::seenOnTables(const std::string& name) const {
  const auto found = seen_on_tables_.find(name);
  if (name.empty() || found == seen_on_tables_.end()) return {};
  return {found->second.begin(), found->second.end()};
}

void ObjectMap::name(MappedObject& mapped, const ObjectIdentity* identity, float range_m) {
  if (identity != nullptr && !identity->name.empty()) {
    const bool near = range_m <= config_.max_name_range_m;
    if (identity->name == mapped.name) {
      // Confirmed already: a near match refreshes the score; a competing
      // pending name loses its count.
      if (near) mapped.name_score = identity->score;
      mapped.pending_name.clear();
      mapped.pending_matches = 0;
    } else {
      if (identity->name != mapped.pending_name) {
        mapped.pending_name = identity->name;
        mapped.pending_matches = 0;
      }
      if (near) ++mapped.pending_matches;
      if (mapped.pending_matches >= config_.name_after_matches) {
        mapped.name = mapped.pending_name;
        mapped.name_score = identity->score;
        mapped.pending_name.clear();
        mapped.pending_matches = 0;
      }
    }
  }
  if (!mapped.name.empty() && mapped.table_id != 0) {
    seen_on_tables_[mapped.name].insert(mapped.table_id);
  }
}

MappedObject ObjectMap::create(const TableObject& seen, const Pose2D& base_in_map, int table_id,
                               std::uint64_t utime) {
  MappedObject mapped;
  mapped.id = next_id_++;
  mapped.centroid = centroidInMap(seen, base_in_map);
  mapped.major_axis = rotate(seen.major_axis, base_in_map.yaw);
  mapped.extents = seen.extents;
  mapped.height_above_top = seen.height_above_top;
  mapped.mean_rgb = seen.mean_rgb;
  mapped.colour_histogram = seen.colour_histogram;
  mapped.point_count = seen.point_count;
  mapped.table_id = table_id;
  mapped.sightings = 1;
  mapped.first_seen_utime = utime;
  mapped.last_seen_utime = utime;
  return mapped;
}

void ObjectMap::absorb(MappedObject& mapped, const TableObject& seen, const Pose2D& base_in_map,
                       int table_id, std::uint64_t utime) const {
  // Weight of the new sighting in a running mean over the last max_mean_sightings.
  const float w = 1.0f / static_cast<float>(
                             std::min(mapped.sightings + 1, config_.max_mean_sightings));
  const auto mix = [w](auto& kept, const auto& now) { kept = (1.0f - w) * kept + w * now; };
  mix(mapped.centroid, centroidInMap(seen, base_in_map));
  Eigen::Vector2f axis = mapped.major_axis;
  mix(axis, alignedAxis(rotate(seen.major_axis, base_in_map.yaw), mapped.major_axis));
  if (axis.norm() > 1e-6f) mapped.major_axis = axis.normalized();
  mix(mapped.extents, seen.extents);
  mix(mapped.height_above_top, seen.height_above_top);
  mix(mapped.mean_rgb, seen.mean_rgb);
  for (int i = 0; i < kObjectColourBins; ++i) {
    mix(mapped.colour_histogram[i], seen.colour_histogram[i]);
  }
  mapped.point_count = seen.point_count;
  mapped.table_id = table_id;
  ++mapped.sightings;
  mapped.misses = 0;
  mapped.last_seen_utime = utime;
}

bool ObjectMap::placeSeen(const MappedObject& mapped, const std::vector<TableCluster>& tables,
                          const Pose2D& map_in_base) const {
  const Eigen::Vector2f in_base = transformPoint(map_in_base, mapped.centroid.head<2>());
  for (const TableCluster& table : tables) {
    // Its height must fit the table too: an object on a shelf above a desk
    // is not where the desk's top was seen.
    const float above = mapped.centroid.z() - table.top_height;
    if (above < 0.0f || above > mapped.height_above_top + config_.match_height_m) continue;
    if (insideDistance(table.hull, in_base) >= config_.seen_margin_m) return true;
  }
  return false;
}

ObjectMapUpdate ObjectMap::update(const std::vector<TableObject>& objects,
                                  const std::vector<TableCluster>& tables,
                                  const std::vector<int>& table_ids, const Pose2D& base_in_map,
                                  std::uint64_t utime,
                                  const std::vector<ObjectIdentity>& identities) {
  checkUpdateInputs(objects, tables, table_ids, identities);
  const auto identityOf = [&](std::size_t c) {
    return identities.empty() ? nullptr : &identities[c];
  };
  const auto tableId = [&](const TableObject& o) { return table_ids.empty() ? 0 : table_ids[o.table]; };
  // The candidate's floor distance from the robot (the base frame's origin).
  const auto rangeOf = [](const TableObject& o) { return o.centroid.head<2>().norm(); };

  // Every admissible (distance, candidate, mapped) pair, nearest first.
  std::vector<std::tuple<float, int, int>> pairs;
  for (int c = 0; c < static_cast<int>(objects.size()); ++c) {
    const Eigen::Vector3f seen = centroidInMap(objects[c], base_in_map);
    for (int m = 0; m < static_cast<int>(objects_.size()); ++m) {
      const MappedObject& mapped = objects_[m];
      const float floor_distance = (seen.head<2>() - mapped.centroid.head<2>()).norm();
      if (floor_distance > config_.match_distance_m) continue;
      if (std::abs(seen.z() - mapped.centroid.z()) > config_.match_height_m) continue;
      if (colourHistogramDistance(objects[c].colour_histogram, mapped.colour_histogram) >
          config_.match_colour_distance) {
        continue;
      }
      pairs.emplace_back(floor_distance, c, m);
    }
  }
  std::sort(pairs.begin(), pairs.end());

  ObjectMapUpdate result;
  result.object_ids.assign(objects.size(), 0);
  std::vector<bool> matched(objects_.size(), false);
  for (const auto& [distance, c, m] : pairs) {
    if (result.object_ids[c] != 0 || matched[m]) continue;
    absorb(objects_[m], objects[c], base_in_map, tableId(objects[c]), utime);
    name(objects_[m], identityOf(static_cast<std::size_t>(c)), rangeOf(objects[c]));
    matched[m] = true;
    result.object_ids[c] = objects_[m].id;
  }

  // Misses, before the new objects join (they were seen in this frame).
  const Pose2D map_in_base = inversePose(base_in_map);
  std::vector<MappedObject> kept;
  kept.reserve(objects_.size() + objects.size());
  for (std::size_t m = 0; m < objects_.size(); ++m) {
    MappedObject& mapped = objects_[m];
    if (!matched[m] && placeSeen(mapped, tables, map_in_base)) ++mapped.misses;
    if (mapped.misses >= config_.forget_misses) {
      result.forgotten.push_back(mapped.id);
    } else {
      kept.push_back(std::move(mapped));
    }
  }
  objects_ = std::move(kept);

  for (std::size_t c = 0; c < objects.size(); ++c) {
    if (result.object_ids[c] != 0) continue;
    objects_.push_back(create(objects[c], base_in_map, tableId(objects[c]), utime));
    name(objects_.back(), identityOf(c), rangeOf(objects[c]));
    result.object_ids[c] = objects_.back().id;
    result.created.push_back(objects_.back().id);
  }
  return result;
}

}  // namespace findmug
