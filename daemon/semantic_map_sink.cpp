// The semantic map sink (semantic_map_sink.hpp).
#include "findmug/daemon/semantic_map_sink.hpp"

#include <spdlog/spdlog.h>

#include <cstdio>
#include <filesystem>

#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/semantic_map_codec.hpp"
#include "findmug/map/table_map.hpp"

namespace findmug::daemon {

SemanticMapSink::SemanticMapSink(Options options, std::shared_ptr<io::Bus> bus,
                                 OnError on_error)
    : options_(std::move(options)),
      on_error_(std::move(on_error)),
      bus_(std::move(bus)),
      map_(options_.map, options_.tables),
      last_save_(Clock::now()) {
  if (!bus_) throw Error("semantic map sink: no output bus");
  // Wakes at least every publish period, so that a change goes out even when no
  // further frame comes.
  StageOptions stage;
  stage.name = "semantic_map";
  stage.mode = options_.threaded ? ExecutionMode::Threaded : ExecutionMode::Sequential;
  stage.queue_capacity = static_cast<std::size_t>(std::max(1, options_.queue_capacity));
  stage.policy = DropPolicy::DropOldest;
  stage.tick_period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(std::max(0.05, options_.publish_period_s)));
  stage.thread_name = "findmug-semmap";
  stage_ = std::make_unique<Stage<Job, Fused>>(
      std::move(stage), StageCallbacks<Job, Fused>{
                            .work = [this](Job& job) -> std::optional<Fused> {
                              fuse(job);
                              publishIfDue(false);
                              saveIfDue(false);
                              return Fused{};
                            },
                            .emit = [](Fused&&) {},
                            .on_drop = [this](const Job&) { skipped_.fetch_add(1); },
                            .on_error = on_error_,
                            .tick =
                                [this] {
                                  publishIfDue(false);
                                  saveIfDue(false);
                                },
                        });
  if (options_.file.empty() || !std::filesystem::exists(options_.file)) return;
  try {
    map_.load(options_.file);
    spdlog::info("semantic map: loaded {} voxels ({} frames) from {}", map_.size(),
                 map_.stats().frames, options_.file);
    changed_ = true;
  } catch (const std::exception& e) {
    const std::string refused = options_.file + ".refused";
    std::error_code ec;
    std::filesystem::rename(options_.file, refused, ec);
    if (on_error_) {
      on_error_(std::string(e.what()) + "; starting with an empty map" +
                (ec ? " (could not rename the file: " + ec.message() + ")"
                    : " (the file is kept as " + refused + ")"));
    }
  }
}

SemanticMapSink::~SemanticMapSink() { stop(false); }

void SemanticMapSink::start() { stage_->start(); }

void SemanticMapSink::consume(FrameResult& result) {
  if (stopped_.load() || !result.pose || !TableMapSink::isEvidence(result.labelled)) return;
  const PreparedFrame& prepared = result.labelled.segmented.prepared;
  Job job;
  job.camera_in_map = cameraInMap(result.pose->pose, prepared.ground->camera_to_ground);
  if (options_.fused_labels) {
    std::unique_lock lock(map_mutex_, std::try_to_lock);
    if (lock.owns_lock()) {
      result.published_labels = map_.projectLabels(prepared.cloud_camera, result.labelled.labels,
                                                   job.camera_in_map);
      fused_frames_.fetch_add(1);
    } else {
      fused_busy_.fetch_add(1);
    }
  }
  job.cloud_camera = prepared.cloud_camera;
  job.labels = result.labelled.labels;
  job.pose = *result.pose;
  job.utime = prepared.frame.utime;
  job.seq = prepared.frame.seq;
  queued_.fetch_add(1);
  stage_->push(std::move(job));  // sequential: fused (and published when due) right here
}

void SemanticMapSink::fuse(Job& job) {
  if (options_.before_fuse) options_.before_fuse();
  std::lock_guard lock(map_mutex_);
  try {
    map_.integrate(job.cloud_camera, job.labels, job.camera_in_map, job.utime);
  } catch (const std::exception& e) {
    failed_.fetch_add(1);
    if (on_error_) on_error_("frame seq " + std::to_string(job.seq) + ": semantic map: " + e.what());
    return;
  }
  integrated_.fetch_add(1);
  changed_ = unsaved_ = true;
  last_pose_ = job.pose;
  last_utime_ = job.utime;
  last_seq_ = job.seq;
}

