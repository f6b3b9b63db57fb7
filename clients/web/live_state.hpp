// live_state.hpp — what findmug-web knows of a running findmugd: the latest label image
// (with the camera and the colour image the daemon sent with it), the latest frame's
// tables, the persistent table map, the fused semantic map seen from above (when findmugd
// publishes it: daemon.semantic_map), the latest frame's table-top object candidates
// (FINDMUG_OBJECTS, with the frame's seq: what the page's teach click names), the latest
// answer to a find (FINDMUG_FIND_RESULT), the latest status and a few minutes of status
// history.
//
// Fed by the bus thread (io::Subscriber callbacks), read by the HTTP threads: every
// member is behind one mutex, and readers get copies (JSON or bytes).
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "findmug/io/lcm_codec_find.hpp"
#include "findmug/io/messages.hpp"
#include "findmug/io/semantic_map_codec.hpp"
#include "findmug_lcm/status_t.hpp"

namespace findmug::web {

// A label image for the page: one byte per pixel (findmug ids, 255 void).
struct LabelPixels {
  std::int64_t seq = 0;
  int width = 0, height = 0;
  std::shared_ptr<const std::vector<std::uint8_t>> labels;
};

// The semantic map from above for the page (clients/semantic_map_picture.hpp,
// topDownCells): a raster of width x height floor cells, row 0 the highest j; the bytes
// are the label plane (findmug ids, 255 none) then the confidence plane (0..255).
struct SemanticMapRaster {
  std::int64_t seq = 0;
  int width = 0, height = 0;
  std::shared_ptr<const std::vector<std::uint8_t>> bytes;
};

class LiveState {
 public:
  explicit LiveState(double history_s) : history_s_(history_s) {}

  // From the bus thread.
  void onLabels(const io::LabelImageMessage& message);
  void onTables(const io::TablesMessage& message);  // FINDMUG_TABLES or FINDMUG_TABLE_MAP
  void onSemanticMap(const io::SemanticMapMessage& message);  // FINDMUG_SEMANTIC_MAP
  void onObjects(const io::ObjectsMessage& message);          // FINDMUG_OBJECTS (frame content)
  void onFindResult(const io::FindResultMessage& message);    // FINDMUG_FIND_RESULT
  void onStatus(const findmug_lcm::status_t& status);
  void onBadMessage(const std::string& channel, const std::string& what);
  void onBusEnded(const std::string& how);

  // For the page: everything but the pixels (GET /api/live).
  nlohmann::json liveJson() const;
  std::optional<LabelPixels> labels() const;
  // The colour JPEG of the latest label image, and its seq; nullopt when it had none.
  std::optional<std::pair<std::int64_t, std::shared_ptr<const std::vector<std::uint8_t>>>>
  colorJpeg() const;

  // The latest semantic map's raster (GET /api/semantic_map.bin); nullopt before one came.
  std::optional<SemanticMapRaster> semanticMap() const;

  // Label images taken so far (for tests and the log).
  std::uint64_t labelImages() const;

 private:
  struct StatusSample {
    double t = 0;  // seconds, status utime
    double input_fps = 0, output_fps = 0, cpu_used = 0, cpu_budget = 0;
    double latency_p50_ms = 0, latency_p95_ms = 0;  // the "total" stage
    std::int64_t dropped_at_door = 0, dropped_in_pipeline = 0, dropped_at_shutdown = 0;
    std::int64_t rejected = 0;
  };

  mutable std::mutex mutex_;
  double history_s_;
  std::uint64_t label_count_ = 0;
  std::int64_t labels_received_us_ = 0;  // host clock when the latest label image arrived
  std::optional<io::LabelImageMessage> labels_meta_;  // pixels moved to labels_bytes_
  std::shared_ptr<const std::vector<std::uint8_t>> labels_bytes_, color_jpeg_;
  std::optional<io::TablesMessage> frame_tables_, table_map_;
  std::optional<io::ObjectsMessage> frame_objects_;
  std::optional<io::FindResultMessage> find_result_;
  nlohmann::json semantic_map_meta_;  // null until a semantic map came
  SemanticMapRaster semantic_map_;
  std::optional<findmug_lcm::status_t> status_;
  std::deque<StatusSample> history_;
  std::map<std::string, std::uint64_t> bad_messages_;
  std::string last_bad_message_, bus_state_ = "listening";
};

// JSON of a tables message for the drawing: hulls, ids, numbered search positions, in the
// base frame and, when the message has the robot's map pose, the map frame.
nlohmann::json tablesJson(const io::TablesMessage& message);

// JSON of a frame's object candidates: per candidate its index in the message (what a
// teach command names), table, centroid, footprint box, height above the top, point
// count, mean colour and truncation bits (base frame); with the robot's map pose also the
// centroid in the map frame (what a find answer's position is in).
nlohmann::json objectsJson(const io::ObjectsMessage& message);

// JSON of a find answer: its request id, name, result ("seen", "look_at", "unknown_name",
// "refused"), summary, where it was seen, the places to look and the taught names.
nlohmann::json findResultJson(const io::FindResultMessage& message);

}  // namespace findmug::web
