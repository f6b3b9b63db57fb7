// lcm_wire (io/src/lcm_wire.cpp) against lcm-gen's own code.
//
// decodeMessage<T> walks each message's layout by hand before handing it to
// the generated decode(), so that corrupt lengths fail before allocating.
// Those hand layouts re-state lcmtypes/*.lcm; nothing but this test ties them
// together. For every findmug LCM type and many generated messages (random
// field values, array lengths from 0 up to a few thousand, strings of 0 to a
// few hundred characters, and one large message per type), the bytes of the
// generated encode() must be accepted by the walk exactly: getEncodedSize()
// bytes decode, one byte more or one byte less does not, and the decoded
// message equals the original field by field (checked as: it re-encodes to the
// same bytes, and a few fields compared directly).
//
// Why this catches drift: a field added to, removed from or moved within a
// .lcm file changes what encode() writes. The walk then reads its counts and
// string lengths from the wrong places, which for random contents gives a
// negative or oversized count, a missing NUL or a size mismatch at the end:
// the message is refused and the test fails. (A field the generator below
// does not know about is still encoded, with its default value.)
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/lcm_codec_objects.hpp"
#include "findmug_lcm/label_image_t.hpp"
#include "findmug_lcm/rgbd_frame_t.hpp"
#include "findmug_lcm/command_t.hpp"
#include "findmug_lcm/objects_t.hpp"
#include "findmug_lcm/robot_pose_t.hpp"
#include "findmug_lcm/status_t.hpp"
#include "findmug_lcm/tables_t.hpp"

namespace findmug::io {
namespace {

using Bytes = std::vector<std::uint8_t>;

// Random field values. `scale` sets how long arrays and strings get: 0 for
// empty ones, larger for longer.
class Random {
 public:
  explicit Random(std::uint64_t seed) : rng_(seed) {}
  std::int64_t i64() { return static_cast<std::int64_t>(rng_()); }
  std::int32_t i32() { return static_cast<std::int32_t>(rng_()); }
  std::int8_t i8() { return static_cast<std::int8_t>(rng_()); }
  bool boolean() { return (rng_() & 1) != 0; }
  double f64() { return std::uniform_real_distribution<double>(-1e6, 1e6)(rng_); }
  float f32() { return std::uniform_real_distribution<float>(-1e3f, 1e3f)(rng_); }
  // A length in [0, max]: often 0 or max, else anything between.
  int length(int max) {
    switch (rng_() % 4) {
      case 0:
        return 0;
      case 1:
        return max;
      default:
        return static_cast<int>(rng_() % (static_cast<std::uint64_t>(max) + 1));
    }
  }
  // Printable, no NUL (an LCM string ends at its first NUL).
  std::string text(int max_length) {
    std::string s(static_cast<std::size_t>(length(max_length)), ' ');
    for (char& c : s) c = static_cast<char>(' ' + rng_() % 95);
    return s;
  }
  std::vector<std::uint8_t> bytes(int max_length) {
    std::vector<std::uint8_t> b(static_cast<std::size_t>(length(max_length)));
    for (auto& x : b) x = static_cast<std::uint8_t>(rng_());
    return b;
  }

