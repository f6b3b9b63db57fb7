// Every length and size field of every findmug LCM message, set to 0, -1,
// INT32_MAX and 0xFFFFFFFF, and every message truncated at every byte: the
// decoders must answer with a findmug::Error naming the message type (never a
// crash, std::bad_alloc or a huge allocation). Run under ASan in the sanitizer
// build, this also catches reads past the buffer.
//
// The field offsets come from this file's own walk of a valid message, written
// from lcmtypes/*.lcm, not from the decoder's wire checker: if the two ever
// disagree, a mutated field lands in the wrong place and the test fails.
#include <gtest/gtest.h>

#include <climits>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/lcm_codec_objects.hpp"
#include "lcm_samples.hpp"

namespace findmug::io {
namespace {

using Bytes = std::vector<std::uint8_t>;

// Offsets of the int32 length/size fields of one encoded message.
struct Field {
  std::string name;
  std::size_t offset;
};

class Walk {
 public:
  explicit Walk(const Bytes& b) : b_(b) {}
  void fixed(std::size_t n) { pos_ += n; }
  std::int32_t i32() {
    const std::int32_t v = static_cast<std::int32_t>(
        (std::uint32_t(b_.at(pos_)) << 24) | (std::uint32_t(b_.at(pos_ + 1)) << 16) |
        (std::uint32_t(b_.at(pos_ + 2)) << 8) | std::uint32_t(b_.at(pos_ + 3)));
    pos_ += 4;
    return v;
  }
  // A length or size field: recorded, returns its value.
  std::int32_t field(const std::string& name) {
    fields.push_back({name, pos_});
    return i32();
  }
  void string(const std::string& name) { pos_ += static_cast<std::size_t>(field(name)); }
  std::size_t pos() const { return pos_; }
  std::vector<Field> fields;

