// The daemon's pipeline in-process: real frames in (NYU, PCL grabber
// sequence, LCM log with corrupt messages), LCM file:// logs out, compared
// frame by frame with Segmenter::process. Also the drop policy under an
// artificially held segmentation stage, and start-up errors naming the key.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

#include "daemon_test_config.hpp"
#include "daemon_test_support.hpp"
#include "findmug/common/error.hpp"
#include "findmug/daemon/daemon.hpp"
#include "findmug/daemon/frame_steps.hpp"
#include "findmug/daemon/pipeline.hpp"
#include "findmug/daemon/status_builder.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/frame_source.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/lcm_codec_objects.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "test_data.hpp"

namespace findmug::daemon {
namespace {

using namespace std::chrono_literals;
using findmug::test::TempDir;

// One model for the whole test program, trained on two NYU frames.
struct SharedModel {
  std::shared_ptr<const RandomForest> forest;
  std::string path;
  TempDir dir;
};

const SharedModel* sharedModel() {
  static SharedModel* model = []() -> SharedModel* {
    const auto nyu = findmug::test::dataPath("nyuv2_labeled");
    if (nyu.empty()) return nullptr;
    auto* m = new SharedModel;
    const std::vector<LabeledFrame> frames = test::framesWithGround(nyu.string(), 2);
    m->path = m->dir.str("tiny.fmf");
    m->forest = test::trainTinyModel(test::fastSegmenterConfig(), frames, m->path);
    return m;
  }();
  return model;
}

test::TestConfig baseConfig(const std::string& source, const std::string& out_log) {
  test::TestConfig config;
  config.segmenter = test::fastSegmenterConfig();
  config.set("daemon.source", source);
  config.set("daemon.lcm_url", "file://" + out_log + "?mode=w");
  config.set("daemon.model_path", sharedModel()->path);
  config.set("daemon.workers", "2");
  config.set("daemon.status_period_s", "0.2");
  return config;
}

struct Published {
  std::vector<io::LabelImageMessage> labels;
  std::vector<io::TablesMessage> tables;
  std::vector<io::ObjectsMessage> objects;
  std::vector<findmug_lcm::status_t> statuses;
};

Published readPublished(const std::string& log) {
  Published p;
  for (const auto& m : test::readLcmLog(log)) {
    if (m.channel == io::kLabelsChannel) {
      p.labels.push_back(io::decodeLabelImage(m.data.data(), m.data.size(), m.channel));
    } else if (m.channel == io::kTablesChannel) {
      p.tables.push_back(io::decodeTables(m.data.data(), m.data.size(), m.channel));
    } else if (m.channel == io::kObjectsChannel) {
      p.objects.push_back(io::decodeObjects(m.data.data(), m.data.size(), m.channel));
    } else if (m.channel == io::kStatusChannel) {
      p.statuses.push_back(
          io::decodeMessage<findmug_lcm::status_t>(m.data.data(), m.data.size(), m.channel));
    } else {
      ADD_FAILURE() << "unexpected channel " << m.channel;
    }
  }
  return p;
}

// Every frame the spec yields, run through the library alone.
std::map<std::int64_t, LabelledFrame> libraryResults(const std::string& spec,
                                                     const SegmenterConfig& config) {
  const Segmenter segmenter(config, sharedModel()->forest);
  auto source = io::makeSource(spec);
  std::map<std::int64_t, LabelledFrame> out;
  while (auto frame = source->next()) {
    const std::int64_t seq = frame->seq;
    out.emplace(seq, segmenter.process(std::move(*frame)));
  }
  return out;
}

void expectSameLabels(const LabelImage& expected, const io::LabelImageMessage& got) {
  ASSERT_EQ(got.image.width, expected.width);
  ASSERT_EQ(got.image.height, expected.height);
  ASSERT_EQ(got.image.labels.size(), expected.labels.size());
  std::size_t differing = 0;
  for (std::size_t i = 0; i < expected.labels.size(); ++i) {
    differing += got.image.labels[i] != expected.labels[i];
  }
  EXPECT_EQ(differing, 0u) << "seq " << got.seq;
  ASSERT_EQ(got.image.confidence.size(), expected.confidence.size());
  for (std::size_t i = 0; i < expected.confidence.size(); i += 97) {
    EXPECT_NEAR(got.image.confidence[i], expected.confidence[i], 0.5 / 255 + 1e-6);
  }
}

// Runs the daemon over a finite source to its end and checks that every
// frame was published exactly once, in order, equal to the library's output.
void runAndCompare(const std::string& spec, std::size_t expected_frames,
                   const std::vector<std::string>& overrides = {}) {
  TempDir tmp;
  const std::string out = tmp.str("out.lcmlog");
  test::TestConfig config = baseConfig(spec, out);
  for (const auto& o : overrides) daemonSchema(config, config.daemon).applyOverride(o);
  config.set("daemon.queue_capacity", "16");  // a finite replay: keep every frame
  const DaemonConfig dc = config.daemon;
  {
    Daemon daemon(config, dc);
    EXPECT_EQ(daemon.run(), 0);
  }
  const auto expected = libraryResults(spec, config.segmenter);
  ASSERT_EQ(expected.size(), expected_frames);
  const Published published = readPublished(out);
  ASSERT_EQ(published.labels.size(), expected_frames);
  ASSERT_EQ(published.tables.size(), expected_frames);
  // One objects_t per frame, after its tables_t, even when it holds no candidate.
  ASSERT_EQ(published.objects.size(), expected_frames);
  std::int64_t previous = -1;
  std::size_t labelled_pixels = 0;
  for (const auto& l : published.labels) {
    for (std::uint8_t y : l.image.labels) labelled_pixels += y != kVoidLabel;
  }
  // How much of the comparison is about real labels (a frame without a
  // ground plane is all void); visible in the test's XML output.
  ::testing::Test::RecordProperty("labelled_pixels", static_cast<int>(labelled_pixels));
  for (std::size_t i = 0; i < published.labels.size(); ++i) {
    const auto& got = published.labels[i];
    EXPECT_GT(got.seq, previous) << "label images out of frame order";
    previous = got.seq;
    ASSERT_TRUE(expected.count(got.seq)) << "unknown seq " << got.seq;
    const LabelledFrame& want = expected.at(got.seq);
    expectSameLabels(want.labels, got);
    EXPECT_EQ(got.utime, published.tables[i].utime);
    EXPECT_EQ(published.tables[i].seq, got.seq);
    EXPECT_EQ(published.tables[i].tables.size(), want.tables.size());
    const io::ObjectsMessage& objects = published.objects[i];
    EXPECT_EQ(objects.seq, got.seq);
    EXPECT_EQ(objects.utime, got.utime);
    EXPECT_EQ(objects.num_tables, static_cast<int>(want.tables.size()));
    EXPECT_EQ(objects.objects.size(), want.table_objects.objects.size());
    EXPECT_GT(got.latency_us, 0);
  }
  ASSERT_FALSE(published.statuses.empty());
  const findmug_lcm::status_t& last =
      published.statuses.back();  // the final status, after the drain
  EXPECT_EQ(last.frames_received, static_cast<std::int64_t>(expected_frames));
  EXPECT_EQ(last.frames_processed, static_cast<std::int64_t>(expected_frames));
  EXPECT_EQ(last.frames_dropped, 0);
  EXPECT_EQ(last.frames_rejected, 0);
  EXPECT_EQ(last.model_id, "tiny.fmf:" + sharedModel()->forest->id());
  EXPECT_EQ(last.source_state, findmug_lcm::status_t::SOURCE_END_OF_STREAM);
  EXPECT_EQ(last.num_queues, 3);
  const auto& names = last.stage_names;
  for (const char* stage :
       {"prepare", "segment", "publish", "oversegmentation", "forest", "tables", "objects",
        "total"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), stage), names.end()) << stage;
  }
  const auto total = std::find(names.begin(), names.end(), "total") - names.begin();
  EXPECT_GT(last.latency_p50_us[total], 0);
  EXPECT_GE(last.latency_max_us[total], last.latency_p95_us[total]);
  EXPECT_GE(last.latency_p95_us[total], last.latency_p50_us[total]);
}

