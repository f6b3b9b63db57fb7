// ObjectSearchSink (findmug/daemon/object_search_sink.hpp): "find NAME" answered on
// FINDMUG_FIND_RESULT from the table map and the object map the sink keeps, updated
// when the robot searches a table; names not taught, and no pose input, refused; a
// corrupt taught-object file reported by name. In-memory bus, hand-built frames.
#include "findmug/daemon/object_search_sink.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <future>
#include <mutex>
#include <fstream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/ground/ground.hpp"
#include "findmug/map/semantic_map.hpp"
#include "findmug/io/bus.hpp"
#include "findmug/io/lcm_codec_find.hpp"
#include "findmug/io/lcm_codec_objects.hpp"
#include "object_scenes.hpp"
#include "table_scenes.hpp"
#include "test_data.hpp"

namespace findmug::daemon {
namespace {

// A mapped table with a search position on each long side.
TableCluster tableAt(float cx, float cy) {
  return test::withSearchPositions(test::tableAt(cx, cy));
}

using namespace std::chrono_literals;
constexpr const char* kFindChannel = "FINDMUG_FIND_RESULT";

// A labelled frame (a ground plane, one labelled pixel) with `tables`.
LabelledFrame frameWith(std::vector<TableCluster> tables, std::uint64_t utime) {
  LabelledFrame f;
  f.segmented.prepared.frame.utime = utime;
  f.segmented.prepared.ground = GroundPlane{};
  f.labels.width = 1;
  f.labels.height = 1;
  f.labels.labels = {static_cast<std::uint8_t>(Label::Table)};
  f.labels.confidence = {1.0f};
  f.tables = std::move(tables);
  return f;
}

// What TableMapSink gives the sinks after it for a frame seen at `pose`: every
// table of the frame in the map under ids 1..n.
void asMapped(FrameResult& result, const Pose2D& pose) {
  result.pose = io::RobotPose{result.labelled.segmented.prepared.frame.utime, pose};
  for (std::size_t i = 0; i < result.labelled.tables.size(); ++i) {
    result.map_info.push_back({static_cast<int>(i + 1), true, 3, 0});
  }
}

struct DaemonFind : ::testing::Test {
  test::TempDir dir;
  std::shared_ptr<io::MemoryBus> bus = std::make_shared<io::MemoryBus>();
  std::vector<std::string> errors;
  std::vector<io::FindResultMessage> received;

  DaemonFind() {
    bus->subscribeTimed(kFindChannel, [this](const std::string& channel, const std::uint8_t* data,
                                             std::size_t size, std::int64_t) {
      received.push_back(io::decodeFindResult(data, size, channel));
    });
  }

  // The answers published since the last call.
  std::vector<io::FindResultMessage> drain() {
    while (bus->handle(0ms) == io::HandleResult::Handled) {
    }
    return std::exchange(received, {});
  }

  std::vector<TableCluster> table_map;  // the table map's confirmed tables (map frame)
  std::uint64_t table_map_revision = 0;

  // Sequential: consume() does the object work before it returns (the threaded worker
  // has tests of its own in daemon_objects_test).
  std::unique_ptr<ObjectSearchSink> makeSink(bool map_objects = true) {
    ObjectSearchSettings settings;
    settings.objects_dir = dir.str();
    settings.map_objects = map_objects;
    settings.mode = ExecutionMode::Sequential;
    return std::make_unique<ObjectSearchSink>(
        settings, bus, ObjectSearchSink::Channels{kFindChannel, "FINDMUG_OBJECT_MAP"},
        TableMapSource{[this] { return table_map_revision; }, [this] { return table_map; }},
        [this](const std::string& what) { errors.push_back(what); });
  }

