// findmug/map/object_search.hpp — the answer to "find my mug".
//
// A robot asks a running findmugd to find a taught object by name. The answer
// comes from what the daemon keeps: the object map (object_map.hpp: objects
// seen on table tops, named by the taught-object matcher) and the table map
// (table_map.hpp: tables with search positions, map frame).
//
//   * Seen: the most recently seen mapped object of that name: where it is
//     (map frame), on which table, when it was last seen, the match score,
//     and where to stand: the reachable search position of its table nearest
//     to it (none when its table is not in the table map).
//   * Not seen: the places to look, every reachable search position of the
//     mapped tables, in three groups: tables holding a mapped object whose
//     name is only pending (MappedObject::pending_name: matched too few times
//     or from too far, "look closer"), searched or not, and tables not yet
//     searched for this request where the object was seen before, then the
//     other tables not yet searched, then the searched ones. Each group is a short tour
//     (visitingOrder) from the robot, or from where the previous group ends.
//   * A name nobody taught is refused, the answer listing the taught names.
//
// A table is searched for a request when, after the request was made, the
// robot stood at one of its search positions (within `position_tolerance_m`,
// heading within `heading_tolerance_rad` of the position's, so that the top was
// in view), or the camera's views showed at least `top_seen_share` of its top
// from within `top_seen_range_m` (TableTopViews, table_top_views.hpp: a top seen
// near enough while driving by needs no visit). ObjectSearch keeps that per
// request: a new request (another request id) starts with no table searched.
//
// Pure core code: no LCM, no clock, no threads.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "findmug/common/pose2d.hpp"
#include "findmug/map/object_map.hpp"
#include "findmug/map/table_top_views.hpp"
#include "findmug/settings/settings.hpp"
#include "findmug/tables/tables.hpp"

namespace findmug {

struct ObjectSearchConfig {
  float position_tolerance_m = 0.3f;   // robot this near a search position stood there
  float heading_tolerance_rad = 0.5f;  // ... facing within this of the position's yaw
  // Views search a table once they showed this share of its top (0: only standing at a
  // search position does) ...
  float top_seen_share = 0.8f;
  // ... from within this distance: the matcher's reach (it names a mug from 1-1.5 m).
  float top_seen_range_m = 1.5f;
};

// Throws findmug::Error naming the setting (`object_search.KEY`) when out of range.
void validateObjectSearchConfig(const ObjectSearchConfig& config);

// The `object_search:` section of the config file, one key per field above.
const SettingsTable<ObjectSearchConfig>& objectSearchSettings();

// One place to look: a search position (map frame) of a mapped table.
struct PlaceToLook {
  int table_id = 0;  // the table map's stable id
  SearchPosition position;
  bool seen_here_before = false;  // the object was once seen on this table
  bool searched = false;          // the robot already stood here (or saw its top) for this request
  bool look_closer = false;       // the table holds an object that may be it: look closer
};

struct FindAnswer {
  enum class Kind { Seen, LookAt, UnknownName };
  Kind kind = Kind::LookAt;
  std::string name;
  // Seen: the mapped object, its table, and where to stand (nullopt when its
  // table has no reachable search position in the table map).
  std::optional<MappedObject> object;
  std::optional<SearchPosition> stand_here;
  // LookAt: the places in the order to visit them.
  std::vector<PlaceToLook> places;
  // One line for people and logs: what was found or why not.
  std::string summary;
};

class ObjectSearch {
 public:
  explicit ObjectSearch(ObjectSearchConfig config = {});

  // The answer to request `request_id` for `name`, given the taught names,
  // the object map, the table map's tables (map frame; TableCluster::id the
  // stable id) and the robot's pose (nullopt: unknown; tours then start at
  // the first place). `now_utime` only words the summary ("seen 12 s ago").
  FindAnswer answer(std::int64_t request_id, const std::string& name,
                    const std::vector<std::string>& taught_names, const ObjectMap& objects,
                    const std::vector<TableCluster>& map_tables,
                    const std::optional<Pose2D>& robot, std::uint64_t now_utime);

  // The robot's pose now: marks, for the current request, the tables at one
  // of whose search positions it stands. Returns the ids newly marked.
  std::vector<int> observeRobot(const Pose2D& robot, const std::vector<TableCluster>& map_tables);

  // A camera view (its depth image and the camera's pose in the map): marks, for the
  // current request, the tables of which the views since the request showed at least
  // top_seen_share of the top. Returns the ids newly marked. Throws findmug::Error naming
  // the frame when its depth image does not fit its size.
  std::vector<int> observeView(const std::vector<TableCluster>& map_tables, const RgbdFrame& frame,
                               const Eigen::Isometry3d& camera_in_map);

  std::int64_t requestId() const { return request_id_; }
  const std::set<int>& searchedTables() const { return searched_; }

 private:
  ObjectSearchConfig config_;
  std::int64_t request_id_ = -1;
  std::set<int> searched_;
  TableTopViews top_views_;  // since the request
};

}  // namespace findmug