// A sink that keeps what it was handed (the pipeline's extension point, used as a client would).
struct RecordingSink : ResultSink {
  std::string label;
  std::vector<std::string>* order;
  std::vector<std::int64_t> seqs, latencies_us;
  std::vector<bool> had_pose;
  RecordingSink(std::string n, std::vector<std::string>* o) : label(std::move(n)), order(o) {}
  std::string name() const override { return "RecordingSink " + label; }
  void consume(FrameResult& r) override {
    order->push_back(label);
    seqs.push_back(r.labelled.segmented.prepared.frame.seq);
    latencies_us.push_back(r.latency_us);
    had_pose.push_back(r.pose.has_value());
  }
};

// The three steps on their own, on real frames: prepare + segment give exactly
// Segmenter::process, and publish hands the result to every sink in order.
TEST(FrameSteps, PrepareSegmentPublishDoWhatSegmenterProcessDoesInOrder) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  const Segmenter segmenter(test::fastSegmenterConfig(), sharedModel()->forest);
  PrepareStep prepare(segmenter);
  std::vector<std::int64_t> held;
  const SegmentStep segment(segmenter, [&](const RgbdFrame& f) { held.push_back(f.seq); });
  PublishStep publish(/*pose_max_age_us=*/100000);
  std::vector<std::string> order;
  auto first = std::make_shared<RecordingSink>("first", &order);
  auto second = std::make_shared<RecordingSink>("second", &order);
  publish.addSink(first);
  publish.addSink(second);

  const std::vector<LabeledFrame> frames = test::framesWithGround(nyu.string(), 2);
  ASSERT_EQ(frames.size(), 2u);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    RgbdFrame frame = frames[i].frame;
    frame.seq = static_cast<std::int64_t>(10 + i);
    const LabelledFrame want = segmenter.process(frame);
    const auto arrival = StepClock::now();
    FrameJob job{frame, arrival, {}};
    PreparedJob prepared = prepare(job);
    EXPECT_TRUE(prepared.prepared.ground.has_value());
    ResultJob result = segment(prepared);
    EXPECT_EQ(result.labelled.labels.labels, want.labels.labels) << frames[i].name;
    EXPECT_EQ(result.labelled.tables.size(), want.tables.size()) << frames[i].name;
    EXPECT_EQ(publish(result, arrival + std::chrono::milliseconds(42)), 42000);
  }
  EXPECT_EQ(held, (std::vector<std::int64_t>{10, 11}));
  EXPECT_EQ(order, (std::vector<std::string>{"first", "second", "first", "second"}));
  EXPECT_EQ(second->seqs, (std::vector<std::int64_t>{10, 11}));
  EXPECT_EQ(second->latencies_us, (std::vector<std::int64_t>{42000, 42000}));
  EXPECT_EQ(second->had_pose, (std::vector<bool>{false, false}));  // no pose input
}

TEST(FrameSteps, ABrokenFrameIsRefusedByPrepareNamingIt) {
  const Segmenter segmenter(SegmenterConfig{}, nullptr);
  PrepareStep prepare(segmenter);
  RgbdFrame frame;
  frame.width = 640;
  frame.height = 480;
  frame.seq = 77;
  frame.depth_mm.assign(10, 1000);  // not 640 x 480 pixels
  FrameJob job{frame, StepClock::now(), {}};
  try {
    prepare(job);
    FAIL() << "a frame whose depth buffer does not match its size was prepared";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("seq 77"), std::string::npos) << e.what();
  }
}

TEST(DaemonPipeline, NyuFramesArePublishedEqualToTheLibraryOutput) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  ASSERT_TRUE(sharedModel());
  TempDir tmp;
  DatasetFolder all(nyu.string());
  // Four frames: the first (whatever the ground estimator makes of it: a
  // frame without ground must come out all void, like the library's), two
  // more, and the one with raw (holey) Kinect depth when present.
  std::vector<std::string> names = {all.names()[0], all.names()[2], all.names()[4]};
  names.push_back(std::find(all.names().begin(), all.names().end(), "0433") != all.names().end()
                      ? "0433"
                      : all.names()[8]);
  test::linkDatasetSubset(nyu, names, tmp.path() / "nyu");
  runAndCompare("dataset:" + (tmp.path() / "nyu").string(), 4);
}

TEST(DaemonPipeline, PclGrabberSequenceIsPublishedEqualToTheLibraryOutput) {
  FINDMUG_REQUIRE_DATA(pcd, "pcl_test_clouds/grabber_sequences/pcd");
  ASSERT_TRUE(sharedModel());
  // The camera looks steeply down at a desk from about 0.6 m and sees no floor:
  // let the ground estimator take the desk plane so that the frames get real
  // labels (the same setting goes to the library run).
  runAndCompare("pcd:" + pcd.string(), 3,
                {"ground.min_camera_height_m=0.3", "ground.max_tilt_deg=70"});
}

