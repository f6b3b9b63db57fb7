// findmug-web's HTTP server (clients/web/web_server.hpp) in-process: the access rules
// (token off the default loopback address, paths confined to the data folders, body
// limit, bad JSON), the live endpoints and the label save. Traffic: loopback only
// (127.0.0.1, and 127.0.0.2 bound explicitly as "another address").
// The project's headers (Eigen) before httplib.h: the <resolv.h> it pulls in defines a
// macro _res, a parameter name inside Eigen.
#include "findmug/frame/image_io.hpp"
#include "findmug/labels/labels.hpp"
#include "live_state.hpp"
#include "test_data.hpp"
#include "web_config.hpp"
#include "web_server.hpp"

#include <gtest/gtest.h>
#include <httplib.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>
#include <tuple>

namespace fs = std::filesystem;
using namespace findmug;

namespace {

constexpr std::size_t kBodyLimit = 64 * 1024;
const std::string kToken = "0123456789abcdef0123456789abcdef";

// A running server on `bind`, any free port, over a small data folder.
class RunningServer {
 public:
  RunningServer(const fs::path& data, const std::string& bind,
                std::optional<std::string> token = std::nullopt)
      : live(300.0) {
    web::ServerOptions options;
    options.bind = bind;
    options.port = 0;
    options.token = std::move(token);
    options.max_body_bytes = kBodyLimit;
    options.static_dir = test::sourceDir() / "clients/web/static";
    options.data_dirs = {data};
    server = std::make_unique<web::WebServer>(options, live);
    server->bind();
    thread = std::thread([this] { server->serve(); });
    client = std::make_unique<httplib::Client>(bind, server->port());
    client->set_connection_timeout(5);
    client->set_keep_alive(true);
    client->set_read_timeout(10);
    // The server is listening once bind() returned; wait until it answers.
    for (int i = 0; i < 100; ++i) {
      if (auto r = client->Get("/api/data", authHeaders(token_copy_ = options.token))) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  // The server logs a refused request after sending the answer: one more request on the
  // same connection, and a moment for a connection the server closed, before reading the log.
  std::string capturedLog() {
    (void)client->Get("/api/data", authHeaders(token_copy_));
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    return testing::internal::GetCapturedStderr();
  }
  ~RunningServer() {
    server->stop();
    thread.join();
  }
  static httplib::Headers authHeaders(const std::optional<std::string>& token) {
    if (!token) return {};
    return {{"Authorization", "Bearer " + *token}};
  }

  web::LiveState live;
  std::unique_ptr<web::WebServer> server;
  std::thread thread;
  std::unique_ptr<httplib::Client> client;

 private:
  std::optional<std::string> token_copy_;
};

class WebAccess : public ::testing::Test {
 protected:
  void SetUp() override {
    fs::create_directories(data_.path() / "rgb");
    fs::create_directories(data_.path() / "label8");
    Image<Rgb8> rgb;
    rgb.width = 4;
    rgb.height = 3;
    rgb.pixels.assign(12, Rgb8{10, 20, 30});
    writePngRgb((data_.path() / "rgb/0001.png").string(), rgb);
    fs::create_directories(outside_.path() / "secret");
    std::ofstream(outside_.path() / "secret/key.txt") << "not for the web\n";
    fs::create_directory_symlink(outside_.path() / "secret", data_.path() / "escape");
  }
  test::TempDir data_, outside_;
};

nlohmann::json labelBody(const std::string& frame, std::uint8_t id, int pixels = 12) {
  return {{"root", 0},  {"frame", frame},    {"width", 4},
          {"height", 3}, {"runs", {{id, pixels}}}, {"author", "tester"}};
}

}  // namespace

// JSON answers go uncompressed even to a browser that accepts Brotli and gzip:
// httplib's Brotli at quality 11 on every live update cost three quarters of
// findmug-web's CPU (web_http.hpp, kJsonContentType).
TEST_F(WebAccess, JsonAnswersAreNotCompressed) {
  RunningServer s(data_.path(), "127.0.0.1");
  s.client->set_decompress(false);
  const httplib::Headers accepts = {{"Accept-Encoding", "gzip, deflate, br"}};
  for (const char* path : {"/api/live", "/api/no-such-endpoint"}) {
    auto r = s.client->Get(path, accepts);
    ASSERT_TRUE(r) << path;
    EXPECT_FALSE(r->has_header("Content-Encoding"))
        << path << " answered with Content-Encoding " << r->get_header_value("Content-Encoding");
    EXPECT_EQ(r->get_header_value("Content-Type").rfind("application/json", 0), 0u) << path;
    EXPECT_TRUE(nlohmann::json::accept(r->body)) << path << ": " << r->body.substr(0, 80);
  }
}

TEST_F(WebAccess, ServesThePageAndTheLiveState) {
  RunningServer s(data_.path(), "127.0.0.1");
  auto page = s.client->Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("/static/live.js"), std::string::npos);
  auto script = s.client->Get("/static/live.js");
  ASSERT_TRUE(script);
  EXPECT_EQ(script->status, 200);
  EXPECT_NE(script->get_header_value("Content-Type").find("javascript"), std::string::npos);

