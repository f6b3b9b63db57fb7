// findmug-nav-client and findmug-label-viewer run as processes on an LCM log
// file the test writes (file://LOG?mode=r&speed=0: no network traffic), with
// tables, label images, a colour frame and corrupt messages in it.
//
//   nav-client    positions in visiting order (checked against
//                 findmug::visitingOrder AND against brute force over every
//                 order, i.e. the geometry), base or map frame, unreachable
//                 positions with their reason, the objects on each table (in
//                 the same frame, the corrupt objects message skipped), JSON
//                 lines that parse, exit 0 at the end of the log, exit 2 on
//                 bad flags;
//   label-viewer  overlay PNGs in the paper's palette (pixel colours against
//                 kLabelColors, blended with the colour frame of the same
//                 utime), the console summary, the corrupt message skipped
//                 with its reason, exit 2 on bad flags; the semantic map drawn
//                 top-down (each floor cell the label on top, faded by
//                 confidence, ceiling and voxels above 2 m left out, the table
//                 map's hulls and the robot over it).
//   replay        findmug-replay --robot-pose: the pose with each frame's utime.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <numeric>
#include <sstream>
#include <thread>
#include <variant>

#include "daemon_test_support.hpp"
#include "findmug/common/error.hpp"
#include "findmug/frame/image_io.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/lcm_codec_objects.hpp"
#include "findmug/io/semantic_map_codec.hpp"
#include "findmug/labels/labels.hpp"
#include "findmug/tables/tables.hpp"
#include "lcm_samples.hpp"
#include "test_data.hpp"
#include "semantic_map_picture.hpp"
#include "findmug/map/visiting_order.hpp"

extern char** environ;