TEST(DaemonPipeline, SequentialModeRunsTheSamePipelineSynchronously) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  ASSERT_TRUE(sharedModel());
  TempDir tmp;
  test::TestConfig config = baseConfig("openni2", tmp.str("out.lcmlog"));
  const DaemonConfig dc = config.daemon;
  DatasetFolder ds(nyu.string());
  const Segmenter segmenter(config.segmenter, sharedModel()->forest);
  std::vector<LabelImage> expected;
  {
    Pipeline pipeline(config.segmenter, dc, sharedModel()->forest, "tiny",
                      ExecutionMode::Sequential);
    pipeline.start();
    for (std::size_t i : {3u, 4u}) {
      RgbdFrame frame = ds.load(i).frame;
      frame.seq = static_cast<std::int64_t>(i);
      expected.push_back(segmenter.process(frame).labels);
      const auto before = pipeline.counters().processed;
      ASSERT_TRUE(pipeline.submit(std::move(frame)));
      // Synchronous: published before submit returned.
      EXPECT_EQ(pipeline.counters().processed, before + 1);
      EXPECT_EQ(pipeline.counters().pending, 0u);
    }
    pipeline.stop(StopMode::Drain);
  }
  const Published published = readPublished(tmp.str("out.lcmlog"));
  ASSERT_EQ(published.labels.size(), 2u);
  EXPECT_EQ(published.labels[0].seq, 3);
  EXPECT_EQ(published.labels[1].seq, 4);
  expectSameLabels(expected[0], published.labels[0]);
  expectSameLabels(expected[1], published.labels[1]);
}

TEST(DaemonPipeline, HeldSegmentStageDropsTheOldestFramesAtTheDoorAndTheNewestWin) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  ASSERT_TRUE(sharedModel());
  TempDir tmp;
  test::TestConfig config = baseConfig("openni2", tmp.str("out.lcmlog"));
  config.set("daemon.workers", "1");
  config.set("daemon.queue_capacity", "2");
  const DaemonConfig dc = config.daemon;

  // The artificially slow stage: segmentation of the first frame is held
  // until every frame has been offered and the prepare stage has gone idle.
  std::mutex m;
  std::condition_variable cv;
  bool first_entered = false, release = false;
  PipelineHooks hooks;
  hooks.before_segment = [&](const RgbdFrame& frame) {
    if (frame.seq != 0) return;
    std::unique_lock lock(m);
    first_entered = true;
    cv.notify_all();
    cv.wait(lock, [&] { return release; });
  };
  DatasetFolder ds(nyu.string());
  const RgbdFrame frame = ds.load(6).frame;
  constexpr int kFrames = 10;
  Pipeline pipeline(config.segmenter, dc, sharedModel()->forest, "tiny", ExecutionMode::Threaded,
                    hooks);
  // Whatever happens below, the held worker is let go before the pipeline is destroyed
  // (its destructor joins the worker).
  struct Releaser {
    std::function<void()> release;
    ~Releaser() { release(); }
  } releaser{[&] {
    {
      std::lock_guard lock(m);
      release = true;
    }
    cv.notify_all();
  }};
  pipeline.start();
  auto submit = [&](int seq) {
    RgbdFrame f = frame;
    f.seq = seq;
    f.utime = 1000 + static_cast<std::uint64_t>(seq);
    ASSERT_TRUE(pipeline.submit(std::move(f)));
  };
  submit(0);
  {
    std::unique_lock lock(m);
    ASSERT_TRUE(cv.wait_for(lock, 120s, [&] { return first_entered; }));
  }
  // The worker is held: no frame can be taken now without dropping one, and a source loop
  // (waitForRoom) leaves it in the source once the place after the door is taken.
  for (int seq = 1; seq < kFrames; ++seq) submit(seq);
  // Wait (deadline only guards a hang) until one prepared frame holds the segment queue's
  // one place: the prepare stage then waits at the door, where newer frames push out older
  // ones, and the source loop would wait too.
  auto segment_depth = [&] {
    const findmug_lcm::status_t s = makeStatus(pipeline);
    for (int i = 0; i < s.num_queues; ++i) {
      if (s.queue_names[i] == "segment") {
        EXPECT_EQ(s.queue_capacities[i], 1);
        return s.queue_depths[i];
      }
    }
    return -1;
  };
  const auto deadline = std::chrono::steady_clock::now() + 120s;
  while (segment_depth() != 1 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_EQ(segment_depth(), 1);
  std::this_thread::sleep_for(200ms);  // let the prepare stage settle at the gate
  EXPECT_FALSE(pipeline.waitForRoom(50ms)) << "a source loop would take a frame that must wait";
  // Held + the segment queue's place + at the door the newest frames that came after the
  // prepare stage took its one: one or two (the door holds two), by timing.
  const std::uint64_t pending = pipeline.counters().pending;
  ASSERT_GE(pending, 3u);
  ASSERT_LE(pending, 4u);
  const auto kept = static_cast<std::int64_t>(pending);
  const findmug_lcm::status_t held = makeStatus(pipeline);
  EXPECT_EQ(held.frames_dropped, kFrames - kept);
  // Every drop happened at the door, before any work was spent on the frame.
  EXPECT_EQ(held.frames_dropped_at_door, kFrames - kept);
  EXPECT_EQ(held.frames_dropped_in_pipeline, 0);
  EXPECT_EQ(held.frames_dropped_at_shutdown, 0);
  releaser.release();
  pipeline.stop(StopMode::Drain);

  // Released: every frame kept is published, in frame order, the newest last.
  const std::int64_t published_count = kept;
  const PipelineCounters c = pipeline.counters();
  EXPECT_EQ(c.received, static_cast<std::uint64_t>(kFrames));
  EXPECT_EQ(c.processed, static_cast<std::uint64_t>(published_count));
  EXPECT_EQ(c.dropped, static_cast<std::uint64_t>(kFrames - published_count));
  EXPECT_EQ(c.dropped_at_door, static_cast<std::uint64_t>(kFrames - published_count));
  EXPECT_EQ(c.rejected, 0u);
  const Published published = readPublished(tmp.str("out.lcmlog"));
  std::vector<std::int64_t> seqs;
  for (const auto& l : published.labels) seqs.push_back(l.seq);
  ASSERT_EQ(static_cast<std::int64_t>(seqs.size()), published_count);
  EXPECT_EQ(seqs.front(), 0);
  EXPECT_TRUE(std::is_sorted(seqs.begin(), seqs.end()));
  EXPECT_EQ(seqs.back(), kFrames - 1);  // the newest frame wins
  ASSERT_FALSE(published.statuses.empty());
  EXPECT_EQ(published.statuses.back().frames_dropped, kFrames - published_count);
  EXPECT_EQ(published.statuses.back().frames_dropped_at_door, kFrames - published_count);
  EXPECT_EQ(published.statuses.back().frames_processed, published_count);
}

