// findmug-nav-client — what a navigation stack would take from findmugd.
//
// Subscribes to FINDMUG_TABLES[_suffix] (tables_t) and, for every message,
// prints the reachable search positions in visiting order from the robot's
// position (shortest open path, see findmug::visitingOrder), then the
// unreachable ones with their reason. Positions are given in the map frame
// when the message carries the robot's map pose (and --frame is auto or
// map), else in the robot base frame, where the robot stands at the origin.
// It also subscribes to FINDMUG_OBJECTS[_suffix] (objects_t; with --map to
// FINDMUG_OBJECT_MAP[_suffix], the object map) and, for every message, lists
// the object candidates on each table: where they stand (same frame choice),
// their height above the top, footprint, colour and whether they may be cut
// off, so that a robot knows what to look at from the search positions; the
// object map's entries also with their stable id, the taught object they were
// named as (with the match score), their sightings and when last seen.
// With --json, one JSON object per message on its own line (JSON lines): a
// tables message's line has "tour", an objects message's line "objects".
//
// With --find NAME it asks instead: it sends command_t "find NAME" on
// FINDMUG_COMMAND and prints findmugd's answer from FINDMUG_FIND_RESULT
// (find_result_t): where the object was seen and where to stand, or the places
// to look in order; then exits (0: an answer; 4: the name was not taught or
// the daemon refused; 1: no answer within --timeout). With --count N it waits
// for N answers: the daemon answers again when the places change (a table
// searched, the object seen).
//
// With --teach NAME SEQ INDEX it sends command_t "teach NAME SEQ INDEX": object
// INDEX of the objects message of frame SEQ (as printed above: "objects seq SEQ",
// "object INDEX") becomes one more view of the taught object NAME in findmugd's
// daemon.objects_dir; it prints the daemon's answer from status_t
// (last_teach_result) and exits (0: taught; 4: refused, with why; 1: no answer
// within --timeout).
//
// Exits cleanly on SIGINT/SIGTERM, after --count messages, or at the end of
// a replayed log (--lcm-url file://LOG?speed=0). Bad messages are reported on
// stderr and skipped.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "client_common.hpp"
#include "findmug/common/error.hpp"
#include "findmug/io/bus.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/lcm_codec_find.hpp"
#include "findmug/io/lcm_codec_objects.hpp"
#include "findmug/io/subscriber.hpp"
#include "findmug/tables/tables.hpp"
#include "findmug_cli.hpp"
#include "findmug_json.hpp"
#include "findmug/map/visiting_order.hpp"

namespace {

using namespace findmug;

constexpr const char* kProgram = "findmug-nav-client";

enum class FrameChoice { Auto, Base, Map };

struct Position {
  int table = 0;
  SearchPosition position;  // in the chosen frame
};

class NavClient {
 public:
  NavClient(FrameChoice frame, bool json) : frame_(frame), json_(json) {}

  // A decoded message (bad ones are reported by the subscriber and skipped).
  void onMessage(const io::TablesMessage& message) {
    const bool use_map = message.map_pose.has_value() && frame_ != FrameChoice::Base;
    if (frame_ == FrameChoice::Map && !message.map_pose) {
      std::fprintf(stderr, "%s: message seq %lld has no map pose; positions in the base frame\n",
                   kProgram, static_cast<long long>(message.seq));
    }
    // The robot: at the base-frame origin, or at its map pose.
    Eigen::Vector2f robot = Eigen::Vector2f::Zero();
    double robot_yaw = 0.0;
    if (use_map) {
      robot = Eigen::Vector2f(static_cast<float>(message.map_pose->pose.x),
                              static_cast<float>(message.map_pose->pose.y));
      robot_yaw = message.map_pose->pose.yaw;
    }
    std::vector<Position> reachable, unreachable;
    for (std::size_t t = 0; t < message.tables.size(); ++t) {
      const auto& positions =
          use_map ? message.map_tables[t].search_positions : message.tables[t].search_positions;
      for (const auto& p : positions) {
        (p.reachable ? reachable : unreachable).push_back({message.tables[t].id, p});
      }
    }
    std::vector<Eigen::Vector2f> points;
    for (const auto& r : reachable) points.push_back(r.position.xy);
    const std::vector<int> order = visitingOrder(robot, points);
    if (json_) {
      printJson(message, use_map, robot, robot_yaw, reachable, order, unreachable);
    } else {
      printText(message, use_map, robot, robot_yaw, reachable, order, unreachable);
    }
    std::fflush(stdout);
  }

