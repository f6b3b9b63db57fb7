// Wire-layout checks run before LCM's generated decode().
//
// The generated code trusts the size fields: a corrupt depth_size of 2e9 makes
// it allocate and zero 2 GB before noticing the message is short, a corrupt
// string length of 0 makes it throw std::length_error. Walking the layout
// first, with every length checked against the bytes that are really left,
// turns all of that into a findmug::Error naming the field. The walkers
// mirror lcmtypes/*.lcm field by field; tests/integration/lcm_wire_test.cpp
// checks them against lcm-gen's encode()/decode() on many random messages of
// every type, and fails when a field is added to, removed from or moved
// within a .lcm file without the walker here following.
#include <cstring>
#include <limits>
#include <string>
#include <string_view>

#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/lcm_codec_find.hpp"
#include "findmug/io/lcm_codec_objects.hpp"

namespace findmug::io {

namespace {

class WireWalker {
 public:
  WireWalker(const void* data, std::size_t size, std::string_view type, std::string_view channel)
      : data_(static_cast<const std::uint8_t*>(data)),
        size_(size),
        type_(type),
        channel_(channel) {}

  [[noreturn]] void fail(std::string_view field, const std::string& what) const {
    throw Error(std::string(channel_) + ": " + std::string(type_) + "." + std::string(field) +
                ": " + what + " (message of " + std::to_string(size_) + " bytes)");
  }

  void hash(std::int64_t expected) {
    need(8, "<hash>");
    const auto got = static_cast<std::int64_t>(bigEndian(8));
    if (got != expected) {
      throw Error(std::string(channel_) + ": not a findmug_lcm." + std::string(type_) +
                  " message (type hash mismatch, " + std::to_string(size_) + " bytes)");
    }
  }

  // Fixed-size fields: just make sure they are there.
  void skip(std::size_t bytes, std::string_view field) {
    need(bytes, field);
    pos_ += bytes;
  }

  std::int32_t int32(std::string_view field) {
    need(4, field);
    return static_cast<std::int32_t>(bigEndian(4));
  }

  // An array length: non-negative and `count * element_bytes` must fit in
  // what is left. Returns the count.
  std::int32_t count(std::string_view field, std::size_t element_bytes) {
    const std::int32_t n = int32(field);
    if (n < 0) fail(field, "negative count " + std::to_string(n));
    if (static_cast<std::size_t>(n) * element_bytes > left()) {
      fail(field, "count " + std::to_string(n) + " needs at least " +
                      std::to_string(static_cast<std::size_t>(n) * element_bytes) +
                      " bytes, only " + std::to_string(left()) + " left");
    }
    return n;
  }

  void array(std::int32_t n, std::size_t element_bytes, std::string_view field) {
    skip(static_cast<std::size_t>(n) * element_bytes, field);
  }

  // LCM string: int32 length including the terminating NUL, bytes, NUL.
  void string(std::string_view field) {
    const std::int32_t n = int32(field);
    if (n < 1) fail(field, "string length " + std::to_string(n) + " (at least 1 for the NUL)");
    need(static_cast<std::size_t>(n), field);
    if (data_[pos_ + static_cast<std::size_t>(n) - 1] != 0)
      fail(field, "string not NUL-terminated");
    pos_ += static_cast<std::size_t>(n);
  }

  void finish() const {
    if (pos_ != size_) {
      throw Error(std::string(channel_) + ": " + std::string(type_) + ": " +
                  std::to_string(size_ - pos_) + " unexpected bytes after the message (" +
                  std::to_string(size_) + " bytes)");
    }
  }

 private:
  std::size_t left() const { return size_ - pos_; }

  void need(std::size_t bytes, std::string_view field) const {
    if (bytes > left()) {
      fail(field, "truncated: needs " + std::to_string(bytes) + " bytes at offset " +
                      std::to_string(pos_) + ", only " + std::to_string(left()) + " left");
    }
  }