namespace findmug {
namespace {

using findmug::test::TempDir;
using Log = std::vector<daemon::test::LogMessage>;

// ---- running a client -----------------------------------------------------------------

struct ProcessResult {
  int exit_code = -1;
  std::string out, err;
};

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

// Runs `exe` with `args`, stdout and stderr to files; kills it after 60 s
// (a hang is a failure, not a timing measurement).
ProcessResult run(const std::string& exe, const std::vector<std::string>& args,
                  const TempDir& tmp) {
  const std::string out_path = tmp.str("stdout.txt"), err_path = tmp.str("stderr.txt");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out_path.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err_path.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<std::string> argv_strings = {exe};
  argv_strings.insert(argv_strings.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_strings) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, exe.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ProcessResult result;
  if (rc != 0) {
    ADD_FAILURE() << "cannot start " << exe << ": " << std::strerror(rc);
    return result;
  }
  int status = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (waitpid(pid, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      ADD_FAILURE() << exe << " did not exit within 60 s";
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  result.out = readFile(out_path);
  result.err = readFile(err_path);
  return result;
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) out.push_back(line);
  return out;
}

std::string replayUrl(const std::string& log) { return "file://" + log + "?mode=r&speed=0"; }

// ---- a small strict JSON reader (enough for the nav client's lines) ---------------

struct Json {
  std::variant<std::nullptr_t, bool, double, std::string, std::vector<Json>,
               std::map<std::string, Json>>
      value;
  const Json& operator[](const std::string& key) const {
    const auto& object = std::get<std::map<std::string, Json>>(value);
    const auto it = object.find(key);
    if (it == object.end()) throw std::runtime_error("JSON: no key " + key);
    return it->second;
  }
  const std::vector<Json>& array() const { return std::get<std::vector<Json>>(value); }
  double number() const { return std::get<double>(value); }
  const std::string& string() const { return std::get<std::string>(value); }
};

class JsonParser {
 public:
  explicit JsonParser(const std::string& text) : text_(text) {}
  Json parseDocument() {
    Json v = parseValue();
    skipSpace();
    if (pos_ != text_.size()) fail("trailing characters");
    return v;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error("JSON: " + what + " at offset " + std::to_string(pos_) + " in " +
                             text_);
  }
  void skipSpace() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
  }
  void expect(char c) {
    skipSpace();
    if (pos_ >= text_.size() || text_[pos_] != c) fail(std::string("expected '") + c + "'");
    ++pos_;
  }
  bool consume(const std::string& word) {
    if (text_.compare(pos_, word.size(), word) != 0) return false;
    pos_ += word.size();
    return true;
  }
  std::string parseString() {
    expect('"');
    std::string out;
    while (pos_ < text_.size() && text_[pos_] != '"') {
      char c = text_[pos_++];
      if (static_cast<unsigned char>(c) < 0x20) fail("control character in a string");
      if (c == '\\') {
        if (pos_ >= text_.size()) fail("unterminated escape");
        const char e = text_[pos_++];
        switch (e) {
          case '"':
            c = '"';
            break;
          case '\\':
            c = '\\';
            break;
          case '/':
            c = '/';
            break;
          case 'n':
            c = '\n';
            break;
          case 't':
            c = '\t';
            break;
          case 'r':
            c = '\r';
            break;
          case 'b':
            c = '\b';
            break;
          case 'f':
            c = '\f';
            break;
          case 'u': {
            if (pos_ + 4 > text_.size()) fail("short \\u escape");
            c = static_cast<char>(std::stoi(text_.substr(pos_, 4), nullptr, 16));
            pos_ += 4;
            break;
          }
          default:
            fail("bad escape");
        }
      }
      out += c;
    }
    if (pos_ >= text_.size()) fail("unterminated string");
    ++pos_;
    return out;
  }
  Json parseValue() {
    skipSpace();
    if (pos_ >= text_.size()) fail("unexpected end");
    const char c = text_[pos_];
    if (c == '{') {
      ++pos_;
      std::map<std::string, Json> object;
      skipSpace();
      if (pos_ < text_.size() && text_[pos_] == '}') {
        ++pos_;
        return Json{object};
      }
      for (;;) {
        skipSpace();
        std::string key = parseString();
        expect(':');
        if (!object.emplace(key, parseValue()).second) fail("duplicate key " + key);
        skipSpace();
        if (pos_ < text_.size() && text_[pos_] == ',') {
          ++pos_;
          continue;
        }
        expect('}');
        return Json{object};
      }
    }
    if (c == '[') {
      ++pos_;
      std::vector<Json> array;
      skipSpace();
      if (pos_ < text_.size() && text_[pos_] == ']') {
        ++pos_;
        return Json{array};
      }
      for (;;) {
        array.push_back(parseValue());
        skipSpace();
        if (pos_ < text_.size() && text_[pos_] == ',') {
          ++pos_;
          continue;
        }
        expect(']');
        return Json{array};
      }
    }
    if (c == '"') return Json{parseString()};
    if (consume("true")) return Json{true};
    if (consume("false")) return Json{false};
    if (consume("null")) return Json{nullptr};
    const std::size_t start = pos_;
    if (text_[pos_] == '-') ++pos_;
    while (pos_ < text_.size() &&
           (std::isdigit(static_cast<unsigned char>(text_[pos_])) || text_[pos_] == '.' ||
            text_[pos_] == 'e' || text_[pos_] == 'E' || text_[pos_] == '+' || text_[pos_] == '-')) {
      ++pos_;
    }
    if (pos_ == start) fail("unexpected character");
    std::size_t used = 0;
    const std::string number = text_.substr(start, pos_ - start);
    const double v = std::stod(number, &used);
    if (used != number.size()) fail("bad number " + number);
    return Json{v};
  }

  const std::string& text_;
  std::size_t pos_ = 0;
};

Json parseJson(const std::string& text) { return JsonParser(text).parseDocument(); }

// ---- the nav client -----------------------------------------------------------------------

SearchPosition position(float x, float y, float yaw, bool reachable = true,
                        const std::string& reason = "") {
  SearchPosition p;
  p.xy = Eigen::Vector2f(x, y);
  p.yaw = yaw;
  p.reachable = reachable;
  p.reason = reason;
  return p;
}

TableCluster table(int id, Eigen::Vector2f center, std::vector<SearchPosition> positions) {
  TableCluster t;
  t.id = id;
  t.centroid = Eigen::Vector3f(center.x(), center.y(), 0.74f);
  t.center = center;
  t.top_height = 0.75f;
  t.extents = Eigen::Vector2f(0.6f, 0.4f);
  t.hull = {center + Eigen::Vector2f(-0.6f, -0.4f), center + Eigen::Vector2f(0.6f, -0.4f),
            center + Eigen::Vector2f(0.6f, 0.4f), center + Eigen::Vector2f(-0.6f, 0.4f)};
  t.point_count = 2000;
  t.mean_confidence = 0.9f;
  t.search_positions = std::move(positions);
  return t;
}

// Two frames' tables: one without a map pose, one with. Positions are placed
// so that the shortest tour is not the listed order.
io::TablesMessage baseFrameTables() {
  io::TablesMessage m;
  m.utime = 1'000'000;
  m.seq = 1;
  m.tables.push_back(table(0, {3.0f, 0.0f},
                           {position(3.0f, -0.9f, 1.57f), position(3.0f, 0.9f, -1.57f),
                            position(2.2f, 0.0f, 0.0f, false, "obstacle within robot radius")}));
  m.tables.push_back(table(
      1, {1.5f, -1.5f},
      {position(1.5f, -2.4f, 1.57f), position(0.6f, -1.5f, 0.0f), position(1.5f, -0.6f, -1.57f)}));
  return m;
}

io::TablesMessage mapFrameTables() {
  io::TablesMessage m = baseFrameTables();
  m.utime = 3'000'000;
  m.seq = 3;
  m.tables[1].search_positions[2].reachable = false;
  m.tables[1].search_positions[2].reason = "no observed floor";
  m.map_pose = io::RobotPose{2'999'000, {10.0, -2.0, M_PI / 2}};
  return m;
}

// One candidate standing on table `table` of `tables`, at `centroid` (base frame), cut off at
// the image border, encoded with the tables' map pose as findmugd does.
std::vector<std::uint8_t> objectOn(const io::TablesMessage& tables, int table,
                                   const Eigen::Vector3f& centroid, int bad_table_id = -1) {
  TableObjectDetection d;
  TableObject o;
  o.table = table;
  o.centroid = centroid;
  o.height_above_top = 0.12f;
  o.extents = Eigen::Vector2f(0.05f, 0.04f);
  o.center = centroid.head<2>();
  o.point_count = 95;
  o.mean_rgb = Eigen::Vector3f(200, 20, 10);
  o.colour_histogram[0] = 1.0f;
  o.truncation = kTruncatedBorder;
  d.objects = {o};
  findmug_lcm::objects_t m =
      io::encodeObjects(tables.utime, tables.seq, d, tables.tables, tables.map_pose, {});
  if (bad_table_id >= 0) m.objects[0].table_id = bad_table_id;
  return io::encodeMessage(m);
}

// What the client should list for a message: (table, x, y) of the
// reachable positions in visiting order, in the requested frame.
struct Stop {
  int table = 0;
  Eigen::Vector2f xy;
};

std::vector<Stop> expectedTour(const io::TablesMessage& message, bool map_frame,
                               Eigen::Vector2f* robot) {
  // Decode what was encoded: exactly the numbers the client sees.
  const auto bytes = io::encodeMessage(io::encodeTables(message));
  const io::TablesMessage m = io::decodeTables(bytes.data(), bytes.size(), "T");
  *robot = map_frame ? Eigen::Vector2f(static_cast<float>(m.map_pose->pose.x),
                                       static_cast<float>(m.map_pose->pose.y))
                     : Eigen::Vector2f::Zero();
  std::vector<Stop> reachable;
  for (std::size_t t = 0; t < m.tables.size(); ++t) {
    const auto& positions =
        map_frame ? m.map_tables[t].search_positions : m.tables[t].search_positions;
    for (const auto& p : positions) {
      if (p.reachable) reachable.push_back({m.tables[t].id, p.xy});
    }
  }
  std::vector<Eigen::Vector2f> points;
  for (const auto& s : reachable) points.push_back(s.xy);
  std::vector<Stop> tour;
  for (int i : visitingOrder(*robot, points))
    tour.push_back(reachable[static_cast<std::size_t>(i)]);
  return tour;
}

double pathLength(const Eigen::Vector2f& start, const std::vector<Eigen::Vector2f>& stops) {
  double total = 0.0;
  Eigen::Vector2f at = start;
  for (const auto& s : stops) {
    total += (s - at).norm();
    at = s;
  }
  return total;
}

// The shortest open path over `stops` from `start`, by trying every order.
double shortestByBruteForce(const Eigen::Vector2f& start, std::vector<Eigen::Vector2f> stops) {
  std::vector<int> order(stops.size());
  std::iota(order.begin(), order.end(), 0);
  double best = std::numeric_limits<double>::infinity();
  do {
    std::vector<Eigen::Vector2f> path;
    for (int i : order) path.push_back(stops[static_cast<std::size_t>(i)]);
    best = std::min(best, pathLength(start, path));
  } while (std::next_permutation(order.begin(), order.end()));
  return best;
}

std::vector<std::uint8_t> truncated(std::vector<std::uint8_t> bytes) {
  bytes.resize(bytes.size() / 2);
  return bytes;
}

// The log both clients read: tables (base frame, corrupt, map frame), a
// colour frame, label images (good, corrupt, good with the colour frame).
struct ClientLog {
  TempDir dir;
  std::string path;
  io::LabelImageMessage labels1, labels3;
  RgbdFrame color3;
};

LabelImage labelBlocks(int width, int height) {
  LabelImage image;
  image.width = width;
  image.height = height;
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      // Floor at the bottom half, wall/table/chair columns above, one void pixel per row.
      std::uint8_t id = v >= height / 2     ? static_cast<std::uint8_t>(Label::Floor)
                        : u < width / 3     ? static_cast<std::uint8_t>(Label::Wall)
                        : u < 2 * width / 3 ? static_cast<std::uint8_t>(Label::Table)
                                            : static_cast<std::uint8_t>(Label::Chair);
      if (u == width - 1) id = kVoidLabel;
      image.labels.push_back(id);
      image.confidence.push_back(id == kVoidLabel ? 0.0f : 0.5f);
    }
  }
  return image;
}

