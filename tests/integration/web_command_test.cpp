// findmug-web's requests to findmugd (clients/web/command_routes.hpp): POST /api/command
// turns into a command_t on FINDMUG_COMMAND that a daemon pipeline (in-process, on an
// in-memory bus, real NYU frames) acts on: "Save this frame" writes the next frame into
// daemon.collect_dir, reload_model swaps in the model installed at daemon.model_path, and
// the status findmug-web shows (/api/live) reports both. Bad requests get 400 and publish
// nothing; without a bus the endpoint answers 503. Traffic: loopback HTTP only.
// The project's headers (Eigen) before httplib.h: the <resolv.h> it pulls in defines a
// macro _res, a parameter name inside Eigen.
#include "daemon_test_config.hpp"
#include "daemon_test_support.hpp"
#include "findmug/common/error.hpp"
#include "findmug/daemon/pipeline.hpp"
#include "findmug/io/bus.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "live_state.hpp"
#include "test_data.hpp"
#include "web_server.hpp"

#include <gtest/gtest.h>
#include <httplib.h>

#include <chrono>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <thread>

namespace fs = std::filesystem;
using namespace findmug;
using namespace std::chrono_literals;
using findmug::test::TempDir;

namespace {

// findmug-web's server on a free loopback port, sending commands through `send`.
struct WebRig {
  explicit WebRig(web::SendCommand send) : live(300.0) {
    web::ServerOptions options;
    options.port = 0;
    options.max_body_bytes = 4096;
    options.static_dir = test::sourceDir() / "clients/web/static";
    options.send_command = std::move(send);
    server = std::make_unique<web::WebServer>(options, live);
    server->bind();
    thread = std::thread([this] { server->serve(); });
    client = std::make_unique<httplib::Client>("127.0.0.1", server->port());
    client->set_read_timeout(10);
    for (int i = 0; i < 100 && !client->Get("/api/live"); ++i) std::this_thread::sleep_for(20ms);
  }
  ~WebRig() {
    server->stop();
    thread.join();
  }
  httplib::Result post(const std::string& body) {
    return client->Post("/api/command", body, "application/json");
  }

  web::LiveState live;
  std::unique_ptr<web::WebServer> server;
  std::thread thread;
  std::unique_ptr<httplib::Client> client;
};

TEST(WebCommand, BadRequestsAre400AndPublishNothing) {
  std::vector<io::CommandMessage> sent;
  WebRig rig([&](const io::CommandMessage& c) { sent.push_back(c); });
  for (const std::string body :
       {"not json", "[1,2]", "{}", R"({"command": 3})", R"({"command": "format_disk"})",
        R"({"command": "reload_model", "argument": "/etc/passwd"})",
        R"({"command": "save_frame", "argument": 7})",
        R"({"command": "save_frame", "argument": "a, b"})",
        R"({"command": "save_frame", "argument": "line\nbreak"})",
        R"({"command": "teach"})", R"({"command": "teach", "argument": "mug 41"})",
        R"({"command": "teach", "argument": "My Mug 41 2"})",
        R"({"command": "teach", "argument": "mug -1 2"})",
        R"({"command": "teach", "argument": "mug 41 two"})",
        R"({"command": "find", "argument": ""})",
        R"({"command": "find", "argument": "../etc"})"}) {
    const auto res = rig.post(body);
    ASSERT_TRUE(res) << body;
    EXPECT_EQ(res->status, 400) << body;
    EXPECT_FALSE(res->get_header_value("X-Findmug-Error").empty()) << body;
  }
  const auto big = rig.post(R"({"command": "save_frame", "argument": ")" +
                            std::string(5000, 'x') + "\"}");
  ASSERT_TRUE(big);
  EXPECT_EQ(big->status, 413);
  EXPECT_TRUE(sent.empty());
  // A good one goes out, with a fresh request id each time.
  const auto a = rig.post(R"({"command": "save_frame", "argument": "two mugs"})");
  const auto b = rig.post(R"({"command": "reload_model"})");
  ASSERT_TRUE(a && b);
  ASSERT_EQ(a->status, 200) << a->body;
  ASSERT_EQ(b->status, 200) << b->body;
  ASSERT_EQ(sent.size(), 2u);
  EXPECT_EQ(sent[0].command, "save_frame");
  EXPECT_EQ(sent[0].argument, "two mugs");
  EXPECT_EQ(sent[1].command, "reload_model");
  EXPECT_EQ(nlohmann::json::parse(a->body)["request_id"].get<std::int64_t>(), sent[0].request_id);
  EXPECT_EQ(sent[1].request_id, sent[0].request_id + 1);
  // The live page's teach click and find box.
  const auto teach = rig.post(R"({"command": "teach", "argument": "mug 41 2"})");
  const auto find = rig.post(R"({"command": "find", "argument": "mug"})");
  ASSERT_TRUE(teach && find);
  ASSERT_EQ(teach->status, 200) << teach->body;
  ASSERT_EQ(find->status, 200) << find->body;
  ASSERT_EQ(sent.size(), 4u);
  EXPECT_EQ(sent[2].command, "teach");
  EXPECT_EQ(sent[2].argument, "mug 41 2");
  EXPECT_EQ(sent[3].command, "find");
  // Why a bad teach is refused is in the answer.
  const auto bad = rig.post(R"({"command": "teach", "argument": "mug 41 x"})");
  ASSERT_TRUE(bad);
  EXPECT_NE(bad->get_header_value("X-Findmug-Error").find("teach INDEX"), std::string::npos)
      << bad->get_header_value("X-Findmug-Error");
}