  // A decoded objects message: the candidates on each table, in the frame
  // the tables are printed in.
  void onObjects(const io::ObjectsMessage& message) {
    const bool use_map = message.map_pose.has_value() && frame_ != FrameChoice::Base;
    std::vector<Eigen::Vector3d> where;
    for (std::size_t k = 0; k < message.objects.size(); ++k) {
      where.push_back(use_map ? message.map_info[k].map_centroid
                              : message.objects[k].centroid.cast<double>());
    }
    if (json_) {
      printObjectsJson(message, use_map, where);
    } else {
      printObjectsText(message, use_map, where);
    }
    std::fflush(stdout);
  }

 private:
  static std::vector<std::string> truncationNames(std::uint8_t bits) {
    std::vector<std::string> names;
    if (bits & kTruncatedOutline) names.push_back("outline");
    if (bits & kTruncatedBorder) names.push_back("border");
    if (bits & kTruncatedDepthHole) names.push_back("depth_hole");
    return names;
  }

  void printObjectsText(const io::ObjectsMessage& m, bool use_map,
                        const std::vector<Eigen::Vector3d>& where) const {
    std::printf("%s seq %lld utime %llu: %zu objects on %d tables, %s frame\n",
                m.content == io::TablesContent::Map ? "object map" : "objects",
                static_cast<long long>(m.seq), static_cast<unsigned long long>(m.utime),
                m.objects.size(), m.num_tables, use_map ? "map" : "base");
    for (std::size_t k = 0; k < m.objects.size(); ++k) {
      const TableObject& o = m.objects[k];
      std::string cut;
      for (const std::string& name : truncationNames(o.truncation)) {
        cut += (cut.empty() ? "  cut off: " : ",") + name;
      }
      std::string mapped;
      if (m.content == io::TablesContent::Map) {
        const io::ObjectMapInfo& info = m.map_info[k];
        char score[32] = "";
        if (!info.name.empty()) {
          std::snprintf(score, sizeof(score), " (score %.2f)", static_cast<double>(info.name_score));
        }
        char text[96];
        std::snprintf(text, sizeof(text), "  seen %d times, last utime %llu", info.sightings,
                      static_cast<unsigned long long>(info.last_seen_utime));
        mapped = "  " + (info.name.empty() ? std::string("(not named)") : info.name) + score + text;
      }
      std::printf(
          "   o  table %d  object %d  x %7.2f  y %7.2f  z %5.2f  height %5.2f m  "
          "%4.2f x %4.2f m  rgb (%3.0f, %3.0f, %3.0f)  %d points%s%s\n",
          o.table, o.id, where[k].x(), where[k].y(), where[k].z(), o.height_above_top,
          2.0f * o.extents.x(), 2.0f * o.extents.y(), o.mean_rgb.x(), o.mean_rgb.y(),
          o.mean_rgb.z(), o.point_count, cut.c_str(), mapped.c_str());
    }
  }