const ClientLog& clientLog() {
  static const ClientLog* log = [] {
    auto* l = new ClientLog;
    Log messages;
    const std::string tables_channel(io::kTablesChannel), labels_channel(io::kLabelsChannel);
    const std::string objects_channel(io::kObjectsChannel);
    messages.push_back({tables_channel, io::encodeMessage(io::encodeTables(baseFrameTables()))});
    messages.push_back({objects_channel, objectOn(baseFrameTables(), 1, {1.5f, -1.5f, 0.85f})});
    messages.push_back(
        {tables_channel, truncated(io::encodeMessage(io::encodeTables(baseFrameTables())))});
    // A table id beyond the frame's two tables: well-formed bytes, bad content.
    messages.push_back({objects_channel, objectOn(baseFrameTables(), 1, {1.5f, -1.5f, 0.85f}, 2)});
    messages.push_back({tables_channel, io::encodeMessage(io::encodeTables(mapFrameTables()))});
    messages.push_back({objects_channel, objectOn(mapFrameTables(), 0, {3.0f, 0.1f, 0.84f})});

    l->labels1.image = labelBlocks(12, 8);
    l->labels1.utime = 1'000'000;
    l->labels1.seq = 1;
    l->labels1.latency_us = 250'000;
    messages.push_back({labels_channel, io::encodeMessage(io::encodeLabelImage(l->labels1))});
    // A label id no class has: a well-formed message with bad content.
    findmug_lcm::label_image_t bad = io::encodeLabelImage(l->labels1, false);
    bad.seq = 2;
    bad.compression = findmug_lcm::label_image_t::COMPRESSION_NONE;
    bad.labels_data.assign(l->labels1.image.labels.begin(), l->labels1.image.labels.end());
    bad.labels_data[17] = 42;
    bad.labels_size = static_cast<std::int32_t>(bad.labels_data.size());
    messages.push_back({labels_channel, io::encodeMessage(bad)});

    l->color3.width = 12;
    l->color3.height = 8;
    l->color3.intrinsics = {10.0, 10.0, 5.5, 3.5};
    l->color3.utime = 3'000'000;
    l->color3.seq = 3;
    l->color3.source = "test";
    for (int i = 0; i < 12 * 8; ++i) {
      l->color3.depth_mm.push_back(1500);
      l->color3.rgb.push_back(Rgb8{static_cast<std::uint8_t>(i * 2),
                                   static_cast<std::uint8_t>(200 - i),
                                   static_cast<std::uint8_t>(100 + i)});
    }
    io::RgbdEncodeOptions lossless;
    lossless.color = io::ColorCompression::None;
    messages.push_back({std::string(io::kRgbdChannel),
                        io::encodeMessage(io::encodeRgbdFrame(l->color3, lossless))});
    l->labels3 = l->labels1;
    l->labels3.utime = 3'000'000;
    l->labels3.seq = 3;
    messages.push_back({labels_channel, io::encodeMessage(io::encodeLabelImage(l->labels3))});

    l->path = l->dir.str("clients.lcmlog");
    daemon::test::writeLcmLog(l->path, messages);
    return l;
  }();
  return *log;
}

// "  %2zu. table %d  x %7.2f  y %7.2f  yaw ..." lines of the text output.
std::vector<Stop> parseTourLines(const std::vector<std::string>& block) {
  std::vector<Stop> out;
  for (const std::string& line : block) {
    int order = 0, table = 0;
    float x = 0, y = 0;
    if (std::sscanf(line.c_str(), " %d. table %d x %f y %f", &order, &table, &x, &y) == 4) {
      EXPECT_EQ(order, static_cast<int>(out.size()) + 1) << line;
      out.push_back({table, Eigen::Vector2f(x, y)});
    }
  }
  return out;
}

// Splits the text output into one block of lines per "tables seq" header.
std::map<int, std::vector<std::string>> blocksBySeq(const std::string& out) {
  std::map<int, std::vector<std::string>> blocks;
  int seq = -1;
  for (const std::string& line : lines(out)) {
    int s = 0;
    if (std::sscanf(line.c_str(), "tables seq %d", &s) == 1) seq = s;
    blocks[seq].push_back(line);
  }
  return blocks;
}

