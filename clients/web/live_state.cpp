// What findmug-web knows of the daemon; see live_state.hpp.
#include "live_state.hpp"

#include <algorithm>
#include <cstdio>

#include "findmug/labels/labels.hpp"
#include "picture.hpp"
#include "semantic_map_picture.hpp"

namespace findmug::web {

namespace {

std::int64_t nowUs() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

nlohmann::json positionJson(const SearchPosition& p, int order) {
  return {{"x", p.xy.x()},   {"y", p.xy.y()},         {"yaw", p.yaw},
          {"order", order},  {"reachable", p.reachable}, {"reason", p.reason}};
}

nlohmann::json hullJson(const std::vector<Eigen::Vector2f>& hull) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& p : hull) out.push_back({p.x(), p.y()});
  return out;
}

nlohmann::json hullJson(const std::vector<Eigen::Vector2d>& hull) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& p : hull) out.push_back({p.x(), p.y()});
  return out;
}

}  // namespace

nlohmann::json tablesJson(const io::TablesMessage& message) {
  nlohmann::json out;
  out["seq"] = message.seq;
  out["utime"] = message.utime;
  out["content"] = message.content == io::TablesContent::Map ? "map" : "frame";
  const auto base_positions = clients::numberedPositions(message, false);
  std::vector<clients::NumberedPosition> map_positions;
  if (message.map_pose) {
    map_positions = clients::numberedPositions(message, true);
    out["map_pose"] = {{"x", message.map_pose->pose.x},
                       {"y", message.map_pose->pose.y},
                       {"yaw", message.map_pose->pose.yaw}};
  } else {
    out["map_pose"] = nullptr;
  }
  nlohmann::json tables = nlohmann::json::array();
  for (std::size_t i = 0; i < message.tables.size(); ++i) {
    const TableCluster& t = message.tables[i];
    nlohmann::json table = {{"id", t.id},
                            {"top_height", t.top_height},
                            {"center", {t.center.x(), t.center.y()}},
                            {"hull", hullJson(t.hull)},
                            {"point_count", t.point_count},
                            {"mean_confidence", t.mean_confidence}};
    if (i < message.map_info.size()) {
      table["map_id"] = message.map_info[i].map_id;
      table["confirmed"] = message.map_info[i].confirmed;
      table["sightings"] = message.map_info[i].sightings;
      table["viewpoints"] = message.map_info[i].viewpoints;
    }
    nlohmann::json positions = nlohmann::json::array();
    for (const auto& p : base_positions) {
      if (p.table == static_cast<int>(i)) positions.push_back(positionJson(p.position, p.order));
    }
    table["search_positions"] = std::move(positions);
    if (message.map_pose && i < message.map_tables.size()) {
      const io::MapFrameTable& m = message.map_tables[i];
      nlohmann::json map_positions_json = nlohmann::json::array();
      for (const auto& p : map_positions) {
        if (p.table == static_cast<int>(i)) {
          map_positions_json.push_back(positionJson(p.position, p.order));
        }
      }
      table["map"] = {{"center", {m.center.x(), m.center.y()}},
                      {"hull", hullJson(m.hull)},
                      {"search_positions", std::move(map_positions_json)}};
    }
    tables.push_back(std::move(table));
  }
  out["tables"] = std::move(tables);
  return out;
}

nlohmann::json objectsJson(const io::ObjectsMessage& message) {
  nlohmann::json objects = nlohmann::json::array();
  for (std::size_t k = 0; k < message.objects.size(); ++k) {
    const TableObject& o = message.objects[k];
    objects.push_back({{"index", k},
                       {"table", o.table},
                       {"centroid", {o.centroid.x(), o.centroid.y(), o.centroid.z()}},
                       {"center", {o.center.x(), o.center.y()}},
                       {"major_axis", {o.major_axis.x(), o.major_axis.y()}},
                       {"extents", {o.extents.x(), o.extents.y()}},
                       {"height_above_top", o.height_above_top},
                       {"point_count", o.point_count},
                       {"mean_rgb", {o.mean_rgb.x(), o.mean_rgb.y(), o.mean_rgb.z()}},
                       {"truncation", o.truncation}});
    if (message.map_pose && k < message.map_info.size()) {
      const Eigen::Vector3d& m = message.map_info[k].map_centroid;
      objects.back()["map_centroid"] = {m.x(), m.y(), m.z()};
    }
  }
  return {{"seq", message.seq}, {"utime", message.utime}, {"objects", std::move(objects)}};
}

