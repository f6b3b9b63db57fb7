// The teach-and-find loop through findmugd's commands, without a browser: a replayed
// synthetic apartment (findmug-synth's dataset layout, the demo's model and settings)
// goes through the pipeline; a table-top candidate that FINDMUG_OBJECTS showed is
// taught with "teach NAME SEQ INDEX" (command_t) and appears as NAME.fmo in
// daemon.objects_dir; after the library has read it, the frames are replayed again and
// "find NAME" is answered "seen". Also the teacher's refusals (object_teacher.hpp), each
// with its reason in the status, and the held frames' bound.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "daemon_test_config.hpp"
#include "daemon_test_support.hpp"
#include "findmug/common/error.hpp"
#include "findmug/daemon/object_teacher.hpp"
#include "findmug/daemon/pipeline.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/io/bus.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/lcm_codec_find.hpp"
#include "findmug/io/lcm_codec_objects.hpp"
#include "findmug/objects/object_model.hpp"
#include "findmug/synth/synth.hpp"
#include "test_data.hpp"

namespace findmug::daemon {
namespace {

using namespace std::chrono_literals;
using findmug::test::TempDir;

constexpr int kFrames = 12;

// Polls `done` for up to a minute (a wait, not a timing assertion).
template <class F>
bool waitFor(F done) {
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(10ms);
  }
  return true;
}

struct Rig {
  TempDir dir;
  std::vector<RgbdFrame> frames;
  std::shared_ptr<io::MemoryBus> out = std::make_shared<io::MemoryBus>(100000);
  std::shared_ptr<io::MemoryBus> commands = std::make_shared<io::MemoryBus>(100);
  std::vector<io::ObjectsMessage> objects;
  std::vector<io::FindResultMessage> answers;
  std::unique_ptr<Pipeline> pipeline;
  std::int64_t next_seq = 0;

  Rig() {
    // The demo's apartment (scripts/demo.sh: seed 7, 5 frames a second).
    synth::SequenceSpec spec;
    spec.seed = 7;
    spec.frames = kFrames;
    spec.fps = 5;
    synth::writeSequence(dir.str("apartment"), spec, {});
    DatasetOptions options;
    options.require_labels = false;
    const DatasetFolder folder(dir.str("apartment"), options);
    for (std::size_t i = 0; i < folder.size(); ++i) frames.push_back(folder.load(i).frame);
    std::filesystem::create_directories(dir.str("objects"));

    // A robot standing still at the map origin, as findmug-replay --robot-pose gives it:
    // a pose for every frame time of two passes over the sequence.
    std::vector<test::LogMessage> poses;
    for (int i = 0; i < 4 * kFrames; ++i) {
      const io::RobotPose pose{utimeOf(i), Pose2D{}};
      poses.push_back({std::string(io::kRobotPoseChannel),
                       io::encodeMessage(io::encodeRobotPose(pose))});
    }
    test::writeLcmLog(dir.str("poses.lcmlog"), poses);

    test::TestConfig config;
    // scripts/demo.sh's settings for its model.
    config.set("learner.classes", "labels");
    config.set("features.objects", "false");
    config.set("mrf.pairwise", "potts");
    config.set("features.regions", "true");  // daemon/findmugd.yaml's
    config.set("features.scene", "true");
    config.set("daemon.objects_dir", dir.str("objects"));
    config.set("daemon.pose_url", "file://" + dir.str("poses.lcmlog") + "?speed=0");
    config.set("daemon.pose_history_s", "1000");
    config.set("daemon.status_period_s", "60");
    PipelineHooks hooks;
    hooks.output_bus = out;
    hooks.command_bus = commands;
    auto forest = std::make_shared<const RandomForest>(RandomForest::load(
        (findmug::test::sourceDir() / "models" / "findmug-nyu-synth.fmf").string()));
    pipeline = std::make_unique<Pipeline>(config.segmenter, config.daemon, forest, "synth",
                                          ExecutionMode::Sequential, hooks);
    out->subscribeTimed(std::string(io::kObjectsChannel),
                        [this](const std::string& c, const std::uint8_t* d, std::size_t n,
                               std::int64_t) { objects.push_back(io::decodeObjects(d, n, c)); });
    out->subscribeTimed(std::string(io::kFindResultChannel),
                        [this](const std::string& c, const std::uint8_t* d, std::size_t n,
                               std::int64_t) { answers.push_back(io::decodeFindResult(d, n, c)); });
    pipeline->start();
    EXPECT_TRUE(waitFor([this] { return pipeline->poseInput()->finished(); }));
  }