// The frame's candidates and the find answer as the page reads them from /api/live.
TEST(WebCommand, LiveCarriesTheFramesCandidatesAndTheLatestFindAnswer) {
  WebRig rig({});
  io::ObjectsMessage objects;
  objects.seq = 41;
  objects.utime = 7;
  objects.num_tables = 1;
  TableObject o;
  o.table = 0;
  o.centroid = {1.5f, 0.2f, 0.8f};
  o.center = {1.5f, 0.2f};
  o.extents = {0.05f, 0.04f};
  o.height_above_top = 0.1f;
  o.point_count = 300;
  o.truncation = kTruncatedDepthHole;
  objects.objects = {o, o};
  objects.map_info.resize(2);
  rig.live.onObjects(objects);
  io::FindResultMessage find;
  find.request_id = 12;
  find.name = "mug";
  find.result = io::FindResult::Seen;
  find.summary = "mug seen at (1.5, 0.2, 0.8) on table 1";
  find.seen_table_id = 1;
  find.seen_position = {1.5, 0.2, 0.8};
  find.taught_names = {"mug"};
  rig.live.onFindResult(find);
  const auto res = rig.client->Get("/api/live");
  ASSERT_TRUE(res);
  const auto live = nlohmann::json::parse(res->body);
  EXPECT_EQ(live["objects"]["seq"], 41);
  ASSERT_EQ(live["objects"]["objects"].size(), 2u);
  EXPECT_EQ(live["objects"]["objects"][1]["index"], 1);
  EXPECT_EQ(live["objects"]["objects"][1]["truncation"], kTruncatedDepthHole);
  EXPECT_NEAR(live["objects"]["objects"][0]["height_above_top"].get<double>(), 0.1, 1e-6);
  EXPECT_EQ(live["find"]["request_id"], 12);
  EXPECT_EQ(live["find"]["result"], "seen");
  EXPECT_EQ(live["find"]["seen"]["table_id"], 1);
  EXPECT_EQ(live["find"]["summary"], find.summary);
}

TEST(WebCommand, WithoutABusTheEndpointIs503) {
  WebRig rig({});
  const auto res = rig.post(R"({"command": "save_frame"})");
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 503);
}