// A sink that blocks until released (a slow disk, a stuck client) holds the publish thread
// only: the segmentation workers go on with every frame, and the publish queue drops its
// oldest results (counted "in the pipeline") instead of making them wait.
TEST(DaemonPipeline, ASlowSinkNeverStallsTheSegmentWorkers) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  ASSERT_TRUE(sharedModel());
  TempDir tmp;
  test::TestConfig config = baseConfig("openni2", tmp.str("out.lcmlog"));
  config.set("daemon.workers", "1");
  config.set("daemon.queue_capacity", "2");

  struct HeldSink : ResultSink {
    std::mutex m;
    std::condition_variable cv;
    bool entered = false, release = false;
    std::vector<std::int64_t> seqs;
    std::string name() const override { return "HeldSink"; }
    void consume(FrameResult& r) override {
      std::unique_lock lock(m);
      seqs.push_back(r.labelled.segmented.prepared.frame.seq);
      entered = true;
      cv.notify_all();
      cv.wait(lock, [&] { return release; });
    }
  };
  auto sink = std::make_shared<HeldSink>();
  std::mutex segmented_mutex;
  std::condition_variable segmented_cv;
  int segmenting = 0;  // frames a worker has started on
  PipelineHooks hooks;
  hooks.before_segment = [&](const RgbdFrame&) {
    std::lock_guard lock(segmented_mutex);
    ++segmenting;
    segmented_cv.notify_all();
  };
  DatasetFolder ds(nyu.string());
  const RgbdFrame frame = ds.load(6).frame;
  constexpr int kFrames = 8;
  Pipeline pipeline(config.segmenter, config.daemon, sharedModel()->forest, "tiny",
                    ExecutionMode::Threaded, hooks);
  pipeline.addSink(sink);
  // Whatever happens below, the sink lets go before the pipeline is destroyed (its
  // destructor drains the publish stage).
  struct Releaser {
    HeldSink& sink;
    ~Releaser() {
      {
        std::lock_guard lock(sink.m);
        sink.release = true;
      }
      sink.cv.notify_all();
    }
  } releaser{*sink};
  pipeline.start();
  for (int seq = 0; seq < kFrames; ++seq) {
    RgbdFrame f = frame;
    f.seq = seq;
    f.utime = 1000 + static_cast<std::uint64_t>(seq);
    ASSERT_TRUE(pipeline.submit(std::move(f)));
    // One frame at a time, each once the previous is in a worker: nothing waits at the door.
    std::unique_lock lock(segmented_mutex);
    ASSERT_TRUE(segmented_cv.wait_for(lock, 120s, [&] { return segmenting == seq + 1; }))
        << "frame " << seq << " never reached a segmentation worker: the worker is stalled";
  }
  {
    std::unique_lock lock(sink->m);
    ASSERT_TRUE(sink->cv.wait_for(lock, 120s, [&] { return sink->entered; }));
  }
  // Frame 0 is in the held sink, the last three results wait in the publish queue (its
  // capacity: daemon.queue_capacity + one per worker); the others were segmented and then
  // dropped at publish. (With a publish queue that made the workers wait, the worker would
  // stop at frame 4 and the loop above would time out.)
  const std::uint64_t expected_drops = kFrames - 1 - 3;
  const auto deadline = std::chrono::steady_clock::now() + 120s;
  while (pipeline.counters().dropped_in_pipeline < expected_drops &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(10ms);
  }
  const PipelineCounters during = pipeline.counters();
  EXPECT_EQ(during.dropped_in_pipeline, expected_drops);
  EXPECT_EQ(during.dropped_at_door, 0u);
  EXPECT_EQ(makeStatus(pipeline).frames_dropped_in_pipeline,
            static_cast<std::int64_t>(expected_drops));
  {
    std::lock_guard lock(sink->m);
    sink->release = true;
  }
  sink->cv.notify_all();
  pipeline.stop(StopMode::Drain);
  const PipelineCounters c = pipeline.counters();
  EXPECT_EQ(c.processed, 4u);
  EXPECT_EQ(c.dropped, expected_drops);
  EXPECT_EQ(sink->seqs, (std::vector<std::int64_t>{0, kFrames - 3, kFrames - 2, kFrames - 1}));
}

// The sinks' order is declared, not implied: a sink that reads a slot of the frame result
// (here the map's ids, which TableMapSink adds) cannot be added before the sink that writes
// it, and a sink that fills a slot it did not declare fails the frame.
TEST(FrameSteps, SinksThatBreakTheDeclaredSlotOrderAreRefused) {
  struct Reader : ResultSink {
    std::string name() const override { return "Reader"; }
    SinkSlots slots() const override { return {0, kMapInfo}; }
    void consume(FrameResult&) override {}
  };
  struct Writer : ResultSink {
    std::string name() const override { return "Writer"; }
    SinkSlots slots() const override { return {kMapInfo, 0}; }
    void consume(FrameResult&) override {}
  };
  struct Sneaky : ResultSink {
    std::string name() const override { return "Sneaky"; }
    void consume(FrameResult& r) override { r.published_labels = LabelImage{}; }
  };
  {
    PublishStep publish(0);
    publish.addSink(std::make_shared<Reader>());
    try {
      publish.addSink(std::make_shared<Writer>());
      FAIL() << "a writer after its reader was accepted";
    } catch (const std::logic_error& e) {
      EXPECT_NE(std::string(e.what()).find("Writer writes map_info, which Reader"),
                std::string::npos)
          << e.what();
    }
  }
  {
    PublishStep publish(0);
    publish.addSink(std::make_shared<Writer>());
    publish.addSink(std::make_shared<Reader>());  // the declared order
    EXPECT_THROW(publish.addSink(std::make_shared<Writer>()), std::logic_error);  // two writers
  }
  {
    // The daemon's own sinks, in the daemon's order, are accepted; the publisher before the
    // table map is not.
    auto bus = std::make_shared<io::MemoryBus>();
    auto table_map = std::make_shared<TableMapSink>(TableMapConfig{}, TableConfig{}, true,
                                                    [](const std::string&) {});
    auto publisher = std::make_shared<LcmPublisherSink>(
        bus, LcmPublisherSink::Channels{"L", "T", "O", "M", "S"}, false, true);
    PublishStep right(0);
    EXPECT_NO_THROW(right.addSink(table_map));
    EXPECT_NO_THROW(right.addSink(publisher));
    PublishStep wrong(0);
    wrong.addSink(publisher);
    EXPECT_THROW(wrong.addSink(table_map), std::logic_error);
  }
  {
    PublishStep publish(0);
    publish.addSink(std::make_shared<Sneaky>());
    LabelledFrame labelled;
    ResultJob job{std::move(labelled), StepClock::now(), {}};
    try {
      publish(job, StepClock::now());
      FAIL() << "an undeclared slot write went through";
    } catch (const std::logic_error& e) {
      EXPECT_NE(std::string(e.what()).find("Sneaky filled published_labels"), std::string::npos)
          << e.what();
    }
  }
}