  void printObjectsJson(const io::ObjectsMessage& m, bool use_map,
                        const std::vector<Eigen::Vector3d>& where) const {
    std::ostringstream out;
    out << "{\"utime\":" << m.utime << ",\"seq\":" << m.seq << ",\"frame\":\""
        << (use_map ? "map" : "base") << "\",\"tables\":" << m.num_tables
        << (m.content == io::TablesContent::Map ? ",\"object_map\":true" : "")
        << ",\"objects\":[";
    for (std::size_t k = 0; k < m.objects.size(); ++k) {
      const TableObject& o = m.objects[k];
      out << (k ? "," : "") << "{\"id\":" << o.id << ",\"table\":" << o.table
          << ",\"x\":" << cli::jsonNumber(where[k].x(), 3)
          << ",\"y\":" << cli::jsonNumber(where[k].y(), 3)
          << ",\"z\":" << cli::jsonNumber(where[k].z(), 3)
          << ",\"height_m\":" << cli::jsonNumber(o.height_above_top, 3)
          << ",\"points\":" << o.point_count;
      if (m.content == io::TablesContent::Map) {
        const io::ObjectMapInfo& info = m.map_info[k];
        out << ",\"name\":" << cli::jsonString(info.name)
            << ",\"score\":" << cli::jsonNumber(info.name_score, 3)
            << ",\"sightings\":" << info.sightings
            << ",\"last_seen_utime\":" << info.last_seen_utime;
      }
      out << ",\"truncated\":[";
      const std::vector<std::string> names = truncationNames(o.truncation);
      for (std::size_t i = 0; i < names.size(); ++i) {
        out << (i ? "," : "") << cli::jsonString(names[i]);
      }
      out << "]}";
    }
    out << "]}";
    std::puts(out.str().c_str());
  }

  void printText(const io::TablesMessage& m, bool use_map, const Eigen::Vector2f& robot,
                 double robot_yaw, const std::vector<Position>& reachable,
                 const std::vector<int>& order, const std::vector<Position>& unreachable) const {
    std::printf(
        "tables seq %lld utime %llu: %zu tables, %zu positions (%zu reachable), %s frame, "
        "robot at (%.2f, %.2f) yaw %.1f deg\n",
        static_cast<long long>(m.seq), static_cast<unsigned long long>(m.utime), m.tables.size(),
        reachable.size() + unreachable.size(), reachable.size(), use_map ? "map" : "base",
        robot.x(), robot.y(), robot_yaw * 180.0 / M_PI);
    Eigen::Vector2f at = robot;
    double total = 0.0;
    for (std::size_t k = 0; k < order.size(); ++k) {
      const Position& p = reachable[order[k]];
      const double leg = (p.position.xy - at).norm();
      total += leg;
      at = p.position.xy;
      std::printf("  %2zu. table %d  x %7.2f  y %7.2f  yaw %7.1f deg  leg %5.2f m  total %6.2f m\n",
                  k + 1, p.table, p.position.xy.x(), p.position.xy.y(),
                  p.position.yaw * 180.0 / M_PI, leg, total);
    }
    for (const Position& p : unreachable) {
      std::printf("   -  table %d  x %7.2f  y %7.2f  yaw %7.1f deg  unreachable: %s\n", p.table,
                  p.position.xy.x(), p.position.xy.y(), p.position.yaw * 180.0 / M_PI,
                  p.position.reason.c_str());
    }
  }

  void printJson(const io::TablesMessage& m, bool use_map, const Eigen::Vector2f& robot,
                 double robot_yaw, const std::vector<Position>& reachable,
                 const std::vector<int>& order, const std::vector<Position>& unreachable) const {
    std::ostringstream out;
    out << "{\"utime\":" << m.utime << ",\"seq\":" << m.seq << ",\"frame\":\""
        << (use_map ? "map" : "base") << "\",\"robot\":{\"x\":" << cli::jsonNumber(robot.x(), 3)
        << ",\"y\":" << cli::jsonNumber(robot.y(), 3)
        << ",\"yaw\":" << cli::jsonNumber(robot_yaw, 4) << "},\"tables\":" << m.tables.size()
        << ",\"tour\":[";
    Eigen::Vector2f at = robot;
    double total = 0.0;
    for (std::size_t k = 0; k < order.size(); ++k) {
      const Position& p = reachable[order[k]];
      total += (p.position.xy - at).norm();
      at = p.position.xy;
      out << (k ? "," : "") << "{\"order\":" << k + 1 << ",\"table\":" << p.table
          << ",\"x\":" << cli::jsonNumber(p.position.xy.x(), 3)
          << ",\"y\":" << cli::jsonNumber(p.position.xy.y(), 3)
          << ",\"yaw\":" << cli::jsonNumber(p.position.yaw, 4)
          << ",\"path_m\":" << cli::jsonNumber(total, 3) << "}";
    }
    out << "],\"unreachable\":[";
    for (std::size_t k = 0; k < unreachable.size(); ++k) {
      const Position& p = unreachable[k];
      out << (k ? "," : "") << "{\"table\":" << p.table
          << ",\"x\":" << cli::jsonNumber(p.position.xy.x(), 3)
          << ",\"y\":" << cli::jsonNumber(p.position.xy.y(), 3)
          << ",\"yaw\":" << cli::jsonNumber(p.position.yaw, 4)
          << ",\"reason\":" << cli::jsonString(p.position.reason) << "}";
    }
    out << "]}";
    std::puts(out.str().c_str());
  }