// The page's two buttons end to end: web -> command_t bytes on the bus -> the daemon's
// pipeline -> its status -> findmug-web's /api/live.
TEST(WebCommand, SaveThisFrameAndReloadReachTheDaemonAndItsStatusComesBack) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  constexpr int kStep = 2;
  std::vector<LabeledFrame> frames;
  for (const LabeledFrame& f : daemon::test::framesWithGround(nyu.string(), 3)) {
    frames.push_back(daemon::test::subsampled(f, kStep));
  }
  const SegmenterConfig segmenter = daemon::test::fastSegmenterConfig(kStep);
  TempDir tmp;
  const auto first = daemon::test::trainTinyModel(segmenter, {frames[0]}, tmp.str("one.fmf"));
  const auto second =
      daemon::test::trainTinyModel(segmenter, {frames[1], frames[2]}, tmp.str("two.fmf"));
  const std::string installed = tmp.str("installed.fmf");
  fs::copy_file(tmp.str("one.fmf"), installed);

  auto commands = std::make_shared<io::MemoryBus>(100);
  auto out = std::make_shared<io::MemoryBus>(10000);
  daemon::test::TestConfig config;
  config.segmenter = segmenter;
  config.set("daemon.model_path", installed);
  config.set("daemon.status_period_s", "60");
  config.set("daemon.pose_input", "false");
  config.set("daemon.collect_dir", tmp.str("collected"));
  daemon::PipelineHooks hooks;
  hooks.output_bus = out;
  hooks.command_bus = commands;
  daemon::Pipeline pipeline(segmenter, config.daemon, first,
                            "installed.fmf:" + first->id(), daemon::ExecutionMode::Sequential,
                            hooks);
  pipeline.start();

  // findmug-web publishing on the daemon's command bus, as web_main does on its LCM URL.
  const std::string channel(io::kCommandChannel);
  WebRig web([&](const io::CommandMessage& c) {
    const auto bytes = io::encodeMessage(io::encodeCommand(c));
    if (!commands->publish(channel, bytes.data(), bytes.size())) throw Error("refused");
  });
  out->subscribe(std::string(io::kStatusChannel),
                 [&](const std::string& c, const std::uint8_t* d, std::size_t n) {
                   web.live.onStatus(io::decodeMessage<findmug_lcm::status_t>(d, n, c));
                 });
  const auto awaitCommands = [&](std::uint64_t n) {
    for (int i = 0; i < 300 && pipeline.commandInput()->handled() < n; ++i) {
      std::this_thread::sleep_for(20ms);
    }
  };

  const auto save = web.post(R"({"command": "save_frame", "argument": "from the page"})");
  ASSERT_TRUE(save);
  ASSERT_EQ(save->status, 200) << save->body;
  awaitCommands(1);
  RgbdFrame frame = frames[0].frame;
  frame.seq = 1;
  frame.utime = 5'000'000;
  ASSERT_TRUE(pipeline.submit(frame));

  // "Install": the new model copied over daemon.model_path in one rename, then reload.
  fs::copy_file(tmp.str("two.fmf"), installed + ".new");
  fs::rename(installed + ".new", installed);
  const auto reload = web.post(R"({"command": "reload_model"})");
  ASSERT_TRUE(reload);
  ASSERT_EQ(reload->status, 200) << reload->body;
  const auto reload_id = nlohmann::json::parse(reload->body)["request_id"].get<std::int64_t>();
  awaitCommands(2);
  for (int i = 0; i < 500 && pipeline.reloadStatus().reloads + pipeline.reloadStatus().refused == 0;
       ++i) {
    std::this_thread::sleep_for(20ms);
  }
  // The frame is written by the collector's own thread.
  for (int i = 0; i < 500 && pipeline.statusSnapshot().frames_collected == 0; ++i) {
    std::this_thread::sleep_for(20ms);
  }
  pipeline.publishStatusNow();
  while (out->handle(0ms) == io::HandleResult::Handled) {
  }

  const auto live = web.client->Get("/api/live");
  ASSERT_TRUE(live);
  const auto status = nlohmann::json::parse(live->body)["status"];
  ASSERT_FALSE(status.is_null());
  EXPECT_EQ(status["frames_collected"], 1);
  EXPECT_EQ(status["last_collected_frame"], "5000000_1");
  EXPECT_TRUE(fs::exists(fs::path(tmp.str("collected")) / "rgb" / "5000000_1.png"));
  EXPECT_EQ(status["model_reloads"], 1);
  EXPECT_EQ(status["last_reload_ok"], true) << status["last_reload_result"];
  EXPECT_EQ(status["last_reload_request_id"], reload_id);
  EXPECT_EQ(status["model_id"], "installed.fmf:" + second->id());
  pipeline.stop(daemon::StopMode::Drain);
}

}  // namespace