  auto empty = s.client->Get("/api/live");
  ASSERT_TRUE(empty);
  EXPECT_TRUE(nlohmann::json::parse(empty->body)["labels"].is_null());
  auto no_labels = s.client->Get("/api/labels.bin");
  ASSERT_TRUE(no_labels);
  EXPECT_EQ(no_labels->status, 404);

  io::LabelImageMessage labels;
  labels.seq = 41;
  labels.utime = 1000;
  labels.image.width = 4;
  labels.image.height = 3;
  labels.image.labels = {0, 1, 2, 3, 4, 5, 6, 7, 255, 4, 4, 4};
  io::CameraView camera;
  camera.intrinsics = {500, 501, 2, 1.5};
  camera.camera_to_base.translation() = Eigen::Vector3d(0, 0, 1.2);
  labels.camera = camera;
  labels.color_jpeg = {0xFF, 0xD8, 1, 2, 0xFF, 0xD9};
  s.live.onLabels(labels);
  auto pixels = s.client->Get("/api/labels.bin");
  ASSERT_TRUE(pixels);
  EXPECT_EQ(pixels->status, 200);
  EXPECT_EQ(pixels->get_header_value("X-Findmug-Seq"), "41");
  EXPECT_EQ(std::vector<std::uint8_t>(pixels->body.begin(), pixels->body.end()),
            labels.image.labels);
  auto jpeg = s.client->Get("/api/color.jpg");
  ASSERT_TRUE(jpeg);
  EXPECT_EQ(jpeg->status, 200);
  EXPECT_EQ(jpeg->body.size(), 6u);
  const auto state = nlohmann::json::parse(s.client->Get("/api/live")->body);
  EXPECT_EQ(state["labels"]["seq"], 41);
  EXPECT_DOUBLE_EQ(state["labels"]["camera"]["fy"].get<double>(), 501.0);
  EXPECT_DOUBLE_EQ(state["labels"]["camera"]["camera_to_base"][2][3].get<double>(), 1.2);
  EXPECT_EQ(state["label_colors"].size(), static_cast<std::size_t>(kNumLabels));
}

// The semantic map from above: nothing before one came (404, null in /api/live); then the
// raster of floor cells (label plane, confidence plane; row 0 the highest y) with the label
// on top of each column below 2 m, not the ceiling, and its corner and size in /api/live.
TEST_F(WebAccess, ServesTheSemanticMapFromAbove) {
  RunningServer s(data_.path(), "127.0.0.1");
  auto none = s.client->Get("/api/semantic_map.bin");
  ASSERT_TRUE(none);
  EXPECT_EQ(none->status, 404);
  EXPECT_TRUE(nlohmann::json::parse(s.client->Get("/api/live")->body)["semantic_map"].is_null());

  io::SemanticMapMessage map;
  map.seq = 77;
  map.frames = 9;
  map.voxel_size_m = 0.1f;
  // Cells i 3..4, j 7..8: floor everywhere, a table top (k 7) over (4, 8), ceiling (k 25)
  // over all, a wall voxel at 2.2 m over (3, 7).
  for (std::int16_t i = 3; i <= 4; ++i) {
    for (std::int16_t j = 7; j <= 8; ++j) {
      map.voxels.push_back({i, j, 0, 1, 255});
      if (i == 4 && j == 8) map.voxels.push_back({i, j, 7, 4, 128});
      if (i == 3 && j == 7) map.voxels.push_back({i, j, 22, 2, 255});
      map.voxels.push_back({i, j, 25, 3, 255});
    }
  }
  s.live.onSemanticMap(map);
  const auto state = nlohmann::json::parse(s.client->Get("/api/live")->body)["semantic_map"];
  EXPECT_EQ(state["seq"], 77);
  EXPECT_EQ(state["frames"], 9);
  EXPECT_EQ(state["voxels"], map.voxels.size());
  EXPECT_EQ(state["min_i"], 3);
  EXPECT_EQ(state["max_j"], 8);
  EXPECT_EQ(state["width"], 2);
  EXPECT_EQ(state["height"], 2);
  EXPECT_EQ(state["cells"], 4);
  auto raster = s.client->Get("/api/semantic_map.bin");
  ASSERT_TRUE(raster);
  EXPECT_EQ(raster->status, 200);
  EXPECT_EQ(raster->get_header_value("X-Findmug-Seq"), "77");
  EXPECT_EQ(raster->get_header_value("X-Findmug-Width"), "2");
  // Row 0 = j 8: (3, 8) floor, (4, 8) table; row 1 = j 7: floor, floor (the wall is above 2 m).
  const std::vector<std::uint8_t> want = {1, 4, 1, 1, 255, 128, 255, 255};
  EXPECT_EQ(std::vector<std::uint8_t>(raster->body.begin(), raster->body.end()), want);
}

TEST_F(WebAccess, PathsStayInsideTheDataFolders) {
  RunningServer s(data_.path(), "127.0.0.1");
  auto ok = s.client->Get("/api/data/file?root=0&path=rgb/0001.png");
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->status, 200);
  EXPECT_EQ(ok->get_header_value("Content-Type"), "image/png");

