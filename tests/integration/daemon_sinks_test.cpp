// The pipeline's result sinks and status builder (result_sinks.hpp,
// status_builder.hpp) on their own: the table-map update rule, what the LCM
// publisher sink puts on a bus (an in-memory one), and status_t from a
// snapshot. No data, no LCM traffic.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <future>
#include <thread>
#include <string>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/daemon/result_sinks.hpp"
#include "findmug/daemon/semantic_map_sink.hpp"
#include "findmug/daemon/status_builder.hpp"
#include "findmug/io/bus.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/lcm_codec_objects.hpp"
#include "findmug_lcm/status_t.hpp"
#include "table_scenes.hpp"

namespace findmug::daemon {
namespace {

using namespace std::chrono_literals;

// A 1.2 m x 0.8 m table top, 0.75 m high, `ahead_m` in front of the robot (base frame).
TableCluster tableAhead(float ahead_m) {
  TableCluster t;
  const float a = 0.6f, b = 0.4f;
  t.center = Eigen::Vector2f(ahead_m, 0.0f);
  t.hull = {{ahead_m - a, -b}, {ahead_m + a, -b}, {ahead_m + a, b}, {ahead_m - a, b}};
  t.major_axis = Eigen::Vector2f(1, 0);
  t.minor_axis = Eigen::Vector2f(0, 1);
  t.extents = Eigen::Vector2f(a, b);
  t.centroid = Eigen::Vector3f(ahead_m, 0.0f, 0.75f);
  t.top_height = 0.75f;
  t.point_count = 5000;
  t.mean_confidence = 0.9f;
  return t;
}

// A labelled frame: with a ground plane or not, with a labelled pixel or not.
LabelledFrame labelledFrame(std::int64_t seq, bool ground, bool labelled_pixel,
                            std::vector<TableCluster> tables) {
  LabelledFrame l;
  RgbdFrame& f = l.segmented.prepared.frame;
  f.width = 2;
  f.height = 2;
  f.seq = seq;
  f.utime = 1000000 + static_cast<std::uint64_t>(seq) * 100000;
  f.source = "test";
  if (ground) l.segmented.prepared.ground = GroundPlane{};
  l.labels.width = 2;
  l.labels.height = 2;
  l.labels.labels.assign(4, kVoidLabel);
  l.labels.confidence.assign(4, 0.0f);
  if (labelled_pixel) {
    l.labels.labels[0] = 1;
    l.labels.confidence[0] = 0.8f;
  }
  l.tables = std::move(tables);
  return l;
}

io::RobotPose poseAt(std::uint64_t utime) { return io::RobotPose{utime, {1.0, 2.0, 0.0}}; }

TEST(TableMapSink, OnlyAFrameWithAPoseAndLabelsUpdatesTheMap) {
  std::vector<std::string> errors;
  TableMapSink sink(TableMapConfig{}, TableConfig{}, true,
                    [&](const std::string& e) { errors.push_back(e); });
  const std::vector<TableCluster> one_table = {tableAhead(2.0f)};

  struct Case {
    bool pose, ground, labelled_pixel;
  };
  // No pose; no ground plane; not a single labelled pixel: no evidence, no update.
  for (const Case c : {Case{false, true, true}, Case{true, false, true}, Case{true, true, false}}) {
    const LabelledFrame l = labelledFrame(1, c.ground, c.labelled_pixel, one_table);
    FrameResult r{l, 0, std::nullopt, {}, std::nullopt};
    if (c.pose) r.pose = poseAt(l.segmented.prepared.frame.utime);
    sink.consume(r);
    EXPECT_TRUE(r.map_info.empty());
    EXPECT_FALSE(r.table_map.has_value());
  }
  EXPECT_EQ(sink.updates(), 0u);
  EXPECT_TRUE(sink.tables().empty());
  EXPECT_FALSE(TableMapSink::isEvidence(labelledFrame(1, true, false, one_table)));
  EXPECT_TRUE(TableMapSink::isEvidence(labelledFrame(1, true, true, {})));

  // With both: every frame updates the map; the map is due after each update
  // and holds the table once it is confirmed (table_map.confirm_sightings = 3).
  for (std::int64_t seq = 2; seq <= 4; ++seq) {
    const LabelledFrame l = labelledFrame(seq, true, true, one_table);
    FrameResult r{l, 0, poseAt(l.segmented.prepared.frame.utime), {}, std::nullopt};
    sink.consume(r);
    ASSERT_EQ(r.map_info.size(), 1u);
    ASSERT_TRUE(r.table_map.has_value());
    EXPECT_EQ(r.table_map->content, io::TablesContent::Map);
    EXPECT_EQ(r.table_map->seq, seq);
    const bool confirmed = seq == 4;
    EXPECT_EQ(r.map_info[0].confirmed, confirmed);
    EXPECT_EQ(r.table_map->tables.size(), confirmed ? 1u : 0u);  // confirmed tables only
  }
  EXPECT_EQ(sink.updates(), 3u);
  EXPECT_EQ(sink.tables().size(), 1u);
  EXPECT_TRUE(errors.empty());

  // A frame older than the last update (a restarted clock): reported, map untouched.
  const LabelledFrame old = labelledFrame(0, true, true, one_table);
  FrameResult r{old, 0, poseAt(old.segmented.prepared.frame.utime), {}, std::nullopt};
  sink.consume(r);
  EXPECT_EQ(sink.updates(), 3u);
  EXPECT_FALSE(r.table_map.has_value());
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("test seq 0: table map not updated"), std::string::npos) << errors[0];
}

TEST(TableMapSink, WithoutPublishingTheMapIsStillUpdated) {
  TableMapSink sink(TableMapConfig{}, TableConfig{}, false, {});
  const LabelledFrame l = labelledFrame(1, true, true, {tableAhead(2.0f)});
  FrameResult r{l, 0, poseAt(l.segmented.prepared.frame.utime), {}, std::nullopt};
  sink.consume(r);
  EXPECT_EQ(sink.updates(), 1u);
  EXPECT_EQ(r.map_info.size(), 1u);
  EXPECT_FALSE(r.table_map.has_value());
}

// The sink gives the table map the frame's depth and camera pose: a confirmed table that a
// wall hides from the robot stays in the map; one whose place the depth shows empty goes.
TEST(TableMapSink, ATableHiddenBehindAWallIsNotForgotten) {
  TableMapSink sink(TableMapConfig{}, TableConfig{}, false, {});  // forget after 3 misses
  for (std::int64_t seq = 1; seq <= 3; ++seq) {
    const LabelledFrame l = labelledFrame(seq, true, true, {tableAhead(2.0f)});
    FrameResult r{l, 0, poseAt(l.segmented.prepared.frame.utime), {}, std::nullopt};
    sink.consume(r);
  }
  ASSERT_EQ(sink.tables().size(), 1u);

  // Frames of a head camera with a depth image and no table detected in them.
  const GroundPlane ground = groundFromExtrinsics(test::headMount());
  const io::RobotPose pose = poseAt(0);
  const Eigen::Isometry3d camera = cameraInMap(pose.pose, ground.camera_to_ground);
  const auto frameOf = [&](std::int64_t seq, std::vector<std::uint16_t> depth) {
    LabelledFrame l = labelledFrame(seq, true, true, {});
    RgbdFrame& f = l.segmented.prepared.frame;
    f.width = 640;
    f.height = 480;
    f.depth_mm = std::move(depth);
    l.segmented.prepared.ground = ground;
    return l;
  };
  const std::vector<std::uint16_t> wall(640 * 480, 1000);  // 1 m in front of the camera
  std::int64_t seq = 4;
  for (int i = 0; i < 6; ++i, ++seq) {
    const LabelledFrame l = frameOf(seq, wall);
    FrameResult r{l, 0, io::RobotPose{l.segmented.prepared.frame.utime, pose.pose}, {},
                  std::nullopt};
    sink.consume(r);
  }
  EXPECT_EQ(sink.tables().size(), 1u) << "a table behind a wall was forgotten";
  const std::vector<std::uint16_t> floor = test::depthOfTops({}, camera).depth_mm;
  for (int i = 0; i < 3; ++i, ++seq) {
    const LabelledFrame l = frameOf(seq, floor);
    FrameResult r{l, 0, io::RobotPose{l.segmented.prepared.frame.utime, pose.pose}, {},
                  std::nullopt};
    sink.consume(r);
  }
  EXPECT_TRUE(sink.tables().empty()) << "a table whose place shows empty floor was kept";
}

// What arrives on the bus's channels, subscribed once, collected by drain().
class Collector {
 public:
  Collector(io::MemoryBus& bus, const LcmPublisherSink::Channels& ch) : bus_(bus) {
    bus.subscribe(ch.labels, [this](const std::string& c, const std::uint8_t* d, std::size_t n) {
      channels.push_back(c);
      labels.push_back(io::decodeLabelImage(d, n, c));
    });
    bus.subscribe(ch.objects, [this](const std::string& c, const std::uint8_t* d, std::size_t n) {
      channels.push_back(c);
      objects.push_back(io::decodeObjects(d, n, c));
    });
    for (const std::string& name : {ch.tables, ch.table_map}) {
      bus.subscribe(name, [this](const std::string& c, const std::uint8_t* d, std::size_t n) {
        channels.push_back(c);
        tables.push_back(io::decodeTables(d, n, c));
      });
    }
    bus.subscribe(ch.status, [this](const std::string& c, const std::uint8_t*, std::size_t) {
      channels.push_back(c);
    });
  }
  // Handles everything published so far; returns the channels in arrival order.
  std::vector<std::string> drain() {
    while (bus_.handle(0ms) == io::HandleResult::Handled) {
    }
    return channels;
  }