  FrameChoice frame_;
  bool json_;
};

}  // namespace

void printPosition(std::ostream& out, const SearchPosition& p) {
  out << "(" << p.xy.x() << ", " << p.xy.y() << ") facing " << p.yaw << " rad";
}

// One answer to --find, as text or one JSON line.
void printFindResult(const io::FindResultMessage& m, bool json) {
  std::ostringstream out;
  out.precision(2);
  out << std::fixed;
  if (json) {
    const char* kinds[] = {"seen", "look_at", "unknown_name", "refused"};
    out << "{\"find\":" << cli::jsonString(m.name) << ",\"request_id\":" << m.request_id
        << ",\"result\":\"" << kinds[static_cast<int>(m.result)] << "\""
        << ",\"summary\":" << cli::jsonString(m.summary);
    if (m.result == io::FindResult::Seen) {
      out << ",\"position\":[" << cli::jsonNumber(m.seen_position.x(), 3) << ","
          << cli::jsonNumber(m.seen_position.y(), 3) << "," << cli::jsonNumber(m.seen_position.z(), 3)
          << "],\"table\":" << m.seen_table_id;
      if (m.stand_here) {
        out << ",\"stand_here\":[" << cli::jsonNumber(m.stand_here->xy.x(), 3) << ","
            << cli::jsonNumber(m.stand_here->xy.y(), 3) << ","
            << cli::jsonNumber(m.stand_here->yaw, 3) << "]";
      }
    }
    out << ",\"places\":[";
    for (std::size_t i = 0; i < m.places.size(); ++i) {
      const PlaceToLook& p = m.places[i];
      out << (i ? "," : "") << "{\"table\":" << p.table_id
          << ",\"x\":" << cli::jsonNumber(p.position.xy.x(), 3)
          << ",\"y\":" << cli::jsonNumber(p.position.xy.y(), 3)
          << ",\"yaw\":" << cli::jsonNumber(p.position.yaw, 3)
          << ",\"seen_before\":" << (p.seen_here_before ? "true" : "false")
          << ",\"searched\":" << (p.searched ? "true" : "false")
          << ",\"look_closer\":" << (p.look_closer ? "true" : "false") << "}";
    }
    out << "]}";
    std::cout << out.str() << std::endl;
    return;
  }
  out << m.summary << "\n";
  if (m.result == io::FindResult::Seen && m.stand_here) {
    out << "  stand at ";
    printPosition(out, *m.stand_here);
    out << "\n";
  }
  for (std::size_t i = 0; i < m.places.size(); ++i) {
    const PlaceToLook& p = m.places[i];
    out << "  " << (i + 1) << ". table " << p.table_id << " at ";
    printPosition(out, p.position);
    if (p.seen_here_before) out << " (seen here before)";
    if (p.searched) out << " (searched)";
    if (p.look_closer) out << " (look closer)";
    out << "\n";
  }
  std::cout << out.str() << std::flush;
}

