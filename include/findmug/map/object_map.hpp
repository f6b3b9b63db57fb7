// findmug/map/object_map.hpp — the objects seen on table tops, kept across frames.
//
// findTableObjects (objects/table_objects.hpp) sees one frame in the robot
// base frame. With the robot's pose in a map frame, the ObjectMap places each
// frame's candidates in the map and keeps them under stable ids, so that a
// robot asked for its mug can be told where it saw it last, and when.
//
//   * A candidate is the same object as a mapped one when their centroids are
//     within `match_distance_m` on the floor and `match_height_m` in height,
//     and their colour histograms are within `match_colour_distance`
//     (colourHistogramDistance, table_objects.hpp): a blue mug put where a red one stood is a new
//     object. Pairs are taken nearest first, one to one (deterministic).
//   * A matched object's position, footprint and colour are the running mean
//     of its last `max_mean_sightings` sightings (objects stand still while
//     they are seen; a few centimetres of depth noise average out).
//   * Names need evidence. A candidate the taught-object matcher named
//     (ObjectIdentity) is one match for that name; its mapped object takes
//     the name once `name_after_matches` sightings matched it from no
//     farther than `max_name_range_m` (floor distance from the robot to the
//     candidate). One match is not enough: from a single view a mug-sized
//     box of the mug's colour is taken for the mug in 4-8 % of single views
//     (BENCHMARKS.md section 8), rarely twice in one visit. Until then the name is only
//     pending (MappedObject::pending_name): "maybe the mug, look closer".
//     A far match never confirms a name: beyond about 1.5 m the depth steps
//     bend a box's faces like a mug's side, and the roundness cue that tells
//     them apart weakens. The defaults (2 matches within 2 m) were chosen on
//     object_recognition_eval's visits of seeds 101-160, and measured on
//     seeds 1-60 (BENCHMARKS.md section 8). A match for another name starts the count again for
//     that name; a sighting without a name changes nothing. A named object
//     keeps its name until another name is confirmed the same way. The map
//     also remembers, per name, the tables it was ever seen on
//     (seenOnTables), forgotten objects included: where the mug was before
//     is where to look for it first.
//   * A mapped object is missed in a frame when its place was seen without it:
//     its floor position lies inside the visible top of one of the frame's
//     tables (its hull shrunk by `seen_margin_m`) and no candidate matched it.
//     After `forget_misses` consecutive misses it is forgotten: somebody took
//     the mug away. An object whose place is out of view is neither matched
//     nor missed: it stays, with its last-seen time.
//
// Pure core code: no LCM, no clock, no threads; the caller passes the time.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "findmug/common/pose2d.hpp"
#include "findmug/objects/table_objects.hpp"
#include "findmug/settings/settings.hpp"
#include "findmug/tables/tables.hpp"

namespace findmug {

struct ObjectMapConfig {
  float match_distance_m = 0.10f;       // centroids this close on the floor ...
  float match_height_m = 0.10f;         // ... and in height may be one object ...
  float match_colour_distance = 0.5f;   // ... when their colours are this close (0..1)
  int forget_misses = 3;                // consecutive frames its place was seen without it
  float seen_margin_m = 0.05f;          // a place is seen when this far inside a visible top
  int max_mean_sightings = 10;          // sightings the running means weigh
  int name_after_matches = 2;           // near matches for a name before the object takes it
  float max_name_range_m = 2.0f;        // a match farther from the robot is not evidence
};

// Throws findmug::Error naming the setting (as `object_map.KEY`) when out of range.
void validateObjectMapConfig(const ObjectMapConfig& config);

// The `object_map:` section of the config file, one key per field above.
const SettingsTable<ObjectMapConfig>& objectMapSettings();

// What the taught-object matcher said of one candidate: its name ("" when it
// matched no taught object) and the match score (higher is better).
struct ObjectIdentity {
  std::string name;
  float score = 0.0f;
};

struct MappedObject {
  int id = 0;  // stable: 1, 2, ... in order of creation, never reused
  // Map frame: floor position and height of the centroid, the footprint's
  // first axis (unit, map frame) and half-lengths, the height above its table.
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
  Eigen::Vector2f major_axis = Eigen::Vector2f::UnitX();
  Eigen::Vector2f extents = Eigen::Vector2f::Zero();
  float height_above_top = 0.0f;
  Eigen::Vector3f mean_rgb = Eigen::Vector3f::Zero();
  ObjectColourHistogram colour_histogram{};
  int point_count = 0;  // of the last sighting
  // The table it was last seen on: the caller's id for it (the table map's
  // stable id; 0 when that table was not in a map).
  int table_id = 0;
  // The taught object it was confirmed as ("" none yet): name_after_matches
  // near matches; the score is that of the last near match.
  std::string name;
  float name_score = 0.0f;
  // A name with matches that do not confirm it yet (too few, or from too far):
  // "maybe this, look closer". "" when none, or when it is `name`.
  std::string pending_name;
  int pending_matches = 0;  // near matches for pending_name so far
  int sightings = 0;  // frames it was seen in
  int misses = 0;     // consecutive frames its place was seen without it
  std::uint64_t first_seen_utime = 0;
  std::uint64_t last_seen_utime = 0;
};

struct ObjectMapUpdate {
  // Per candidate of the frame (same order): the id of the mapped object it
  // is now part of (matched or created).
  std::vector<int> object_ids;
  std::vector<int> created;
  std::vector<int> forgotten;
};

class ObjectMap {
 public:
  explicit ObjectMap(ObjectMapConfig config = {});

  // One labelled frame's candidates (`objects`, base frame) on its `tables`
  // (base frame), with `table_ids[i]` the caller's id of tables[i] (e.g. its
  // table map id, 0 for none; empty: all 0), taken at `base_in_map` at time
  // `utime` (microseconds). `identities` (empty, or one per candidate) are
  // the matcher's names for the candidates. Throws findmug::Error when an
  // object's table index, table_ids' or identities' size does not fit.
  ObjectMapUpdate update(const std::vector<TableObject>& objects,
                         const std::vector<TableCluster>& tables,
                         const std::vector<int>& table_ids, const Pose2D& base_in_map,
                         std::uint64_t utime, const std::vector<ObjectIdentity>& identities = {});

  const std::vector<MappedObject>& objects() const { return objects_; }
  // The caller's ids of the tables (non-zero ones) an object of this name was
  // ever seen on, ascending; forgotten objects count too. Empty for "".
  std::vector<int> seenOnTables(const std::string& name) const;
  void clear();
  const ObjectMapConfig& config() const { return config_; }

 private:
  void absorb(MappedObject& mapped, const TableObject& seen, const Pose2D& base_in_map,
              int table_id, std::uint64_t utime) const;
  MappedObject create(const TableObject& seen, const Pose2D& base_in_map, int table_id,
                      std::uint64_t utime);
  void name(MappedObject& mapped, const ObjectIdentity* identity, float range_m);
  bool placeSeen(const MappedObject& mapped, const std::vector<TableCluster>& tables,
                 const Pose2D& map_in_base) const;

  ObjectMapConfig config_;
  std::vector<MappedObject> objects_;
  std::map<std::string, std::set<int>> seen_on_tables_;  // name -> table ids
  int next_id_ = 1;
};

}  // namespace findmug
