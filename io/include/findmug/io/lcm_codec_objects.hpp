// findmug/io/lcm_codec_objects.hpp — table-top object candidates <-> objects_t (LCM).
//
// One frame's TableObjectDetection (include/findmug/objects/table_objects.hpp)
// goes out on FINDMUG_OBJECTS beside the frame's tables_t, naming each
// object's table by its index in that message (and its map id when the table
// map took the frame); the object map (include/findmug/map/object_map.hpp) on
// FINDMUG_OBJECT_MAP, each object under its stable id with its name. The decoder trusts nothing, as those of lcm_codec.hpp:
// the wire layout is walked before LCM allocates (lcm_wire.cpp), then sizes,
// finite numbers, ranges, unit axes, histogram sums, truncation bits and the
// table ids are checked; any problem is a findmug::Error naming the channel
// and the field, e.g.
//   "FINDMUG_OBJECTS: objects_t.objects[2].table_id: 3 outside [0, num_tables 2)".
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/messages.hpp"
#include "findmug/map/object_map.hpp"
#include "findmug/objects/table_objects.hpp"
#include "findmug/tables/tables.hpp"
#include "findmug_lcm/objects_t.hpp"

namespace findmug::io {

// Walks the wire layout of an objects_t, then lets LCM decode it (lcm_wire.cpp).
template <>
findmug_lcm::objects_t decodeMessage<findmug_lcm::objects_t>(const void*, std::size_t,
                                                             std::string_view);

// A frame's candidates (Frame content). `tables` are the frame's tables the
// objects' `table` indices refer to; `table_map_info` is empty or one entry
// per table (FrameResult::map_info); with `map_pose` the map_centroid fields
// are the centroids in the map frame, as encodeTables computes the tables'.
// Throws findmug::Error when an object's table index is outside `tables`,
// table_map_info has another size, or the message breaks a rule decodeObjects checks
// (e.g. a colour histogram that does not sum to 1), naming the field as it does.
findmug_lcm::objects_t encodeObjects(std::uint64_t utime, std::int64_t seq,
                                     const TableObjectDetection& detection,
                                     std::span<const TableCluster> tables,
                                     const std::optional<RobotPose>& map_pose,
                                     std::span<const TableMapInfo> table_map_info);

// The object map (Map content, FINDMUG_OBJECT_MAP) after an update with the frame of
// `utime`/`seq` seen at `map_pose`: every object of `objects` (map frame; the fields
// without the map_ prefix are computed relative to the robot at map_pose, as encodeTables
// does for the table map), its table_id the index of its table (MappedObject::table_id,
// a table map id) in `map_tables` (the table map's confirmed tables, in the order
// FINDMUG_TABLE_MAP lists them), -1 when it is not there. Throws findmug::Error, naming
// the field, for what decodeObjects would refuse.
findmug_lcm::objects_t encodeObjectMap(std::uint64_t utime, std::int64_t seq,
                                       std::span<const MappedObject> objects,
                                       std::span<const TableCluster> map_tables,
                                       const RobotPose& map_pose);

// Checks every field (see the header comment; with Frame content the object-map
// fields must be 0 and the name "", with Map content has_map_pose, id == map_id > 0,
// sightings > 0, table_id -1 or a table, and a name that is "" or a taught-object
// name); fills map_info for every object.
ObjectsMessage decodeObjects(const findmug_lcm::objects_t& message, std::string_view channel);
ObjectsMessage decodeObjects(const void* data, std::size_t size, std::string_view channel);

}  // namespace findmug::io