// --find NAME: asks findmugd and prints its answers (see the header comment).
int runFind(io::Bus& bus, const std::string& name, bool json, long count, double timeout_s) {
  const auto started = std::chrono::steady_clock::now();
  const std::int64_t request_id =
      std::chrono::duration_cast<std::chrono::microseconds>(
          std::chrono::system_clock::now().time_since_epoch())
          .count() %
      1000000000;
  long answers = 0;
  int code = 1;
  io::Subscriber<io::FindResultMessage> results(
      bus, std::string(io::kFindResultChannel),
      [](const std::uint8_t* d, std::size_t n, const std::string& c) {
        return io::decodeFindResult(d, n, c);
      },
      [&](const io::FindResultMessage& m, const std::string&) {
        if (m.request_id != request_id) return;  // another client's question
        printFindResult(m, json);
        ++answers;
        const bool refused =
            m.result == io::FindResult::UnknownName || m.result == io::FindResult::Refused;
        code = refused ? 4 : 0;
      },
      [](const std::string& error) {
        std::fprintf(stderr, "%s: skipping bad message: %s\n", kProgram, error.c_str());
      });
  io::CommandMessage command;
  command.utime = static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::microseconds>(
          std::chrono::system_clock::now().time_since_epoch())
          .count());
  command.request_id = request_id;
  command.command = "find";
  command.argument = name;
  if (!io::publishMessage(bus, std::string(io::kCommandChannel), io::encodeCommand(command))) {
    std::fprintf(stderr, "%s: could not send the find command on %s\n", kProgram,
                 std::string(io::kCommandChannel).c_str());
    return 1;
  }
  const long wanted = count > 0 ? count : 1;
  const int loop = clients::receiveLoop(bus, kProgram, [&] {
    const double waited =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    return answers >= wanted || code == 4 || waited > timeout_s;
  });
  if (loop != 0) return loop;
  if (answers == 0) {
    std::fprintf(stderr, "%s: no answer to \"find %s\" within %.1f s on %s (is findmugd running "
                 "with a command input?)\n", kProgram, name.c_str(), timeout_s,
                 std::string(io::kFindResultChannel).c_str());
  }
  return code;
}

// --teach NAME SEQ INDEX: asks findmugd to teach and prints its answer (see the header comment).
int runTeach(io::Bus& bus, const io::TeachRequest& teach, double timeout_s) {
  const auto started = std::chrono::steady_clock::now();
  const auto now_us = std::chrono::duration_cast<std::chrono::microseconds>(
                          std::chrono::system_clock::now().time_since_epoch())
                          .count();
  const std::int64_t request_id = now_us % 1000000000;
  int code = 1;
  io::Subscriber<findmug_lcm::status_t> status(
      bus, std::string(io::kStatusChannel),
      [](const std::uint8_t* d, std::size_t n, const std::string& c) {
        return io::decodeMessage<findmug_lcm::status_t>(d, n, c);
      },
      [&](const findmug_lcm::status_t& s, const std::string&) {
        if (s.last_teach_request_id != request_id || code != 1) return;
        std::printf("%s\n", s.last_teach_result.c_str());
        code = s.last_teach_ok ? 0 : 4;
      },
      [](const std::string& error) {
        std::fprintf(stderr, "%s: skipping bad message: %s\n", kProgram, error.c_str());
      });
  const io::CommandMessage command{static_cast<std::uint64_t>(now_us), request_id, "teach",
                                   io::teachArgument(teach)};
  if (!io::publishMessage(bus, std::string(io::kCommandChannel), io::encodeCommand(command))) {
    std::fprintf(stderr, "%s: could not send the teach command on %s\n", kProgram,
                 std::string(io::kCommandChannel).c_str());
    return 1;
  }
  const int loop = clients::receiveLoop(bus, kProgram, [&] {
    return code != 1 ||
           std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count() >
               timeout_s;
  });
  if (loop != 0) return loop;
  if (code == 1) {
    std::fprintf(stderr, "%s: no answer to \"teach %s\" within %.1f s on %s (is findmugd running "
                 "with a command input?)\n", kProgram, command.argument.c_str(), timeout_s,
                 std::string(io::kStatusChannel).c_str());
  }
  return code;
}