nlohmann::json findResultJson(const io::FindResultMessage& m) {
  static constexpr const char* kResults[] = {"seen", "look_at", "unknown_name", "refused"};
  const auto r = static_cast<std::size_t>(m.result);
  nlohmann::json places = nlohmann::json::array();
  for (const PlaceToLook& p : m.places) {
    places.push_back({{"table_id", p.table_id},
                      {"x", p.position.xy.x()},
                      {"y", p.position.xy.y()},
                      {"searched", p.searched},
                      {"look_closer", p.look_closer},
                      {"seen_here_before", p.seen_here_before}});
  }
  nlohmann::json out = {{"request_id", m.request_id},
                        {"utime", m.utime},
                        {"name", m.name},
                        {"result", r < std::size(kResults) ? kResults[r] : "refused"},
                        {"summary", m.summary},
                        {"places", std::move(places)},
                        {"taught_names", m.taught_names}};
  if (m.result == io::FindResult::Seen) {
    out["seen"] = {{"table_id", m.seen_table_id},
                   {"position", {m.seen_position.x(), m.seen_position.y(), m.seen_position.z()}},
                   {"utime", m.seen_utime},
                   {"score", m.seen_score}};
  }
  return out;
}

void LiveState::onObjects(const io::ObjectsMessage& message) {
  if (message.content != io::TablesContent::Frame) return;
  std::lock_guard lock(mutex_);
  frame_objects_ = message;
}

void LiveState::onFindResult(const io::FindResultMessage& message) {
  std::lock_guard lock(mutex_);
  find_result_ = message;
}

void LiveState::onLabels(const io::LabelImageMessage& message) {
  auto bytes = std::make_shared<const std::vector<std::uint8_t>>(message.image.labels);
  std::shared_ptr<const std::vector<std::uint8_t>> jpeg;
  if (!message.color_jpeg.empty()) {
    jpeg = std::make_shared<const std::vector<std::uint8_t>>(message.color_jpeg);
  }
  io::LabelImageMessage meta;
  meta.utime = message.utime;
  meta.seq = message.seq;
  meta.latency_us = message.latency_us;
  meta.camera = message.camera;
  meta.image.width = message.image.width;
  meta.image.height = message.image.height;
  std::lock_guard lock(mutex_);
  ++label_count_;
  labels_received_us_ = nowUs();
  labels_meta_ = std::move(meta);
  labels_bytes_ = std::move(bytes);
  color_jpeg_ = std::move(jpeg);
}

void LiveState::onTables(const io::TablesMessage& message) {
  std::lock_guard lock(mutex_);
  if (message.content == io::TablesContent::Map) {
    table_map_ = message;
  } else {
    frame_tables_ = message;
  }
}

void LiveState::onSemanticMap(const io::SemanticMapMessage& message) {
  const clients::TopDownCells cells = clients::topDownCells(message);
  auto bytes = std::make_shared<std::vector<std::uint8_t>>(cells.label);
  bytes->insert(bytes->end(), cells.confidence.begin(), cells.confidence.end());
  nlohmann::json meta = {{"seq", message.seq},
                         {"utime", message.utime},
                         {"frames", message.frames},
                         {"voxels", message.voxels.size()},
                         {"voxel_size_m", cells.voxel_size_m},
                         {"cells", cells.cells},
                         {"min_i", cells.min_i},
                         {"max_j", cells.max_j},
                         {"width", cells.width},
                         {"height", cells.height},
                         {"max_height_m", clients::kTopDownMaxHeightM}};
  std::lock_guard lock(mutex_);
  semantic_map_meta_ = std::move(meta);
  semantic_map_ = {message.seq, cells.width, cells.height, std::move(bytes)};
}

std::optional<SemanticMapRaster> LiveState::semanticMap() const {
  std::lock_guard lock(mutex_);
  if (!semantic_map_.bytes) return std::nullopt;
  return semantic_map_;
}