  std::vector<std::string> channels;
  std::vector<io::LabelImageMessage> labels;
  std::vector<io::TablesMessage> tables;
  std::vector<io::ObjectsMessage> objects;

 private:
  io::MemoryBus& bus_;
};

const LcmPublisherSink::Channels kChannels{"L", "T", "O", "M", "S"};

// A mug-sized candidate standing on table `table` of a frame.
TableObject mugOn(int table, const Eigen::Vector3f& centroid) {
  TableObject o;
  o.table = table;
  o.centroid = centroid;
  o.height_above_top = 0.1f;
  o.extents = Eigen::Vector2f(0.04f, 0.04f);
  o.center = centroid.head<2>();
  o.point_count = 120;
  o.mean_rgb = Eigen::Vector3f(200, 30, 20);
  o.colour_histogram[0] = 1.0f;
  o.pixels = {0, 1};
  return o;
}

TEST(LcmPublisherSink, PublishesLabelsTablesObjectsAndMapInThatOrder) {
  auto bus = std::make_shared<io::MemoryBus>();
  LcmPublisherSink sink(bus, kChannels, true, true);
  const LabelledFrame l = labelledFrame(7, true, true, {tableAhead(2.0f)});
  FrameResult r{
      l, 1234, poseAt(l.segmented.prepared.frame.utime), {{5, false, 1}}, io::TablesMessage{}};
  r.table_map->content = io::TablesContent::Map;
  r.table_map->seq = 7;
  r.table_map->map_pose = r.pose;
  Collector p(*bus, kChannels);
  sink.consume(r);
  EXPECT_EQ(p.drain(), (std::vector<std::string>{"L", "T", "O", "M"}));
  ASSERT_EQ(p.labels.size(), 1u);
  EXPECT_EQ(p.labels[0].seq, 7);
  EXPECT_EQ(p.labels[0].latency_us, 1234);
  EXPECT_EQ(p.labels[0].image.labels, l.labels.labels);
  ASSERT_EQ(p.tables.size(), 2u);
  EXPECT_EQ(p.tables[0].content, io::TablesContent::Frame);
  ASSERT_EQ(p.tables[0].tables.size(), 1u);
  ASSERT_TRUE(p.tables[0].map_pose.has_value());
  EXPECT_DOUBLE_EQ(p.tables[0].map_pose->pose.y, 2.0);
  ASSERT_EQ(p.tables[0].map_info.size(), 1u);
  EXPECT_EQ(p.tables[0].map_info[0].map_id, 5);
  EXPECT_EQ(p.tables[1].content, io::TablesContent::Map);
  // A table without candidates still gets its (empty) objects message.
  ASSERT_EQ(p.objects.size(), 1u);
  EXPECT_EQ(p.objects[0].seq, 7);
  EXPECT_EQ(p.objects[0].num_tables, 1);
  EXPECT_TRUE(p.objects[0].objects.empty());
  EXPECT_EQ(sink.publishFailures(), 0u);
}

// The frame's candidates go out with their table's index and map id, and the
// map-frame centroid through the frame's pose (poseAt: x + 1, y + 2, no turn).
TEST(LcmPublisherSink, ObjectsCarryTheirTableAndMapFrameCentroid) {
  auto bus = std::make_shared<io::MemoryBus>();
  LcmPublisherSink sink(bus, kChannels, true, true);
  LabelledFrame l = labelledFrame(9, true, true, {tableAhead(2.0f), tableAhead(4.0f)});
  l.tables[1].id = 1;
  l.table_objects.objects = {mugOn(1, Eigen::Vector3f(4.1f, 0.2f, 0.8f))};
  FrameResult r{l, 0, poseAt(l.segmented.prepared.frame.utime), {{3, true, 4}, {8, false, 1}},
                std::nullopt};
  Collector p(*bus, kChannels);
  sink.consume(r);
  EXPECT_EQ(p.drain(), (std::vector<std::string>{"L", "T", "O"}));
  ASSERT_EQ(p.objects.size(), 1u);
  const io::ObjectsMessage& m = p.objects[0];
  EXPECT_EQ(m.utime, l.segmented.prepared.frame.utime);
  EXPECT_EQ(m.num_tables, 2);
  ASSERT_EQ(m.objects.size(), 1u);
  EXPECT_EQ(m.objects[0].table, 1);
  EXPECT_EQ(m.map_info[0].table_map_id, 8);
  ASSERT_TRUE(m.map_pose.has_value());
  EXPECT_NEAR(m.map_info[0].map_centroid.x(), 5.1, 1e-5);
  EXPECT_NEAR(m.map_info[0].map_centroid.y(), 2.2, 1e-5);
  EXPECT_NEAR(m.map_info[0].map_centroid.z(), 0.8, 1e-5);
  EXPECT_EQ(m.objects[0].point_count, 120);
  EXPECT_TRUE(m.objects[0].pixels.empty());  // not on the wire
}

TEST(LcmPublisherSink, TablesCanBeSwitchedOff) {
  auto bus = std::make_shared<io::MemoryBus>();
  LcmPublisherSink sink(bus, kChannels, false, false);
  const LabelledFrame l = labelledFrame(1, true, true, {tableAhead(2.0f)});
  FrameResult r{l, 0, std::nullopt, {}, std::nullopt};
  Collector p(*bus, kChannels);
  sink.consume(r);
  EXPECT_EQ(p.drain(), (std::vector<std::string>{"L"}));
  EXPECT_TRUE(p.labels[0].image.confidence.empty());  // daemon.publish_confidence off
}

// Every label image carries the camera the frame was processed with (its ground plane's
// camera-to-ground transform and the frame's intrinsics); the colour image only with
// daemon.publish_color.
TEST(LcmPublisherSink, LabelImagesCarryTheCameraAndOptionallyTheColourImage) {
  auto bus = std::make_shared<io::MemoryBus>();
  LcmPublisherSink sink(bus, kChannels, true, false);
  LabelledFrame l = labelledFrame(4, true, true, {});
  RgbdFrame& f = l.segmented.prepared.frame;
  f.intrinsics = CameraIntrinsics{400, 401, 1, 0.5};
  f.rgb.assign(4, Rgb8{200, 100, 50});
  GroundPlane ground;
  ground.camera_to_ground.linear() =
      Eigen::AngleAxisf(0.4f, Eigen::Vector3f::UnitX()).toRotationMatrix();
  ground.camera_to_ground.translation() = Eigen::Vector3f(0, 0, 1.25f);
  l.segmented.prepared.ground = ground;
  const LabelledFrame no_ground = labelledFrame(5, false, true, {});
  Collector p(*bus, kChannels);
  FrameResult r{l, 0, std::nullopt, {}, std::nullopt};
  sink.consume(r);
  sink.publishColor(90);
  sink.consume(r);
  FrameResult r2{no_ground, 0, std::nullopt, {}, std::nullopt};
  sink.consume(r2);
  p.drain();
  ASSERT_EQ(p.labels.size(), 3u);
  ASSERT_TRUE(p.labels[0].camera.has_value());
  EXPECT_EQ(p.labels[0].camera->intrinsics.fy, 401);
  EXPECT_TRUE(p.labels[0].camera->camera_to_base.isApprox(ground.camera_to_ground.cast<double>()));
  EXPECT_TRUE(p.labels[0].color_jpeg.empty());
  const std::vector<Rgb8> colour = io::decodeLabelImageColor(p.labels[1], "L");
  ASSERT_EQ(colour.size(), 4u);
  EXPECT_NEAR(colour[0].r, 200, 8);
  EXPECT_NEAR(colour[3].b, 50, 8);
  EXPECT_FALSE(p.labels[2].camera.has_value());  // no floor: no camera to draw with
}

TEST(LcmPublisherSink, ARefusedPublishNamesTheChannelAndFrameAndIsCounted) {
  auto memory = std::make_shared<io::MemoryBus>();
  auto faulty = std::make_shared<io::FaultyBus>(memory);
  LcmPublisherSink sink(faulty, kChannels, true, true);
  Collector p(*memory, kChannels);
  const LabelledFrame l = labelledFrame(3, true, true, {});
  faulty->failPublish("T", true);
  FrameResult r{l, 0, std::nullopt, {}, std::nullopt};
  try {
    sink.consume(r);
    FAIL() << "a refused publish must throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("LCM publish on T failed for test seq 3"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(sink.publishFailures(), 1u);
  // The labels went out before the refused tables; no objects without their tables.
  EXPECT_EQ(p.drain(), (std::vector<std::string>{"L"}));
  // A refused status is counted, not thrown; after close() nothing goes out.
  faulty->failPublish("S", true);
  EXPECT_FALSE(sink.publishStatus(StatusSnapshot{}));
  EXPECT_EQ(sink.publishFailures(), 2u);
  faulty->failPublish("S", false);
  EXPECT_TRUE(sink.publishStatus(StatusSnapshot{}));
  sink.close();
  EXPECT_FALSE(sink.publishStatus(StatusSnapshot{}));
  EXPECT_EQ(p.drain(), (std::vector<std::string>{"L", "S"}));
}

// A refused objects message fails the frame like a refused tables message: the
// publish stage counts it, and the table map (after it) is not sent.
TEST(LcmPublisherSink, ARefusedObjectsPublishFailsTheFrame) {
  auto memory = std::make_shared<io::MemoryBus>();
  auto faulty = std::make_shared<io::FaultyBus>(memory);
  LcmPublisherSink sink(faulty, kChannels, true, true);
  Collector p(*memory, kChannels);
  const LabelledFrame l = labelledFrame(4, true, true, {tableAhead(2.0f)});
  faulty->failPublish("O", true);
  FrameResult r{l, 0, std::nullopt, {}, io::TablesMessage{}};
  r.table_map->content = io::TablesContent::Map;
  r.table_map->map_pose = poseAt(1);
  try {
    sink.consume(r);
    FAIL() << "a refused publish must throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("LCM publish on O failed for test seq 4"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(sink.publishFailures(), 1u);
  EXPECT_EQ(p.drain(), (std::vector<std::string>{"L", "T"}));
}

// A candidate the object stage got wrong (here a histogram that does not sum to 1) is
// refused before it goes out: the frame fails with the field named, its labels and tables
// are out already.
TEST(LcmPublisherSink, ACandidateTheDecoderWouldRefuseFailsTheFrame) {
  auto bus = std::make_shared<io::MemoryBus>();
  LcmPublisherSink sink(bus, kChannels, true, true);
  LabelledFrame l = labelledFrame(6, true, true, {tableAhead(2.0f)});
  l.table_objects.objects = {mugOn(0, Eigen::Vector3f(2.0f, 0.0f, 0.8f))};
  l.table_objects.objects[0].colour_histogram[0] = 0.5f;
  FrameResult r{l, 0, std::nullopt, {}, std::nullopt};
  Collector p(*bus, kChannels);
  try {
    sink.consume(r);
    FAIL() << "a bad candidate must fail the frame";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("objects[0].colour_histogram"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(p.drain(), (std::vector<std::string>{"L", "T"}));
}

StatusSnapshot sampleSnapshot() {
  StatusSnapshot s;
  s.utime = 5000000;
  s.uptime_us = 42;
  s.counters.received = 10;
  s.counters.processed = 6;
  s.counters.dropped = 3;
  s.counters.dropped_at_door = 2;
  s.counters.dropped_in_pipeline = 1;
  s.counters.rejected = 1;
  s.window_s = 10.0;
  s.input_fps = 30.0;
  s.output_fps = 5.5;
  s.latencies = {{"prepare", {10.0, 20.0, 30.0, 4}}, {"total", {100.0, 200.0, 300.0, 4}}};
  s.queues = {{"prepare", 1, 4}, {"segment", 2, 4}};
  s.model_id = "model";
  s.cpu_budget_cores = 2.0;
  s.cpu_used_cores = 1.5;
  s.processing_threads = 3;
  s.last_error = "pipeline error";
  s.last_error_utime = 100;
  s.publish_failures = 7;
  s.heap_in_use_bytes = 123456789;
  s.semantic_map_frames = 40;
  s.semantic_map_skipped = 3;
  s.semantic_map_voxels = 250000;
  s.objects = {120, 2, 300, 40, 101, 91, 51, 11, 5, 4, 1, 3, 4, 6, 118};
  return s;
}

TEST(StatusBuilder, FillsEveryFieldFromTheSnapshot) {
  const findmug_lcm::status_t s = StatusBuilder::build(sampleSnapshot());
  EXPECT_EQ(s.utime, 5000000);
  EXPECT_EQ(s.uptime_us, 42);
  EXPECT_EQ(s.frames_received, 10);
  EXPECT_EQ(s.frames_processed, 6);
  EXPECT_EQ(s.frames_dropped, 3);
  EXPECT_EQ(s.frames_dropped_at_door, 2);
  EXPECT_EQ(s.frames_dropped_in_pipeline, 1);
  EXPECT_EQ(s.frames_dropped_at_shutdown, 0);
  EXPECT_EQ(s.frames_rejected, 1);
  EXPECT_DOUBLE_EQ(s.window_s, 10.0);
  EXPECT_FLOAT_EQ(s.input_fps, 30.0f);
  EXPECT_FLOAT_EQ(s.output_fps, 5.5f);
  ASSERT_EQ(s.num_stages, 2);
  EXPECT_EQ(s.stage_names, (std::vector<std::string>{"prepare", "total"}));
  EXPECT_EQ(s.latency_p50_us, (std::vector<std::int64_t>{10000, 100000}));
  EXPECT_EQ(s.latency_p95_us, (std::vector<std::int64_t>{20000, 200000}));
  EXPECT_EQ(s.latency_max_us, (std::vector<std::int64_t>{30000, 300000}));
  ASSERT_EQ(s.num_queues, 2);
  EXPECT_EQ(s.queue_names, (std::vector<std::string>{"prepare", "segment"}));
  EXPECT_EQ(s.queue_depths, (std::vector<std::int32_t>{1, 2}));
  EXPECT_EQ(s.queue_capacities, (std::vector<std::int32_t>{4, 4}));
  EXPECT_EQ(s.model_id, "model");
  EXPECT_FLOAT_EQ(s.cpu_budget_cores, 2.0f);
  EXPECT_FLOAT_EQ(s.cpu_used_cores, 1.5f);
  EXPECT_EQ(s.processing_threads, 3);
  // No source: frames come in-process.
  EXPECT_EQ(s.source, "(in-process)");
  EXPECT_EQ(s.source_state, findmug_lcm::status_t::SOURCE_RUNNING);
  EXPECT_EQ(s.source_state_name, "running");
  EXPECT_EQ(s.last_error, "pipeline error");
  EXPECT_EQ(s.last_error_utime, 100);
  EXPECT_EQ(s.publish_failures, 7);
  EXPECT_EQ(s.heap_in_use_bytes, 123456789);
  EXPECT_EQ(s.semantic_map_frames, 40);
  EXPECT_EQ(s.semantic_map_skipped, 3);
  EXPECT_EQ(s.semantic_map_voxels, 250000);
  EXPECT_EQ(s.frames_lost_in_transit, 0);
  // The object work, each counter in its own field.
  EXPECT_EQ(s.object_frames, 120);
  EXPECT_EQ(s.object_frames_skipped, 2);
  EXPECT_EQ(s.object_candidates, 300);
  EXPECT_EQ(s.objects_named, 40);
  EXPECT_EQ(s.objects_refused_too_big, 101);
  EXPECT_EQ(s.objects_refused_too_small, 91);
  EXPECT_EQ(s.objects_refused_colour, 51);
  EXPECT_EQ(s.objects_refused_not_round, 11);
  EXPECT_EQ(s.objects_refused_shape, 5);
  EXPECT_EQ(s.objects_refused_few_points, 4);
  EXPECT_EQ(s.object_files_refused, 1);
  EXPECT_EQ(s.find_requests, 3);
  EXPECT_EQ(s.find_answers, 4);
  EXPECT_EQ(s.mapped_objects, 6);
  EXPECT_EQ(s.object_map_publishes, 118);
}

TEST(StatusBuilder, TheSourceStateAndTheNewerErrorWin) {
  StatusSnapshot snap = sampleSnapshot();
  snap.source = StatusSnapshot::Source{"lcm:FINDMUG_RGBD (memq://)", io::SourceState::Reconnecting,
                                       "source error", 200, 2, 9};
  findmug_lcm::status_t s = StatusBuilder::build(snap);
  EXPECT_EQ(s.source_reconnects, 2);
  EXPECT_EQ(s.frames_lost_in_transit, 9);
  EXPECT_EQ(s.source, "lcm:FINDMUG_RGBD (memq://)");
  EXPECT_EQ(s.source_state, findmug_lcm::status_t::SOURCE_RECONNECTING);
  EXPECT_EQ(s.source_state_name, "reconnecting");
  EXPECT_EQ(s.last_error, "source error");
  EXPECT_EQ(s.last_error_utime, 200);
  snap.source->last_error_utime = 50;  // older than the pipeline's
  s = StatusBuilder::build(snap);
  EXPECT_EQ(s.last_error, "pipeline error");
  EXPECT_EQ(s.last_error_utime, 100);
}

// ---- the semantic map sink ----------------------------------------------------------------

// A frame of a 40 x 40 camera looking straight down from 1.5 m at a floor with a table top:
// labelled, with a ground plane whose camera_to_ground is that mount.
LabelledFrame topDownFrame(std::int64_t seq, Label top_label = Label::Table) {
  LabelledFrame l;
  RgbdFrame& f = l.segmented.prepared.frame;
  f.width = f.height = 40;
  f.seq = seq;
  f.utime = 1000000 + static_cast<std::uint64_t>(seq) * 100000;
  f.source = "test";
  GroundPlane ground;
  ground.camera_to_ground.linear() << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  ground.camera_to_ground.translation() = Eigen::Vector3f(0.0f, 0.0f, 1.5f);
  l.segmented.prepared.ground = ground;
  OrganizedCloud& cloud = l.segmented.prepared.cloud_camera;
  cloud.width = l.labels.width = 40;
  cloud.height = l.labels.height = 40;
  for (int y = 0; y < 40; ++y) {
    for (int x = 0; x < 40; ++x) {
      const bool top = x >= 10 && x < 30 && y >= 10 && y < 30;
      // Pixels 2.5 cm apart, each pair (2k, 2k + 1) in one 5 cm voxel: the unsampled
      // pixels (pixel_stride 2) share the voxels of the sampled ones.
      cloud.points.emplace_back(0.025f * static_cast<float>(x - 20) - 0.0125f,
                                0.025f * static_cast<float>(y - 20) - 0.0125f, top ? 0.75f : 1.5f);
      cloud.colors.push_back(Rgb8{});
      l.labels.labels.push_back(static_cast<std::uint8_t>(top ? top_label : Label::Floor));
      l.labels.confidence.push_back(0.9f);
    }
  }
  return l;
}

SemanticMapSink::Options sinkOptions(bool threaded) {
  SemanticMapSink::Options o;
  o.threaded = threaded;
  o.queue_capacity = 2;
  o.publish_period_s = 0.0;
  o.map_channel = "SM";
  o.table_map_channel = "TM";
  o.map.min_voxel_frames = 1;
  o.map.min_table_voxels = 20;
  return o;
}

TEST(SemanticMapSink, AFullQueueDropsTheOldestFrameAndNeverHoldsThePublishThread) {
  auto bus = std::make_shared<io::MemoryBus>();
  std::promise<void> entered, release;
  std::shared_future<void> released = release.get_future().share();
  std::atomic<int> fused{0};
  SemanticMapSink::Options options = sinkOptions(true);
  options.before_fuse = [&] {
    if (fused.fetch_add(1) == 0) {
      entered.set_value();
      released.wait();  // the map thread is busy with the first frame
    }
  };
  SemanticMapSink sink(options, bus, nullptr);
  sink.start();
  std::vector<LabelledFrame> frames;
  for (int i = 1; i <= 5; ++i) frames.push_back(topDownFrame(i));
  auto consume = [&](const LabelledFrame& l) {
    FrameResult r{l, 0, poseAt(l.segmented.prepared.frame.utime), {}, std::nullopt, std::nullopt};
    sink.consume(r);
  };
  consume(frames[0]);
  entered.get_future().wait();
  // While the map is busy, four more frames arrive: two wait, two are dropped (the oldest).
  for (int i = 1; i < 5; ++i) consume(frames[static_cast<std::size_t>(i)]);
  SemanticMapSink::Counters c = sink.counters();
  EXPECT_EQ(c.queued, 5u);
  EXPECT_EQ(c.skipped, 2u);
  EXPECT_EQ(c.queue_depth, 2u);
  EXPECT_EQ(c.integrated, 0u);
  release.set_value();
  sink.stop(true);
  c = sink.counters();
  EXPECT_EQ(c.integrated, 3u);
  EXPECT_EQ(c.failed, 0u);
  EXPECT_GE(c.publishes, 1u);
  // The tables of the map went out on the map channels.
  std::vector<io::TablesMessage> tables;
  bus->subscribe("TM", [&](const std::string& ch, const std::uint8_t* d, std::size_t n) {
    tables.push_back(io::decodeTables(d, n, ch));
  });
  int maps = 0;
  bus->subscribe("SM", [&](const std::string&, const std::uint8_t*, std::size_t) { ++maps; });
  bus->end();
  while (bus->handle(0ms) != io::HandleResult::EndOfLog) {
  }
  ASSERT_FALSE(tables.empty());
  EXPECT_GE(maps, 1);
  ASSERT_EQ(tables.back().tables.size(), 1u);
  EXPECT_EQ(tables.back().content, io::TablesContent::Map);
  EXPECT_EQ(tables.back().map_info[0].sightings, 3);  // the three frames fused
  // ... all from one pose: one viewpoint, as the map counted it.
  EXPECT_EQ(tables.back().map_info[0].viewpoints, 1);
  ASSERT_EQ(sink.tables().size(), 1u);
  EXPECT_EQ(sink.tables()[0].viewpoints, 1);
  // Map frame: the robot at (1, 2), the top 0.5 m square under the camera.
  ASSERT_EQ(tables.back().map_tables.size(), 1u);
  EXPECT_NEAR(tables.back().map_tables[0].center.x(), 1.0, 0.05);
  EXPECT_NEAR(tables.back().map_tables[0].center.y(), 2.0, 0.05);
}

TEST(SemanticMapSink, FusedLabelsReplaceAWrongFramesLabels) {
  auto bus = std::make_shared<io::MemoryBus>();
  SemanticMapSink::Options options = sinkOptions(false);
  options.fused_labels = true;
  SemanticMapSink sink(options, bus, nullptr);
  sink.start();
  for (int i = 1; i <= 3; ++i) {
    const LabelledFrame l = topDownFrame(i);
    FrameResult r{l, 0, poseAt(l.segmented.prepared.frame.utime), {}, std::nullopt, std::nullopt};
    sink.consume(r);
  }
  // A frame calling the top a chair is published with the map's labels: table.
  const LabelledFrame wrong = topDownFrame(4, Label::Chair);
  FrameResult r{wrong, 0, poseAt(wrong.segmented.prepared.frame.utime), {}, std::nullopt,
                std::nullopt};
  sink.consume(r);
  ASSERT_TRUE(r.published_labels.has_value());
  int chair = 0, table = 0;
  for (std::size_t i = 0; i < wrong.labels.labels.size(); ++i) {
    if (wrong.labels.labels[i] != static_cast<std::uint8_t>(Label::Chair)) continue;
    chair += r.published_labels->labels[i] == static_cast<std::uint8_t>(Label::Chair);
    table += r.published_labels->labels[i] == static_cast<std::uint8_t>(Label::Table);
  }
  EXPECT_EQ(chair, 0);
  EXPECT_EQ(table, 400);

  EXPECT_EQ(sink.counters().fused_frames, 4u);
  // A frame without a pose is neither fused nor relabelled.
  FrameResult no_pose{wrong, 0, std::nullopt, {}, std::nullopt, std::nullopt};
  sink.consume(no_pose);
  EXPECT_FALSE(no_pose.published_labels.has_value());
  EXPECT_EQ(sink.counters().integrated, 4u);
  sink.stop(true);
}

}  // namespace
}  // namespace findmug::daemon