// The object work (matching, object map) runs on its own worker: while it is held, the
// publish thread goes on publishing every frame's labels, the object queue keeps the
// newest frames and status_t counts what it dropped; released, it catches up.
TEST(DaemonPipeline, HeldObjectWorkerNeverHoldsTheLabelsAndItsDropsAreCounted) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  ASSERT_TRUE(sharedModel());
  TempDir tmp;
  std::filesystem::create_directories(tmp.path() / "objects");
  test::TestConfig config = baseConfig("openni2", tmp.str("out.lcmlog"));
  config.set("daemon.objects_dir", tmp.str("objects"));
  config.set("daemon.objects_queue", "2");
  config.set("daemon.queue_capacity", "16");
  const DaemonConfig dc = config.daemon;
  std::mutex m;
  std::condition_variable cv;
  bool held = false, release = false;
  PipelineHooks hooks;
  hooks.before_object_job = [&] {
    std::unique_lock lock(m);
    held = true;
    cv.notify_all();
    cv.wait(lock, [&] { return release; });
  };
  DatasetFolder ds(nyu.string());
  const RgbdFrame frame = ds.load(6).frame;
  constexpr int kFrames = 6;
  Pipeline pipeline(config.segmenter, dc, sharedModel()->forest, "tiny", ExecutionMode::Threaded,
                    hooks);
  pipeline.start();
  for (int seq = 0; seq < kFrames; ++seq) {
    RgbdFrame f = frame;
    f.seq = seq;
    f.utime = 1000 + static_cast<std::uint64_t>(seq);
    ASSERT_TRUE(pipeline.waitForRoom(120s));
    ASSERT_TRUE(pipeline.submit(std::move(f)));
  }
  // Every label image goes out while the object worker still holds the first frame.
  const auto deadline = std::chrono::steady_clock::now() + 300s;
  while (pipeline.counters().processed < static_cast<std::uint64_t>(kFrames) &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(10ms);
  }
  const findmug_lcm::status_t during = makeStatus(pipeline);
  bool was_held = false;
  {
    std::lock_guard lock(m);
    was_held = held;
    release = true;
  }
  cv.notify_all();
  EXPECT_TRUE(was_held);
  EXPECT_EQ(during.frames_processed, kFrames) << "the labels waited for the object work";
  EXPECT_EQ(during.object_frames, kFrames);
  // The held frame, two waiting: the other three were dropped from the object queue.
  EXPECT_EQ(during.object_frames_skipped, kFrames - 3);
  EXPECT_EQ(during.frames_dropped, 0) << "an object drop is no frame drop";
  int object_queue = -1;
  for (int i = 0; i < during.num_queues; ++i) {
    if (during.queue_names[i] == "object_search") object_queue = i;
  }
  ASSERT_GE(object_queue, 0) << "the object queue is in status";
  EXPECT_EQ(during.queue_depths[object_queue], 2);
  EXPECT_EQ(during.queue_capacities[object_queue], 2);
  pipeline.stop(StopMode::Drain);
  const Published published = readPublished(tmp.str("out.lcmlog"));
  EXPECT_EQ(published.labels.size(), static_cast<std::size_t>(kFrames));
  ASSERT_FALSE(published.statuses.empty());
  const findmug_lcm::status_t& last = published.statuses.back();
  EXPECT_EQ(last.object_frames_skipped, kFrames - 3);
  bool timed = false;
  for (int i = 0; i < last.num_stages; ++i) {
    if (last.stage_names[i] == "object_search") timed = last.latency_max_us[i] > 0;
  }
  EXPECT_TRUE(timed) << "the object work's time per frame is in status";
}

// Counts the threads of this process (/proc/self/task).
int threadCount() {
  int n = 0;
  for ([[maybe_unused]] const auto& entry :
       std::filesystem::directory_iterator("/proc/self/task")) {
    ++n;
  }
  return n;
}

// daemon.max_cpu_cores decides how many threads process frames: below 2
// every stage runs on the source thread, from 2 the threaded pipeline with
// floor(budget) - 1 segmentation workers. Status reports the budget, the
// thread count and the CPU used.
TEST(DaemonPipeline, CpuBudgetSetsTheProcessingThreadsAndStatusReportsIt) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  ASSERT_TRUE(sharedModel());
  struct Run {
    int extra_threads = -1;  // threads alive while a frame is segmented, minus before start
    Published published;
  };
  auto run_with = [&](const std::string& budget, const std::string& workers) {
    TempDir tmp;
    test::TestConfig config = baseConfig("dataset:" + nyu.string() + "?loop=0", tmp.str("out.lcmlog"));
    config.set("daemon.max_cpu_cores", budget);
    config.set("daemon.workers", workers);
    config.set("daemon.pose_input", "false");
    const DaemonConfig dc = config.daemon;
    Run run;
    std::atomic<int> seen{-1};
    PipelineHooks hooks;
    hooks.before_segment = [&](const RgbdFrame&) {
      if (seen.load() < 0) seen.store(threadCount());
    };
    const int before = threadCount();
    {
      Daemon daemon(config, dc, hooks);
      EXPECT_EQ(daemon.run(), 0);
    }
    run.extra_threads = seen.load() - before;
    run.published = readPublished(tmp.str("out.lcmlog"));
    return run;
  };
  const Run one = run_with("1", "4");
  const Run three = run_with("3", "4");
  const Run none = run_with("0", "3");
  // One core: the source thread does everything (no pipeline thread).
  // Three cores: prepare + 2 segmentation workers + publish besides it.
  // No budget: prepare + 3 workers + publish.
  EXPECT_EQ(three.extra_threads - one.extra_threads, 4);
  EXPECT_EQ(none.extra_threads - one.extra_threads, 5);
  for (const Run* r : {&one, &three, &none}) {
    ASSERT_FALSE(r->published.statuses.empty());
    EXPECT_EQ(r->published.labels.size(), 31u);  // a finite source: every frame, no drop
  }
  EXPECT_EQ(one.published.statuses.back().processing_threads, 1);
  EXPECT_FLOAT_EQ(one.published.statuses.back().cpu_budget_cores, 1.0f);
  EXPECT_EQ(three.published.statuses.back().processing_threads, 4);
  EXPECT_FLOAT_EQ(three.published.statuses.back().cpu_budget_cores, 3.0f);
  EXPECT_EQ(none.published.statuses.back().processing_threads, 5);
  EXPECT_FLOAT_EQ(none.published.statuses.back().cpu_budget_cores, 0.0f);
  // Frames were segmented: the process used CPU, and the status says so.
  float most = 0;
  for (const auto& st : one.published.statuses) most = std::max(most, st.cpu_used_cores);
  EXPECT_GT(most, 0.05f);
}

