// findmug/io/channels.hpp — LCM channel names used by findmug.
//
// Every channel is a base name plus an optional suffix, so that several
// robots / cameras can share one LCM network: suffix "KITCHEN" turns
// FINDMUG_RGBD into FINDMUG_RGBD_KITCHEN. The suffix is configured once
// (daemon.channel_suffix, --channel-suffix) and applied by the bus
// (io::SuffixedBus, bus.hpp): programs publish and subscribe by base name.
//
//   FINDMUG_RGBD        findmug_lcm::rgbd_frame_t   frames in (sensor, findmug-grab)
//   FINDMUG_LABELS      findmug_lcm::label_image_t  per-pixel labels out
//   FINDMUG_TABLES      findmug_lcm::tables_t       tables + search positions out (one frame)
//   FINDMUG_OBJECTS     findmug_lcm::objects_t      object candidates on the table tops, out with
//                                               every FINDMUG_TABLES message (same seq; none
//                                               found: an empty list)
//   FINDMUG_TABLE_MAP   findmug_lcm::tables_t       confirmed tables of the persistent map, out
//                                               after each map update (needs robot poses)
//   FINDMUG_OBJECT_MAP  findmug_lcm::objects_t      the object map (stable ids, names), out after
//                                               each object map update (needs robot poses)
//   FINDMUG_STATUS      findmug_lcm::status_t       daemon health, about 1 Hz
//   FINDMUG_ROBOT_POSE  findmug_lcm::robot_pose_t   robot pose in the map (input, optional)
//   FINDMUG_SEMANTIC_MAP findmug_lcm::semantic_map_t the fused 3-D semantic map, out at a low
//                                               rate when it changed (daemon.semantic_map)
//   FINDMUG_COMMAND     findmug_lcm::command_t      requests to the daemon (reload_model), input
//   FINDMUG_FIND_RESULT findmug_lcm::find_result_t  the answer to a "find NAME" command
#pragma once

#include <string>
#include <string_view>

namespace findmug::io {

inline constexpr std::string_view kRgbdChannel = "FINDMUG_RGBD";
inline constexpr std::string_view kLabelsChannel = "FINDMUG_LABELS";
inline constexpr std::string_view kTablesChannel = "FINDMUG_TABLES";
inline constexpr std::string_view kObjectsChannel = "FINDMUG_OBJECTS";
inline constexpr std::string_view kTableMapChannel = "FINDMUG_TABLE_MAP";
inline constexpr std::string_view kObjectMapChannel = "FINDMUG_OBJECT_MAP";
inline constexpr std::string_view kStatusChannel = "FINDMUG_STATUS";
inline constexpr std::string_view kRobotPoseChannel = "FINDMUG_ROBOT_POSE";
inline constexpr std::string_view kSemanticMapChannel = "FINDMUG_SEMANTIC_MAP";
inline constexpr std::string_view kCommandChannel = "FINDMUG_COMMAND";
inline constexpr std::string_view kFindResultChannel = "FINDMUG_FIND_RESULT";

// `base` + "_" + `suffix`, or `base` when the suffix is empty. The suffix may
// hold only letters, digits and '_' (and may not start with '_'); anything
// else throws findmug::Error naming the suffix, because a typo there would
// silently make publisher and subscriber miss each other.
std::string channelName(std::string_view base, std::string_view suffix);
// Throws the same findmug::Error for a suffix channelName() refuses (a flag's check).
void checkChannelSuffix(std::string_view suffix);

}  // namespace findmug::io