  testing::internal::CaptureStderr();
  for (const std::string& path : std::vector<std::string>{
           "../" + outside_.path().filename().string() + "/secret/key.txt", "rgb/../../etc/passwd",
           "%2e%2e/%2e%2e/etc/passwd", "/etc/passwd", "rgb//0001.png", "./rgb/0001.png"}) {
    auto r = s.client->Get("/api/data/file?root=0&path=" + path);
    ASSERT_TRUE(r) << path;
    EXPECT_EQ(r->status, 400) << path << ": " << r->body;
    EXPECT_NE(nlohmann::json::parse(r->body)["error"].get<std::string>(), "") << path;
  }
  // A symlink inside the folder that leads out of it.
  auto escape = s.client->Get("/api/data/file?root=0&path=escape/key.txt");
  ASSERT_TRUE(escape);
  EXPECT_EQ(escape->status, 403) << escape->body;
  EXPECT_EQ(escape->body.find("not for the web"), std::string::npos);
  auto listing = s.client->Get("/api/data/list?root=0&path=escape");
  ASSERT_TRUE(listing);
  EXPECT_EQ(listing->status, 403);
  auto bad_root = s.client->Get("/api/data/list?root=7&path=rgb");
  ASSERT_TRUE(bad_root);
  EXPECT_EQ(bad_root->status, 400);
  // A frame name that is a path is refused before it is joined to anything.
  auto save = s.client->Post("/api/label", labelBody("../../escape/x", 1).dump(),
                             "application/json");
  ASSERT_TRUE(save);
  EXPECT_EQ(save->status, 400);
  const std::string log = s.capturedLog();
  EXPECT_NE(log.find("403 for GET /api/data/file from 127.0.0.1"), std::string::npos) << log;
  EXPECT_NE(log.find("400 for POST /api/label"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(outside_.path() / "x.png"));
}

TEST_F(WebAccess, BodiesOverTheLimitGet413OnEveryEndpoint) {
  RunningServer s(data_.path(), "127.0.0.1");
  const std::string big(kBodyLimit + 1, 'x');
  testing::internal::CaptureStderr();
  for (const std::string path : {"/api/label", "/api/live", "/", "/no/such/endpoint"}) {
    auto r = s.client->Post(path, big, "application/json");
    ASSERT_TRUE(r) << path;
    EXPECT_EQ(r->status, 413) << path << ": " << r->body;
  }
  auto get = s.client->Get("/api/live");  // the server still answers afterwards
  ASSERT_TRUE(get);
  EXPECT_EQ(get->status, 200);
  const std::string log = s.capturedLog();
  EXPECT_NE(log.find("413 for POST /api/label"), std::string::npos) << log;
}

TEST_F(WebAccess, BadJsonGets400) {
  RunningServer s(data_.path(), "127.0.0.1");
  nlohmann::json no_runs = labelBody("0001", 1);
  no_runs.erase("runs");
  for (const std::string& body : std::vector<std::string>{
           std::string("{not json"), std::string("[1, 2]"), std::string(""), no_runs.dump(),
        nlohmann::json(labelBody("0001", 9)).dump(),       // no such label id
        nlohmann::json(labelBody("0001", 1, 11)).dump(),   // too few pixels
        nlohmann::json(labelBody("0001", 1, 13)).dump()}) {  // too many
    auto r = s.client->Post("/api/label", body, "application/json");
    ASSERT_TRUE(r) << body;
    EXPECT_EQ(r->status, 400) << body << ": " << r->body;
  }
  EXPECT_FALSE(fs::exists(data_.path() / "label8/0001.png"));
}

TEST_F(WebAccess, SavesLabelsAndRefusesToOverwriteNewerOnes) {
  RunningServer s(data_.path(), "127.0.0.1");
  nlohmann::json body = labelBody("0001", 4);
  body["runs"] = {{4, 5}, {255, 2}, {1, 5}};
  auto r = s.client->Post("/api/label", body.dump(), "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  const Image<std::uint8_t> written = readPng8((data_.path() / "label8/0001.png").string());
  EXPECT_EQ(written.pixels,
            (std::vector<std::uint8_t>{4, 4, 4, 4, 4, 255, 255, 1, 1, 1, 1, 1}));
  std::ifstream sidecar(data_.path() / "label8/0001.json");
  const auto who = nlohmann::json::parse(sidecar);
  EXPECT_EQ(who["author"], "tester");
  EXPECT_EQ(who["saved_utc"].get<std::string>().size(), 20u);
  const auto mtime = std::stoll(nlohmann::json::parse(r->body)["mtime_ns"].get<std::string>());

  // Without the mtime it was read at, or with an older one: someone saved since.
  body["runs"] = {{2, 12}};
  auto again = s.client->Post("/api/label", body.dump(), "application/json");
  ASSERT_TRUE(again);
  EXPECT_EQ(again->status, 409) << again->body;
  body["base_mtime_ns"] = mtime - 1;
  again = s.client->Post("/api/label", body.dump(), "application/json");
  ASSERT_TRUE(again);
  EXPECT_EQ(again->status, 409);
  EXPECT_EQ(readPng8((data_.path() / "label8/0001.png").string()).pixels, written.pixels);
  body["base_mtime_ns"] = std::to_string(mtime);  // as the page sends it: text
  again = s.client->Post("/api/label", body.dump(), "application/json");
  ASSERT_TRUE(again);
  EXPECT_EQ(again->status, 200) << again->body;
  EXPECT_EQ(readPng8((data_.path() / "label8/0001.png").string()).pixels,
            std::vector<std::uint8_t>(12, 2));
  // And again from the answer of that save (a page saving twice).
  body["base_mtime_ns"] = nlohmann::json::parse(again->body)["mtime_ns"];
  body["runs"] = {{3, 12}};
  again = s.client->Post("/api/label", body.dump(), "application/json");
  ASSERT_TRUE(again);
  EXPECT_EQ(again->status, 200) << again->body;
  // Nanoseconds through a double (what a page using a JSON number would send) are refused.
  body["base_mtime_ns"] = static_cast<double>(
      std::stoll(nlohmann::json::parse(again->body)["mtime_ns"].get<std::string>()) + 1);
  again = s.client->Post("/api/label", body.dump(), "application/json");
  ASSERT_TRUE(again);
  EXPECT_EQ(again->status, 409);
}

TEST_F(WebAccess, AnotherAddressNeedsTheToken) {
  // 127.0.0.2 stands for "an address other than the default": the token is required.
  RunningServer s(data_.path(), "127.0.0.2", kToken);
  testing::internal::CaptureStderr();
  auto none = s.client->Get("/api/live");
  ASSERT_TRUE(none);
  EXPECT_EQ(none->status, 401);
  auto page = s.client->Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 401);
  EXPECT_EQ(page->body.find("live.js"), std::string::npos);
  auto wrong = s.client->Get("/api/live", {{"Authorization", "Bearer " + kToken + "x"}});
  ASSERT_TRUE(wrong);
  EXPECT_EQ(wrong->status, 403);
  auto wrong_same_length =
      s.client->Get("/api/live", {{"Authorization", "Bearer " + std::string(kToken.size(), 'z')}});
  ASSERT_TRUE(wrong_same_length);
  EXPECT_EQ(wrong_same_length->status, 403);
  // Oversized bodies are refused after the token check: no token, 401.
  auto big = s.client->Post("/api/label", std::string(kBodyLimit + 1, 'x'), "application/json");
  ASSERT_TRUE(big);
  EXPECT_EQ(big->status, 401);
  const std::string log = s.capturedLog();
  EXPECT_NE(log.find("401 for GET /api/live from 127.0.0.1"), std::string::npos) << log;

  auto right = s.client->Get("/api/live", RunningServer::authHeaders(kToken));
  ASSERT_TRUE(right);
  EXPECT_EQ(right->status, 200);
  // ?token= (how a person opens the page) sets the cookie the page's own requests carry.
  auto opened = s.client->Get("/?token=" + kToken);
  ASSERT_TRUE(opened);
  EXPECT_EQ(opened->status, 200);
  const std::string cookie = opened->get_header_value("Set-Cookie");
  EXPECT_EQ(cookie.rfind("findmug_token=" + kToken + ";", 0), 0u) << cookie;
  EXPECT_NE(cookie.find("HttpOnly"), std::string::npos);
  auto with_cookie = s.client->Get("/static/live.js", {{"Cookie", "findmug_token=" + kToken}});
  ASSERT_TRUE(with_cookie);
  EXPECT_EQ(with_cookie->status, 200);
}

TEST(WebConfig, TokenFilesAndAddresses) {
  test::TempDir dir;
  const fs::path token = dir.path() / "token";
  std::ofstream(token) << "  " << kToken << "  \nsecond line\n";
  ::chmod(token.c_str(), 0600);
  EXPECT_EQ(web::readTokenFile(token), kToken);
  ::chmod(token.c_str(), 0640);
  EXPECT_THROW(web::readTokenFile(token), Error);  // others may read it
  std::ofstream(dir.path() / "short") << "abc\n";
  ::chmod((dir.path() / "short").c_str(), 0600);
  EXPECT_THROW(web::readTokenFile(dir.path() / "short"), Error);
  EXPECT_THROW(web::readTokenFile(dir.path() / "missing"), Error);

  EXPECT_TRUE(web::isDefaultLoopback("127.0.0.1"));
  EXPECT_FALSE(web::isDefaultLoopback("127.0.0.2"));
  EXPECT_FALSE(web::isDefaultLoopback("0.0.0.0"));
  EXPECT_TRUE(web::isLoopbackAddress("127.0.0.2"));
  EXPECT_FALSE(web::isLoopbackAddress("10.0.0.1"));

  // The web: section read as findmug-web reads it: each value into its WebConfig field.
  web::WebConfig config;
  SettingsSchema schema;
  schema.bind(web::webSettings(), config);
  schema.readYaml("web:\n  port: 9000\n  bind: 192.168.1.5\n", "web.yaml");
  EXPECT_EQ(config.port, 9000);
  EXPECT_EQ(config.bind, "192.168.1.5");
  EXPECT_THROW(schema.applyOverride("web.port=70000"), Error);
  try {
    schema.readYaml("web:\n  prot: 1\n", "web.yaml");
    ADD_FAILURE() << "web.prot accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("web.yaml: line 2: unknown setting 'web.prot'"),
              std::string::npos)
        << e.what();
  }
}