TEST(DaemonPipeline, CorruptLcmMessagesAreCountedAndSkipped) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  ASSERT_TRUE(sharedModel());
  TempDir tmp;
  DatasetFolder ds(nyu.string());
  RgbdFrame good = ds.load(7).frame;
  good.seq = 10;
  const findmug_lcm::rgbd_frame_t good_msg = io::encodeRgbdFrame(good);
  const std::vector<std::uint8_t> good_bytes = io::encodeMessage(good_msg);

  std::vector<test::LogMessage> in;
  const std::string ch(io::kRgbdChannel);
  in.push_back({ch, good_bytes});
  // Truncated in the middle of the depth payload.
  in.push_back({ch, std::vector<std::uint8_t>(good_bytes.begin(),
                                              good_bytes.begin() + good_bytes.size() / 2)});
  // Garbage (wrong type hash).
  in.push_back({ch, std::vector<std::uint8_t>(4096, 0xA5)});
  // Absurd dimensions.
  findmug_lcm::rgbd_frame_t huge = good_msg;
  huge.width = 100000;
  huge.height = 100000;
  in.push_back({ch, io::encodeMessage(huge)});
  // Size field consistent with the array but not with width x height.
  findmug_lcm::rgbd_frame_t short_depth = good_msg;
  short_depth.depth_compression = findmug_lcm::rgbd_frame_t::DEPTH_NONE;
  short_depth.depth_size = 100;
  short_depth.depth_data.assign(100, 0);
  in.push_back({ch, io::encodeMessage(short_depth)});
  // Empty message.
  in.push_back({ch, {}});
  findmug_lcm::rgbd_frame_t second = good_msg;
  second.seq = 11;
  in.push_back({ch, io::encodeMessage(second)});
  const std::string in_log = tmp.str("in.lcmlog");
  test::writeLcmLog(in_log, in);

  const std::string out = tmp.str("out.lcmlog");
  test::TestConfig config = baseConfig("lcm:" + ch + "?url=file://" + in_log + "?speed=0", out);
  config.set("daemon.queue_capacity", "8");
  const DaemonConfig dc = config.daemon;
  {
    Daemon daemon(config, dc);
    EXPECT_EQ(daemon.run(), 0);  // the log's end is the stream's end
  }
  const Published published = readPublished(out);
  ASSERT_EQ(published.labels.size(), 2u);
  EXPECT_EQ(published.labels[0].seq, 10);
  EXPECT_EQ(published.labels[1].seq, 11);
  const Segmenter segmenter(test::fastSegmenterConfig(), sharedModel()->forest);
  const LabelledFrame expected = segmenter.process(io::decodeRgbdFrame(good_msg, ch));
  expectSameLabels(expected.labels, published.labels[0]);
  ASSERT_FALSE(published.statuses.empty());
  const findmug_lcm::status_t& last = published.statuses.back();
  EXPECT_EQ(last.frames_received, 2);
  EXPECT_EQ(last.frames_processed, 2);
  EXPECT_EQ(last.frames_rejected, 5);
  EXPECT_FALSE(last.last_error.empty());
  EXPECT_GT(last.last_error_utime, 0);
}

// daemon.frame_trace_file: one row per published frame, in frame order, whose intervals add
// up to no more than the frame's total; a file that cannot be written is refused naming the key.
TEST(DaemonPipeline, FrameTraceHasOneRowPerPublishedFrame) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  ASSERT_TRUE(sharedModel());
  TempDir tmp;
  test::TestConfig config = baseConfig("openni2", tmp.str("out.lcmlog"));
  config.set("daemon.frame_trace_file", tmp.str("trace.csv"));
  DatasetFolder ds(nyu.string());
  const RgbdFrame frame = ds.load(6).frame;
  constexpr int kFrames = 4;
  {
    Pipeline pipeline(config.segmenter, config.daemon, sharedModel()->forest, "tiny",
                      ExecutionMode::Threaded);
    pipeline.start();
    for (int seq = 0; seq < kFrames; ++seq) {
      RgbdFrame f = frame;
      f.seq = seq;
      f.utime = 1000 + static_cast<std::uint64_t>(seq);
      ASSERT_TRUE(pipeline.waitForRoom(120s));
      ASSERT_TRUE(pipeline.submit(std::move(f)));
    }
    pipeline.stop(StopMode::Drain);
    ASSERT_EQ(pipeline.counters().processed, static_cast<std::uint64_t>(kFrames));
  }
  std::ifstream in(tmp.str("trace.csv"));
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  EXPECT_EQ(line,
            "seq,frame_utime,source_us,door_us,prepare_us,segment_wait_us,segment_us,reorder_us,"
            "publish_wait_us,publish_us,total_us");
  std::vector<std::int64_t> seqs;
  while (std::getline(in, line)) {
    std::vector<std::int64_t> v;
    std::stringstream row(line);
    for (std::string cell; std::getline(row, cell, ',');) v.push_back(std::stoll(cell));
    ASSERT_EQ(v.size(), 11u) << line;
    seqs.push_back(v[0]);
    std::int64_t parts = 0;
    for (std::size_t i = 3; i < 10; ++i) {
      EXPECT_GE(v[i], 0) << "interval " << i << " of " << line;
      parts += v[i];
    }
    EXPECT_GT(v[6], 0) << "no segmentation time: " << line;
    EXPECT_LE(parts, v[10]) << line;
    EXPECT_GE(parts, v[10] - 1000) << "time unaccounted for: " << line;
  }
  EXPECT_EQ(seqs, (std::vector<std::int64_t>{0, 1, 2, 3}));

  config.set("daemon.frame_trace_file", tmp.str("no-such-dir/trace.csv"));
  try {
    Pipeline pipeline(config.segmenter, config.daemon, sharedModel()->forest, "tiny",
                      ExecutionMode::Threaded);
    FAIL() << "an unwritable trace file was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("daemon.frame_trace_file"), std::string::npos)
        << e.what();
  }
}