void LiveState::onStatus(const findmug_lcm::status_t& status) {
  StatusSample s;
  s.t = static_cast<double>(status.utime) * 1e-6;
  s.input_fps = status.input_fps;
  s.output_fps = status.output_fps;
  s.cpu_used = status.cpu_used_cores;
  s.cpu_budget = status.cpu_budget_cores;
  for (int i = 0; i < status.num_stages; ++i) {
    if (status.stage_names[static_cast<std::size_t>(i)] == "total") {
      s.latency_p50_ms = static_cast<double>(status.latency_p50_us[static_cast<std::size_t>(i)]) / 1000.0;
      s.latency_p95_ms = static_cast<double>(status.latency_p95_us[static_cast<std::size_t>(i)]) / 1000.0;
    }
  }
  s.dropped_at_door = status.frames_dropped_at_door;
  s.dropped_in_pipeline = status.frames_dropped_in_pipeline;
  s.dropped_at_shutdown = status.frames_dropped_at_shutdown;
  s.rejected = status.frames_rejected;
  std::lock_guard lock(mutex_);
  status_ = status;
  // A daemon restarted (or a log replayed again) goes back in time: start over.
  if (!history_.empty() && s.t < history_.back().t) history_.clear();
  history_.push_back(s);
  while (!history_.empty() && history_.front().t < s.t - history_s_) history_.pop_front();
}

void LiveState::onBadMessage(const std::string& channel, const std::string& what) {
  std::fprintf(stderr, "findmug-web: skipping bad message on %s: %s\n", channel.c_str(),
               what.c_str());
  std::lock_guard lock(mutex_);
  ++bad_messages_[channel];
  last_bad_message_ = what;
}

void LiveState::onBusEnded(const std::string& how) {
  std::lock_guard lock(mutex_);
  bus_state_ = how;
}

std::uint64_t LiveState::labelImages() const {
  std::lock_guard lock(mutex_);
  return label_count_;
}

std::optional<LabelPixels> LiveState::labels() const {
  std::lock_guard lock(mutex_);
  if (!labels_meta_) return std::nullopt;
  return LabelPixels{labels_meta_->seq, labels_meta_->image.width, labels_meta_->image.height,
                     labels_bytes_};
}

std::optional<std::pair<std::int64_t, std::shared_ptr<const std::vector<std::uint8_t>>>>
LiveState::colorJpeg() const {
  std::lock_guard lock(mutex_);
  if (!labels_meta_ || !color_jpeg_) return std::nullopt;
  return std::make_pair(labels_meta_->seq, color_jpeg_);
}