  static std::uint64_t utimeOf(int i) { return 1'000'000'000ull + static_cast<std::uint64_t>(i) * 200'000; }

  // Frame `index` of the sequence as the next frame of the replay (new seq and time).
  void replay(std::size_t index) {
    RgbdFrame frame = frames[index];
    frame.seq = next_seq;
    frame.utime = utimeOf(static_cast<int>(next_seq));
    ++next_seq;
    ASSERT_TRUE(pipeline->submit(std::move(frame)));
    drain();
  }

  void drain() {
    while (out->handle(0ms) == io::HandleResult::Handled) {
    }
  }

  void command(std::int64_t id, const std::string& name, const std::string& argument) {
    const auto bytes =
        io::encodeMessage(io::encodeCommand(io::CommandMessage{1, id, name, argument}));
    ASSERT_TRUE(commands->publish(std::string(io::kCommandChannel), bytes.data(), bytes.size()));
  }

  TeachStatus teachAnswer(std::int64_t id) {
    EXPECT_TRUE(waitFor([&] { return pipeline->objectTeacher().status().last_request_id == id; }))
        << "no answer to teach request " << id;
    return pipeline->objectTeacher().status();
  }
};

TEST(DaemonTeach, ACandidateTaughtFromTheLiveStreamIsFoundSeen) {
  Rig rig;
  for (std::size_t i = 0; i < rig.frames.size(); ++i) rig.replay(i);
  ASSERT_EQ(rig.objects.size(), rig.frames.size());

  // The candidate to teach: the largest one not cut by the image border (the teacher
  // refuses those) of the pass.
  std::optional<std::pair<std::int64_t, int>> pick;
  int best_points = 0;
  std::size_t pick_frame = 0;
  for (std::size_t f = 0; f < rig.objects.size(); ++f) {
    const io::ObjectsMessage& m = rig.objects[f];
    for (std::size_t k = 0; k < m.objects.size(); ++k) {
      const TableObject& o = m.objects[k];
      if ((o.truncation & kTruncatedBorder) == 0 && o.point_count > best_points) {
        best_points = o.point_count;
        pick = {m.seq, static_cast<int>(k)};
        pick_frame = f;
      }
    }
  }
  ASSERT_TRUE(pick) << "no whole table-top candidate in the replayed apartment";

  rig.command(7, "teach", "thing " + std::to_string(pick->first) + " " +
                              std::to_string(pick->second));
  const TeachStatus taught = rig.teachAnswer(7);
  ASSERT_TRUE(taught.last_ok) << taught.last_result;
  EXPECT_EQ(taught.taught, 1u);
  EXPECT_NE(taught.last_result.find("taught thing (1 view)"), std::string::npos)
      << taught.last_result;
  const ObjectModel model = loadObjectModel(rig.dir.str("objects/thing.fmo"));
  EXPECT_EQ(model.name, "thing");
  ASSERT_EQ(model.views.size(), 1u);

  // A second view of the same object: one more view in the same file.
  rig.command(8, "teach", "thing " + std::to_string(pick->first) + " " +
                              std::to_string(pick->second));
  EXPECT_TRUE(rig.teachAnswer(8).last_ok);
  EXPECT_EQ(loadObjectModel(rig.dir.str("objects/thing.fmo")).views.size(), 2u);

  // The library reads the folder about once a second: then the replay goes on, and the
  // taught object is named where it stands.
  std::this_thread::sleep_for(1200ms);
  for (std::size_t i = 0; i < rig.frames.size(); ++i) rig.replay(i);
  rig.replay(pick_frame);
  rig.command(9, "find", "thing");
  ASSERT_TRUE(waitFor([&] {
    rig.drain();
    return !rig.answers.empty();
  }));
  const io::FindResultMessage& answer = rig.answers.back();
  EXPECT_EQ(answer.request_id, 9);
  EXPECT_EQ(answer.result, io::FindResult::Seen) << answer.summary;
  EXPECT_NE(answer.summary.find("thing seen"), std::string::npos) << answer.summary;
  rig.pipeline->stop(StopMode::Drain);
}

TEST(DaemonTeach, RefusalsSayWhyAndAreCounted) {
  Rig rig;
  for (std::size_t i = 0; i < 3; ++i) rig.replay(i);
  const io::ObjectsMessage& last = rig.objects.back();
  const std::int64_t seq = last.seq;

  struct Case {
    std::string argument, expected;
  };
  const std::vector<Case> cases = {
      {"mug 999999 0", "frame seq 999999 is not held"},
      {"mug " + std::to_string(seq) + " 9999", "no index 9999"},
  };
  std::int64_t id = 20;
  for (const Case& c : cases) {
    rig.command(id, "teach", c.argument);
    const TeachStatus s = rig.teachAnswer(id);
    EXPECT_FALSE(s.last_ok);
    EXPECT_NE(s.last_result.find(c.expected), std::string::npos) << s.last_result;
    ++id;
  }
  EXPECT_EQ(rig.pipeline->objectTeacher().status().refused, cases.size());
  EXPECT_EQ(rig.pipeline->objectTeacher().status().taught, 0u);
  EXPECT_FALSE(std::filesystem::exists(rig.dir.str("objects/mug.fmo")));
  rig.pipeline->stop(StopMode::Drain);
}

// The teacher alone: a bounded number of frames held, a model full at ten views, no
// folder to write to.
TEST(ObjectTeacher, HoldsTheLastFramesOnlyAndRefusesAFullModelAndNoFolder) {
  TempDir dir;
  ObjectTeacher teacher(dir.str(), 3);
  LabelledFrame frame;
  frame.segmented.prepared.cloud_ground.width = 8;
  frame.segmented.prepared.cloud_ground.height = 8;
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 8; ++x) {
      // A small bowl: points that span a surface.
      frame.segmented.prepared.cloud_ground.points.emplace_back(
          0.01f * x, 0.01f * y, 0.8f + 0.002f * static_cast<float>((x - 4) * (x - 4) + (y - 4) * (y - 4)));
      frame.segmented.prepared.cloud_ground.colors.push_back(Rgb8{200, 30, 30});
    }
  }
  TableObject o;
  o.height_above_top = 0.1f;
  o.extents = {0.04f, 0.04f};
  o.colour_histogram[0] = 1.0f;
  o.point_count = 64;
  for (int i = 0; i < 64; ++i) o.pixels.push_back(i);
  frame.table_objects.objects = {o};
  for (int s = 1; s <= 5; ++s) {
    frame.segmented.prepared.frame.seq = s;
    FrameResult r{frame, 0, std::nullopt, {}, std::nullopt};
    teacher.consume(r);
  }
  EXPECT_EQ(teacher.heldSeqs(), (std::vector<std::int64_t>{3, 4, 5}));
  EXPECT_THROW(teacher.teach(1, "cup 1 0"), Error);
  EXPECT_NE(teacher.status().last_result.find("is not held"), std::string::npos);
  EXPECT_THROW(teacher.teach(2, "Cup! 5 0"), Error);
  EXPECT_NE(teacher.status().last_result.find("teach NAME"), std::string::npos)
      << teacher.status().last_result;
  for (int i = 0; i < kMaxObjectViews; ++i) {
    EXPECT_EQ(teacher.teach(10 + i, "cup 5 0").find("taught cup (" + std::to_string(i + 1)),
              0u);
  }
  EXPECT_THROW(teacher.teach(30, "cup 5 0"), Error);
  EXPECT_NE(teacher.status().last_result.find("already has 10 views"), std::string::npos)
      << teacher.status().last_result;
  EXPECT_EQ(teacher.status().last_request_id, 30);
  EXPECT_EQ(teacher.status().taught, 10u);
  EXPECT_EQ(teacher.status().refused, 3u);

  // A candidate cut by the image border is refused.
  frame.table_objects.objects[0].truncation = kTruncatedBorder;
  frame.segmented.prepared.frame.seq = 6;
  FrameResult r{frame, 0, std::nullopt, {}, std::nullopt};
  teacher.consume(r);
  EXPECT_THROW(teacher.teach(31, "other 6 0"), Error);
  EXPECT_NE(teacher.status().last_result.find("image border"), std::string::npos);

  // A folder that cannot be written (here: none there): refused, saying where.
  ObjectTeacher unwritable(dir.str("missing"), 3);
  frame.table_objects.objects[0].truncation = 0;
  FrameResult again{frame, 0, std::nullopt, {}, std::nullopt};
  unwritable.consume(again);
  EXPECT_THROW(unwritable.teach(40, "cup 6 0"), Error);
  EXPECT_NE(unwritable.status().last_result.find("cannot open"), std::string::npos)
      << unwritable.status().last_result;
  EXPECT_EQ(unwritable.status().refused, 1u);

  ObjectTeacher nowhere("", 3);
  EXPECT_THROW(nowhere.teach(1, "cup 1 0"), Error);
  EXPECT_NE(nowhere.status().last_result.find("daemon.objects_dir"), std::string::npos);
}

}  // namespace
}  // namespace findmug::daemon