TEST(DaemonPipeline, StartupErrorsNameTheKey) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  ASSERT_TRUE(sharedModel());
  TempDir tmp;
  auto error_of = [&](test::TestConfig config) -> std::string {
    try {
      const DaemonConfig dc = config.daemon;
      Daemon daemon(config, dc);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  };
  test::TestConfig missing_model = baseConfig("dataset:" + nyu.string(), tmp.str("o.lcmlog"));
  missing_model.set("daemon.model_path", tmp.str("nope.fmf"));
  EXPECT_NE(error_of(missing_model).find("daemon.model_path"), std::string::npos);

  test::TestConfig corrupt_model = baseConfig("dataset:" + nyu.string(), tmp.str("o.lcmlog"));
  {
    std::ofstream f(tmp.str("bad.fmf"), std::ios::binary);
    f << "not a model";
  }
  corrupt_model.set("daemon.model_path", tmp.str("bad.fmf"));
  EXPECT_NE(error_of(corrupt_model).find("daemon.model_path"), std::string::npos);

  test::TestConfig bad_source = baseConfig("dataset:" + tmp.str("no-such-dir"), tmp.str("o.lcmlog"));
  EXPECT_NE(error_of(bad_source).find("daemon.source"), std::string::npos);

  test::TestConfig bad_url = baseConfig("dataset:" + nyu.string(), tmp.str("o.lcmlog"));
  bad_url.set("daemon.lcm_url", "bogus://x");
  EXPECT_NE(error_of(bad_url).find("daemon.lcm_url"), std::string::npos);
}

}  // namespace
}  // namespace findmug::daemon

namespace findmug::daemon {
namespace {

// The watchdog is fed while frames progress, withheld while the bottleneck
// is stuck with frames waiting, and fed again once it recovers. The notify
// socket belongs to the test (NOTIFY_SOCKET / WATCHDOG_USEC as systemd sets them).
TEST(DaemonPipeline, WatchdogIsWithheldWhileTheSegmentStageIsStuck) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  ASSERT_TRUE(sharedModel());
  TempDir tmp;
  test::NotifySocket notify(tmp.str("notify.sock"));
  setenv("NOTIFY_SOCKET", notify.path().c_str(), 1);
  // WatchdogSec 3 s: stall limit 1.5 s (longer than any frame takes here), a ping every second.
  setenv("WATCHDOG_USEC", "3000000", 1);
  test::TestConfig config = baseConfig("dataset:" + nyu.string() + "?loop=1&rate_hz=20", tmp.str("o.lcmlog"));
  config.set("daemon.workers", "1");
  const DaemonConfig dc = config.daemon;