void expectTour(const std::vector<Stop>& got, const io::TablesMessage& message, bool map_frame,
                double tolerance) {
  Eigen::Vector2f robot;
  const std::vector<Stop> want = expectedTour(message, map_frame, &robot);
  ASSERT_EQ(got.size(), want.size());
  std::vector<Eigen::Vector2f> printed;
  for (std::size_t k = 0; k < want.size(); ++k) {
    EXPECT_EQ(got[k].table, want[k].table) << "stop " << k + 1;
    EXPECT_NEAR(got[k].xy.x(), want[k].xy.x(), tolerance) << "stop " << k + 1;
    EXPECT_NEAR(got[k].xy.y(), want[k].xy.y(), tolerance) << "stop " << k + 1;
    printed.push_back(want[k].xy);
  }
  // The geometry: the printed order is a shortest tour from the robot.
  std::vector<Eigen::Vector2f> stops = printed;
  EXPECT_NEAR(pathLength(robot, printed), shortestByBruteForce(robot, stops), 1e-4);
}

TEST(NavClient, PrintsReachablePositionsInVisitingOrderAndSkipsTheCorruptMessage) {
  const ClientLog& log = clientLog();
  TempDir tmp;
  const ProcessResult r = run(FINDMUG_NAV_CLIENT_EXE, {"--lcm-url", replayUrl(log.path)}, tmp);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const auto blocks = blocksBySeq(r.out);
  ASSERT_TRUE(blocks.count(1) && blocks.count(3)) << r.out;
  EXPECT_EQ(blocks.size(), 2u) << "the corrupt message must not be printed:\n" << r.out;

  // Without a map pose: base frame, robot at the origin.
  EXPECT_NE(blocks.at(1)[0].find("2 tables, 6 positions (5 reachable), base frame"),
            std::string::npos)
      << blocks.at(1)[0];
  expectTour(parseTourLines(blocks.at(1)), baseFrameTables(), false, 0.006);
  // With one (auto): map frame, robot at its map pose.
  EXPECT_NE(blocks.at(3)[0].find("(4 reachable), map frame, robot at (10.00, -2.00)"),
            std::string::npos)
      << blocks.at(3)[0];
  expectTour(parseTourLines(blocks.at(3)), mapFrameTables(), true, 0.006);
  // Unreachable positions are listed with their reason.
  int unreachable = 0;
  for (const auto& line : blocks.at(3)) {
    if (line.find("unreachable: ") == std::string::npos) continue;
    ++unreachable;
    EXPECT_TRUE(line.find("obstacle within robot radius") != std::string::npos ||
                line.find("no observed floor") != std::string::npos)
        << line;
  }
  EXPECT_EQ(unreachable, 2);
  // The corrupt message: reported with the decoder's reason, then skipped.
  EXPECT_NE(r.err.find("skipping bad message: FINDMUG_TABLES: tables_t"), std::string::npos)
      << r.err;
}

// The objects message after each tables message: its candidates, in the frame the tables
// are printed in (map: the robot at (10, -2) facing map +y turns base (3.0, 0.1) into
// (9.9, 1.0)); the corrupt one reported and skipped.
TEST(NavClient, PrintsTheObjectsOnEachTable) {
  const ClientLog& log = clientLog();
  TempDir tmp;
  const ProcessResult r = run(FINDMUG_NAV_CLIENT_EXE, {"--lcm-url", replayUrl(log.path)}, tmp);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  std::vector<std::string> headers, objects;
  for (const std::string& line : lines(r.out)) {
    if (line.rfind("objects seq", 0) == 0) headers.push_back(line);
    if (line.rfind("   o  table", 0) == 0) objects.push_back(line);
  }
  ASSERT_EQ(headers.size(), 2u) << r.out;
  ASSERT_EQ(objects.size(), 2u) << r.out;
  EXPECT_NE(headers[0].find("objects seq 1 utime 1000000: 1 objects on 2 tables, base frame"),
            std::string::npos)
      << headers[0];
  EXPECT_NE(headers[1].find("objects seq 3 utime 3000000: 1 objects on 2 tables, map frame"),
            std::string::npos)
      << headers[1];
  int table = -1, id = -1;
  float x = 0, y = 0, z = 0;
  ASSERT_EQ(std::sscanf(objects[0].c_str(), "   o  table %d  object %d  x %f  y %f  z %f", &table,
                        &id, &x, &y, &z),
            5)
      << objects[0];
  EXPECT_EQ(table, 1);
  EXPECT_NEAR(x, 1.5f, 0.006f);
  EXPECT_NEAR(y, -1.5f, 0.006f);
  EXPECT_NEAR(z, 0.85f, 0.006f);
  EXPECT_NE(objects[0].find("height  0.12 m"), std::string::npos) << objects[0];
  EXPECT_NE(objects[0].find("cut off: border"), std::string::npos) << objects[0];
  ASSERT_EQ(std::sscanf(objects[1].c_str(), "   o  table %d  object %d  x %f  y %f  z %f", &table,
                        &id, &x, &y, &z),
            5)
      << objects[1];
  EXPECT_EQ(table, 0);
  EXPECT_NEAR(x, 9.9f, 0.006f);
  EXPECT_NEAR(y, 1.0f, 0.006f);
  EXPECT_NE(r.err.find("skipping bad message: FINDMUG_OBJECTS: objects_t.objects[0].table_id"),
            std::string::npos)
      << r.err;
}

