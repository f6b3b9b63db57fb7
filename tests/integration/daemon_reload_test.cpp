// Model reload in findmugd (model_reload.hpp, command_input.hpp): a model
// swapped in while frames flow at 30 fps (in-process pipeline on in-memory
// buses: frames submitted at 30 fps, the reload asked for by a command_t on
// FINDMUG_COMMAND) drops no frame, classifies every frame wholly with one
// model, the old one until the swap and the new one after, and status names
// the new model; a model trained with other feature settings runs with them
// (they are the defaults of the keys it records) unless the config gives one of
// them another value: then it is refused naming the setting, as a corrupt file is;
// hostile commands are refused and counted, and frames keep flowing with the old
// model; and SIGHUP makes the
// findmugd process reload (what systemd's ExecReload sends).
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <thread>
#include <utility>
#include <vector>

#include "daemon_test_config.hpp"
#include "daemon_test_support.hpp"
#include "findmug/daemon/pipeline.hpp"
#include "findmug/common/error.hpp"
#include "findmug/io/bus.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "test_data.hpp"

extern char** environ;

namespace findmug::daemon {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
using findmug::test::TempDir;

// Frames at half size (320x240 from NYU's 640x480): cheap enough for a loaded
// 2-core machine to keep up with 30 fps.
constexpr int kStep = 2;

LabeledFrame halfSize(const LabeledFrame& in) { return test::subsampled(in, kStep); }
SegmenterConfig reloadConfig() { return test::fastSegmenterConfig(kStep); }

// A tiny model trained with `config` on `frames`, recording `config`'s
// feature-extraction settings as findmug-train does.
std::shared_ptr<const RandomForest> trainRecorded(const SegmenterConfig& config,
                                                  const std::vector<LabeledFrame>& frames,
                                                  const std::string& path) {
  test::trainTinyModel(config, frames, path);
  RandomForest forest = RandomForest::load(path);
  forest.setExtractionSettings(extractionSettings(config));
  forest.save(path);
  return std::make_shared<const RandomForest>(RandomForest::load(path));
}

// Replaces `path` by `from` in one rename, as an installer must.
void installAtomically(const std::string& from, const std::string& path) {
  std::filesystem::copy_file(from, path + ".new", std::filesystem::copy_options::overwrite_existing);
  std::filesystem::rename(path + ".new", path);
}

struct Models {
  TempDir dir;
  std::vector<LabeledFrame> frames;  // quartered, each with a ground plane at full size
  std::string a, b, mismatched;      // model files
  std::shared_ptr<const RandomForest> forest_a, forest_b, forest_mismatched;
};

const Models* models() {
  static Models* m = []() -> Models* {
    const auto nyu = findmug::test::dataPath("nyuv2_labeled");
    if (nyu.empty()) return nullptr;
    auto* out = new Models;
    for (const LabeledFrame& f : test::framesWithGround(nyu.string(), 6)) {
      out->frames.push_back(halfSize(f));
    }
    const SegmenterConfig config = reloadConfig();
    out->a = out->dir.str("a.fmf");
    out->b = out->dir.str("b.fmf");
    out->mismatched = out->dir.str("other_settings.fmf");
    out->forest_a = trainRecorded(config, {out->frames[0], out->frames[1]}, out->a);
    out->forest_b = trainRecorded(config, {out->frames[2], out->frames[3], out->frames[4]}, out->b);
    // Trained with points cut at 8 m instead of the config's 10 m.
    Config other;
    other.segmenter = config;
    applyOverride(other, "cloud.max_depth_m=8");
    out->forest_mismatched =
        trainRecorded(other.segmenter, {out->frames[0], out->frames[1]}, out->mismatched);
    return out;
  }();
  return m;
}

std::string idOf(const std::string& path, const RandomForest& forest) {
  return std::filesystem::path(path).filename().string() + ":" + forest.id();
}

struct Collected {
  std::vector<io::LabelImageMessage> labels;
  std::vector<findmug_lcm::status_t> statuses;
};

void collect(io::MemoryBus& bus, Collected* out) {
  bus.subscribe(std::string(io::kLabelsChannel),
                [out](const std::string& c, const std::uint8_t* d, std::size_t n) {
                  out->labels.push_back(io::decodeLabelImage(d, n, c));
                });
  bus.subscribe(std::string(io::kStatusChannel),
                [out](const std::string& c, const std::uint8_t* d, std::size_t n) {
                  out->statuses.push_back(io::decodeMessage<findmug_lcm::status_t>(d, n, c));
                });
}

void drain(io::MemoryBus& bus) {
  while (bus.handle(0ms) == io::HandleResult::Handled) {
  }
}

void sendCommand(io::Bus& bus, const std::string& command, std::int64_t request_id,
                 const std::string& argument = "") {
  const auto bytes = io::encodeMessage(io::encodeCommand(
      io::CommandMessage{1'700'000'000'000'000ULL, request_id, command, argument}));
  ASSERT_TRUE(bus.publish(std::string(io::kCommandChannel), bytes.data(), bytes.size()));
}

// A pipeline as findmugd runs it (threaded, model file at `model_path`), on
// in-memory buses; frames go in at 30 fps.
class ReloadRig {
 public:
  // `given`: segmenter settings the config states explicitly, as a file or --set would.
  ReloadRig(const std::string& model_path, std::shared_ptr<const RandomForest> forest,
            const std::vector<std::pair<std::string, std::string>>& given = {}) {
    config_.segmenter = reloadConfig();
    for (const auto& [key, value] : given) config_.set(key, value);
    config_.set("daemon.model_path", model_path);
    config_.set("daemon.workers", "2");
    config_.set("daemon.queue_capacity", "8");
    config_.set("daemon.status_period_s", "0.2");
    config_.set("daemon.pose_input", "false");
    collect(*out_, &got);
    PipelineHooks hooks;
    hooks.output_bus = out_;
    hooks.command_bus = commands;
    pipeline = std::make_unique<Pipeline>(config_.segmenter, config_.daemon,
                                          forest, idOf(model_path, *forest),
                                          ExecutionMode::Threaded, hooks);
    pipeline->start();
  }

  // Submits `count` frames at 30 fps (cycling the test frames), calling
  // `at(i)` before frame i; returns the seq of each submitted frame's source frame.
  void stream(int count, const std::function<void(int)>& at = {}) {
    const auto period = std::chrono::microseconds(33333);
    auto next = Clock::now();
    for (int i = 0; i < count; ++i) {
      if (at) at(i);
      std::this_thread::sleep_until(next);
      next += period;
      const auto& frames = models()->frames;
      RgbdFrame frame = frames[static_cast<std::size_t>(submitted_) % frames.size()].frame;
      frame.seq = submitted_;
      frame.utime = 1'000'000 + static_cast<std::uint64_t>(submitted_) * 33333;
      ASSERT_TRUE(pipeline->submit(std::move(frame)));
      ++submitted_;
    }
  }

  // Waits until the reloader has finished `count` reloads (ok or refused).
  ReloadStatus awaitReloads(std::uint64_t count) {
    const auto deadline = Clock::now() + 60s;
    ReloadStatus s = pipeline->reloadStatus();
    while (s.reloads + s.refused < count && Clock::now() < deadline) {
      std::this_thread::sleep_for(10ms);
      s = pipeline->reloadStatus();
    }
    return s;
  }

  void finish() {
    pipeline->stop(StopMode::Drain);
    drain(*out_);
  }

  int submitted() const { return submitted_; }
  std::int64_t submitted_extra = 1000;  // seqs of frames a test submits itself

  Collected got;
  std::shared_ptr<io::MemoryBus> commands = std::make_shared<io::MemoryBus>(100);
  std::unique_ptr<Pipeline> pipeline;

 private:
  test::TestConfig config_;
  std::shared_ptr<io::MemoryBus> out_ = std::make_shared<io::MemoryBus>(100000);
  int submitted_ = 0;
};

// What each model makes of each test frame, through the library alone.
std::vector<LabelImage> libraryLabels(const std::shared_ptr<const RandomForest>& forest) {
  const Segmenter segmenter(reloadConfig(), forest);
  std::vector<LabelImage> out;
  for (const LabeledFrame& f : models()->frames) out.push_back(segmenter.process(f.frame).labels);
  return out;
}

bool sameLabels(const LabelImage& expected, const io::LabelImageMessage& got) {
  return got.image.width == expected.width && got.image.labels == expected.labels;
}

TEST(ModelReload, SwappedInWhileFramesFlowAt30FpsWithoutDroppingOne) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  const Models* m = models();
  ASSERT_TRUE(m);
  TempDir tmp;
  const std::string model_path = tmp.str("installed.fmf");
  installAtomically(m->a, model_path);
  const auto with_a = libraryLabels(m->forest_a);
  const auto with_b = libraryLabels(m->forest_b);

  ReloadRig rig(model_path, m->forest_a);
  const std::string id_a = idOf(model_path, *m->forest_a);
  const std::string id_b = idOf(model_path, *m->forest_b);
  ASSERT_NE(id_a, id_b);
  EXPECT_EQ(rig.pipeline->modelId(), id_a);
  // 4 s of frames; the new model is installed and asked for after 1 s.
  rig.stream(120, [&](int i) {
    if (i == 30) {
      installAtomically(m->b, model_path);
      sendCommand(*rig.commands, "reload_model", 7);
    }
  });
  const ReloadStatus reload = rig.awaitReloads(1);
  rig.finish();

  EXPECT_EQ(reload.reloads, 1u);
  EXPECT_EQ(reload.refused, 0u);
  EXPECT_TRUE(reload.last_ok) << reload.last_result;
  EXPECT_EQ(reload.last_request_id, 7);
  EXPECT_NE(reload.last_result.find(id_b), std::string::npos) << reload.last_result;
  EXPECT_EQ(rig.pipeline->modelId(), id_b);

  const PipelineCounters c = rig.pipeline->counters();
  EXPECT_EQ(c.received, 120u);
  EXPECT_EQ(c.processed, 120u);
  EXPECT_EQ(c.dropped, 0u) << "at the door " << c.dropped_at_door << ", in the pipeline "
                           << c.dropped_in_pipeline;
  EXPECT_EQ(c.rejected, 0u);

  // Every frame published, in order, each wholly the old model's result or
  // wholly the new one's; never the old one after the new one.
  ASSERT_EQ(rig.got.labels.size(), 120u);
  const std::size_t n = m->frames.size();
  bool switched = false;
  int differing_after_switch = 0;
  for (std::size_t i = 0; i < rig.got.labels.size(); ++i) {
    const auto& got = rig.got.labels[i];
    ASSERT_EQ(got.seq, static_cast<std::int64_t>(i));
    const std::size_t k = i % n;
    const bool is_a = sameLabels(with_a[k], got), is_b = sameLabels(with_b[k], got);
    ASSERT_TRUE(is_a || is_b) << "frame " << i << " is neither model's output";
    if (is_b && !is_a) switched = true;
    if (switched) {
      EXPECT_TRUE(is_b) << "frame " << i << " classified by the old model after the swap";
      differing_after_switch += !is_a;
    }
    if (i == 0) {
      EXPECT_TRUE(is_a) << "the first frame, long before the reload";
    }
  }
  EXPECT_TRUE(switched);
  EXPECT_GT(differing_after_switch, 10);  // the models really differ on these frames

  // Status: the final one names the new model and the reload's outcome.
  ASSERT_FALSE(rig.got.statuses.empty());
  const findmug_lcm::status_t& last = rig.got.statuses.back();
  EXPECT_EQ(last.model_id, id_b);
  EXPECT_EQ(last.model_reloads, 1);
  EXPECT_EQ(last.model_reloads_refused, 0);
  EXPECT_TRUE(last.last_reload_ok);
  EXPECT_EQ(last.last_reload_request_id, 7);
  EXPECT_GT(last.last_reload_utime, 0);
  EXPECT_EQ(last.commands_accepted, 1);
  EXPECT_EQ(last.commands_rejected, 0);
  EXPECT_EQ(last.frames_dropped, 0);
  // Statuses before the swap named the old model.
  EXPECT_EQ(rig.got.statuses.front().model_id, id_a);
}

// The floor a stream follows belongs to the stream, not to the model: after a reload the
// frames keep the plane found before it instead of estimating it again.
TEST(ModelReload, KeepsTheFloorTheStreamFollows) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  const Models* m = models();
  ASSERT_NE(m, nullptr);
  installAtomically(m->a, m->dir.str("live.fmf"));
  ReloadRig rig(m->dir.str("live.fmf"), m->forest_a, {{"ground.reestimate_every_frames", "1000"}});
  // One view again and again: confirmGround keeps its floor every time.
  const RgbdFrame& view = m->frames[0].frame;
  auto submit = [&](int count) {
    for (int i = 0; i < count; ++i) {
      RgbdFrame frame = view;
      frame.seq = rig.submitted_extra++;
      ASSERT_TRUE(rig.pipeline->waitForRoom(10s));  // none dropped at the door
      ASSERT_TRUE(rig.pipeline->submit(std::move(frame)));
    }
  };
  submit(6);
  installAtomically(m->b, m->dir.str("live.fmf"));
  sendCommand(*rig.commands, "reload_model", 5);
  const ReloadStatus reload = rig.awaitReloads(1);
  ASSERT_EQ(reload.reloads, 1u) << reload.last_result;
  submit(6);
  rig.finish();
  ASSERT_EQ(rig.got.labels.size(), 12u);
  const GroundTracker& ground = rig.pipeline->groundTracker();
  ASSERT_TRUE(ground.plane().has_value());
  // Estimated on the first frame, kept by the eleven after it, the reload's included.
  EXPECT_EQ(ground.framesSinceEstimate(), 11);
}

TEST(ModelReload, MismatchedCorruptAndHostileAreRefusedAndFramesGoOnWithTheOldModel) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  const Models* m = models();
  ASSERT_TRUE(m);
  TempDir tmp;
  const std::string model_path = tmp.str("installed.fmf");
  installAtomically(m->a, model_path);
  const auto with_a = libraryLabels(m->forest_a);
  // The config states the depth cut the mismatched model records otherwise.
  ReloadRig rig(model_path, m->forest_a, {{"cloud.max_depth_m", "10"}});
  const std::string id_a = idOf(model_path, *m->forest_a);

  ReloadStatus mismatched, corrupt;
  rig.stream(30, [&](int i) {
    if (i == 5) {
      installAtomically(m->mismatched, model_path);
      rig.pipeline->requestModelReload(-1, "test (as SIGHUP)");
    }
    if (i == 12) {
      mismatched = rig.awaitReloads(1);
      // A truncated copy of a good model.
      const std::string bytes = [&] {
        std::ifstream in(m->b, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(in), {});
      }();
      std::ofstream(tmp.str("broken.fmf"), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
      installAtomically(tmp.str("broken.fmf"), model_path);
      sendCommand(*rig.commands, "reload_model", 9);
    }
    if (i == 20) {
      corrupt = rig.awaitReloads(2);
      // Hostile and wrong commands: undecodable bytes, an unknown command, an
      // argument where none is taken, a command of forbidden characters.
      const std::string junk = "\x01\x02garbage";
      ASSERT_TRUE(rig.commands->publish(std::string(io::kCommandChannel), junk.data(), junk.size()));
      sendCommand(*rig.commands, "format_disk", 10);
      sendCommand(*rig.commands, "reload_model", 11, "/etc/passwd");
      findmug_lcm::command_t raw;
      raw.utime = 1;
      raw.request_id = 12;
      raw.command = "RELOAD MODEL";
      raw.argument = "";
      const auto bytes = io::encodeMessage(raw);
      ASSERT_TRUE(rig.commands->publish(std::string(io::kCommandChannel), bytes.data(), bytes.size()));
    }
  });
  // Request 9 and the four refused ones, all dealt with by the command thread.
  for (int i = 0; i < 500 && rig.pipeline->commandInput()->handled() < 5; ++i) {
    std::this_thread::sleep_for(20ms);
  }
  rig.finish();

  EXPECT_FALSE(mismatched.last_ok);
  EXPECT_EQ(mismatched.refused, 1u);
  EXPECT_EQ(mismatched.last_request_id, -1);
  // The refusal names the file, the setting and both values.
  EXPECT_NE(mismatched.last_result.find(model_path), std::string::npos) << mismatched.last_result;
  EXPECT_NE(mismatched.last_result.find("cloud.max_depth_m = 10 (the program) but model " +
                                        model_path + " records cloud.max_depth_m = 8"),
            std::string::npos)
      << mismatched.last_result;
  EXPECT_NE(mismatched.last_result.find("still running " + id_a), std::string::npos)
      << mismatched.last_result;
  EXPECT_FALSE(corrupt.last_ok);
  EXPECT_EQ(corrupt.refused, 2u);
  EXPECT_EQ(corrupt.last_request_id, 9);
  EXPECT_NE(corrupt.last_result.find(model_path), std::string::npos) << corrupt.last_result;
  EXPECT_EQ(rig.pipeline->modelId(), id_a);

  const PipelineCounters c = rig.pipeline->counters();
  EXPECT_EQ(c.processed, 30u);
  EXPECT_EQ(c.dropped, 0u);
  EXPECT_EQ(c.rejected, 0u);
  ASSERT_EQ(rig.got.labels.size(), 30u);
  for (std::size_t i = 0; i < rig.got.labels.size(); ++i) {
    EXPECT_TRUE(sameLabels(with_a[i % m->frames.size()], rig.got.labels[i])) << "frame " << i;
  }
  ASSERT_FALSE(rig.got.statuses.empty());
  const findmug_lcm::status_t& last = rig.got.statuses.back();
  EXPECT_EQ(last.model_id, id_a);
  EXPECT_EQ(last.model_reloads, 0);
  EXPECT_EQ(last.model_reloads_refused, 2);
  EXPECT_FALSE(last.last_reload_ok);
  EXPECT_EQ(last.commands_accepted, 1);  // request 9
  EXPECT_EQ(last.commands_rejected, 4);
  EXPECT_NE(last.last_error.find("command_t.command"), std::string::npos) << last.last_error;
}

// A model trained with another depth cut, reloaded into a daemon whose config does not
// state it, runs with the cut it records: every frame after the swap is what the library
// makes of it with that model and its settings.
TEST(ModelReload, AModelWithOtherFeatureSettingsRunsWithThem) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  const Models* m = models();
  ASSERT_TRUE(m);
  TempDir tmp;
  const std::string model_path = tmp.str("installed.fmf");
  installAtomically(m->a, model_path);
  const auto with_a = libraryLabels(m->forest_a);
  const auto with_other = libraryLabels(m->forest_mismatched);
  EXPECT_EQ(Segmenter(reloadConfig(), m->forest_mismatched).config().max_depth_m, 8.0f);
  // The same trees run with the config's 10 m cut label some frames otherwise: the
  // comparison below can tell whether the model's cut was taken.
  RandomForest unrecorded = *m->forest_mismatched;
  unrecorded.setExtractionSettings({});
  const auto with_config_cut = libraryLabels(std::make_shared<const RandomForest>(unrecorded));
  int cut_matters = 0;
  for (std::size_t k = 0; k < with_other.size(); ++k) {
    cut_matters += with_other[k].labels != with_config_cut[k].labels;
  }
  EXPECT_GT(cut_matters, 0);
  ReloadRig rig(model_path, m->forest_a);

  ReloadStatus reload;
  rig.stream(30, [&](int i) {
    if (i == 5) {
      installAtomically(m->mismatched, model_path);
      sendCommand(*rig.commands, "reload_model", 3);
    }
    if (i == 12) reload = rig.awaitReloads(1);
  });
  rig.finish();

  EXPECT_TRUE(reload.last_ok) << reload.last_result;
  EXPECT_EQ(reload.reloads, 1u);
  EXPECT_EQ(rig.pipeline->modelId(), idOf(model_path, *m->forest_mismatched));
  ASSERT_EQ(rig.got.labels.size(), 30u);
  const std::size_t n = m->frames.size();
  // Frames submitted before the reload are either model's (a swap lands between frames);
  // those submitted after it finished are the new model's with its settings.
  for (std::size_t i = 0; i < 5; ++i) {
    EXPECT_TRUE(sameLabels(with_a[i % n], rig.got.labels[i]) ||
                sameLabels(with_other[i % n], rig.got.labels[i]))
        << "frame " << i;
  }
  for (std::size_t i = 12; i < rig.got.labels.size(); ++i) {
    EXPECT_TRUE(sameLabels(with_other[i % n], rig.got.labels[i])) << "frame " << i;
  }
}

// ---- the findmugd process: SIGHUP ----------------------------------------------

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

bool awaitInFile(const std::string& path, const std::string& what, Clock::duration timeout) {
  const auto deadline = Clock::now() + timeout;
  while (Clock::now() < deadline) {
    if (readFile(path).find(what) != std::string::npos) return true;
    std::this_thread::sleep_for(50ms);
  }
  return false;
}

TEST(ModelReload, FindmugdReloadsOnSighupAndKeepsPublishing) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  TempDir tmp;
  // Full-size models for the daemon's full-size frames.
  const std::vector<LabeledFrame> full = test::framesWithGround(nyu.string(), 3);
  const std::string model_path = tmp.str("installed.fmf");
  const auto first = trainRecorded(test::fastSegmenterConfig(), {full[0]}, tmp.str("one.fmf"));
  const auto second = trainRecorded(test::fastSegmenterConfig(), {full[1], full[2]},
                                    tmp.str("two.fmf"));
  installAtomically(tmp.str("one.fmf"), model_path);
  const std::string out = tmp.str("out.lcmlog");
  {
    std::ofstream yaml(tmp.str("findmugd.yaml"));
    yaml << "oversegmentation:\n  method: organized\n"
         << "daemon:\n"
         << "  source: dataset:" << nyu.string() << "?rate_hz=4&loop=1\n"
         << "  model_path: " << model_path << "\n"
         << "  lcm_url: file://" << out << "?mode=w\n"
         << "  workers: 1\n"
         << "  status_period_s: 0.25\n";
  }
  test::NotifySocket notify(tmp.str("notify.sock"));
  std::vector<std::string> args = {FINDMUGD_EXE, "--config", tmp.str("findmugd.yaml")};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::vector<std::string> env_s = {"NOTIFY_SOCKET=" + notify.path()};
  for (char** e = environ; *e; ++e) {
    const std::string entry = *e;
    if (entry.rfind("NOTIFY_SOCKET=", 0) != 0 && entry.rfind("LCM_DEFAULT_URL=", 0) != 0 &&
        entry.rfind("WATCHDOG_", 0) != 0) {
      env_s.push_back(entry);
    }
  }
  std::vector<char*> envp;
  for (auto& e : env_s) envp.push_back(e.data());
  envp.push_back(nullptr);
  const std::string log = tmp.str("stderr.txt");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  pid_t pid = -1;
  ASSERT_EQ(posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), envp.data()), 0);
  posix_spawn_file_actions_destroy(&actions);

  bool ready = false;
  for (const auto deadline = Clock::now() + 120s; !ready && Clock::now() < deadline;) {
    if (auto msg = notify.receive(100ms)) ready = msg->find("READY=1") != std::string::npos;
  }
  const auto stop = [&] {
    kill(pid, SIGTERM);
    int status = 0;
    waitpid(pid, &status, 0);
    return status;
  };
  if (!ready) {
    stop();
    FAIL() << "no READY=1:\n" << readFile(log);
  }
  // The first model's statuses are in the log before the reload is asked for.
  bool first_status = false;
  for (const auto deadline = Clock::now() + 60s; !first_status && Clock::now() < deadline;) {
    std::this_thread::sleep_for(100ms);
    try {
      for (const auto& msg : test::readLcmLog(out)) first_status |= msg.channel == io::kStatusChannel;
    } catch (const std::exception&) {
      // A log caught in the middle of an event: read it again.
    }
  }
  installAtomically(tmp.str("two.fmf"), model_path);
  ASSERT_EQ(kill(pid, SIGHUP), 0);
  const bool reloaded = awaitInFile(log, "model reload (SIGHUP): loaded", 60s);
  // A few frames after it, with the new model.
  std::this_thread::sleep_for(1500ms);
  const int status = stop();
  ASSERT_TRUE(first_status) << "no status in the output log before the reload";
  ASSERT_TRUE(reloaded) << readFile(log);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << readFile(log);

  std::vector<findmug_lcm::status_t> statuses;
  std::size_t labels = 0;
  for (const auto& msg : test::readLcmLog(out)) {
    if (msg.channel == io::kStatusChannel) {
      statuses.push_back(io::decodeMessage<findmug_lcm::status_t>(msg.data.data(),
                                                                  msg.data.size(), msg.channel));
    }
    labels += msg.channel == io::kLabelsChannel;
  }
  ASSERT_FALSE(statuses.empty());
  EXPECT_GT(labels, 0u);
  const auto& last = statuses.back();
  EXPECT_EQ(last.model_id, idOf(model_path, *second));
  EXPECT_EQ(last.model_reloads, 1);
  EXPECT_TRUE(last.last_reload_ok);
  EXPECT_EQ(last.last_reload_request_id, -1);
  EXPECT_EQ(statuses.front().model_id, idOf(model_path, *first));
  EXPECT_EQ(last.frames_rejected, 0);
}

}  // namespace
}  // namespace findmug::daemon