int main(int argc, char** argv) {
  using namespace findmug;
  std::string url, suffix, frame_name = "auto";
  FrameChoice frame = FrameChoice::Auto;
  bool json = false, map = false;
  long count = 0;
  std::string find;
  std::vector<std::string> teach_words;
  double timeout_s = 10.0;
  auto app = cli::makeApp(kProgram,
                          "Prints the tables' search positions in visiting order from the robot");
  cli::addLcmUrlFlag(*app, url,
                     "LCM provider (default: LCM_DEFAULT_URL or udpm default); "
                     "file://LOG?speed=0 replays a log and exits at its end");
  cli::addChannelSuffixFlag(*app, suffix);
  app->add_flag("--map", map,
                "listen on the persistent table map (FINDMUG_TABLE_MAP): confirmed tables "
                "with stable ids, in the map frame; and on the object map (FINDMUG_OBJECT_MAP)");
  app->add_option("--frame", frame_name,
                  "frame of the printed positions (auto: map when the message has the "
                  "robot's map pose)")
      ->check(CLI::IsMember({"auto", "base", "map"}))
      ->capture_default_str();
  app->add_flag("--json", json, "one JSON object per message (JSON lines)");
  app->add_option("--count", count, "exit after N messages")->check(cli::positive());
  app->add_option("--find", find,
                  "ask findmugd where the taught object NAME is (command_t find) and print "
                  "its answer: where it was seen, or the places to look in order");
  app->add_option("--teach", teach_words,
                  "teach findmugd object INDEX of the objects message of frame SEQ as the "
                  "object NAME (command_t teach) and print its answer")
      ->type_name("NAME SEQ INDEX")
      ->expected(3)
      ->excludes("--find");
  app->add_option("--timeout", timeout_s,
                  "with --find or --teach: give up after this many seconds")
      ->check(CLI::Range(0.1, 3600.0))
      ->capture_default_str();
  if (auto code = cli::parse(*app, argc, argv)) return *code;
  std::optional<io::TeachRequest> teach;
  if (!teach_words.empty()) {
    try {
      teach = io::parseTeachArgument(teach_words[0] + " " + teach_words[1] + " " + teach_words[2],
                                     "--teach");
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: %s (see --help)\n", kProgram, e.what());
      return 2;
    }
  }
  if (frame_name == "base") frame = FrameChoice::Base;
  if (frame_name == "map") frame = FrameChoice::Map;
  const std::string channel(map ? io::kTableMapChannel : io::kTablesChannel);
  try {
    io::checkChannelSuffix(suffix);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: --channel-suffix: %s (see --help)\n", kProgram, e.what());
    return 2;
  }

  const std::shared_ptr<io::Bus> bus = clients::openBus(url, kProgram, suffix);
  if (!bus) return 1;
  clients::installStopHandlers();
  if (!find.empty()) return runFind(*bus, find, json, count, timeout_s);
  if (teach) return runTeach(*bus, *teach, timeout_s);
  NavClient client(frame, json);
  // This thread owns the bus: the callbacks run inside receiveLoop.
  io::Subscriber<io::TablesMessage> tables(
      *bus, channel,
      [](const std::uint8_t* d, std::size_t n, const std::string& c) {
        return io::decodeTables(d, n, c);
      },
      [&](const io::TablesMessage& m, const std::string&) { client.onMessage(m); },
      [](const std::string& error) {
        std::fprintf(stderr, "%s: skipping bad message: %s\n", kProgram, error.c_str());
      });
  // The objects on the frame's tables; with --map, the object map.
  const std::string objects_channel(map ? io::kObjectMapChannel : io::kObjectsChannel);
  std::optional<io::Subscriber<io::ObjectsMessage>> objects;
  {
    objects.emplace(
        *bus, objects_channel,
        [](const std::uint8_t* d, std::size_t n, const std::string& c) {
          return io::decodeObjects(d, n, c);
        },
        [&](const io::ObjectsMessage& m, const std::string&) { client.onObjects(m); },
        [](const std::string& error) {
          std::fprintf(stderr, "%s: skipping bad message: %s\n", kProgram, error.c_str());
        });
  }
  if (!json) {
    std::fprintf(stderr, "%s: listening on %s and %s, %s\n", kProgram, channel.c_str(),
                 objects_channel.c_str(), bus->describe().c_str());
  }
  // --count counts every tables message, bad ones included.
  return clients::receiveLoop(*bus, kProgram, [&] {
    return count > 0 && tables.received() >= static_cast<std::uint64_t>(count);
  });
}