  void mapTables(const std::vector<TableCluster>& tables) {
    table_map.clear();
    for (std::size_t i = 0; i < tables.size(); ++i) {
      table_map.push_back(tables[i]);
      table_map.back().id = static_cast<int>(i + 1);
    }
    ++table_map_revision;
  }
};

TEST_F(DaemonFind, FindListsThePlacesToLookAndPutsASearchedTableLast) {
  saveObjectModel(dir.str("mug.fmo"), test::sampleObjectModel("mug", 1));
  auto sink = makeSink();
  EXPECT_EQ(sink->taughtNames(), std::vector<std::string>{"mug"});

  // Two tables ahead of the robot at the map origin (pose = identity: base = map).
  mapTables({tableAt(2.0f, 0.0f), tableAt(5.0f, 0.0f)});
  LabelledFrame frame = frameWith({tableAt(2.0f, 0.0f), tableAt(5.0f, 0.0f)}, 1000);
  FrameResult result{frame, 0, std::nullopt, {}, std::nullopt};
  asMapped(result, Pose2D{});
  sink->consume(result);

  sink->requestFind(11, "mug", 2000);
  auto answers = drain();
  ASSERT_EQ(answers.size(), 1u);
  EXPECT_EQ(answers[0].request_id, 11);
  EXPECT_EQ(answers[0].result, io::FindResult::LookAt);
  ASSERT_EQ(answers[0].places.size(), 4u);
  EXPECT_EQ(answers[0].places.front().table_id, 1);  // the nearer table first
  EXPECT_EQ(answers[0].taught_names, std::vector<std::string>{"mug"});

  // The robot stands at table 1's south position, facing it: searched, and
  // the answer changes (table 2 first now) and is published again.
  LabelledFrame there = frameWith({}, 3000);
  FrameResult at_table{there, 0, std::nullopt, {}, std::nullopt};
  at_table.pose = io::RobotPose{3000, Pose2D{2.0, -0.9, M_PI / 2}};
  sink->consume(at_table);
  answers = drain();
  ASSERT_EQ(answers.size(), 1u);
  EXPECT_EQ(answers[0].places.front().table_id, 2);
  EXPECT_TRUE(answers[0].places.back().searched);
  EXPECT_EQ(answers[0].places.back().table_id, 1);

  // The same pose again changes nothing: no new message.
  sink->consume(at_table);
  EXPECT_TRUE(drain().empty());
  EXPECT_EQ(sink->counters().find_requests, 1u);
  EXPECT_EQ(sink->counters().find_answers, 2u);
}

// A 640x480 depth image, seen by the head camera (1.2 m up, 0.5 rad down) of a robot at
// `robot` (map = base frame here), of table tops 0.75 m up over `tables`' oriented boxes and
// the floor elsewhere; its ground plane from the same mount.
LabelledFrame viewOf(const std::vector<TableCluster>& tables, const Pose2D& robot,
                     std::uint64_t utime) {
  LabelledFrame f = frameWith({}, utime);
  f.segmented.prepared.ground = groundFromExtrinsics(test::headMount());
  f.segmented.prepared.frame =
      test::depthOfTops(tables, cameraInMap(robot, f.segmented.prepared.ground->camera_to_ground));
  f.segmented.prepared.frame.utime = utime;
  return f;
}

// A table whose top the camera showed from near enough while a find is open is searched:
// it moves to the end of the answer without the robot standing at it.
TEST_F(DaemonFind, ATableTopSeenNearEnoughIsSearchedWithoutStandingThere) {
  saveObjectModel(dir.str("mug.fmo"), test::sampleObjectModel("mug", 1));
  ObjectSearchSettings settings;
  settings.objects_dir = dir.str();
  settings.mode = ExecutionMode::Sequential;
  settings.object_search.top_seen_range_m = 2.5f;
  auto sink = std::make_unique<ObjectSearchSink>(
      settings, bus, ObjectSearchSink::Channels{kFindChannel, "FINDMUG_OBJECT_MAP"},
      TableMapSource{[this] { return table_map_revision; }, [this] { return table_map; }},
      [this](const std::string& what) { errors.push_back(what); });
  mapTables({tableAt(2.0f, 0.0f), tableAt(5.0f, 0.0f)});
  // A frame without depth brings the table map; the find is asked after it.
  FrameResult first{frameWith({tableAt(2.0f, 0.0f), tableAt(5.0f, 0.0f)}, 1000), 0,
                    std::nullopt, {}, std::nullopt};
  asMapped(first, Pose2D{});
  sink->consume(first);
  sink->requestFind(12, "mug", 1500);
  auto answers = drain();
  ASSERT_EQ(answers.size(), 1u);
  ASSERT_EQ(answers[0].places.size(), 4u);
  EXPECT_EQ(answers[0].places.front().table_id, 1);

  // A view before which nothing is in front: table 1's top whole within 2.5 m, table 2's not.
  const Pose2D robot{0.5, 0.0, 0.0};
  FrameResult view{viewOf(table_map, robot, 2000), 0, std::nullopt, {}, std::nullopt};
  view.pose = io::RobotPose{2000, robot};
  sink->consume(view);
  answers = drain();
  ASSERT_EQ(answers.size(), 1u);
  ASSERT_EQ(answers[0].places.size(), 4u);
  EXPECT_EQ(answers[0].places.front().table_id, 2);
  EXPECT_EQ(answers[0].places.back().table_id, 1);
  EXPECT_TRUE(answers[0].places.back().searched);
  EXPECT_TRUE(errors.empty());
}

TEST_F(DaemonFind, AnUntaughtNameIsAnsweredWithTheTaughtNamesABadNameIsRefused) {
  saveObjectModel(dir.str("mug.fmo"), test::sampleObjectModel("mug", 1));
  auto sink = makeSink();
  sink->requestFind(3, "teapot", 10);
  const auto answers = drain();
  ASSERT_EQ(answers.size(), 1u);
  EXPECT_EQ(answers[0].result, io::FindResult::UnknownName);
  EXPECT_NE(answers[0].summary.find("taught: mug"), std::string::npos) << answers[0].summary;
  EXPECT_THROW(sink->requestFind(4, "Tea Pot!", 10), Error);
  EXPECT_TRUE(drain().empty());
}

TEST_F(DaemonFind, WithoutAPoseInputFindIsRefusedWithTheReason) {
  auto sink = makeSink(/*map_objects=*/false);
  sink->requestFind(5, "mug", 10);
  const auto answers = drain();
  ASSERT_EQ(answers.size(), 1u);
  EXPECT_EQ(answers[0].result, io::FindResult::Refused);
  EXPECT_NE(answers[0].summary.find("daemon.pose_input"), std::string::npos);
}

TEST_F(DaemonFind, ACorruptTaughtObjectIsReportedByNameAndTheGoodOnesStay) {
  saveObjectModel(dir.str("mug.fmo"), test::sampleObjectModel("mug", 1));
  { std::ofstream(dir.str("broken.fmo")) << "FMOBJECT garbage"; }
  auto sink = makeSink();
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("broken.fmo"), std::string::npos) << errors[0];
  EXPECT_EQ(sink->counters().object_files_refused, 1u);
  EXPECT_EQ(sink->taughtNames(), std::vector<std::string>{"mug"});
}

// A candidate made of `model`'s first view's points, standing on the table at (x, y) of
// the frame (top 0.75 m), its points appended to `cloud` (one row); `colour_bin` and
// `height` as it was measured.
TableObject candidateLike(const ObjectModel& model, float x, float y, int colour_bin, float height,
                          OrganizedCloud& cloud, int id) {
  const ObjectView& view = model.views.front();
  TableObject c;
  c.id = id;
  c.table = 0;
  c.centroid = {x, y, 0.75f + height / 2};
  c.height_above_top = height;
  c.extents = view.extents;
  c.center = {x, y};
  c.mean_rgb = {200, 40, 40};
  c.colour_histogram[colour_bin] = 1.0f;
  for (const Eigen::Vector3f& p : view.points) {
    c.pixels.push_back(static_cast<int>(cloud.points.size()));
    cloud.points.push_back(p + c.centroid);
  }
  c.point_count = static_cast<int>(c.pixels.size());
  cloud.width = static_cast<int>(cloud.points.size());
  cloud.height = 1;
  return c;
}

// A frame on the table at (2, 0) with three candidates: the taught mug, one of the mug's
// shape in another colour, and one far too tall.
LabelledFrame frameWithCandidates(const ObjectModel& mug, std::uint64_t utime) {
  LabelledFrame frame = frameWith({tableAt(2.0f, 0.0f)}, utime);
  OrganizedCloud& cloud = frame.segmented.prepared.cloud_ground;
  auto& objects = frame.table_objects.objects;
  objects.push_back(candidateLike(mug, 1.8f, 0.0f, 1, 0.10f, cloud, 0));
  objects.push_back(candidateLike(mug, 2.0f, 0.2f, 9, 0.10f, cloud, 1));
  objects.push_back(candidateLike(mug, 2.2f, -0.2f, 1, 0.50f, cloud, 2));
  return frame;
}

TEST_F(DaemonFind, TheObjectMapIsPublishedWithStableIdsAndNamesAndRefusalsAreCounted) {
  const ObjectModel mug = test::sampleObjectModel("mug", 1);
  saveObjectModel(dir.str("mug.fmo"), mug);
  std::vector<io::ObjectsMessage> maps;
  bus->subscribeTimed("FINDMUG_OBJECT_MAP",
                      [&](const std::string& channel, const std::uint8_t* data, std::size_t size,
                          std::int64_t) { maps.push_back(io::decodeObjects(data, size, channel)); });
  auto sink = makeSink();
  mapTables({tableAt(2.0f, 0.0f)});
  for (std::uint64_t utime : {1000u, 2000u}) {
    LabelledFrame frame = frameWithCandidates(mug, utime);
    frame.segmented.prepared.frame.seq = static_cast<std::int64_t>(utime / 1000);
    FrameResult result{frame, 0, std::nullopt, {}, std::nullopt};
    asMapped(result, Pose2D{0.5, 0.0, 0.0});
    sink->consume(result);
  }
  drain();
  ASSERT_EQ(maps.size(), 2u) << "one object map per frame the map took";
  const io::ObjectsMessage& map = maps.back();
  EXPECT_EQ(map.content, io::TablesContent::Map);
  EXPECT_EQ(map.seq, 2);
  EXPECT_EQ(map.num_tables, 1);
  ASSERT_TRUE(map.map_pose.has_value());
  ASSERT_EQ(map.objects.size(), 3u);
  int named = 0;
  for (std::size_t i = 0; i < map.objects.size(); ++i) {
    const io::ObjectMapInfo& info = map.map_info[i];
    EXPECT_EQ(info.map_id, static_cast<int>(i + 1)) << "the same three objects, ids kept";
    EXPECT_EQ(info.sightings, 2);
    EXPECT_EQ(info.last_seen_utime, 2000u);
    EXPECT_EQ(info.table_map_id, 1);
    EXPECT_EQ(map.objects[i].table, 0) << "the table map's first confirmed table";
    if (info.name.empty()) continue;
    ++named;
    EXPECT_EQ(info.name, "mug");
    EXPECT_GT(info.name_score, 0.0f);
    // Map frame: the candidate at (1.8, 0) of a robot at (0.5, 0).
    EXPECT_NEAR(info.map_centroid.x(), 2.3, 1e-4);
    EXPECT_NEAR(map.objects[i].centroid.x(), 1.8, 1e-4) << "relative to the robot at map_pose";
  }
  EXPECT_EQ(named, 1);

  const ObjectSearchSink::Counters c = sink->counters();
  EXPECT_EQ(c.frames_queued, 2u);
  EXPECT_EQ(c.frames_matched, 2u);
  EXPECT_EQ(c.candidates, 6u);
  EXPECT_EQ(c.matches, 2u);
  EXPECT_EQ(c.refused_colour, 2u);
  EXPECT_EQ(c.refused_too_big, 2u);
  EXPECT_EQ(c.refused_too_small + c.refused_shape + c.refused_not_round + c.refused_few_points,
            0u);
  EXPECT_EQ(c.map_publishes, 2u);
  EXPECT_EQ(c.mapped_objects, 3u);
  EXPECT_EQ(c.table_map_copies, 1u) << "the table map did not change between the frames";
  EXPECT_EQ(c.frames_skipped, 0u);
}

TEST_F(DaemonFind, WithoutPublishObjectMapNoMapGoesOut) {
  const ObjectModel mug = test::sampleObjectModel("mug", 1);
  int maps = 0;
  bus->subscribeTimed("FINDMUG_OBJECT_MAP",
                      [&](const std::string&, const std::uint8_t*, std::size_t, std::int64_t) {
                        ++maps;
                      });
  ObjectSearchSettings settings;
  settings.mode = ExecutionMode::Sequential;
  settings.publish_map = false;
  ObjectSearchSink sink(settings, bus, {kFindChannel, "FINDMUG_OBJECT_MAP"}, {},
                        [this](const std::string& what) { errors.push_back(what); });
  LabelledFrame frame = frameWithCandidates(mug, 1000);
  FrameResult result{frame, 0, std::nullopt, {}, std::nullopt};
  asMapped(result, Pose2D{});
  sink.consume(result);
  drain();
  EXPECT_EQ(maps, 0);
  EXPECT_EQ(sink.counters().mapped_objects, 3u) << "the map itself is kept";
}

// The worker has a thread of its own: with it held (an ESF on a big candidate can take
// tens of milliseconds), the publish thread's consume() returns at once, the queue keeps
// the newest frames and counts what it dropped, and the worker catches up afterwards.
TEST_F(DaemonFind, ASlowObjectWorkerNeverHoldsThePublishThreadAndItsDropsAreCounted) {
  const ObjectModel mug = test::sampleObjectModel("mug", 1);
  saveObjectModel(dir.str("mug.fmo"), mug);
  std::mutex gate_mutex;
  std::condition_variable gate_changed;
  bool held = false, released = false;
  ObjectSearchSettings settings;
  settings.objects_dir = dir.str();
  settings.queue_capacity = 2;
  settings.before_job = [&] {
    std::unique_lock lock(gate_mutex);
    held = true;
    gate_changed.notify_all();
    gate_changed.wait(lock, [&] { return released; });
  };
  ObjectSearchSink sink(settings, bus, {kFindChannel, "FINDMUG_OBJECT_MAP"}, {},
                        [this](const std::string& what) { errors.push_back(what); });
  std::vector<LabelledFrame> frames;
  for (int i = 0; i < 5; ++i) frames.push_back(frameWithCandidates(mug, 1000u * (i + 1)));
  auto consumeFrame = [&](int i) {
    FrameResult result{frames[static_cast<std::size_t>(i)], 0, std::nullopt, {}, std::nullopt};
    asMapped(result, Pose2D{});
    sink.consume(result);
  };
  consumeFrame(0);
  {
    std::unique_lock lock(gate_mutex);
    ASSERT_TRUE(gate_changed.wait_for(lock, 10s, [&] { return held; }))
        << "the worker never took the first frame";
  }
  // The worker is held with frame 0: the next four must not wait for it.
  auto publishing = std::async(std::launch::async, [&] {
    for (int i = 1; i < 5; ++i) consumeFrame(i);
  });
  const bool returned = publishing.wait_for(10s) == std::future_status::ready;
  ObjectSearchSink::Counters c = sink.counters();
  {
    std::lock_guard lock(gate_mutex);
    released = true;
  }
  gate_changed.notify_all();
  ASSERT_TRUE(returned) << "consume() waited for the held object worker";
  EXPECT_EQ(c.frames_queued, 5u);
  EXPECT_EQ(c.frames_skipped, 2u) << "frames 1 and 2 made room for 3 and 4";
  EXPECT_EQ(c.queue_depth, 2u);
  EXPECT_EQ(c.queue_capacity, 2u);
  ASSERT_TRUE(sink.waitIdle(30s));
  c = sink.counters();
  EXPECT_EQ(c.frames_matched, 3u) << "frames 0, 3 and 4";
  EXPECT_EQ(c.map_publishes, 3u);
  EXPECT_EQ(c.latency.samples, 3u);
  sink.stop(true);
  sink.consume(*std::make_unique<FrameResult>(FrameResult{frames[0], 0, std::nullopt, {},
                                                          std::nullopt}));
  EXPECT_EQ(sink.counters().frames_queued, 5u) << "nothing is taken after stop()";
}

TEST(FindCodec, RoundTripsAndRefusesWhatIsNotAnAnswer) {
  io::FindResultMessage m;
  m.utime = 5;
  m.request_id = 9;
  m.name = "mug";
  m.result = io::FindResult::Seen;
  m.summary = "mug seen";
  m.seen_object_id = 3;
  m.seen_position = {1.0, 2.0, 0.8};
  m.seen_table_id = 2;
  m.seen_utime = 4;
  m.seen_score = 0.7f;
  SearchPosition stand;
  stand.xy = {1.0f, 1.1f};
  m.stand_here = stand;
  m.taught_names = {"book", "mug"};
  std::vector<std::uint8_t> bytes = io::encodeMessage(io::encodeFindResult(m));
  const io::FindResultMessage back = io::decodeFindResult(bytes.data(), bytes.size(), "C");
  EXPECT_EQ(back.seen_object_id, 3);
  EXPECT_EQ(back.seen_table_id, 2);
  ASSERT_TRUE(back.stand_here.has_value());
  EXPECT_FLOAT_EQ(back.stand_here->xy.y(), 1.1f);
  EXPECT_EQ(back.taught_names, m.taught_names);
  // A "look at" answer's places keep their flags, "look closer" among them.
  io::FindResultMessage look;
  look.utime = 6;
  look.request_id = 9;
  look.name = "mug";
  look.result = io::FindResult::LookAt;
  look.summary = "mug not seen yet";
  look.taught_names = {"mug"};
  PlaceToLook place;
  place.table_id = 4;
  place.position = stand;
  place.look_closer = true;
  look.places = {place, place};
  look.places[1].look_closer = false;
  look.places[1].searched = true;
  bytes = io::encodeMessage(io::encodeFindResult(look));
  const io::FindResultMessage look_back = io::decodeFindResult(bytes.data(), bytes.size(), "C");
  ASSERT_EQ(look_back.places.size(), 2u);
  EXPECT_TRUE(look_back.places[0].look_closer);
  EXPECT_FALSE(look_back.places[0].searched);
  EXPECT_FALSE(look_back.places[1].look_closer);
  EXPECT_TRUE(look_back.places[1].searched);

  auto refused = [](findmug_lcm::find_result_t lcm, const std::string& field) {
    try {
      io::decodeFindResult(lcm, "C");
      ADD_FAILURE() << "accepted a message with a bad " << field;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  findmug_lcm::find_result_t lcm = io::encodeFindResult(m);
  lcm.result = 7;
  refused(lcm, "result");
  lcm = io::encodeFindResult(m);
  lcm.seen_score = std::nanf("");
  refused(lcm, "seen_score");
  lcm = io::encodeFindResult(m);
  lcm.taught_names[0] = "Bad Name";
  refused(lcm, "taught_names[0]");
  lcm = io::encodeFindResult(m);
  lcm.result = findmug_lcm::find_result_t::RESULT_LOOK_AT;  // seen_ fields still set
  refused(lcm, "seen_");
  // Truncated on the wire: refused before LCM allocates anything.
  bytes.resize(bytes.size() - 3);
  EXPECT_THROW(io::decodeFindResult(bytes.data(), bytes.size(), "C"), Error);
}

}  // namespace
}  // namespace findmug::daemon