// With --map: the object map's entries with their stable ids, names, scores and sightings.
TEST(NavClient, MapListsTheObjectMapWithNamesAndSightings) {
  TempDir tmp;
  const std::string log = tmp.str("object_map.lcmlog");
  findmug_lcm::objects_t map = test::sampleObjectMap();
  map.num_tables = 1;
  map.objects[0].table_id = 0;
  daemon::test::writeLcmLog(log, {{std::string(io::kObjectMapChannel), io::encodeMessage(map)}});
  const ProcessResult r =
      run(FINDMUG_NAV_CLIENT_EXE, {"--lcm-url", replayUrl(log), "--map"}, tmp);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("object map seq 9 utime 5550001: 2 objects on 1 tables, map frame"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("mug (score 0.80)  seen 12 times, last utime 5550001"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("table -1  object 2"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("(not named)  seen 12 times, last utime 4550001"), std::string::npos)
      << r.out;
  const ProcessResult json =
      run(FINDMUG_NAV_CLIENT_EXE, {"--lcm-url", replayUrl(log), "--map", "--json"}, tmp);
  EXPECT_EQ(json.exit_code, 0) << json.err;
  EXPECT_NE(json.out.find("\"object_map\":true"), std::string::npos) << json.out;
  EXPECT_NE(json.out.find("\"name\":\"mug\",\"score\":0.800,\"sightings\":12"), std::string::npos)
      << json.out;
}

TEST(NavClient, BaseFrameIsUsedWhenAskedEvenWithAMapPose) {
  const ClientLog& log = clientLog();
  TempDir tmp;
  const ProcessResult r =
      run(FINDMUG_NAV_CLIENT_EXE, {"--lcm-url", replayUrl(log.path), "--frame", "base"}, tmp);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const auto blocks = blocksBySeq(r.out);
  ASSERT_TRUE(blocks.count(3)) << r.out;
  EXPECT_NE(blocks.at(3)[0].find("base frame, robot at (0.00, 0.00)"), std::string::npos)
      << blocks.at(3)[0];
  expectTour(parseTourLines(blocks.at(3)), mapFrameTables(), false, 0.006);
}

TEST(NavClient, JsonLinesParseAndCarryTheTour) {
  const ClientLog& log = clientLog();
  TempDir tmp;
  const ProcessResult r =
      run(FINDMUG_NAV_CLIENT_EXE, {"--lcm-url", replayUrl(log.path), "--json"}, tmp);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  // One object per good message, nothing else on stdout: tables lines carry "tour", objects
  // lines "objects".
  std::vector<std::string> out, objects;
  for (const std::string& line : lines(r.out)) {
    (line.find("\"objects\":") != std::string::npos ? objects : out).push_back(line);
  }
  ASSERT_EQ(out.size(), 2u) << r.out;
  ASSERT_EQ(objects.size(), 2u) << r.out;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    Json j;
    ASSERT_NO_THROW(j = parseJson(objects[i])) << objects[i];
    EXPECT_EQ(j["seq"].number(), i == 0 ? 1.0 : 3.0);
    EXPECT_EQ(j["frame"].string(), i == 0 ? "base" : "map");
    ASSERT_EQ(j["objects"].array().size(), 1u);
    const Json& o = j["objects"].array()[0];
    EXPECT_EQ(o["table"].number(), i == 0 ? 1.0 : 0.0);
    EXPECT_NEAR(o["x"].number(), i == 0 ? 1.5 : 9.9, 0.0006);
    EXPECT_NEAR(o["y"].number(), i == 0 ? -1.5 : 1.0, 0.0006);
    ASSERT_EQ(o["truncated"].array().size(), 1u);
    EXPECT_EQ(o["truncated"].array()[0].string(), "border");
  }
  const io::TablesMessage expected[] = {baseFrameTables(), mapFrameTables()};
  for (std::size_t i = 0; i < out.size(); ++i) {
    Json j;
    ASSERT_NO_THROW(j = parseJson(out[i])) << out[i];
    const bool map_frame = i == 1;
    EXPECT_EQ(j["seq"].number(), static_cast<double>(expected[i].seq));
    EXPECT_EQ(j["frame"].string(), map_frame ? "map" : "base");
    EXPECT_EQ(j["tables"].number(), 2.0);
    std::vector<Stop> tour;
    double previous_path = 0.0;
    for (const Json& stop : j["tour"].array()) {
      EXPECT_EQ(stop["order"].number(), static_cast<double>(tour.size() + 1));
      tour.push_back({static_cast<int>(stop["table"].number()),
                      Eigen::Vector2f(static_cast<float>(stop["x"].number()),
                                      static_cast<float>(stop["y"].number()))});
      EXPECT_GE(stop["path_m"].number(), previous_path);  // cumulative
      previous_path = stop["path_m"].number();
    }
    expectTour(tour, expected[i], map_frame, 0.0006);
    for (const Json& u : j["unreachable"].array()) EXPECT_FALSE(u["reason"].string().empty());
  }
  EXPECT_EQ(parseJson(out[1])["unreachable"].array().size(), 2u);
}

TEST(NavClient, CountStopsEarly) {
  const ClientLog& log = clientLog();
  TempDir tmp;
  const ProcessResult r = run(FINDMUG_NAV_CLIENT_EXE,
                              {"--lcm-url", replayUrl(log.path), "--json", "--count", "1"}, tmp);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(lines(r.out).size(), 1u) << r.out;
}

TEST(NavClient, BadFlagsExitWithCode2AndAMessage) {
  TempDir tmp;
  for (const std::vector<std::string>& args :
       std::vector<std::vector<std::string>>{{"--frame", "sideways"},
                                             {"--count", "0"},
                                             {"--count", "many"},
                                             {"--no-such-flag"},
                                             {"--lcm-url"},
                                             {"--channel-suffix", "bad suffix"}}) {
    const ProcessResult r = run(FINDMUG_NAV_CLIENT_EXE, args, tmp);
    EXPECT_EQ(r.exit_code, 2) << args[0] << ": " << r.err;
    EXPECT_NE(r.err.find("findmug-nav-client: "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("--help"), std::string::npos) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
}

// ---- the label viewer -----------------------------------------------------------------------

// The top-left w x h of an image (the label viewer's overlays carry a legend panel).
Image<Rgb8> cropped(const Image<Rgb8>& image, int w, int h) {
  Image<Rgb8> out{w, h, {}};
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) out.pixels.push_back(image.pixels[y * image.width + x]);
  }
  return out;
}

TEST(LabelViewer, WritesPaletteOverlaysAndSummariesAndSkipsTheCorruptImage) {
  const ClientLog& log = clientLog();
  TempDir tmp;
  std::filesystem::create_directories(tmp.path() / "png");
  const ProcessResult r =
      run(FINDMUG_LABEL_VIEWER_EXE,
          {"--lcm-url", replayUrl(log.path), "--out", tmp.str("png"), "--alpha", "0.5"}, tmp);
  EXPECT_EQ(r.exit_code, 0) << r.err;

  // Console: one summary per good image, shares of each class.
  const auto out = lines(r.out);
  ASSERT_EQ(out.size(), 2u) << r.out;
  // 12x8: bottom half floor (48 px), top rows: wall 4, table 4, chair 3 columns
  // (x4 rows) minus the void last column (8 px).
  for (const char* share : {"labels seq 1 utime 1000000 12x8 latency 250.0 ms:", "floor 45.8%",
                            "wall 16.7%", "table 16.7%", "chair 12.5%", "void 8.3%",
                            "mean confidence 0.50", "palette (no colour frame)"}) {
    EXPECT_NE(out[0].find(share), std::string::npos) << share << " not in: " << out[0];
  }
  EXPECT_NE(out[1].find("labels seq 3"), std::string::npos) << out[1];
  EXPECT_NE(out[1].find("overlay "), std::string::npos) << out[1];
  // The corrupt image: skipped with the decoder's reason, no PNG.
  EXPECT_NE(r.err.find("skipping bad label image"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("label id 42"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(tmp.path() / "png" / "labels_00000002.png"));

  // seq 1, no colour frame: the plain palette (void black), with the legend panel
  // (150 px) to its right; the label pixels are the top-left 12x8.
  const Image<Rgb8> with_legend = readPngRgb(tmp.str("png/labels_00000001.png"));
  ASSERT_EQ(with_legend.width, 12 + 150);
  ASSERT_GE(with_legend.height, 8);
  const Image<Rgb8> palette = cropped(with_legend, 12, 8);
  // The legend's swatches: one per class in the palette, top to bottom, 22 px apart.
  for (int id = 0; id < kNumLabels; ++id) {
    const Rgb8 swatch =
        with_legend
            .pixels[static_cast<std::size_t>(34 + 22 * id + 7) * with_legend.width + 12 + 10 + 8];
    EXPECT_TRUE(swatch == kLabelColors[id]) << "legend swatch " << id;
  }
  for (std::size_t i = 0; i < palette.pixels.size(); ++i) {
    const std::uint8_t id = log.labels1.image.labels[i];
    const Rgb8 want = id == kVoidLabel ? Rgb8{0, 0, 0} : kLabelColors[id];
    const Rgb8 got = palette.pixels[i];
    ASSERT_TRUE(got.r == want.r && got.g == want.g && got.b == want.b)
        << "pixel " << i << " label " << int(id) << ": got " << int(got.r) << "," << int(got.g)
        << "," << int(got.b);
  }
  // The paper's colours for the classes in the image (floor red, wall blue, table green).
  EXPECT_EQ(palette.pixels[12 * 7].r, 220);
  EXPECT_EQ(palette.pixels[0].b, 220);
  EXPECT_EQ(palette.pixels[5].g, 180);

  // seq 3, with the colour frame of the same utime: half label colour, half image.
  const Image<Rgb8> overlay = cropped(readPngRgb(tmp.str("png/labels_00000003.png")), 12, 8);
  ASSERT_EQ(overlay.pixels.size(), log.color3.rgb.size());
  for (std::size_t i = 0; i < overlay.pixels.size(); ++i) {
    const std::uint8_t id = log.labels3.image.labels[i];
    const Rgb8 c = id == kVoidLabel ? Rgb8{0, 0, 0} : kLabelColors[id];
    const Rgb8 image = log.color3.rgb[i];
    auto blend = [](int a, int b) { return 0.5 * a + 0.5 * b; };
    EXPECT_NEAR(overlay.pixels[i].r, blend(c.r, image.r), 0.51) << i;
    EXPECT_NEAR(overlay.pixels[i].g, blend(c.g, image.g), 0.51) << i;
    EXPECT_NEAR(overlay.pixels[i].b, blend(c.b, image.b), 0.51) << i;
  }
}

TEST(LabelViewer, NoPngWritesNothingAndBadFlagsExitWithCode2) {
  const ClientLog& log = clientLog();
  TempDir tmp;
  std::filesystem::create_directories(tmp.path() / "png");
  const ProcessResult r =
      run(FINDMUG_LABEL_VIEWER_EXE,
          {"--lcm-url", replayUrl(log.path), "--out", tmp.str("png"), "--no-png"}, tmp);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(lines(r.out).size(), 2u) << r.out;
  EXPECT_TRUE(std::filesystem::is_empty(tmp.path() / "png"));

  for (const std::vector<std::string>& args :
       std::vector<std::vector<std::string>>{{"--alpha", "2"},
                                             {"--every", "0"},
                                             {"--out", tmp.str("no-such-dir")},
                                             {"--bogus"},
                                             {"--channel-suffix", "bad suffix"}}) {
    const ProcessResult bad = run(FINDMUG_LABEL_VIEWER_EXE, args, tmp);
    EXPECT_EQ(bad.exit_code, 2) << args[0] << ": " << bad.err;
    EXPECT_TRUE(bad.out.empty()) << bad.out;
    EXPECT_NE(bad.err.find("findmug-label-viewer: "), std::string::npos) << bad.err;
    EXPECT_NE(bad.err.find("--help"), std::string::npos) << bad.err;
  }
}


// A replay without FINDMUG_RGBD: the label image carries the camera the daemon used and
// the frame's colour image (daemon.publish_color), so the viewer draws the tables over
// that image (it used to say "no camera extrinsics with the colour frame").
TEST(LabelViewer, DrawsTablesWithTheDaemonsCameraOverTheCarriedImage) {
  TempDir tmp;
  std::filesystem::create_directories(tmp.path() / "png");
  io::TablesMessage tables = baseFrameTables();
  tables.utime = 5'000'000;
  tables.seq = 5;
  io::LabelImageMessage labels;
  labels.image = labelBlocks(64, 48);
  labels.utime = 5'000'000;
  labels.seq = 5;
  auto message = io::encodeLabelImage(labels);
  // A level camera 1.2 m above the floor looking along the base frame's x axis.
  Eigen::Isometry3d camera_to_base = Eigen::Isometry3d::Identity();
  camera_to_base.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  camera_to_base.translation() = Eigen::Vector3d(0, 0, 1.2);
  io::setCameraView(message, CameraIntrinsics{40, 40, 31.5, 23.5}, camera_to_base);
  io::setColorJpeg(message, std::vector<Rgb8>(64 * 48, Rgb8{90, 90, 90}), 90);
  // A yellow mug on table 0, 3 m ahead and 0.35 m below the camera: pixel (31.5, 28.2).
  TableObjectDetection objects;
  TableObject mug;
  mug.centroid = Eigen::Vector3f(3.0f, 0.0f, 0.85f);
  mug.point_count = 60;
  mug.mean_rgb = Eigen::Vector3f(250.0f, 200.0f, 10.0f);
  mug.colour_histogram[2] = 1.0f;
  objects.objects = {mug};
  const std::string log = tmp.str("camera.lcmlog");
  daemon::test::writeLcmLog(
      log, {{std::string(io::kLabelsChannel), io::encodeMessage(message)},
            {std::string(io::kTablesChannel), io::encodeMessage(io::encodeTables(tables))},
            {std::string(io::kObjectsChannel),
             io::encodeMessage(
                 io::encodeObjects(tables.utime, tables.seq, objects, tables.tables, {}, {}))}});
  const ProcessResult r =
      run(FINDMUG_LABEL_VIEWER_EXE, {"--lcm-url", replayUrl(log), "--out", tmp.str("png")}, tmp);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("overlay "), std::string::npos) << r.out;  // over the carried image
  EXPECT_EQ(r.out.find("no colour frame"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("with 2 of 2 tables in view"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("objects seq 5: 1 objects; redrawn"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("tables in view, 1 of 1 objects"), std::string::npos) << r.out;
  // The hulls are drawn in white (the carried image is grey, the labels blend with it).
  const Image<Rgb8> overlay = cropped(readPngRgb(tmp.str("png/labels_00000005.png")), 64, 48);
  int white = 0;
  for (const Rgb8& p : overlay.pixels) white += (p.r == 255 && p.g == 255 && p.b == 255) ? 1 : 0;
  EXPECT_GT(white, 10);
  // The mug's marker, in its own colour, where the camera sees its centroid.
  int mug_pixels = 0;
  for (int v = 26; v <= 30; ++v) {
    for (int u = 30; u <= 33; ++u) {
      mug_pixels += overlay.pixels[static_cast<std::size_t>(v) * 64 + u] == Rgb8{250, 200, 10};
    }
  }
  EXPECT_GE(mug_pixels, 12);
}

// A known semantic map at 10 cm: a 2 x 1 m floor, a table top (0.7 m) over part of it, a
// chair seat the map is unsure of, a ceiling over all of it, a wall voxel above 2 m and a
// cell with only ceiling; the table map holds the table with the robot beside it.
// semantic_map.png must show each cell in the colour of what is on top there, faded by
// confidence, and nothing where only ceiling is; the hull and the robot over it.
TEST(LabelViewer, DrawsTheSemanticMapTopDownWithTheTableMap) {
  TempDir tmp;
  std::filesystem::create_directories(tmp.path() / "png");
  io::SemanticMapMessage map;
  map.utime = 7'000'000;
  map.seq = 70;
  map.frames = 12;
  map.voxel_size_m = 0.1f;
  auto voxel = [&](int i, int j, int k, Label label, int confidence) {
    map.voxels.push_back({static_cast<std::int16_t>(i), static_cast<std::int16_t>(j),
                          static_cast<std::int16_t>(k), static_cast<std::uint8_t>(label),
                          static_cast<std::uint8_t>(confidence)});
  };
  for (int i = 0; i < 20; ++i) {
    for (int j = 0; j < 10; ++j) {
      voxel(i, j, 0, Label::Floor, 255);
      if (i >= 5 && i <= 9 && j >= 2 && j <= 5) voxel(i, j, 7, Label::Table, 255);
      if (i >= 14 && i <= 15 && j >= 2 && j <= 3) voxel(i, j, 4, Label::Chair, 64);
      if (i == 0) voxel(i, j, 22, Label::Wall, 255);  // above 2 m: not drawn
      voxel(i, j, 25, Label::Ceiling, 255);
    }
  }
  voxel(22, 5, 25, Label::Ceiling, 255);  // only ceiling there
  std::sort(map.voxels.begin(), map.voxels.end(), [](const auto& a, const auto& b) {
    return std::tie(a.i, a.j, a.k) < std::tie(b.i, b.j, b.k);
  });
  io::TablesMessage table_map;
  table_map.utime = map.utime;
  table_map.seq = map.seq;
  table_map.content = io::TablesContent::Map;
  table_map.map_pose = io::RobotPose{map.utime, {1.5, 0.8, 0.0}};
  TableCluster table;  // base frame: the robot at (1.5, 0.8), yaw 0
  table.id = 4;
  table.top_height = 0.7f;
  table.hull = {{0.45f - 1.5f, 0.15f - 0.8f}, {0.95f - 1.5f, 0.15f - 0.8f},
                {0.95f - 1.5f, 0.55f - 0.8f}, {0.45f - 1.5f, 0.55f - 0.8f}};
  table.center = {0.7f - 1.5f, 0.35f - 0.8f};
  table.centroid = {table.center.x(), table.center.y(), 0.7f};
  table.major_axis = {1.0f, 0.0f};
  table.minor_axis = {0.0f, 1.0f};
  table.extents = {0.25f, 0.2f};
  table_map.tables = {table};
  table_map.map_info = {io::TableMapInfo{4, true, 9, 5}};
  const std::string log = tmp.str("semantic.lcmlog");
  daemon::test::writeLcmLog(
      log, {{std::string(io::kTableMapChannel), io::encodeMessage(io::encodeTables(table_map))},
            {std::string(io::kSemanticMapChannel),
             io::encodeMessage(io::encodeSemanticMap(map))}});
  const ProcessResult r =
      run(FINDMUG_LABEL_VIEWER_EXE, {"--lcm-url", replayUrl(log), "--out", tmp.str("png")}, tmp);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("semantic map seq 70: " + std::to_string(map.voxels.size()) +
                       " voxels, 12 frames"),
            std::string::npos)
      << r.out;
  const Image<Rgb8> png = readPngRgb(tmp.str("png/semantic_map.png"));
  ASSERT_EQ(png.width, 600);
  ASSERT_EQ(png.height, 600);
  // Where the picture put the map frame (from the decoded messages, as the viewer has them).
  const auto decoded_map = io::decodeTables(io::encodeMessage(io::encodeTables(table_map)).data(),
                                            io::encodeMessage(io::encodeTables(table_map)).size(),
                                            "T");
  const clients::TopDownView view = clients::semanticMapView(
      clients::topDownCells(map), &decoded_map, png.width);
  // The whole map and the robot are inside the picture.
  for (auto [x, y] : {std::pair{-0.05, -0.05}, {1.95, 0.95}, {2.25, 0.55}, {1.5, 0.8}}) {
    const Eigen::Vector2d p = view.px(x, y);
    EXPECT_TRUE(p.x() >= view.margin && p.x() <= png.width - view.margin && p.y() >= view.margin &&
                p.y() <= png.height - view.margin)
        << x << ", " << y;
  }
  auto at = [&](double x, double y) {
    const Eigen::Vector2d p = view.px(x, y);
    return png.pixels[static_cast<std::size_t>(std::lround(p.y())) * png.width +
                      static_cast<std::size_t>(std::lround(p.x()))];
  };
  auto expectColor = [&](double x, double y, Rgb8 want, const char* what) {
    const Rgb8 got = at(x, y);
    EXPECT_TRUE(got == want) << what << " at (" << x << ", " << y << "): got " << int(got.r)
                             << "," << int(got.g) << "," << int(got.b) << ", want " << int(want.r)
                             << "," << int(want.g) << "," << int(want.b);
  };
  const Rgb8 floor = kLabelColors[static_cast<int>(Label::Floor)];
  expectColor(1.2, 0.8, floor, "floor under the ceiling");
  expectColor(0.02, 0.42, floor, "floor under a wall voxel above 2 m");
  expectColor(0.52, 0.22, kLabelColors[static_cast<int>(Label::Table)], "table top over the floor");
  // The chair: 64/255 sure, faded to a quarter plus three quarters of 64/255 of its colour.
  const Rgb8 chair = kLabelColors[static_cast<int>(Label::Chair)];
  const double keep = 0.25 + 0.75 * 64.0 / 255.0;
  auto fade = [&](int c) { return static_cast<std::uint8_t>(std::lround(255 - keep * (255 - c))); };
  expectColor(1.45, 0.25, Rgb8{fade(chair.r), fade(chair.g), fade(chair.b)}, "unsure chair");
  EXPECT_FALSE(at(1.45, 0.25) == chair);
  expectColor(2.22, 0.52, Rgb8{255, 255, 255}, "a cell with only ceiling");
  expectColor(2.3, 0.2, Rgb8{255, 255, 255}, "outside the map");
  expectColor(1.5, 0.8, Rgb8{30, 110, 255}, "the robot");
  expectColor(0.6, 0.55, Rgb8{0, 0, 0}, "the table's hull (its far edge)");
  // The id and "9F 5V" beside the table's centre: black text on a white box.
  int black = 0;
  const Eigen::Vector2d c = view.px(0.7, 0.35);
  for (int y = static_cast<int>(c.y()) - 8; y < static_cast<int>(c.y()) + 20; ++y) {
    for (int x = static_cast<int>(c.x()); x < static_cast<int>(c.x()) + 30; ++x) {
      black += png.pixels[static_cast<std::size_t>(y) * png.width + x] == Rgb8{0, 0, 0} ? 1 : 0;
    }
  }
  EXPECT_GT(black, 40);
}

// findmug-replay --robot-pose: before each replayed frame, the fixed robot pose with that
// frame's utime on FINDMUG_ROBOT_POSE (what daemon_bench.sh gives findmugd's semantic map).
TEST(Replay, RobotPoseGoesOutWithEveryFrame) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  TempDir tmp;
  const std::string log = tmp.str("replay.lcmlog");
  const ProcessResult r =
      run(FINDMUG_REPLAY_EXE,
          {"--source", "dataset:" + nyu.string(), "--max-frames", "2", "--count", "3", "--rate",
           "20", "--robot-pose", "1.5,-2,0.25", "--url", "file://" + log + "?mode=w"},
          tmp);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto messages = daemon::test::readLcmLog(log);
  ASSERT_EQ(messages.size(), 6u);
  for (std::size_t k = 0; k < 6; k += 2) {
    ASSERT_EQ(messages[k].channel, io::kRobotPoseChannel) << k;
    ASSERT_EQ(messages[k + 1].channel, io::kRgbdChannel) << k;
    const io::RobotPose pose =
        io::decodeRobotPose(messages[k].data.data(), messages[k].data.size(), "P");
    const RgbdFrame frame =
        io::decodeRgbdFrame(messages[k + 1].data.data(), messages[k + 1].data.size(), "F");
    EXPECT_EQ(pose.utime, frame.utime) << k;
    EXPECT_DOUBLE_EQ(pose.pose.x, 1.5);
    EXPECT_DOUBLE_EQ(pose.pose.y, -2.0);
    EXPECT_DOUBLE_EQ(pose.pose.yaw, 0.25);
  }
  // A pose needs all three numbers.
  const ProcessResult bad = run(FINDMUG_REPLAY_EXE,
                                {"--source", "dataset:" + nyu.string(), "--count", "1", "--rate",
                                 "20", "--robot-pose", "1,2", "--url", "file://" + log + "?mode=w"},
                                tmp);
  EXPECT_EQ(bad.exit_code, 2) << bad.err;
}

}  // namespace
}  // namespace findmug
