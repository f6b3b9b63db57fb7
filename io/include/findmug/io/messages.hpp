// findmug/io/messages.hpp — the plain C++ form of findmug's output messages
// (label images, tables, the robot's pose), without the generated LCM types.
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

}  // namespace findmug::io
