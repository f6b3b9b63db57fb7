// findmug/io/messages.hpp — the plain C++ form of findmug's output messages
// (label images, tables, table-top objects, the robot's pose), without the
// generated LCM types.
//
// lcm_codec.hpp encodes and decodes them; code that only passes them around
// (the daemon's pipeline and sinks, the pose input) includes this header and
// stays free of <findmug_lcm/*.hpp>.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "findmug/common/pose2d.hpp"
#include "findmug/frame/frame.hpp"
#include "findmug/labels/label_image.hpp"
#include "findmug/objects/table_objects.hpp"
#include "findmug/tables/tables.hpp"

namespace findmug::io {

// The camera of a labelled frame as the daemon used it (label_image_t.has_camera):
// intrinsics and the camera-to-base transform (p_base = camera_to_base * p_camera).
struct CameraView {
  CameraIntrinsics intrinsics;
  Eigen::Isometry3d camera_to_base = Eigen::Isometry3d::Identity();
};

struct LabelImageMessage {
  LabelImage image;         // confidence empty when the message had none
  std::uint64_t utime = 0;  // source frame's utime
  std::int64_t seq = 0;     // source frame's seq
  std::int64_t latency_us = 0;
  std::optional<CameraView> camera;     // label_image_t.has_camera
  std::vector<std::uint8_t> color_jpeg;  // label_image_t.color_data when COLOR_JPEG, else empty
};

// The robot base's pose in the map at a time (robot_pose_t): a time-stamped Pose2D.
struct RobotPose {
  std::uint64_t utime = 0;  // host clock, microseconds
  Pose2D pose;
};

// A request to the daemon (command_t on FINDMUG_COMMAND): what, its argument, and
// the sender's id for it (reported back in status_t).
struct CommandMessage {
  std::uint64_t utime = 0;
  std::int64_t request_id = 0;
  std::string command;
  std::string argument;
};

// Map-frame copies of one table (tables_t with has_map_pose).
struct MapFrameTable {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Vector2d center = Eigen::Vector2d::Zero();  // oriented box centre
  std::vector<Eigen::Vector2d> hull;
  std::vector<SearchPosition> search_positions;  // xy, yaw in the map frame
};

// What a tables_t holds (tables_t.content): one frame's detections
// (FINDMUG_TABLES) or the confirmed tables of the persistent table map
// (FINDMUG_TABLE_MAP).
enum class TablesContent : std::int8_t { Frame = 0, Map = 1 };

// A table's entry in the daemon's table map (table_t.map_id/confirmed/sightings/viewpoints).
struct TableMapInfo {
  int map_id = 0;  // stable id, 1, 2, ...; 0 = not in the map
  bool confirmed = false;
  int sightings = 0;   // frames that saw it
  int viewpoints = 0;  // distinct viewpoints among them (semantic map only; else 0)
};

struct TablesMessage {
  std::uint64_t utime = 0;  // source frame's utime
  std::int64_t seq = 0;
  TablesContent content = TablesContent::Frame;
  std::vector<TableCluster> tables;       // robot base frame
  std::optional<RobotPose> map_pose;      // when the pose was known
  std::vector<MapFrameTable> map_tables;  // one per table when map_pose, else empty
  // One per table, or empty (= no table is in the map). Always filled by the decoder.
  std::vector<TableMapInfo> map_info;
};

// What an objects_t carries per object besides the TableObject itself
// (table_object_t's map fields). With Frame content map_id, sightings,
// last_seen_utime and the name are 0 / "".
struct ObjectMapInfo {
  int table_map_id = 0;  // the map id of the table it stands on; 0 = not in the map
  Eigen::Vector3d map_centroid = Eigen::Vector3d::Zero();  // valid when the message has map_pose
  int map_id = 0;        // stable id in the object map (FINDMUG_OBJECT_MAP); 0 with Frame content
  int sightings = 0;
  std::uint64_t last_seen_utime = 0;
  std::string name;        // the taught object it was named as ("" none)
  float name_score = 0.0f;
};

// One frame's object candidates on FINDMUG_OBJECTS (objects_t;
// lcm_codec_objects.hpp). The content ids are those of tables_t.
struct ObjectsMessage {
  std::uint64_t utime = 0;  // source frame's utime
  std::int64_t seq = 0;
  TablesContent content = TablesContent::Frame;
  int num_tables = 0;  // tables in the tables_t of the same seq; objects' `table` < this
  std::optional<RobotPose> map_pose;
  // Base frame; `table` is table_object_t.table_id (with Map content -1 when the object's
  // table is not among the table map's confirmed tables) and `pixels` is empty (not on the wire).
  std::vector<TableObject> objects;
  std::vector<ObjectMapInfo> map_info;  // one per object; always filled by the decoder
};

}  // namespace findmug::io