void SemanticMapSink::publishIfDue(bool force) {
  io::TablesMessage tables_message;
  findmug_lcm::semantic_map_t map_message;
  {
    std::lock_guard lock(map_mutex_);
    const auto now = Clock::now();
    const bool due =
        last_publish_ == Clock::time_point{} ||
        now - last_publish_ >= std::chrono::duration<double>(options_.publish_period_s);
    if (!changed_ || (!due && !force)) return;
    last_publish_ = now;
    changed_ = false;
    try {
      tables_ = map_.tables();
    } catch (const std::exception& e) {
      // Keep the last tables; the map itself is still published.
      if (on_error_) on_error_(std::string("semantic map: no tables: ") + e.what());
    }
    tables_message.utime = last_utime_;
    tables_message.seq = last_seq_;
    tables_message.content = io::TablesContent::Map;
    tables_message.map_pose = last_pose_;
    // The encoder derives the map_ fields from base-frame tables and the pose.
    const Pose2D map_to_base = inversePose(last_pose_.pose);
    for (const FusedTable& t : tables_) {
      tables_message.tables.push_back(transformTable(t.table, map_to_base));
      tables_message.map_info.push_back({t.table.id, true, t.frames, t.viewpoints});
    }
    map_message = io::encodeSemanticMap(io::semanticMapMessage(map_, last_utime_, last_seq_));
  }
  if (spdlog::should_log(spdlog::level::debug)) {
    for (const FusedTable& t : tables()) {
      spdlog::debug("semantic map: table {} at ({:.2f}, {:.2f}), {} voxels, {} frames, {} "
                    "viewpoints",
                    t.table.id, t.table.center.x(), t.table.center.y(), t.voxels, t.frames,
                    t.viewpoints);
    }
  }
  const bool sent_tables = io::publishMessage(*bus_, options_.table_map_channel,
                                              io::encodeTables(tables_message));
  const bool sent_map = io::publishMessage(*bus_, options_.map_channel, map_message);
  if (!sent_tables || !sent_map) {
    if (on_error_) {
      on_error_("semantic map: LCM publish on " +
                (sent_tables ? options_.map_channel : options_.table_map_channel) + " failed");
    }
    return;
  }
  publishes_.fetch_add(1);
}

void SemanticMapSink::saveIfDue(bool force) {
  if (options_.file.empty()) return;
  std::lock_guard lock(map_mutex_);
  const auto now = Clock::now();
  if (!unsaved_) return;
  if (!force && now - last_save_ < std::chrono::duration<double>(options_.save_period_s)) return;
  last_save_ = now;
  try {
    map_.save(options_.file);
    unsaved_ = false;
  } catch (const std::exception& e) {
    if (on_error_) on_error_(e.what());
  }
}

void SemanticMapSink::stop(bool drain) {
  if (stopped_.exchange(true)) return;
  stage_->stop(drain ? StopMode::Drain : StopMode::Discard);
  if (bus_) {
    publishIfDue(true);
    saveIfDue(true);
  }
  bus_.reset();
}

SemanticMapSink::Counters SemanticMapSink::counters() const {
  Counters c;
  c.queued = queued_.load();
  c.skipped = skipped_.load();
  c.integrated = integrated_.load();
  c.failed = failed_.load();
  c.publishes = publishes_.load();
  c.fused_frames = fused_frames_.load();
  c.fused_busy = fused_busy_.load();
  c.queue_depth = stage_->queueSize();
  c.queue_capacity = static_cast<std::size_t>(std::max(1, options_.queue_capacity));
  std::lock_guard lock(map_mutex_);
  const SemanticMapStats stats = map_.stats();
  c.voxels = stats.voxels;
  c.memory_bytes = stats.memory_bytes;
  return c;
}

std::vector<FusedTable> SemanticMapSink::tables() const {
  std::lock_guard lock(map_mutex_);
  return tables_;
}

}  // namespace findmug::daemon