nlohmann::json LiveState::liveJson() const {
  std::lock_guard lock(mutex_);
  nlohmann::json out;
  out["server_time_us"] = nowUs();
  out["bus"] = bus_state_;
  out["label_images"] = label_count_;
  nlohmann::json names = nlohmann::json::array();
  for (auto name : kLabelNames) names.push_back(std::string(name));
  out["label_names"] = std::move(names);
  nlohmann::json colors = nlohmann::json::array();
  for (const Rgb8& c : kLabelColors) colors.push_back({c.r, c.g, c.b});
  out["label_colors"] = std::move(colors);
  if (labels_meta_) {
    const auto& m = *labels_meta_;
    nlohmann::json labels = {{"seq", m.seq},
                             {"utime", m.utime},
                             {"width", m.image.width},
                             {"height", m.image.height},
                             {"latency_us", m.latency_us},
                             {"received_us", labels_received_us_},
                             {"has_color", color_jpeg_ != nullptr}};
    if (m.camera) {
      const auto& k = m.camera->intrinsics;
      const Eigen::Matrix4d t = m.camera->camera_to_base.matrix();
      nlohmann::json rows = nlohmann::json::array();
      for (int i = 0; i < 3; ++i) rows.push_back({t(i, 0), t(i, 1), t(i, 2), t(i, 3)});
      labels["camera"] = {{"fx", k.fx}, {"fy", k.fy}, {"cx", k.cx}, {"cy", k.cy},
                          {"camera_to_base", std::move(rows)}};
    } else {
      labels["camera"] = nullptr;
    }
    out["labels"] = std::move(labels);
  } else {
    out["labels"] = nullptr;
  }
  out["tables"] = frame_tables_ ? tablesJson(*frame_tables_) : nlohmann::json(nullptr);
  out["table_map"] = table_map_ ? tablesJson(*table_map_) : nlohmann::json(nullptr);
  out["semantic_map"] = semantic_map_meta_;
  out["objects"] = frame_objects_ ? objectsJson(*frame_objects_) : nlohmann::json(nullptr);
  out["find"] = find_result_ ? findResultJson(*find_result_) : nlohmann::json(nullptr);
  if (status_) {
    const auto& s = *status_;
    nlohmann::json stages = nlohmann::json::array();
    for (int i = 0; i < s.num_stages; ++i) {
      const auto u = static_cast<std::size_t>(i);
      stages.push_back({{"name", s.stage_names[u]},
                        {"p50_ms", static_cast<double>(s.latency_p50_us[u]) / 1000.0},
                        {"p95_ms", static_cast<double>(s.latency_p95_us[u]) / 1000.0},
                        {"max_ms", static_cast<double>(s.latency_max_us[u]) / 1000.0}});
    }
    nlohmann::json queues = nlohmann::json::array();
    for (int i = 0; i < s.num_queues; ++i) {
      const auto u = static_cast<std::size_t>(i);
      queues.push_back({{"name", s.queue_names[u]},
                        {"depth", s.queue_depths[u]},
                        {"capacity", s.queue_capacities[u]}});
    }
    out["status"] = {{"utime", s.utime},
                     {"uptime_s", static_cast<double>(s.uptime_us) * 1e-6},
                     {"frames_received", s.frames_received},
                     {"frames_processed", s.frames_processed},
                     {"frames_dropped", s.frames_dropped},
                     {"dropped_at_door", s.frames_dropped_at_door},
                     {"dropped_in_pipeline", s.frames_dropped_in_pipeline},
                     {"dropped_at_shutdown", s.frames_dropped_at_shutdown},
                     {"frames_rejected", s.frames_rejected},
                     {"frames_lost_in_transit", s.frames_lost_in_transit},
                     {"publish_failures", s.publish_failures},
                     {"input_fps", s.input_fps},
                     {"output_fps", s.output_fps},
                     {"window_s", s.window_s},
                     {"cpu_used_cores", s.cpu_used_cores},
                     {"cpu_budget_cores", s.cpu_budget_cores},
                     {"processing_threads", s.processing_threads},
                     {"model_id", s.model_id},
                     {"source", s.source},
                     {"source_state", s.source_state_name},
                     {"source_reconnects", s.source_reconnects},
                     {"last_error", s.last_error},
                     {"model_reloads", s.model_reloads},
                     {"model_reloads_refused", s.model_reloads_refused},
                     {"last_reload_ok", s.last_reload_ok != 0},
                     {"last_reload_result", s.last_reload_result},
                     {"last_reload_request_id", s.last_reload_request_id},
                     {"frames_collected", s.frames_collected},
                     {"frames_collect_refused", s.frames_collect_refused},
                     {"last_collected_frame", s.last_collected_frame},
                     {"objects_taught", s.objects_taught},
                     {"teach_refused", s.teach_refused},
                     {"last_teach_ok", s.last_teach_ok != 0},
                     {"last_teach_result", s.last_teach_result},
                     {"last_teach_request_id", s.last_teach_request_id},
                     {"objects",
                      {{"frames", s.object_frames},
                       {"skipped", s.object_frames_skipped},
                       {"candidates", s.object_candidates},
                       {"named", s.objects_named},
                       {"refused",
                        {{"too_big", s.objects_refused_too_big},
                         {"too_small", s.objects_refused_too_small},
                         {"colour", s.objects_refused_colour},
                         {"not_round", s.objects_refused_not_round},
                         {"shape", s.objects_refused_shape},
                         {"few_points", s.objects_refused_few_points}}},
                       {"files_refused", s.object_files_refused},
                       {"find_requests", s.find_requests},
                       {"find_answers", s.find_answers},
                       {"mapped", s.mapped_objects}}},
                     {"stages", std::move(stages)},
                     {"queues", std::move(queues)}};
  } else {
    out["status"] = nullptr;
  }
  nlohmann::json history = nlohmann::json::array();
  for (const auto& h : history_) {
    history.push_back({h.t, h.input_fps, h.output_fps, h.cpu_used, h.cpu_budget,
                       h.latency_p50_ms, h.latency_p95_ms,
                       h.dropped_at_door + h.dropped_in_pipeline + h.dropped_at_shutdown,
                       h.rejected});
  }
  out["history_fields"] = {"t",           "input_fps",      "output_fps", "cpu_used",
                           "cpu_budget",  "latency_p50_ms", "latency_p95_ms", "dropped",
                           "rejected"};
  out["history"] = std::move(history);
  out["history_s"] = history_s_;
  nlohmann::json bad = nlohmann::json::object();
  for (const auto& [channel, n] : bad_messages_) bad[channel] = n;
  out["bad_messages"] = std::move(bad);
  std::uint64_t bad_total = 0;
  for (const auto& [channel, n] : bad_messages_) bad_total += n;
  out["bad_messages_count"] = bad_total;
  out["last_bad_message"] = last_bad_message_;
  return out;
}

}  // namespace findmug::web
