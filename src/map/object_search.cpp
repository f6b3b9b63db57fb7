// The answer to a "find" request (findmug/map/object_search.hpp): where the
// named object was seen, or the places to look in the order to visit them.
#include "findmug/map/object_search.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "findmug/common/error.hpp"
#include "findmug/map/visiting_order.hpp"

namespace findmug {
namespace {

std::string joinNames(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out.empty() ? "none" : out;
}

// The most recently seen mapped object of `name` (ties: the better score, then the lower id).
const MappedObject* newestNamed(const ObjectMap& objects, const std::string& name) {
  const MappedObject* best = nullptr;
  for (const MappedObject& o : objects.objects()) {
    if (o.name != name) continue;
    if (best == nullptr || o.last_seen_utime > best->last_seen_utime ||
        (o.last_seen_utime == best->last_seen_utime && o.name_score > best->name_score)) {
      best = &o;
    }
  }
  return best;
}

const TableCluster* tableWithId(const std::vector<TableCluster>& tables, int id) {
  for (const TableCluster& t : tables) {
    if (t.id == id && id != 0) return &t;
  }
  return nullptr;
}

std::optional<SearchPosition> nearestReachablePosition(const TableCluster& table,
                                                       const Eigen::Vector2f& to) {
  std::optional<SearchPosition> best;
  for (const SearchPosition& p : table.search_positions) {
    if (!p.reachable) continue;
    if (!best || (p.xy - to).norm() < (best->xy - to).norm()) best = p;
  }
  return best;
}

std::string secondsAgo(std::uint64_t now_utime, std::uint64_t then_utime) {
  std::ostringstream text;
  text.precision(1);
  text << std::fixed << (now_utime > then_utime ? (now_utime - then_utime) * 1e-6 : 0.0) << " s ago";
  return text.str();
}

// `places` reordered as a short tour from `start`; returns where it ends.
Eigen::Vector2f tourFrom(const Eigen::Vector2f& start, std::vector<PlaceToLook>& places) {
  if (places.empty()) return start;
  std::vector<Eigen::Vector2f> points;
  points.reserve(places.size());
  for (const PlaceToLook& p : places) points.push_back(p.position.xy);
  std::vector<PlaceToLook> ordered;
  ordered.reserve(places.size());
  for (const int i : visitingOrder(start, points)) ordered.push_back(places[i]);
  places = std::move(ordered);
  return places.back().position.xy;
}

}  // namespace

void validateObjectSearchConfig(const ObjectSearchConfig& c) {
  if (!std::isfinite(c.position_tolerance_m) || c.position_tolerance_m <= 0.0f) {
    throw Error("object_search.position_tolerance_m = " + std::to_string(c.position_tolerance_m) +
                ": must be a positive number");
  }
  if (!std::isfinite(c.heading_tolerance_rad) || c.heading_tolerance_rad <= 0.0f ||
      c.heading_tolerance_rad > static_cast<float>(M_PI)) {
    throw Error("object_search.heading_tolerance_rad = " +
                std::to_string(c.heading_tolerance_rad) + ": must be in (0, pi]");
  }
  if (!std::isfinite(c.top_seen_share) || c.top_seen_share < 0.0f || c.top_seen_share > 1.0f) {
    throw Error("object_search.top_seen_share = " + std::to_string(c.top_seen_share) +
                ": must be in [0, 1]");
  }
  if (!std::isfinite(c.top_seen_range_m) || c.top_seen_range_m <= 0.0f) {
    throw Error("object_search.top_seen_range_m = " + std::to_string(c.top_seen_range_m) +
                ": must be a positive number");
  }
}

namespace {

TableTopViewsConfig topViewsConfig(const ObjectSearchConfig& c) {
  TableTopViewsConfig out;
  out.range_m = c.top_seen_range_m > 0.0f ? c.top_seen_range_m : out.range_m;
  return out;
}

}  // namespace

const SettingsTable<ObjectSearchConfig>& objectSearchSettings() {
  using S = ObjectSearchConfig;
  static const SettingsTable<S> table = [] {
    SettingsTable<S> t("object_search");
    t.add(numberSetting<S, float>(
        "object_search.position_tolerance_m",
        [](S& s) -> float& { return s.position_tolerance_m; }, 0, 10,
        "the robot this near a table's search position has searched the table ..."));
    t.add(numberSetting<S, float>(
        "object_search.heading_tolerance_rad",
        [](S& s) -> float& { return s.heading_tolerance_rad; }, 0, 3.14159f,
        "... when it faces within this of the position's heading (the top in view)"));
    t.add(numberSetting<S, float>(
        "object_search.top_seen_share", [](S& s) -> float& { return s.top_seen_share; }, 0, 1,
        "views that showed this share of a table's top have searched it (0: views do not)"));
    t.add(numberSetting<S, float>(
        "object_search.top_seen_range_m", [](S& s) -> float& { return s.top_seen_range_m; },
        0.1, 10, "... from within this distance of the camera (the matcher's reach)"));
    return t;
  }();
  return table;
}

ObjectSearch::ObjectSearch(ObjectSearchConfig config)
    : config_((validateObjectSearchConfig(config), config)), top_views_(topViewsConfig(config)) {}

std::vector<int> ObjectSearch::observeView(const std::vector<TableCluster>& map_tables,
                                           const RgbdFrame& frame,
                                           const Eigen::Isometry3d& camera_in_map) {
  std::vector<int> marked;
  if (config_.top_seen_share <= 0.0f) return marked;
  top_views_.observe(map_tables, frame, camera_in_map);
  for (const TableCluster& table : map_tables) {
    if (searched_.count(table.id) != 0) continue;
    if (top_views_.seenShare(table) >= config_.top_seen_share) {
      searched_.insert(table.id);
      marked.push_back(table.id);
    }
  }
  return marked;
}

std::vector<int> ObjectSearch::observeRobot(const Pose2D& robot,
                                            const std::vector<TableCluster>& map_tables) {
  std::vector<int> marked;
  const Eigen::Vector2f at(static_cast<float>(robot.x), static_cast<float>(robot.y));
  for (const TableCluster& table : map_tables) {
    if (searched_.count(table.id) != 0) continue;
    for (const SearchPosition& p : table.search_positions) {
      const bool near = (p.xy - at).norm() <= config_.position_tolerance_m;
      const bool facing =
          std::abs(wrapAngle(robot.yaw - p.yaw)) <= config_.heading_tolerance_rad;
      if (near && facing) {
        searched_.insert(table.id);
        marked.push_back(table.id);
        break;
      }
    }
  }
  return marked;
}

FindAnswer ObjectSearch::answer(std::int64_t request_id, const std::string& name,
                                const std::vector<std::string>& taught_names,
                                const ObjectMap& objects,
                                const std::vector<TableCluster>& map_tables,
                                const std::optional<Pose2D>& robot, std::uint64_t now_utime) {
  if (request_id != request_id_) {
    request_id_ = request_id;
    searched_.clear();
    top_views_.clear();
  }
  FindAnswer answer;
  answer.name = name;
  if (std::find(taught_names.begin(), taught_names.end(), name) == taught_names.end()) {
    answer.kind = FindAnswer::Kind::UnknownName;
    answer.summary = "no object named '" + name + "' was taught (taught: " +
                     joinNames(taught_names) + ")";
    return answer;
  }

  if (const MappedObject* seen = newestNamed(objects, name)) {
    answer.kind = FindAnswer::Kind::Seen;
    answer.object = *seen;
    std::ostringstream text;
    text.precision(2);
    text << std::fixed << name << " seen at (" << seen->centroid.x() << ", " << seen->centroid.y()
         << ", " << seen->centroid.z() << ") on table " << seen->table_id << ", "
         << secondsAgo(now_utime, seen->last_seen_utime) << ", score " << seen->name_score;
    if (const TableCluster* table = tableWithId(map_tables, seen->table_id)) {
      answer.stand_here = nearestReachablePosition(*table, seen->centroid.head<2>());
    }
    if (answer.stand_here) {
      text << "; stand at (" << answer.stand_here->xy.x() << ", " << answer.stand_here->xy.y()
           << ")";
    } else {
      text << "; no reachable search position of its table is known";
    }
    answer.summary = text.str();
    return answer;
  }

  answer.kind = FindAnswer::Kind::LookAt;
  const std::vector<int> before = objects.seenOnTables(name);
  // Tables holding an object that may be it (matched, but too few times or
  // from too far to be sure): look closer there first, searched or not.
  std::set<int> maybe_here;
  for (const MappedObject& o : objects.objects()) {
    if (o.pending_name == name && o.table_id != 0) maybe_here.insert(o.table_id);
  }
  std::vector<PlaceToLook> groups[3];  // maybe here or seen before, not searched, searched
  for (const TableCluster& table : map_tables) {
    const bool seen_before = std::binary_search(before.begin(), before.end(), table.id);
    const bool searched = searched_.count(table.id) != 0;
    const bool maybe = maybe_here.count(table.id) != 0;
    for (const SearchPosition& p : table.search_positions) {
      if (!p.reachable) continue;
      const int group = maybe ? 0 : (searched ? 2 : (seen_before ? 0 : 1));
      groups[group].push_back({table.id, p, seen_before, searched, maybe});
    }
  }
  Eigen::Vector2f from = robot ? Eigen::Vector2f(static_cast<float>(robot->x),
                                                 static_cast<float>(robot->y))
                               : Eigen::Vector2f::Zero();
  bool have_start = robot.has_value();
  for (auto& group : groups) {
    if (group.empty()) continue;
    if (!have_start) {
      from = group.front().position.xy;
      have_start = true;
    }
    from = tourFrom(from, group);
    answer.places.insert(answer.places.end(), group.begin(), group.end());
  }
  std::ostringstream text;
  text << name << " not seen yet; " << answer.places.size() << " place(s) to look on "
       << (map_tables.size()) << " mapped table(s), " << searched_.size() << " searched";
  if (!before.empty()) text << ", seen before on " << before.size() << " of them";
  if (!maybe_here.empty()) {
    text << "; maybe on table";
    for (const int id : maybe_here) text << " " << id;
    text << " (matched too few times or from too far): look closer there first";
  }
  answer.summary = text.str();
  return answer;
}

}  // namespace findmug
