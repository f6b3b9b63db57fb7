// Fault injection on the daemon in-process (issue 11): the camera disappears
// mid-run and comes back. The daemon's source is the DeviceSource every
// device source uses (the OpenNI2 one included) over a "camera" that streams
// real NYU frames and that the test unplugs and plugs back in. The daemon
// must report the loss (source state, last error, reconnect count: in
// makeStatus() while it runs and in the status_t messages on the wire),
// reconnect with back-off, and segment frames again without a restart.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <thread>

#include "daemon_test_config.hpp"
#include "daemon_test_support.hpp"
#include "findmug/daemon/daemon.hpp"
#include "findmug/daemon/status_builder.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/device_source.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "test_data.hpp"
#include "unpluggable_device.hpp"

namespace findmug::daemon {
namespace {

using namespace std::chrono_literals;
using findmug::test::TempDir;

// Waits (without asserting on time) until `done` holds, at most `limit`
// (generous: segmentation on a loaded 2-core machine is slow).
template <typename F>
bool waitFor(F&& done, std::chrono::seconds limit = 300s) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(10ms);
  }
  return done();
}

TEST(DaemonFaults, CameraThatDisappearsMidRunIsReconnectedWithBackoffAndFramesFlowAgain) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  TempDir tmp;
  // A tiny model trained on two NYU frames (as the pipeline tests do).
  const SegmenterConfig segmenter = test::fastSegmenterConfig();
  const std::string model = tmp.str("tiny.fmf");
  test::trainTinyModel(segmenter, test::framesWithGround(nyu.string(), 2), model);
  // The camera streams four NYU frames at 5 fps, over and over.
  test::linkDatasetSubset(nyu, {"0001", "0002", "0009", "0014"}, tmp.path() / "camera");

  const std::string out = tmp.str("out.lcmlog");
  test::TestConfig config;
  config.segmenter = segmenter;
  config.set("daemon.source", "lcm:unused");  // replaced by the source below
  config.set("daemon.lcm_url", "file://" + out + "?mode=w");
  config.set("daemon.model_path", model);
  config.set("daemon.workers", "2");
  config.set("daemon.status_period_s", "0.2");
  const DaemonConfig dc = config.daemon;

  auto device = std::make_unique<findmug::test::UnpluggableDevice>(
      "dataset:" + (tmp.path() / "camera").string() + "?loop=1&rate_hz=5");
  findmug::test::UnpluggableDevice& camera = *device;
  io::DeviceSourceSettings settings;
  settings.reconnect_initial = 50ms;
  settings.reconnect_max = 200ms;
  settings.poll = 20ms;
  auto owned = std::make_unique<io::DeviceSource>(std::move(device), settings);
  io::DeviceSource& source = *owned;
  auto daemon = std::make_unique<Daemon>(config, dc, std::move(owned));
  int code = -1;
  std::thread runner([&] { code = daemon->run(); });
  // A failed ASSERT returns early: stop the daemon and join, not terminate.
  struct Cleanup {
    std::unique_ptr<Daemon>& daemon;
    std::thread& runner;
    ~Cleanup() {
      if (daemon) daemon->requestStop();
      if (runner.joinable()) runner.join();
    }
  } cleanup{daemon, runner};
  auto status = [&] { return makeStatus(daemon->pipeline()); };

  // Running: frames are segmented and published.
  ASSERT_TRUE(waitFor([&] { return status().frames_processed >= 2; }));
  EXPECT_EQ(status().source_state, findmug_lcm::status_t::SOURCE_RUNNING);

  // Unplugged: the daemon keeps running, reports the source reconnecting
  // and retries with growing delays until the cap.
  camera.unplug();
  ASSERT_TRUE(waitFor([&] {
    return status().source_state == findmug_lcm::status_t::SOURCE_RECONNECTING &&
           source.reconnectAttempts().size() >= 5;
  }));
  const findmug_lcm::status_t lost = status();
  EXPECT_NE(lost.last_error.find("unplugged); retrying in 200 ms"), std::string::npos)
      << lost.last_error;
  EXPECT_EQ(lost.source_reconnects, 0);
  // Long enough for several status periods on the wire while reconnecting.
  std::this_thread::sleep_for(1s);
  // Frames taken before the loss may still be in the pipeline (a slow,
  // sanitized build): count from what the source had delivered.
  const auto delivered_before = static_cast<std::int64_t>(source.stats().frames_delivered);
  const auto plugged_at = io::hostUtimeNow();

  // Plugged back in: frames flow again, without a restart.
  camera.plug();
  ASSERT_TRUE(waitFor([&] {
    const auto s = status();
    return s.source_state == findmug_lcm::status_t::SOURCE_RUNNING &&
           s.frames_processed >= delivered_before + 2;  // so 2 taken after the plug
  }));
  EXPECT_EQ(status().source_reconnects, 1);
  EXPECT_EQ(source.stats().reconnects, 1u);
  EXPECT_EQ(camera.opens(), 2);
  const auto attempts = source.reconnectAttempts();
  ASSERT_GE(attempts.size(), 6u);
  EXPECT_TRUE(attempts.back().succeeded);
  // Back-off: 50, 100, 200, 200, ... ms; each attempt at least its delay after the previous one.
  auto expected = settings.reconnect_initial;
  for (std::size_t i = 0; i < attempts.size(); ++i) {
    EXPECT_EQ(attempts[i].waited, expected) << i;
    EXPECT_EQ(attempts[i].succeeded, i + 1 == attempts.size()) << i;
    if (i > 0) {
      EXPECT_GE(attempts[i].at - attempts[i - 1].at, attempts[i].waited) << i;
    }
    expected = std::min(expected * 2, settings.reconnect_max);
  }
  daemon->requestStop();
  runner.join();
  EXPECT_EQ(code, 0);
  daemon.reset();  // closes the output log

  // On the wire: status running -> reconnecting (naming the loss) -> running
  // with one reconnect; label images before and after the loss, in one
  // unbroken seq order (the same daemon, not a restarted one).
  std::vector<findmug_lcm::status_t> statuses;
  std::vector<io::LabelImageMessage> labels;
  for (const auto& m : test::readLcmLog(out)) {
    if (m.channel == io::kStatusChannel) {
      statuses.push_back(
          io::decodeMessage<findmug_lcm::status_t>(m.data.data(), m.data.size(), m.channel));
    } else if (m.channel == io::kLabelsChannel) {
      labels.push_back(io::decodeLabelImage(m.data.data(), m.data.size(), m.channel));
    }
  }
  using S = findmug_lcm::status_t;
  auto find_state = [&](std::size_t from, std::int8_t state) {
    return std::find_if(statuses.begin() + static_cast<std::ptrdiff_t>(from), statuses.end(),
                        [&](const S& s) { return s.source_state == state; }) -
           statuses.begin();
  };
  const auto running = static_cast<std::size_t>(find_state(0, S::SOURCE_RUNNING));
  ASSERT_LT(running, statuses.size());
  const auto reconnecting = static_cast<std::size_t>(find_state(running, S::SOURCE_RECONNECTING));
  ASSERT_LT(reconnecting, statuses.size()) << "no status reported the source reconnecting";
  EXPECT_EQ(statuses[reconnecting].source_state_name, "reconnecting");
  EXPECT_NE(statuses[reconnecting].last_error.find("device"), std::string::npos)
      << statuses[reconnecting].last_error;
  EXPECT_EQ(statuses[reconnecting].source_reconnects, 0);
  const auto back = static_cast<std::size_t>(find_state(reconnecting, S::SOURCE_RUNNING));
  ASSERT_LT(back, statuses.size()) << "no status after the reconnect reported the source running";
  EXPECT_EQ(statuses[back].source_reconnects, 1);
  EXPECT_EQ(statuses.back().source_reconnects, 1);
  EXPECT_GE(statuses[back].uptime_us, statuses[reconnecting].uptime_us);  // one daemon, one clock

  ASSERT_GE(labels.size(), 4u);
  std::size_t after_plug = 0;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    if (i > 0) {
      EXPECT_GT(labels[i].seq, labels[i - 1].seq) << i;
    }
    after_plug += labels[i].utime > plugged_at;
  }
  EXPECT_GE(after_plug, 2u) << "no frames segmented after the camera came back";
}

}  // namespace
}  // namespace findmug::daemon
