// ObjectSearchSink (findmug/daemon/object_search_sink.hpp): "find NAME" answered on
// FINDMUG_FIND_RESULT from the table map and the object map the sink keeps, updated
// when the robot searches a table; names not taught, and no pose input, refused; a
// corrupt taught-object file reported by name. In-memory bus, hand-built frames.
#include "findmug/daemon/object_search_sink.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/io/bus.hpp"
#include "findmug/io/lcm_codec_find.hpp"
#include "object_scenes.hpp"
#include "test_data.hpp"

namespace findmug::daemon {
namespace {

using namespace std::chrono_literals;
constexpr const char* kFindChannel = "FINDMUG_FIND_RESULT";

// A 1.2 x 0.8 m table centred at (cx, cy) of the frame's base frame, with one
// search position on each long side facing it.
TableCluster tableAt(float cx, float cy) {
  TableCluster t;
  t.top_height = 0.75f;
  t.centroid = {cx, cy, 0.75f};
  t.center = {cx, cy};
  t.extents = {0.6f, 0.4f};
  t.hull = {{cx - 0.6f, cy - 0.4f}, {cx + 0.6f, cy - 0.4f}, {cx + 0.6f, cy + 0.4f},
            {cx - 0.6f, cy + 0.4f}};
  SearchPosition north, south;
  north.xy = {cx, cy + 0.9f};
  north.yaw = static_cast<float>(-M_PI / 2);
  south.xy = {cx, cy - 0.9f};
  south.yaw = static_cast<float>(M_PI / 2);
  t.search_positions = {north, south};
  return t;
}

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

  std::vector<MappedTable> table_map;  // what the table map holds (map frame)

  std::unique_ptr<ObjectSearchSink> makeSink(bool map_objects = true) {
    ObjectSearchSettings settings;
    settings.objects_dir = dir.str();
    settings.map_objects = map_objects;
    return std::make_unique<ObjectSearchSink>(
        settings, bus, kFindChannel, [this] { return table_map; },
        [this](const std::string& what) { errors.push_back(what); });
  }

  void mapTables(const std::vector<TableCluster>& tables) {
    table_map.clear();
    for (std::size_t i = 0; i < tables.size(); ++i) {
      MappedTable m;
      m.table = tables[i];
      m.table.id = static_cast<int>(i + 1);
      m.confirmed = true;
      table_map.push_back(m);
    }
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