 private:
  std::mt19937_64 rng_;
};

// Sizes of one round: `array` for array lengths, `text` for string lengths.
struct Scale {
  int array;
  int text;
  int blob;  // byte arrays (image payloads)
};

findmug_lcm::robot_pose_t makePose(Random& r) {
  findmug_lcm::robot_pose_t m;
  m.utime = r.i64();
  m.x = r.f64();
  m.y = r.f64();
  m.yaw = r.f64();
  return m;
}

findmug_lcm::rgbd_frame_t makeFrame(Random& r, const Scale& s) {
  findmug_lcm::rgbd_frame_t m;
  m.utime = r.i64();
  m.seq = r.i64();
  m.source = r.text(s.text);
  m.width = r.i32();
  m.height = r.i32();
  m.fx = r.f64();
  m.fy = r.f64();
  m.cx = r.f64();
  m.cy = r.f64();
  m.has_extrinsics = r.boolean();
  m.height_m = r.f64();
  m.pitch_rad = r.f64();
  m.roll_rad = r.f64();
  m.depth_compression = r.i8();
  m.depth_data = r.bytes(s.blob);
  m.depth_size = static_cast<std::int32_t>(m.depth_data.size());
  m.color_compression = r.i8();
  m.color_data = r.bytes(s.blob);
  m.color_size = static_cast<std::int32_t>(m.color_data.size());
  return m;
}

findmug_lcm::label_image_t makeLabels(Random& r, const Scale& s) {
  findmug_lcm::label_image_t m;
  m.utime = r.i64();
  m.seq = r.i64();
  m.width = r.i32();
  m.height = r.i32();
  m.label_names.resize(static_cast<std::size_t>(r.length(s.array)));
  for (auto& name : m.label_names) name = r.text(s.text);
  m.num_labels = static_cast<std::int32_t>(m.label_names.size());
  m.compression = r.i8();
  m.labels_data = r.bytes(s.blob);
  m.labels_size = static_cast<std::int32_t>(m.labels_data.size());
  m.has_confidence = r.boolean();
  m.confidence_data = r.bytes(s.blob);
  m.confidence_size = static_cast<std::int32_t>(m.confidence_data.size());
  m.latency_us = r.i64();
  m.has_camera = r.boolean();
  m.fx = r.f64();
  m.fy = r.f64();
  m.cx = r.f64();
  m.cy = r.f64();
  for (auto& row : m.camera_to_base) {
    for (double& v : row) v = r.f64();
  }
  m.color_format = r.i8();
  m.color_data = r.bytes(s.blob);
  m.color_size = static_cast<std::int32_t>(m.color_data.size());
  return m;
}

findmug_lcm::search_position_t makePosition(Random& r, const Scale& s) {
  findmug_lcm::search_position_t p;
  p.x = r.f64();
  p.y = r.f64();
  p.yaw = r.f64();
  p.reachable = r.boolean();
  p.reason = r.text(s.text);
  return p;
}

findmug_lcm::tables_t makeTables(Random& r, const Scale& s) {
  findmug_lcm::tables_t m;
  m.utime = r.i64();
  m.seq = r.i64();
  m.has_map_pose = r.boolean();
  m.map_pose = makePose(r);
  // Tables nest two arrays deep: keep the product of the lengths moderate.
  m.tables.resize(static_cast<std::size_t>(r.length(std::max(1, s.array / 8))));
  for (auto& t : m.tables) {
    t.id = r.i32();
    for (double& v : t.centroid) v = r.f64();
    t.top_height = r.f64();
    for (double& v : t.major_axis) v = r.f64();
    for (double& v : t.minor_axis) v = r.f64();
    for (double& v : t.extents) v = r.f64();
    const int hull = r.length(s.array);
    t.hull.assign(static_cast<std::size_t>(hull), std::vector<double>(2));
    t.map_hull.assign(static_cast<std::size_t>(hull), std::vector<double>(2));
    for (auto& q : t.hull) q = {r.f64(), r.f64()};
    for (auto& q : t.map_hull) q = {r.f64(), r.f64()};
    t.hull_size = hull;
    t.point_count = r.i32();
    t.mean_confidence = r.f32();
    const int positions = r.length(std::max(1, s.array / 8));
    for (int i = 0; i < positions; ++i) {
      t.search_positions.push_back(makePosition(r, s));
      t.map_search_positions.push_back(makePosition(r, s));
    }
    t.num_search_positions = positions;
    for (double& v : t.map_centroid) v = r.f64();
    for (double& v : t.center) v = r.f64();
    for (double& v : t.map_center) v = r.f64();
    t.map_id = r.i32();
    t.confirmed = r.boolean();
    t.sightings = r.i32();
  }
  m.num_tables = static_cast<std::int32_t>(m.tables.size());
  m.content = r.i8();
  return m;
}

findmug_lcm::objects_t makeObjects(Random& r, const Scale& s) {
  findmug_lcm::objects_t m;
  m.utime = r.i64();
  m.seq = r.i64();
  m.content = r.i8();
  m.num_tables = r.i32();
  m.has_map_pose = r.boolean();
  m.map_pose = makePose(r);
  m.objects.resize(static_cast<std::size_t>(r.length(s.array)));
  for (auto& o : m.objects) {
    o.id = r.i32();
    o.table_id = r.i32();
    o.table_map_id = r.i32();
    for (double& v : o.centroid) v = r.f64();
    for (double& v : o.map_centroid) v = r.f64();
    o.height_above_top = r.f64();
    for (double& v : o.major_axis) v = r.f64();
    for (double& v : o.extents) v = r.f64();
    for (double& v : o.center) v = r.f64();
    o.point_count = r.i32();
    for (float& v : o.mean_rgb) v = r.f32();
    for (float& v : o.colour_histogram) v = r.f32();
    o.truncation = r.i8();
    o.map_id = r.i32();
    o.sightings = r.i32();
    o.last_seen_utime = r.i64();
    o.name = r.text(s.text);
    o.name_score = r.f32();
  }
  m.num_objects = static_cast<std::int32_t>(m.objects.size());
  return m;
}

findmug_lcm::status_t makeStatus(Random& r, const Scale& s) {
  findmug_lcm::status_t m;
  m.utime = r.i64();
  m.uptime_us = r.i64();
  m.frames_received = r.i64();
  m.frames_processed = r.i64();
  m.frames_dropped = r.i64();
  m.frames_rejected = r.i64();
  m.window_s = r.f64();
  m.input_fps = r.f32();
  m.output_fps = r.f32();
  const int stages = r.length(s.array);
  for (int i = 0; i < stages; ++i) {
    m.stage_names.push_back(r.text(s.text));
    m.latency_p50_us.push_back(r.i64());
    m.latency_p95_us.push_back(r.i64());
    m.latency_max_us.push_back(r.i64());
  }
  m.num_stages = stages;
  const int queues = r.length(s.array);
  for (int i = 0; i < queues; ++i) {
    m.queue_names.push_back(r.text(s.text));
    m.queue_depths.push_back(r.i32());
    m.queue_capacities.push_back(r.i32());
  }
  m.num_queues = queues;
  m.model_id = r.text(s.text);
  m.source = r.text(s.text);
  m.source_state_name = r.text(s.text);
  m.source_state = r.i8();
  m.last_error = r.text(s.text);
  m.last_error_utime = r.i64();
  m.frames_dropped_at_door = r.i64();
  m.frames_dropped_in_pipeline = r.i64();
  m.frames_dropped_at_shutdown = r.i64();
  m.cpu_budget_cores = r.f32();
  m.cpu_used_cores = r.f32();
  m.processing_threads = r.i32();
  m.source_reconnects = r.i64();
  m.frames_lost_in_transit = r.i64();
  m.publish_failures = r.i64();
  m.heap_in_use_bytes = r.i64();
  m.semantic_map_frames = r.i64();
  m.semantic_map_skipped = r.i64();
  m.semantic_map_voxels = r.i64();
  m.model_reloads = r.i64();
  m.model_reloads_refused = r.i64();
  m.last_reload_ok = (r.i32() & 1) != 0;
  m.last_reload_result = r.text(s.text);
  m.last_reload_utime = r.i64();
  m.last_reload_request_id = r.i64();
  m.commands_accepted = r.i64();
  m.commands_rejected = r.i64();
  m.frames_collected = r.i64();
  m.frames_collect_refused = r.i64();
  m.last_collected_frame = r.text(s.text);
  m.objects_taught = r.i64();
  m.teach_refused = r.i64();
  m.last_teach_ok = (r.i32() & 1) != 0;
  m.last_teach_result = r.text(s.text);
  m.last_teach_request_id = r.i64();
  m.object_frames = r.i64();
  m.object_frames_skipped = r.i64();
  m.object_candidates = r.i64();
  m.objects_named = r.i64();
  m.objects_refused_too_big = r.i64();
  m.objects_refused_too_small = r.i64();
  m.objects_refused_colour = r.i64();
  m.objects_refused_not_round = r.i64();
  m.objects_refused_shape = r.i64();
  m.objects_refused_few_points = r.i64();
  m.object_files_refused = r.i64();
  m.find_requests = r.i64();
  m.find_answers = r.i64();
  m.mapped_objects = r.i64();
  m.object_map_publishes = r.i64();
  return m;
}

findmug_lcm::command_t makeCommand(Random& r, const Scale& s) {
  findmug_lcm::command_t m;
  m.utime = r.i64();
  m.request_id = r.i64();
  m.command = r.text(s.text);
  m.argument = r.text(s.text);
  return m;
}

template <typename Msg>
Bytes encode(const Msg& m) {
  Bytes b(static_cast<std::size_t>(m.getEncodedSize()));
  const int written = m.encode(b.data(), 0, static_cast<int>(b.size()));
  EXPECT_EQ(written, static_cast<int>(b.size())) << Msg::getTypeName();
  return b;
}

// The walk accepts exactly the generated encoding, and the decoded message
// is the original. Returns the decoded message for field checks.
template <typename Msg>
Msg expectExactWalk(const Msg& original, const std::string& what) {
  const Bytes bytes = encode(original);
  Msg decoded;
  try {
    decoded = decodeMessage<Msg>(bytes.data(), bytes.size(), "T");
  } catch (const Error& e) {
    ADD_FAILURE() << what << ": lcm_wire refused a message lcm-gen encoded (" << bytes.size()
                  << " bytes): " << e.what();
    return decoded;
  }
  EXPECT_EQ(encode(decoded), bytes) << what << ": decoded message differs from the original";
  // One byte less or more than getEncodedSize() is refused.
  Bytes longer = bytes;
  longer.push_back(0);
  EXPECT_THROW(decodeMessage<Msg>(longer.data(), longer.size(), "T"), Error) << what;
  EXPECT_THROW(decodeMessage<Msg>(bytes.data(), bytes.size() - 1, "T"), Error) << what;
  return decoded;
}

// Rounds: empty arrays and strings, then growing ones, then one large message.
const Scale kScales[] = {{0, 0, 0}, {3, 8, 16}, {40, 100, 2000}, {400, 300, 70000}};
constexpr int kMessagesPerScale = 60;

// kMessagesPerScale messages per scale from `make(random, scale)`, each
// through expectExactWalk, then `check(decoded, original)` on its fields.
template <typename Make, typename Check>
void forEachMessage(std::uint64_t seed, const Make& make, const Check& check) {
  Random r(seed);
  for (const Scale& s : kScales) {
    for (int i = 0; i < kMessagesPerScale; ++i) {
      const auto m = make(r, s);
      const auto d = expectExactWalk(m, std::string(m.getTypeName()) + " #" + std::to_string(i));
      check(d, m);
    }
  }
}

TEST(LcmWire, RobotPoseWalkMatchesGeneratedCode) {
  forEachMessage(
      1, [](Random& r, const Scale&) { return makePose(r); },
      [](const auto& d, const auto& m) {
        EXPECT_EQ(d.utime, m.utime);
        EXPECT_EQ(d.yaw, m.yaw);
      });
}

TEST(LcmWire, RgbdFrameWalkMatchesGeneratedCode) {
  forEachMessage(2, makeFrame, [](const auto& d, const auto& m) {
    EXPECT_EQ(d.source, m.source);
    EXPECT_EQ(d.depth_data, m.depth_data);
    EXPECT_EQ(d.color_compression, m.color_compression);
  });
}

TEST(LcmWire, LabelImageWalkMatchesGeneratedCode) {
  forEachMessage(3, makeLabels, [](const auto& d, const auto& m) {
    EXPECT_EQ(d.label_names, m.label_names);
    EXPECT_EQ(d.confidence_data, m.confidence_data);
    EXPECT_EQ(d.latency_us, m.latency_us);
  });
}

TEST(LcmWire, TablesWalkMatchesGeneratedCode) {
  forEachMessage(4, makeTables, [](const auto& d, const auto& m) {
    ASSERT_EQ(d.tables.size(), m.tables.size());
    for (std::size_t t = 0; t < m.tables.size(); ++t) {
      EXPECT_EQ(d.tables[t].map_hull, m.tables[t].map_hull);
      EXPECT_EQ(d.tables[t].sightings, m.tables[t].sightings);
    }
    EXPECT_EQ(d.content, m.content);
  });
}

TEST(LcmWire, ObjectsWalkMatchesGeneratedCode) {
  forEachMessage(7, makeObjects, [](const auto& d, const auto& m) {
    ASSERT_EQ(d.objects.size(), m.objects.size());
    for (std::size_t k = 0; k < m.objects.size(); ++k) {
      EXPECT_EQ(d.objects[k].table_id, m.objects[k].table_id);
      EXPECT_EQ(d.objects[k].colour_histogram[27], m.objects[k].colour_histogram[27]);
      EXPECT_EQ(d.objects[k].last_seen_utime, m.objects[k].last_seen_utime);
      EXPECT_EQ(d.objects[k].name, m.objects[k].name);
      EXPECT_EQ(d.objects[k].name_score, m.objects[k].name_score);
    }
    EXPECT_EQ(d.num_tables, m.num_tables);
  });
}

TEST(LcmWire, StatusWalkMatchesGeneratedCode) {
  forEachMessage(5, makeStatus, [](const auto& d, const auto& m) {
    EXPECT_EQ(d.queue_names, m.queue_names);
    EXPECT_EQ(d.last_error, m.last_error);
    EXPECT_EQ(d.processing_threads, m.processing_threads);
    EXPECT_EQ(d.source_reconnects, m.source_reconnects);
    EXPECT_EQ(d.frames_lost_in_transit, m.frames_lost_in_transit);
    EXPECT_EQ(d.publish_failures, m.publish_failures);
    EXPECT_EQ(d.heap_in_use_bytes, m.heap_in_use_bytes);
    EXPECT_EQ(d.semantic_map_frames, m.semantic_map_frames);
    EXPECT_EQ(d.semantic_map_skipped, m.semantic_map_skipped);
    EXPECT_EQ(d.semantic_map_voxels, m.semantic_map_voxels);
    EXPECT_EQ(d.model_reloads_refused, m.model_reloads_refused);
    EXPECT_EQ(d.last_reload_ok, m.last_reload_ok);
    EXPECT_EQ(d.last_reload_result, m.last_reload_result);
    EXPECT_EQ(d.last_reload_request_id, m.last_reload_request_id);
    EXPECT_EQ(d.commands_rejected, m.commands_rejected);
    EXPECT_EQ(d.frames_collect_refused, m.frames_collect_refused);
    EXPECT_EQ(d.last_collected_frame, m.last_collected_frame);
    EXPECT_EQ(d.object_frames, m.object_frames);
    EXPECT_EQ(d.objects_refused_not_round, m.objects_refused_not_round);
    EXPECT_EQ(d.object_map_publishes, m.object_map_publishes);
  });
}

TEST(LcmWire, CommandWalkMatchesGeneratedCode) {
  forEachMessage(6, makeCommand, [](const auto& d, const auto& m) {
    EXPECT_EQ(d.request_id, m.request_id);
    EXPECT_EQ(d.command, m.command);
    EXPECT_EQ(d.argument, m.argument);
  });
}

}  // namespace
}  // namespace findmug::io