// Both directions: every key findmug-web knows is in its shipped file, and every value
// there is the built-in default.
TEST(WebConfig, ShippedFileIsValidAndDocumentsEveryKey) {
  const fs::path shipped = test::sourceDir() / "clients/web/findmug-web.yaml";
  web::WebConfig read;
  SettingsSchema schema;
  schema.bind(web::webSettings(), read);
  schema.readFile(shipped.string());
  const web::WebConfig defaults;
  EXPECT_EQ(web::webSettings().values(read), web::webSettings().values(defaults))
      << shipped << " must hold the built-in defaults";
  std::ifstream in(shipped);
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  for (const auto& setting : web::webSettings().settings()) {
    const std::string name = setting.key.substr(setting.key.find('.') + 1);
    EXPECT_NE(text.find("\n  " + name + ":"), std::string::npos)
        << setting.key << " not in " << shipped;
  }
}

// The program refuses to serve another address than the default loopback one without a
// token, and a token file others may read.
TEST(WebProgram, AnotherAddressWithoutATokenIsRefusedAtStart) {
  test::TempDir dir;
  const std::string exe = FINDMUG_WEB_EXE;
  const std::string common = " --lcm-url memq:// --static-dir " +
                             (test::sourceDir() / "clients/web/static").string() + " > " +
                             dir.str("out.txt") + " 2>&1";
  auto run = [&](const std::string& flags) {
    const int status = std::system((exe + " " + flags + common).c_str());
    std::ifstream in(dir.path() / "out.txt");
    std::stringstream text;
    text << in.rdbuf();
    return std::make_pair(WEXITSTATUS(status), text.str());
  };
  auto [code, out] = run("--bind 127.0.0.2 --port 18097");
  EXPECT_EQ(code, 2) << out;
  EXPECT_NE(out.find("needs an access token"), std::string::npos) << out;
  std::ofstream(dir.path() / "token") << kToken << "\n";
  ::chmod((dir.path() / "token").c_str(), 0644);
  std::tie(code, out) = run("--bind 127.0.0.2 --port 18097 --token-file " + dir.str("token"));
  EXPECT_EQ(code, 2) << out;
  EXPECT_NE(out.find("readable by its owner only"), std::string::npos) << out;
  std::tie(code, out) = run("--data " + dir.str("no-such-folder") + " --port 18097");
  EXPECT_EQ(code, 1) << out;
  EXPECT_NE(out.find("no-such-folder: not a folder"), std::string::npos) << out;
}