  std::mutex m;
  std::condition_variable cv;
  bool stuck = false, release = false;
  PipelineHooks hooks;
  hooks.before_segment = [&](const RgbdFrame& frame) {
    if (frame.seq < 3) return;  // not == 3: under load frame 3 itself may be dropped
    std::unique_lock lock(m);
    stuck = true;
    cv.notify_all();
    cv.wait(lock, [&] { return release; });
  };
  // sd_notify reads NOTIFY_SOCKET at each call: keep it set while the daemon runs.
  auto daemon = std::make_unique<Daemon>(config, dc, hooks);
  int code = -1;
  std::thread runner([&] { code = daemon->run(); });
  auto count_pings = [&](std::chrono::milliseconds window) {
    int pings = 0;
    const auto end = std::chrono::steady_clock::now() + window;
    while (std::chrono::steady_clock::now() < end) {
      if (auto msg = notify.receive(20ms); msg && msg->find("WATCHDOG=1") != std::string::npos) {
        ++pings;
      }
    }
    return pings;
  };
  {
    std::unique_lock lock(m);
    ASSERT_TRUE(cv.wait_for(lock, 120s, [&] { return stuck; }));
  }
  // Frames keep arriving (and being dropped) but none completes: after the
  // stall limit the pings must stop. The limit counts from the last frame
  // completed, and frames already past the segment stage may still complete
  // after it got stuck (under TSan on a slow host a frame takes up to 1.7 s):
  // drain until a spell longer than the ping period passes without a ping,
  // which must come within 30 s.
  const auto drain_deadline = std::chrono::steady_clock::now() + 30s;
  bool pings_stopped = false;
  while (!pings_stopped && std::chrono::steady_clock::now() < drain_deadline) {
    pings_stopped = count_pings(1500ms) == 0;
  }
  const int pings_while_stuck = count_pings(2000ms);
  {
    std::lock_guard lock(m);
    release = true;
  }
  cv.notify_all();
  const int pings_after_recovery = count_pings(5000ms);
  const PipelineCounters c = daemon->pipeline().counters();
  daemon->requestStop();
  runner.join();
  unsetenv("NOTIFY_SOCKET");
  unsetenv("WATCHDOG_USEC");
  EXPECT_EQ(code, 0);
  EXPECT_TRUE(pings_stopped) << "the watchdog was still fed 30 s after the segment stage got stuck";
  EXPECT_EQ(pings_while_stuck, 0);
  EXPECT_GT(pings_after_recovery, 0)
      << c.received << " received, " << c.processed << " processed, " << c.pending << " pending";
}

// Fault injection (issue 11): the frame stream repeats seq/utime, reorders,
// jumps back an hour (a log replay restarted) and carries a corrupt message
// after every third frame. Every good frame must come out, in input order,
// with its own seq and utime; every corrupt one is counted as rejected.
TEST(DaemonFaults, StreamThatRepeatsReordersJumpsBackAndHasACorruptFrameEveryThird) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  ASSERT_TRUE(sharedModel());
  TempDir tmp;
  DatasetFolder ds(nyu.string());
  const findmug_lcm::rgbd_frame_t base = io::encodeRgbdFrame(ds.load(3).frame);
  const std::int64_t u0 = 1'700'000'000'000'000;
  const std::vector<std::pair<std::int64_t, std::int64_t>> seq_utime = {
      {0, u0},
      {1, u0 + 33'000},
      {2, u0 + 66'000},
      {3, u0 + 99'000},
      {3, u0 + 99'000},  // repeated
      {2, u0 + 66'000},  // reordered: older than the last
      {0, u0 - 3'600'000'000},
      {1, u0 - 3'600'000'000 + 33'000},  // replay restarted
      {7, u0 + 500'000}};                // jumps ahead again
  std::vector<test::LogMessage> in;
  const std::string ch(io::kRgbdChannel);
  int corrupt = 0;
  for (std::size_t i = 0; i < seq_utime.size(); ++i) {
    findmug_lcm::rgbd_frame_t m = base;
    m.seq = seq_utime[i].first;
    m.utime = seq_utime[i].second;
    const auto bytes = io::encodeMessage(m);
    in.push_back({ch, bytes});
    if (i % 3 == 2) {  // a corrupt frame every third: cut inside the colour payload
      in.push_back({ch, std::vector<std::uint8_t>(bytes.begin(), bytes.end() - 7)});
      ++corrupt;
    }
  }
  const std::string in_log = tmp.str("in.lcmlog");
  test::writeLcmLog(in_log, in);
  const std::string out = tmp.str("out.lcmlog");
  test::TestConfig config = baseConfig("lcm:" + ch + "?url=file://" + in_log + "?speed=0", out);
  config.set("daemon.queue_capacity", "16");
  const DaemonConfig dc = config.daemon;
  {
    Daemon daemon(config, dc);
    EXPECT_EQ(daemon.run(), 0);
  }
  const Published published = readPublished(out);
  ASSERT_EQ(published.labels.size(), seq_utime.size());
  for (std::size_t i = 0; i < seq_utime.size(); ++i) {
    EXPECT_EQ(published.labels[i].seq, seq_utime[i].first) << i;
    EXPECT_EQ(static_cast<std::int64_t>(published.labels[i].utime), seq_utime[i].second) << i;
  }
  ASSERT_FALSE(published.statuses.empty());
  const findmug_lcm::status_t& last = published.statuses.back();
  EXPECT_EQ(last.frames_received, static_cast<std::int64_t>(seq_utime.size()));
  EXPECT_EQ(last.frames_processed, static_cast<std::int64_t>(seq_utime.size()));
  EXPECT_EQ(last.frames_dropped, 0);
  EXPECT_EQ(last.frames_rejected, corrupt);
}

// A source that hangs on command: it delivers copies of one frame at 20 fps,
// and while hang(true) it blocks inside next() still reporting Running — a
// camera driver call that never returns — until hang(false) or stop().
class CommandedSource : public io::FrameSourceBase {
 public:
  explicit CommandedSource(RgbdFrame frame) : frame_(std::move(frame)) {
    setState(io::SourceState::Running);
  }
  std::optional<RgbdFrame> next() override {
    {
      std::unique_lock lock(m_);
      cv_.wait(lock, [&] { return stopped_ || !hang_; });
      if (stopped_) return std::nullopt;
    }
    if (!pace(20.0)) return std::nullopt;
    RgbdFrame f = frame_;
    f.seq = seq_++;
    f.utime = io::hostUtimeNow();
    recordDelivered();
    return f;
  }
  void hang(bool on) {
    std::lock_guard lock(m_);
    hang_ = on;
    cv_.notify_all();
  }
  std::string describe() const override { return "commanded test source"; }

 protected:
  void onStop() override {
    std::lock_guard lock(m_);
    stopped_ = true;
    cv_.notify_all();
  }

 private:
  RgbdFrame frame_;
  std::int64_t seq_ = 0;
  std::mutex m_;
  std::condition_variable cv_;
  bool hang_ = false, stopped_ = false;
};

// Fault injection (issue 11): every blocking read has a timeout. A source
// that hangs in next() while "running" is detected after daemon.source_timeout_s,
// reported (log, systemd STATUS=), and the watchdog is no longer fed, so
// systemd restarts the service; when frames return the pings resume.
TEST(DaemonFaults, HungSourceIsReportedAndStarvesTheWatchdog) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  ASSERT_TRUE(sharedModel());
  TempDir tmp;
  test::NotifySocket notify(tmp.str("notify.sock"));
  setenv("NOTIFY_SOCKET", notify.path().c_str(), 1);
  // WatchdogSec 3 s: stall limit 1.5 s, a ping every second while healthy.
  setenv("WATCHDOG_USEC", "3000000", 1);
  test::TestConfig config = baseConfig("lcm:unused", tmp.str("o.lcmlog"));
  config.set("daemon.source_timeout_s", "1");
  const DaemonConfig dc = config.daemon;
  DatasetFolder ds(nyu.string());
  auto owned = std::make_unique<CommandedSource>(ds.load(3).frame);
  CommandedSource* source = owned.get();
  auto daemon = std::make_unique<Daemon>(config, dc, std::move(owned));
  int code = -1;
  std::thread runner([&] { code = daemon->run(); });
  std::vector<std::string> other;
  auto count_pings = [&](std::chrono::milliseconds window) {
    int pings = 0;
    const auto end = std::chrono::steady_clock::now() + window;
    while (std::chrono::steady_clock::now() < end) {
      if (auto msg = notify.receive(20ms)) {
        if (msg->find("WATCHDOG=1") != std::string::npos) {
          ++pings;
        } else {
          other.push_back(*msg);
        }
      }
    }
    return pings;
  };
  const int pings_running = count_pings(4000ms);
  source->hang(true);
  count_pings(3000ms);  // timeout (1 s) + stall limit (1.5 s) + what was already sent
  const int pings_while_hung = count_pings(3000ms);
  source->hang(false);
  const int pings_after = count_pings(5000ms);
  const auto delivered = source->stats().frames_delivered;
  daemon->requestStop();
  runner.join();
  unsetenv("NOTIFY_SOCKET");
  unsetenv("WATCHDOG_USEC");
  EXPECT_EQ(code, 0);
  EXPECT_GT(pings_running, 0);
  EXPECT_EQ(pings_while_hung, 0);
  EXPECT_GT(pings_after, 0) << delivered << " frames delivered";
  bool reported = false;
  for (const auto& m : other) reported |= m.find("STATUS=source hung") != std::string::npos;
  EXPECT_TRUE(reported) << "no STATUS=source hung among " << other.size() << " messages";
}

}  // namespace
}  // namespace findmug::daemon