 private:
  const Bytes& b_;
  std::size_t pos_ = 0;
};

void walkRgbd(Walk& w) {
  w.fixed(8 + 8 + 8);  // hash, utime, seq
  w.string("source");
  w.field("width");
  w.field("height");
  w.fixed(4 * 8 + 1 + 3 * 8 + 1);  // fx..cy, has_extrinsics, height/pitch/roll, depth_compression
  w.fixed(static_cast<std::size_t>(w.field("depth_size")));
  w.fixed(1);
  w.fixed(static_cast<std::size_t>(w.field("color_size")));
}

void walkLabels(Walk& w) {
  w.fixed(8 + 8 + 8);
  w.field("width");
  w.field("height");
  const int n = w.field("num_labels");
  for (int i = 0; i < n; ++i) w.string("label_names[" + std::to_string(i) + "]");
  w.fixed(1);
  w.fixed(static_cast<std::size_t>(w.field("labels_size")));
  w.fixed(1);
  w.fixed(static_cast<std::size_t>(w.field("confidence_size")));
  w.fixed(8);
  w.fixed(1 + 4 * 8 + 12 * 8 + 1);  // has_camera, fx..cy, camera_to_base, color_format
  w.fixed(static_cast<std::size_t>(w.field("color_size")));
}

void walkSearchPosition(Walk& w, const std::string& name) {
  w.fixed(3 * 8 + 1);
  w.string(name + ".reason");
}

void walkTables(Walk& w) {
  w.fixed(8 + 8 + 8 + 1 + 4 * 8);  // hash, utime, seq, has_map_pose, map_pose (nested: no hash)
  const int n = w.field("num_tables");
  for (int t = 0; t < n; ++t) {
    const std::string table = "tables[" + std::to_string(t) + "]";
    w.fixed(4 + 3 * 8 + 8 + 2 * 8 * 3);  // id, centroid, top_height, major, minor, extents
    const int hull = w.field(table + ".hull_size");
    w.fixed(static_cast<std::size_t>(hull) * 16 + 4 + 4);  // hull, point_count, mean_confidence
    const int sp = w.field(table + ".num_search_positions");
    for (int i = 0; i < sp; ++i) walkSearchPosition(w, table + ".search_positions");
    w.fixed(3 * 8 + static_cast<std::size_t>(hull) * 16);  // map_centroid, map_hull
    for (int i = 0; i < sp; ++i) walkSearchPosition(w, table + ".map_search_positions");
    w.fixed(2 * 8 + 2 * 8 + 4 + 1 + 4 + 4);  // center, map_center, map_id, confirmed, sightings,
                                             // viewpoints
  }
  w.fixed(1);
}

void walkObjects(Walk& w) {
  // hash, utime, seq, content, num_tables, has_map_pose, map_pose (nested: no hash)
  // (num_tables is a count of another message's tables, not a length of this one.)
  w.fixed(8 + 8 + 8 + 1 + 4 + 1 + 4 * 8);
  const int n = w.field("num_objects");
  // Each table_object_t: id, table_id, table_map_id, centroid, map_centroid,
  // height_above_top, major_axis, extents, center, point_count, mean_rgb,
  // colour_histogram[28], truncation, map_id, sightings, last_seen_utime; name, name_score.
  constexpr std::size_t kObject =
      3 * 4 + 3 * 8 + 3 * 8 + 8 + 2 * 8 + 2 * 8 + 2 * 8 + 4 + 3 * 4 + 28 * 4 + 1 + 4 + 4 + 8;
  for (int i = 0; i < n; ++i) {
    w.fixed(kObject);
    w.string("objects.name");
    w.fixed(4);
  }
}

void walkStatus(Walk& w) {
  w.fixed(8 + 6 * 8 + 8 + 4 + 4);
  const int stages = w.field("num_stages");
  for (int i = 0; i < stages; ++i) w.string("stage_names");
  w.fixed(static_cast<std::size_t>(stages) * 3 * 8);
  const int queues = w.field("num_queues");
  for (int i = 0; i < queues; ++i) w.string("queue_names");
  w.fixed(static_cast<std::size_t>(queues) * 2 * 4);
  w.string("model_id");
  w.string("source");
  w.string("source_state_name");
  w.fixed(1);
  w.string("last_error");
  w.fixed(8);
  // frames_dropped_{at_door,in_pipeline,at_shutdown}, cpu_{budget,used}_cores, processing_threads,
  // source_reconnects, frames_lost_in_transit, publish_failures, heap_in_use_bytes,
  // semantic_map_{frames,skipped,voxels}
  w.fixed(3 * 8 + 2 * 4 + 4 + 8 + 3 * 8 + 3 * 8);
  w.fixed(2 * 8 + 1);  // model_reloads, model_reloads_refused, last_reload_ok
  w.string("last_reload_result");
  // last_reload_utime, last_reload_request_id, commands_accepted, commands_rejected
  w.fixed(4 * 8);
  w.fixed(2 * 8);  // frames_collected, frames_collect_refused
  w.string("last_collected_frame");
  w.fixed(2 * 8 + 1);  // objects_taught, teach_refused, last_teach_ok
  w.string("last_teach_result");
  w.fixed(8);  // last_teach_request_id
  w.fixed(15 * 8);  // object_frames ... object_map_publishes
}

RgbdFrame frame() {
  RgbdFrame f;
  f.width = 8;
  f.height = 6;
  f.source = "test";
  for (int i = 0; i < 48; ++i) {
    f.depth_mm.push_back(static_cast<std::uint16_t>(1000 + i));
    f.rgb.push_back(Rgb8{static_cast<std::uint8_t>(i), 7, 9});
  }
  f.utime = 123;
  return f;
}

struct Case {
  std::string name;
  Bytes bytes;
  std::function<void(Walk&)> walk;
  std::function<void(const Bytes&)> decode;
  std::string type;  // the type name every error must mention
};

std::vector<Case> cases() {
  std::vector<Case> out;
  auto rgbd = [](const Bytes& b) { (void)decodeRgbdFrame(b.data(), b.size(), "CH"); };
  for (auto [name, depth, color] :
       {std::tuple{"rgbd_raw", DepthCompression::None, ColorCompression::None},
        std::tuple{"rgbd_zlib_jpeg", DepthCompression::Zlib, ColorCompression::Jpeg},
        std::tuple{"rgbd_zlib_png", DepthCompression::Zlib, ColorCompression::Png}}) {
    RgbdEncodeOptions o;
    o.depth = depth;
    o.color = color;
    out.push_back({name, encodeMessage(encodeRgbdFrame(frame(), o)), walkRgbd, rgbd, "rgbd_frame_t"});
  }
  LabelImageMessage labels;
  labels.image.width = 4;
  labels.image.height = 3;
  labels.image.labels = {0, 1, 2, 3, 4, 5, 6, 7, kVoidLabel, 0, 1, 2};
  labels.image.confidence = {.5f, .5f, .5f, .5f, .5f, .5f, .5f, .5f, 0.f, .5f, .5f, .5f};
  out.push_back({"label_image", encodeMessage(encodeLabelImage(labels)), walkLabels,
                 [](const Bytes& b) { (void)decodeLabelImage(b.data(), b.size(), "CH"); },
                 "label_image_t"});
  // With the camera and its colour image (daemon.publish_color).
  labels.camera = CameraView{};
  labels.camera->intrinsics = CameraIntrinsics{50, 50, 2, 1.5};
  {
    auto with_color = encodeLabelImage(labels);
    setColorJpeg(with_color, std::vector<Rgb8>(12, Rgb8{90, 60, 30}), 80);
    out.push_back({"label_image_camera_color", encodeMessage(with_color), walkLabels,
                   [](const Bytes& b) { (void)decodeLabelImage(b.data(), b.size(), "CH"); },
                   "label_image_t"});
  }
  TablesMessage tables;
  TableCluster t;
  t.extents = Eigen::Vector2f(0.5f, 0.3f);
  t.hull = {{0, 0}, {1, 0}, {1, 1}};
  SearchPosition p;
  p.reason = "ok";
  t.search_positions = {p, p};
  tables.tables = {t, t};
  tables.map_pose = RobotPose{1, {2, 3, 0.5}};
  out.push_back({"tables", encodeMessage(encodeTables(tables)), walkTables,
                 [](const Bytes& b) { (void)decodeTables(b.data(), b.size(), "CH"); }, "tables_t"});
  out.push_back({"objects", encodeMessage(test::sampleObjects()), walkObjects,
                 [](const Bytes& b) { (void)decodeObjects(b.data(), b.size(), "CH"); },
                 "objects_t"});
  out.push_back({"object_map", encodeMessage(test::sampleObjectMap()), walkObjects,
                 [](const Bytes& b) { (void)decodeObjects(b.data(), b.size(), "CH"); },
                 "objects_t"});
  findmug_lcm::status_t s{};
  s.num_stages = 2;
  s.stage_names = {"cloud", "total"};
  s.latency_p50_us = s.latency_p95_us = s.latency_max_us = {1, 2};
  s.num_queues = 1;
  s.queue_names = {"frames"};
  s.queue_depths = {0};
  s.queue_capacities = {2};
  s.model_id = "m";
  s.source = "s";
  s.source_state_name = "running";
  s.last_error = "";
  out.push_back(
      {"status", encodeMessage(s), walkStatus,
       [](const Bytes& b) { (void)decodeMessage<findmug_lcm::status_t>(b.data(), b.size(), "CH"); },
       "status_t"});
  out.push_back({"robot_pose", encodeMessage(encodeRobotPose(RobotPose{1, {2, 3, 0.5}})),
                 [](Walk& w) { w.fixed(8 + 8 + 3 * 8); },
                 [](const Bytes& b) { (void)decodeRobotPose(b.data(), b.size(), "CH"); },
                 "robot_pose_t"});
  out.push_back({"command",
                 encodeMessage(encodeCommand(CommandMessage{5, 6, "reload_model", "x y"})),
                 [](Walk& w) {
                   w.fixed(8 + 2 * 8);
                   w.string("command");
                   w.string("argument");
                 },
                 [](const Bytes& b) { (void)decodeCommand(b.data(), b.size(), "CH"); },
                 "command_t"});
  return out;
}

// Decodes, expecting a findmug::Error that names the type; any other outcome fails.
void expectRejected(const Case& c, const Bytes& bytes, const std::string& what) {
  try {
    c.decode(bytes);
    ADD_FAILURE() << c.name << ": " << what << " was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(c.type), std::string::npos)
        << c.name << ": " << what << ": error does not name " << c.type << ": " << e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << c.name << ": " << what << ": " << typeid(e).name() << ": " << e.what();
  }
}

TEST(LcmFields, TheWalkCoversEachValidMessageExactly) {
  for (const auto& c : cases()) {
    Walk w(c.bytes);
    c.walk(w);
    EXPECT_EQ(w.pos(), c.bytes.size()) << c.name;
    EXPECT_NO_THROW(c.decode(c.bytes)) << c.name;
  }
}

TEST(LcmFields, EveryLengthFieldAt0MinusOneInt32MaxAnd0xFFFFFFFFIsRejected) {
  std::size_t mutated = 0;
  for (const auto& c : cases()) {
    Walk w(c.bytes);
    c.walk(w);
    for (const auto& f : w.fields) {
      for (const std::uint32_t value : {0u, 0xFFFFFFFFu /* -1 */, std::uint32_t{INT32_MAX},
                                         0xFFFFFFFFu, 0x80000000u}) {
        Bytes bytes = c.bytes;
        const std::uint32_t original = (std::uint32_t(bytes[f.offset]) << 24) |
                                       (std::uint32_t(bytes[f.offset + 1]) << 16) |
                                       (std::uint32_t(bytes[f.offset + 2]) << 8) |
                                       std::uint32_t(bytes[f.offset + 3]);
        if (value == original) continue;  // not a mutation
        for (int k = 0; k < 4; ++k) bytes[f.offset + k] = std::uint8_t(value >> (24 - 8 * k));
        expectRejected(c, bytes, f.name + " = " + std::to_string(value));
        ++mutated;
      }
    }
  }
  RecordProperty("mutated_messages", static_cast<int>(mutated));
  EXPECT_GT(mutated, 100u);  // the walks found the fields
}

TEST(LcmFields, EveryMessageTruncatedAtEveryByteIsRejected) {
  std::size_t truncations = 0;
  for (const auto& c : cases()) {
    for (std::size_t n = 0; n < c.bytes.size(); ++n) {
      const Bytes cut(c.bytes.begin(), c.bytes.begin() + static_cast<std::ptrdiff_t>(n));
      expectRejected(c, cut, "truncated at " + std::to_string(n));
    }
    truncations += c.bytes.size();
    Bytes longer = c.bytes;
    longer.push_back(0);
    expectRejected(c, longer, "one trailing byte");
  }
  RecordProperty("truncated_messages", static_cast<int>(truncations));
}

}  // namespace
}  // namespace findmug::io