  // Reads `bytes` big-endian bytes at pos_ and advances.
  std::uint64_t bigEndian(int bytes) {
    std::uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v = (v << 8) | data_[pos_++];
    return v;
  }

  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
  std::string_view type_;
  std::string_view channel_;
};

// Sizes on the wire.
constexpr std::size_t kI8 = 1, kBool = 1, kI32 = 4, kI64 = 8, kF32 = 4, kF64 = 8;
constexpr std::size_t kMinString = 5;  // length + NUL
constexpr std::size_t kMinSearchPosition = 3 * kF64 + kBool + kMinString;

void walkRobotPose(WireWalker& w) {
  w.skip(kI64, "utime");
  w.skip(3 * kF64, "x/y/yaw");
}

void walkSearchPosition(WireWalker& w, std::string_view field) {
  w.skip(3 * kF64, field);
  w.skip(kBool, field);
  w.string(field);
}

void walkTable(WireWalker& w) {
  w.skip(kI32, "tables.id");
  w.skip(3 * kF64 + kF64, "tables.centroid/top_height");
  w.skip(6 * kF64, "tables.major_axis/minor_axis/extents");
  const std::int32_t hull = w.count("tables.hull_size", 2 * kF64);
  w.array(hull, 2 * kF64, "tables.hull");
  w.skip(kI32 + kF32, "tables.point_count/mean_confidence");
  const std::int32_t positions = w.count("tables.num_search_positions", kMinSearchPosition);
  for (std::int32_t i = 0; i < positions; ++i) walkSearchPosition(w, "tables.search_positions");
  w.skip(3 * kF64, "tables.map_centroid");
  w.array(hull, 2 * kF64, "tables.map_hull");
  for (std::int32_t i = 0; i < positions; ++i) walkSearchPosition(w, "tables.map_search_positions");
  w.skip(4 * kF64, "tables.center/map_center");
  w.skip(kI32 + kBool + 2 * kI32, "tables.map_id/confirmed/sightings/viewpoints");
}

// table_object_t: the fixed-size fields id, table_id, table_map_id, centroid,
// map_centroid, height_above_top, major_axis, extents, center, point_count, mean_rgb,
// colour_histogram, truncation, map_id, sightings, last_seen_utime; then name (a
// string) and name_score.
constexpr std::size_t kTableObjectFixed =
    3 * kI32 + 6 * kF64 + kF64 + 6 * kF64 + kI32 + 3 * kF32 + 28 * kF32 + kI8 + 2 * kI32 + kI64;
constexpr std::size_t kMinTableObject = kTableObjectFixed + kMinString + kF32;

void walkTableObject(WireWalker& w) {
  w.skip(kTableObjectFixed, "objects");
  w.string("objects.name");
  w.skip(kF32, "objects.name_score");
}

template <typename Msg>
Msg decodeWalked(const void* data, std::size_t size, std::string_view channel) {
  Msg msg;
  int rc = -1;
  try {
    rc = msg.decode(data, 0, static_cast<int>(size));
  } catch (const std::exception& e) {
    throw Error(std::string(channel) + ": " + Msg::getTypeName() +
                ": LCM decode failed: " + e.what());
  }
  if (rc != static_cast<int>(size)) {
    throw Error(std::string(channel) + ": " + Msg::getTypeName() + ": LCM decode failed (" +
                std::to_string(rc) + " of " + std::to_string(size) + " bytes)");
  }
  return msg;
}

void checkSize(std::size_t size, std::string_view type, std::string_view channel) {
  if (size > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    throw Error(std::string(channel) + ": " + std::string(type) + ": message of " +
                std::to_string(size) + " bytes is too large");
  }
}

// Every decoder below: the size check, the walk over the type's layout (each length
// capped before anything is allocated), then lcm-gen's decode of bytes now known to fit.
template <typename Msg, typename Walk>
Msg walkThenDecode(const void* data, std::size_t size, std::string_view channel, Walk walk) {
  checkSize(size, Msg::getTypeName(), channel);
  WireWalker w(data, size, Msg::getTypeName(), channel);
  w.hash(Msg::getHash());
  walk(w);
  w.finish();
  return decodeWalked<Msg>(data, size, channel);
}

}  // namespace

template <>
findmug_lcm::rgbd_frame_t decodeMessage<findmug_lcm::rgbd_frame_t>(const void* data,
                                                                   std::size_t size,
                                                                   std::string_view channel) {
  return walkThenDecode<findmug_lcm::rgbd_frame_t>(data, size, channel, [](WireWalker& w) {
    w.skip(2 * kI64, "utime/seq");
    w.string("source");
    w.skip(2 * kI32, "width/height");
    w.skip(4 * kF64, "fx/fy/cx/cy");
    w.skip(kBool + 3 * kF64, "extrinsics");
    w.skip(kI8, "depth_compression");
    w.array(w.count("depth_size", 1), 1, "depth_data");
    w.skip(kI8, "color_compression");
    w.array(w.count("color_size", 1), 1, "color_data");
  });
}

template <>
findmug_lcm::label_image_t decodeMessage<findmug_lcm::label_image_t>(const void* data,
                                                                     std::size_t size,
                                                                     std::string_view channel) {
  return walkThenDecode<findmug_lcm::label_image_t>(data, size, channel, [](WireWalker& w) {
    w.skip(2 * kI64 + 2 * kI32, "utime/seq/width/height");
    const std::int32_t names = w.count("num_labels", kMinString);
    for (std::int32_t i = 0; i < names; ++i) w.string("label_names");
    w.skip(kI8, "compression");
    w.array(w.count("labels_size", 1), 1, "labels_data");
    w.skip(kBool, "has_confidence");
    w.array(w.count("confidence_size", 1), 1, "confidence_data");
    w.skip(kI64, "latency_us");
    w.skip(kBool + 4 * kF64 + 12 * kF64, "has_camera/fx/fy/cx/cy/camera_to_base");
    w.skip(kI8, "color_format");
    w.array(w.count("color_size", 1), 1, "color_data");
  });
}

template <>
findmug_lcm::tables_t decodeMessage<findmug_lcm::tables_t>(const void* data, std::size_t size,
                                                           std::string_view channel) {
  return walkThenDecode<findmug_lcm::tables_t>(data, size, channel, [](WireWalker& w) {
    w.skip(2 * kI64 + kBool, "utime/seq/has_map_pose");
    walkRobotPose(w);
    // A table is at least its fixed fields: id, centroid, top height, axes,
    // extents, hull_size, point_count, mean_confidence, num_search_positions,
    // map centroid, centres, map_id, confirmed, sightings, viewpoints.
    const std::int32_t tables = w.count("num_tables", kI32 + 10 * kF64 + 2 * kI32 + kF32 + kI32 +
                                                          3 * kF64 + 4 * kF64 + 3 * kI32 + kBool);
    for (std::int32_t i = 0; i < tables; ++i) walkTable(w);
    w.skip(kI8, "content");
  });
}

template <>
findmug_lcm::objects_t decodeMessage<findmug_lcm::objects_t>(const void* data, std::size_t size,
                                                             std::string_view channel) {
  return walkThenDecode<findmug_lcm::objects_t>(data, size, channel, [](WireWalker& w) {
    w.skip(2 * kI64 + kI8 + kI32 + kBool, "utime/seq/content/num_tables/has_map_pose");
    walkRobotPose(w);
    const std::int32_t objects = w.count("num_objects", kMinTableObject);
    for (std::int32_t i = 0; i < objects; ++i) walkTableObject(w);
  });
}

template <>
findmug_lcm::find_result_t decodeMessage<findmug_lcm::find_result_t>(const void* data,
                                                                     std::size_t size,
                                                                     std::string_view channel) {
  return walkThenDecode<findmug_lcm::find_result_t>(data, size, channel, [](WireWalker& w) {
    w.skip(2 * kI64, "utime/request_id");
    w.string("name");
    w.skip(kI8, "result");
    w.string("summary");
    w.skip(kI32 + 3 * kF64 + kI32 + kI64 + kF32 + kBool, "seen_*/has_stand_here");
    walkSearchPosition(w, "stand_here");
    const std::int32_t places =
        w.count("num_places", kMinSearchPosition + kI32 + 3 * kBool);
    for (std::int32_t i = 0; i < places; ++i) walkSearchPosition(w, "places");
    w.array(places, kI32, "place_table_ids");
    w.array(places, kBool, "place_seen_before");
    w.array(places, kBool, "place_searched");
    w.array(places, kBool, "place_look_closer");
    const std::int32_t taught = w.count("num_taught", kMinString);
    for (std::int32_t i = 0; i < taught; ++i) w.string("taught_names");
  });
}

template <>
findmug_lcm::status_t decodeMessage<findmug_lcm::status_t>(const void* data, std::size_t size,
                                                           std::string_view channel) {
  return walkThenDecode<findmug_lcm::status_t>(data, size, channel, [](WireWalker& w) {
    w.skip(2 * kI64 + 4 * kI64, "utime/uptime_us/frame counters");
    w.skip(kF64 + 2 * kF32, "window_s/input_fps/output_fps");
    const std::int32_t stages = w.count("num_stages", kMinString + 3 * kI64);
    for (std::int32_t i = 0; i < stages; ++i) w.string("stage_names");
    w.array(stages, kI64, "latency_p50_us");
    w.array(stages, kI64, "latency_p95_us");
    w.array(stages, kI64, "latency_max_us");
    const std::int32_t queues = w.count("num_queues", kMinString + 2 * kI32);
    for (std::int32_t i = 0; i < queues; ++i) w.string("queue_names");
    w.array(queues, kI32, "queue_depths");
    w.array(queues, kI32, "queue_capacities");
    w.string("model_id");
    w.string("source");
    w.string("source_state_name");
    w.skip(kI8, "source_state");
    w.string("last_error");
    w.skip(kI64, "last_error_utime");
    w.skip(3 * kI64, "frames_dropped_at_door/in_pipeline/at_shutdown");
    w.skip(2 * kF32 + kI32, "cpu_budget_cores/cpu_used_cores/processing_threads");
    w.skip(kI64, "source_reconnects");
    w.skip(3 * kI64, "frames_lost_in_transit/publish_failures/heap_in_use_bytes");
    w.skip(3 * kI64, "semantic_map_frames/skipped/voxels");
    w.skip(2 * kI64 + kBool, "model_reloads/model_reloads_refused/last_reload_ok");
    w.string("last_reload_result");
    w.skip(2 * kI64, "last_reload_utime/last_reload_request_id");
    w.skip(2 * kI64, "commands_accepted/commands_rejected");
    w.skip(2 * kI64, "frames_collected/frames_collect_refused");
    w.string("last_collected_frame");
    w.skip(2 * kI64 + kBool, "objects_taught/teach_refused/last_teach_ok");
    w.string("last_teach_result");
    w.skip(kI64, "last_teach_request_id");
    w.skip(15 * kI64, "object_frames ... object_map_publishes");
  });
}

template <>
findmug_lcm::robot_pose_t decodeMessage<findmug_lcm::robot_pose_t>(const void* data,
                                                                   std::size_t size,
                                                                   std::string_view channel) {
  return walkThenDecode<findmug_lcm::robot_pose_t>(data, size, channel,
                                                   [](WireWalker& w) { walkRobotPose(w); });
}

template <>
findmug_lcm::command_t decodeMessage<findmug_lcm::command_t>(const void* data, std::size_t size,
                                                             std::string_view channel) {
  return walkThenDecode<findmug_lcm::command_t>(data, size, channel, [](WireWalker& w) {
    w.skip(2 * kI64, "utime/request_id");
    w.string("command");
    w.string("argument");
  });
}

}  // namespace findmug::io