// findmug-web reads a shared config file with every program's real tables: an unknown key
// of its own section, a typo in findmugd's, or a section no program has stops it at start,
// naming the setting; before it listens on anything.
TEST(WebProgram, UnknownSettingsAreRefusedAtStartNamingTheKey) {
  test::TempDir dir;
  const std::string exe = FINDMUG_WEB_EXE;
  auto run = [&](const std::string& yaml) {
    std::ofstream(dir.path() / "web.yaml") << yaml;
    const std::string command = exe + " --lcm-url memq:// --port 18098 --config " +
                                dir.str("web.yaml") + " > " + dir.str("out.txt") + " 2>&1";
    const int status = std::system(command.c_str());
    std::ifstream in(dir.path() / "out.txt");
    std::stringstream text;
    text << in.rdbuf();
    return std::make_pair(WEXITSTATUS(status), text.str());
  };
  auto [code, out] = run("web:\n  port: 18098\n  prot: 1\n");
  EXPECT_EQ(code, 2) << out;
  EXPECT_NE(out.find("web.yaml: line 3: unknown setting 'web.prot' (web keys: "), std::string::npos)
      << out;
  std::tie(code, out) = run("daemon:\n  wokers: 2\n");
  EXPECT_EQ(code, 2) << out;
  EXPECT_NE(out.find("unknown setting 'daemon.wokers' (daemon keys: "), std::string::npos) << out;
  std::tie(code, out) = run("clients:\n  viewer_scale: 2\n");
  EXPECT_EQ(code, 2) << out;
  EXPECT_NE(out.find("unknown setting 'clients.viewer_scale': no section 'clients'"),
            std::string::npos)
      << out;
}
