// The table-map and LCM publisher sinks; see result_sinks.hpp.
#include "findmug/daemon/result_sinks.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <optional>
#include <utility>

#include "findmug/common/error.hpp"
#include "findmug/daemon/status_builder.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/lcm_codec_objects.hpp"
#include "findmug/map/depth_view.hpp"
#include "findmug/map/semantic_map.hpp"

namespace findmug::daemon {

std::string frameName(const RgbdFrame& f) {
  return (f.source.empty() ? std::string("frame") : f.source) + " seq " + std::to_string(f.seq);
}

// ---- TableMapSink -------------------------------------------------------------------

TableMapSink::TableMapSink(const TableMapConfig& map_config, const TableConfig& tables_config,
                           bool publish_map, OnError on_error)
    : publish_map_(publish_map), on_error_(std::move(on_error)), map_(map_config, tables_config) {}

bool TableMapSink::isEvidence(const LabelledFrame& labelled) {
  return labelled.segmented.prepared.ground.has_value() &&
         std::any_of(labelled.labels.labels.begin(), labelled.labels.labels.end(),
                     [](std::uint8_t id) { return id != kVoidLabel; });
}

std::string resultSlotNames(unsigned slots) {
  std::string names;
  for (const auto& [bit, name] : {std::pair<unsigned, const char*>{kMapInfo, "map_info"},
                                  {kTableMapMessage, "table_map"},
                                  {kPublishedLabels, "published_labels"}}) {
    if (!(slots & bit)) continue;
    if (!names.empty()) names += ", ";
    names += name;
  }
  return names;
}

void TableMapSink::consume(FrameResult& result) {
  if (!result.pose || !isEvidence(result.labelled)) return;
  if (!update(result.labelled, *result.pose, &result.map_info)) return;
  updates_.fetch_add(1);
  if (publish_map_) {
    result.table_map = mapMessage(result.labelled.segmented.prepared.frame, *result.pose);
  }
}

bool TableMapSink::update(const LabelledFrame& labelled, const io::RobotPose& pose,
                          std::vector<io::TableMapInfo>* map_info) {
  const RgbdFrame& frame = labelled.segmented.prepared.frame;
  const Pose2D& base_in_map = pose.pose;
  std::lock_guard lock(mutex_);
  // The frame's depth and its camera in the map: a mapped table that something hid from
  // this view is not missed in it.
  std::optional<DepthView> view;
  const auto& ground = labelled.segmented.prepared.ground;
  if (ground && frame.width > 0 && frame.height > 0 &&
      frame.depth_mm.size() == static_cast<std::size_t>(frame.width) * frame.height)
    view.emplace(frame, cameraInMap(base_in_map, ground->camera_to_ground));
  TableMapUpdate update;
  try {
    update = map_.update(labelled.tables, base_in_map, frame.utime, view ? &*view : nullptr);
  } catch (const std::exception& e) {
    // E.g. a source that restarted its clock: the frame is still published,
    // in the base frame and with its map pose, but the map skips it.
    if (on_error_) on_error_(frameName(frame) + ": table map not updated: " + e.what());
    return false;
  }
  if (spdlog::should_log(spdlog::level::debug)) {
    auto ids = [](const std::vector<int>& v) {
      std::string out;
      for (int id : v) {
        if (!out.empty()) out += ',';
        out += std::to_string(id);
      }
      return out.empty() ? std::string("-") : out;
    };
    spdlog::debug(
        "{}: table map at ({:.2f}, {:.2f}, yaw {:.3f}): {} seen -> ids [{}]; created [{}], "
        "confirmed [{}], forgotten [{}]; {} mapped",
        frameName(frame), pose.pose.x, pose.pose.y, pose.pose.yaw, labelled.tables.size(),
        ids(update.assigned_ids), ids(update.created), ids(update.confirmed), ids(update.forgotten),
        map_.tables().size());
    for (const std::string& line : update.diagnostics) {
      spdlog::debug("{}: table map: {}", frameName(frame), line);
    }
  }
  if (!update.assigned_ids.empty() || !update.created.empty() || !update.confirmed.empty() ||
      !update.forgotten.empty()) {
    revision_.fetch_add(1);
  }
  map_info->clear();
  for (int id : update.assigned_ids) {
    io::TableMapInfo info;
    for (const MappedTable& t : map_.tables()) {
      if (t.table.id == id) info = {id, t.confirmed, t.sightings, 0};
    }
    map_info->push_back(info);
  }
  return true;
}

io::TablesMessage TableMapSink::mapMessage(const RgbdFrame& frame,
                                           const io::RobotPose& pose) const {
  io::TablesMessage message;
  message.utime = frame.utime;
  message.seq = frame.seq;
  message.content = io::TablesContent::Map;
  message.map_pose = pose;
  // The encoder derives the map_ fields from base-frame tables and the pose:
  // hand it the mapped tables relative to the robot at this pose.
  const Pose2D map_to_base = inversePose(pose.pose);
  std::lock_guard lock(mutex_);
  for (const MappedTable& t : map_.tables()) {
    if (!t.confirmed) continue;
    message.tables.push_back(transformTable(t.table, map_to_base));
    message.map_info.push_back({t.table.id, true, t.sightings, 0});  // no viewpoints counted
  }
  return message;
}

std::vector<MappedTable> TableMapSink::tables() const {
  std::lock_guard lock(mutex_);
  return map_.tables();
}

std::vector<TableCluster> TableMapSink::confirmedTables() const {
  std::lock_guard lock(mutex_);
  return map_.confirmedTables();
}

// ---- LcmPublisherSink -----------------------------------------------------------------

LcmPublisherSink::LcmPublisherSink(std::shared_ptr<io::Bus> bus, Channels channels,
                                   bool publish_confidence, bool publish_tables)
    : bus_(std::move(bus)),
      channels_(std::move(channels)),
      publish_confidence_(publish_confidence),
      publish_tables_(publish_tables) {}

std::shared_ptr<io::Bus> LcmPublisherSink::bus() const {
  std::lock_guard lock(bus_mutex_);
  return bus_;
}

template <class Msg>
bool LcmPublisherSink::send(const std::string& channel, const Msg& message) {
  const std::shared_ptr<io::Bus> bus = this->bus();
  if (bus && io::publishMessage(*bus, channel, message)) return true;
  failures_.fetch_add(1);
  return false;
}

void LcmPublisherSink::consume(FrameResult& result) {
  const RgbdFrame& frame = result.labelled.segmented.prepared.frame;
  // Encoded from the frame's own label image and tables: copying them into
  // message structs first cost a copy of 1.5 MB and of every table's pixel
  // list per frame.
  // The map's labels when the semantic map sink replaced them (daemon.semantic_map_fused_labels).
  const LabelImage& published =
      result.published_labels ? *result.published_labels : result.labelled.labels;
  findmug_lcm::label_image_t labels = io::encodeLabelImage(
      published, frame.utime, frame.seq, result.latency_us, publish_confidence_);
  // The camera as this frame used it (mount or estimated floor), so that viewers can
  // draw the tables over the image for every source.
  if (const auto& ground = result.labelled.segmented.prepared.ground) {
    io::setCameraView(labels, frame.intrinsics, ground->camera_to_ground.cast<double>());
  }
  if (color_jpeg_quality_ > 0 && frame.rgb.size() == published.labels.size()) {
    io::setColorJpeg(labels, frame.rgb, color_jpeg_quality_);
  }
  if (!send(channels_.labels, labels)) {
    throw Error("LCM publish on " + channels_.labels + " failed for " + frameName(frame));
  }
  if (publish_tables_) {
    if (!send(channels_.tables,
              io::encodeTables(frame.utime, frame.seq, io::TablesContent::Frame,
                               result.labelled.tables, result.pose, result.map_info))) {
      throw Error("LCM publish on " + channels_.tables + " failed for " + frameName(frame));
    }
    // With every tables_t, even without candidates: an empty list tells a
    // client the tables were looked at and hold nothing.
    if (!send(channels_.objects,
              io::encodeObjects(frame.utime, frame.seq, result.labelled.table_objects,
                                result.labelled.tables, result.pose, result.map_info))) {
      throw Error("LCM publish on " + channels_.objects + " failed for " + frameName(frame));
    }
  }
  if (result.table_map) {
    if (!send(channels_.table_map, io::encodeTables(*result.table_map))) {
      throw Error("LCM publish on " + channels_.table_map + " failed for " + frameName(frame));
    }
  }
}

bool LcmPublisherSink::publishStatus(const StatusSnapshot& snapshot) {
  if (!bus()) return false;  // closed: the final status has gone out already
  if (!send(channels_.status, StatusBuilder::build(snapshot))) {
    spdlog::warn("LCM publish on {} failed", channels_.status);
    return false;
  }
  return true;
}

void LcmPublisherSink::close() {
  std::shared_ptr<io::Bus> released;
  {
    std::lock_guard lock(bus_mutex_);
    released = std::move(bus_);
  }
  // `released` goes here (unless a publish still holds it: then after that one).
}

}  // namespace findmug::daemon
