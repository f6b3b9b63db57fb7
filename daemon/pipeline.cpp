// The daemon's threaded pipeline; see pipeline.hpp for the picture.
#include "findmug/daemon/pipeline.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <lcm/lcm-cpp.hpp>
#include <thread>

#include "findmug/error.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/frame_source.hpp"
#include "findmug/io/lcm_codec.hpp"

namespace findmug::daemon {

struct Pipeline::FrameJob {
  RgbdFrame frame;
  Clock::time_point arrival;
};
struct Pipeline::PreparedJob {
  PreparedFrame prepared;
  Clock::time_point arrival;
};
struct Pipeline::ResultJob {
  LabelledFrame labelled;
  Clock::time_point arrival;
};

namespace {

// Sub-stage names reported in status_t, in pipeline order, with the
// StageTimings field each comes from. "prepare"/"segment"/"publish" are the
// pipeline stages' wall times, "total" is arrival to published.
const std::vector<std::pair<std::string, double StageTimings::*>>& subStages() {
  static const std::vector<std::pair<std::string, double StageTimings::*>> all = {
      {"cloud", &StageTimings::cloud_ms},       {"normals", &StageTimings::normals_ms},
      {"ground", &StageTimings::ground_ms},     {"supervoxels", &StageTimings::overseg_ms},
      {"features", &StageTimings::features_ms}, {"regions", &StageTimings::regions_ms},
      {"forest", &StageTimings::forest_ms},     {"context", &StageTimings::context_ms},
      {"mrf", &StageTimings::mrf_ms},           {"labels", &StageTimings::labels_ms},
      {"tables", &StageTimings::tables_ms}};
  return all;
}

std::uint64_t utimeNow() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                        std::chrono::system_clock::now().time_since_epoch())
                                        .count());
}

double processCpuSeconds() {
  timespec ts{};
  if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts) != 0) return 0.0;
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

std::string frameName(const RgbdFrame& f) {
  return (f.source.empty() ? std::string("frame") : f.source) + " seq " + std::to_string(f.seq);
}

}  // namespace

Pipeline::Pipeline(const SegmenterConfig& segmenter_config, const DaemonConfig& daemon_config,
                   std::shared_ptr<const RandomForest> forest, std::string model_id,
                   ExecutionMode mode, PipelineHooks hooks)
    : daemon_config_(daemon_config),
      labels_channel_(io::channelName(io::kLabelsChannel, daemon_config.channel_suffix)),
      tables_channel_(io::channelName(io::kTablesChannel, daemon_config.channel_suffix)),
      status_channel_(io::channelName(io::kStatusChannel, daemon_config.channel_suffix)),
      table_map_channel_(io::channelName(io::kTableMapChannel, daemon_config.channel_suffix)),
      segmenter_(segmenter_config, forest),
      model_id_(std::move(model_id)),
      mode_(mode),
      hooks_(std::move(hooks)),
      workers_(daemon_config.effectiveWorkers()),
      pose_max_age_us_(static_cast<std::uint64_t>(std::llround(daemon_config.pose_max_age_s * 1e6))),
      table_map_(daemon_config.table_map, segmenter_config.tables),
      started_(Clock::now()),
      last_sequential_status_(started_),
      cpu_sample_time_(started_),
      cpu_sample_s_(processCpuSeconds()) {
  if (!forest || forest->empty()) throw Error("findmugd: the model has no trees");
  const std::string url = effectiveLcmUrl(daemon_config_);
  lcm_ = std::make_unique<lcm::LCM>(url);
  if (!lcm_->good()) {
    throw Error("daemon.lcm_url: cannot open LCM provider '" + (url.empty() ? "<default>" : url) +
                "'");
  }
  const auto window = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(daemon_config_.stats_window_s));
  input_rate_ = RateMeter(1000, window);
  output_rate_ = RateMeter(1000, window);
  for (const auto& [name, field] : subStages()) latency_.emplace(name, LatencyWindow(window));
  latency_.emplace("total", LatencyWindow(window));

  const auto capacity = static_cast<std::size_t>(daemon_config_.queue_capacity);
  auto on_error = [this](const std::string& what) { recordError(what); };

  StageOptions publish_options{"publish",
                               mode_,
                               1,
                               capacity,
                               DropPolicy::Block,
                               window,
                               std::chrono::duration_cast<Clock::duration>(
                                   std::chrono::duration<double>(daemon_config_.status_period_s))};
  publish_ = std::make_unique<Stage<ResultJob, Published>>(
      publish_options,
      [this](ResultJob& job) -> std::optional<Published> {
        publishResult(job);
        return Published{};
      },
      [](Published&&) {}, Stage<ResultJob, Published>::OnDrop{}, on_error,
      [this] { publishStatus(); });

  StageOptions segment_options{"segment", mode_, workers_, capacity, DropPolicy::DropOldest,
                               window};
  segment_ = std::make_unique<Stage<PreparedJob, ResultJob>>(
      segment_options,
      [this](PreparedJob& job) -> std::optional<ResultJob> {
        if (hooks_.before_segment) hooks_.before_segment(job.prepared.frame);
        const std::string name = frameName(job.prepared.frame);
        try {
          return ResultJob{segmenter_.classify(segmenter_.oversegment(std::move(job.prepared))),
                           job.arrival};
        } catch (const std::exception& e) {
          throw Error(name + ": " + e.what());
        }
      },
      [this](ResultJob&& r) {
        if (!publish_->push(std::move(r))) abandoned_.fetch_add(1);  // only after stop()
      },
      [](const PreparedJob& dropped) {
        spdlog::debug("segment queue full: dropped {}", frameName(dropped.prepared.frame));
      },
      on_error);

  StageOptions prepare_options{"prepare", mode_, 1, capacity, DropPolicy::DropOldest, window};
  prepare_ = std::make_unique<Stage<FrameJob, PreparedJob>>(
      prepare_options,
      [this](FrameJob& job) -> std::optional<PreparedJob> {
        const std::string name = frameName(job.frame);
        try {
          validateFrame(job.frame);
          return PreparedJob{segmenter_.prepare(std::move(job.frame)), job.arrival};
        } catch (const std::exception& e) {
          throw Error(name + ": " + e.what());
        }
      },
      [this](PreparedJob&& p) {
        if (!segment_->push(std::move(p))) abandoned_.fetch_add(1);  // only after stop()
      },
      [](const FrameJob& dropped) {
        spdlog::debug("pipeline entry full: dropped {} at the door", frameName(dropped.frame));
      },
      on_error, Stage<FrameJob, PreparedJob>::Tick{},
      // The door: take the next frame only when the segment queue can accept
      // it, so that under overload frames wait — and the oldest is dropped —
      // here, before any work is spent on them.
      [this] {
        while (!segment_->waitForRoom(std::chrono::milliseconds(50))) {
          if (segment_->closed()) break;
          // Stopping: discarded (nothing left to take) or draining into a
          // live segment stage (waits for room like any frame).
          if (prepare_->closed() && prepare_->queueSize() == 0) break;
        }
      });

  // Last: its thread reports through recordError, so everything it may touch
  // must exist already.
  if (const auto pose_url = effectivePoseUrl(daemon_config_)) {
    const std::string channel =
        io::channelName(io::kRobotPoseChannel, daemon_config_.channel_suffix);
    pose_input_ = std::make_unique<PoseInput>(*pose_url, channel, daemon_config_.pose_history_s,
                                              [this](const std::string& what) {
                                                recordError(what);
                                              });
    spdlog::info("robot poses from {} on {}: tables also in the map frame, table map on {}",
                 pose_url->empty() ? "the default LCM provider" : *pose_url, channel,
                 table_map_channel_);
  } else {
    spdlog::info("no robot pose input ({}): tables in the base frame only, no table map",
                 daemon_config_.pose_input ? "the output is a log file and daemon.pose_url is empty"
                                           : "daemon.pose_input is off");
  }
}

Pipeline::~Pipeline() { stop(StopMode::Discard); }

void Pipeline::attachSource(const io::FrameSource* source) { source_.store(source); }

void Pipeline::start() {
  publish_->start();
  segment_->start();
  prepare_->start();
}

bool Pipeline::submit(RgbdFrame frame) {
  {
    std::lock_guard lock(stop_mutex_);
    if (stopped_) return false;
  }
  received_.fetch_add(1);
  {
    std::lock_guard lock(stats_mutex_);
    input_rate_.tick();
  }
  const bool accepted = prepare_->push(FrameJob{std::move(frame), Clock::now()});
  // No publish thread ticks in sequential mode: keep the status period here.
  publishStatusIfDue();
  return accepted;
}

bool Pipeline::waitForRoom(Clock::duration timeout) {
  if (mode_ == ExecutionMode::Sequential) return true;  // submit() runs the frame itself
  return prepare_->waitForRoom(timeout);
}

void Pipeline::publishStatusIfDue() {
  if (mode_ != ExecutionMode::Sequential) return;  // the publish thread does it
  std::lock_guard lock(sequential_status_mutex_);
  const auto now = Clock::now();
  if (now - last_sequential_status_ >=
      std::chrono::duration<double>(daemon_config_.status_period_s)) {
    publishStatus();
    last_sequential_status_ = now;
  }
}

void Pipeline::publishStatusNow() { publishStatus(); }

int Pipeline::processingThreads() const {
  // Sequential: the caller's thread runs every stage. Threaded: prepare,
  // the segmentation workers and publish.
  return mode_ == ExecutionMode::Sequential ? 1 : workers_ + 2;
}

void Pipeline::stop(StopMode mode) {
  {
    std::lock_guard lock(stop_mutex_);
    if (stopped_) return;
    stopped_ = true;
  }
  // Upstream first, so every stage can still hand its last results on.
  prepare_->stop(mode);
  segment_->close(mode);
  if (mode == StopMode::Drain) {
    segment_->join();
  } else {
    // A segmentation cannot be interrupted. Wait for the frames in flight
    // only as long as the shutdown budget allows; later ones are abandoned
    // (counted as dropped) and their workers joined by the destructor.
    const auto deadline =
        Clock::now() + std::chrono::duration_cast<Clock::duration>(
                           std::chrono::duration<double>(daemon_config_.shutdown_grace_s));
    while (segment_->stats().in_flight > 0 && Clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    if (segment_->stats().in_flight == 0) segment_->join();
  }
  publish_->stop(StopMode::Drain);  // finished results are always published
  // Nobody looks poses up any more: stop the pose thread, close its handle.
  if (pose_input_) pose_input_->stop();
  finalized_.store(true);
  // The publish thread is gone: this thread may use the LCM handle now.
  publishStatus();
  // Close the handle: flushes a file:// log, leaves a udpm multicast group.
  std::lock_guard lcm_lock(lcm_mutex_);
  lcm_.reset();
  const auto c = counters();
  spdlog::info("pipeline stopped: {} received, {} processed, {} dropped, {} rejected", c.received,
               c.processed, c.dropped, c.rejected);
}

void Pipeline::recordError(const std::string& message) {
  spdlog::warn("{}", message);
  std::lock_guard lock(stats_mutex_);
  last_error_ = message;
  last_error_utime_ = utimeNow();
}

void Pipeline::publishResult(ResultJob& job) {
  const LabelledFrame& labelled = job.labelled;
  const RgbdFrame& frame = labelled.segmented.prepared.frame;
  const auto now = Clock::now();
  const auto latency_us =
      std::chrono::duration_cast<std::chrono::microseconds>(now - job.arrival).count();

  io::LabelImageMessage labels;
  labels.image = labelled.labels;
  labels.utime = frame.utime;
  labels.seq = frame.seq;
  labels.latency_us = latency_us;
  const findmug_lcm::label_image_t label_msg =
      io::encodeLabelImage(labels, daemon_config_.publish_confidence);
  std::unique_lock lcm_lock(lcm_mutex_);
  if (lcm_->publish(labels_channel_, &label_msg) != 0) {
    throw Error("LCM publish on " + labels_channel_ + " failed for " + frameName(frame));
  }
  lcm_lock.unlock();
  if (spdlog::should_log(spdlog::level::debug)) {
    for (const std::string& line : labelled.table_diagnostics) {
      spdlog::debug("{}: tables: {}", frameName(frame), line);
    }
  }

  // The robot's pose for this frame, if one close enough in time has arrived.
  std::optional<io::RobotPose> pose;
  if (pose_input_) pose = pose_input_->history().closest(frame.utime, pose_max_age_us_);
  std::vector<io::TableMapInfo> map_info;
  bool map_updated = false;
  // Only a labelled frame is evidence about tables: without a ground plane
  // nothing was classified, and with no labelled pixel at all (no valid
  // depth: a covered or blinded sensor, while the mount still gives a
  // ground plane) nothing was seen. "No table seen" would then wrongly count
  // as a miss for every mapped table in view.
  const bool evidence =
      labelled.segmented.prepared.ground.has_value() &&
      std::any_of(labelled.labels.labels.begin(), labelled.labels.labels.end(),
                  [](std::uint8_t id) { return id != kVoidLabel; });
  if (pose && evidence) {
    map_updated = updateTableMap(labelled, *pose, &map_info);
  }

  if (daemon_config_.publish_tables) {
    io::TablesMessage tables;
    tables.utime = frame.utime;
    tables.seq = frame.seq;
    tables.tables = labelled.tables;
    tables.map_pose = pose;
    tables.map_info = std::move(map_info);
    const findmug_lcm::tables_t tables_msg = io::encodeTables(tables);
    std::lock_guard lcm_lock2(lcm_mutex_);
    if (lcm_->publish(tables_channel_, &tables_msg) != 0) {
      throw Error("LCM publish on " + tables_channel_ + " failed for " + frameName(frame));
    }
  }
  if (map_updated && daemon_config_.publish_table_map) publishTableMap(frame, *pose);
  processed_.fetch_add(1);
  std::lock_guard lock(stats_mutex_);
  output_rate_.tick(now);
  for (const auto& [name, field] : subStages()) latency_.at(name).add(labelled.timings.*field, now);
  latency_.at("total").add(static_cast<double>(latency_us) / 1000.0, now);
}

bool Pipeline::updateTableMap(const LabelledFrame& labelled, const io::RobotPose& pose,
                              std::vector<io::TableMapInfo>* map_info) {
  const RgbdFrame& frame = labelled.segmented.prepared.frame;
  const Pose2D base_in_map{pose.x, pose.y, pose.yaw};
  std::lock_guard lock(map_mutex_);
  TableMapUpdate update;
  try {
    update = table_map_.update(labelled.tables, base_in_map, frame.utime);
  } catch (const std::exception& e) {
    // E.g. a source that restarted its clock: the frame is still published,
    // in the base frame and with its map pose, but the map skips it.
    recordError(frameName(frame) + ": table map not updated: " + e.what());
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
        frameName(frame), pose.x, pose.y, pose.yaw, labelled.tables.size(),
        ids(update.assigned_ids), ids(update.created), ids(update.confirmed),
        ids(update.forgotten), table_map_.tables().size());
    for (const std::string& line : update.diagnostics) {
      spdlog::debug("{}: table map: {}", frameName(frame), line);
    }
  }
  map_info->clear();
  for (int id : update.assigned_ids) {
    io::TableMapInfo info;
    for (const MappedTable& t : table_map_.tables()) {
      if (t.table.id == id) info = {id, t.confirmed, t.sightings};
    }
    map_info->push_back(info);
  }
  return true;
}

void Pipeline::publishTableMap(const RgbdFrame& frame, const io::RobotPose& pose) {
  io::TablesMessage message;
  message.utime = frame.utime;
  message.seq = frame.seq;
  message.content = io::TablesContent::Map;
  message.map_pose = pose;
  // The encoder derives the map_ fields from base-frame tables and the pose:
  // hand it the mapped tables relative to the robot at this pose.
  const Pose2D map_to_base = inversePose(Pose2D{pose.x, pose.y, pose.yaw});
  {
    std::lock_guard lock(map_mutex_);
    for (const MappedTable& t : table_map_.tables()) {
      if (!t.confirmed) continue;
      message.tables.push_back(transformTable(t.table, map_to_base));
      message.map_info.push_back({t.table.id, true, t.sightings});
    }
  }
  const findmug_lcm::tables_t msg = io::encodeTables(message);
  std::lock_guard lcm_lock(lcm_mutex_);
  if (lcm_->publish(table_map_channel_, &msg) != 0) {
    throw Error("LCM publish on " + table_map_channel_ + " failed for " + frameName(frame));
  }
}

std::vector<MappedTable> Pipeline::mappedTables() const {
  std::lock_guard lock(map_mutex_);
  return table_map_.tables();
}

PipelineCounters Pipeline::counters() const {
  PipelineCounters c;
  c.received = received_.load();
  c.processed = processed_.load();
  const StageStats pre = prepare_->stats(), seg = segment_->stats(), pub = publish_->stats();
  for (const StageStats* s : {&pre, &seg, &pub}) {
    c.dropped += s->dropped;
    c.rejected += s->failed;
    c.pending += s->queue_depth + s->in_flight;
    c.dropped_at_shutdown += s->dropped - s->evicted;  // discarded by stop()
  }
  c.dropped_at_door = pre.evicted;  // the prepare queue is the pipeline's entry
  c.dropped_in_pipeline = seg.evicted + pub.evicted;
  c.dropped += abandoned_.load();
  c.dropped_at_shutdown += abandoned_.load();
  if (pose_input_) c.rejected += pose_input_->rejected();
  if (finalized_.load()) {
    // Stopped: whatever is still in a stage will never be published.
    c.dropped += c.pending;
    c.dropped_at_shutdown += c.pending;
    c.pending = 0;
  }
  if (const io::FrameSource* source = source_.load()) {
    const io::SourceStats s = source->stats();
    // The source drops before decoding: at the door (its frames still
    // queued at a stop are counted there too).
    c.dropped += s.frames_dropped;
    c.dropped_at_door += s.frames_dropped;
    c.rejected += s.frames_rejected;
  }
  return c;
}

ProgressSnapshot Pipeline::progress() const {
  ProgressSnapshot p;
  const StageStats seg = segment_->stats(), pub = publish_->stats(), pre = prepare_->stats();
  // Frames that LEFT the pipeline: published, or failed in some stage. A
  // frame merely passing an early stage does not count: with the bottleneck
  // stuck, prepare would otherwise keep "progressing" forever.
  p.frames_completed = pre.failed + seg.failed + pub.completed + pub.failed;
  p.frames_pending = pre.queue_depth + pre.in_flight + seg.queue_depth + seg.in_flight +
                     pub.queue_depth + pub.in_flight;
  return p;
}

findmug_lcm::status_t Pipeline::makeStatus() const {
  findmug_lcm::status_t s{};
  const auto now = Clock::now();
  s.utime = static_cast<std::int64_t>(utimeNow());
  s.uptime_us = std::chrono::duration_cast<std::chrono::microseconds>(now - started_).count();
  const PipelineCounters c = counters();
  s.frames_received = static_cast<std::int64_t>(c.received);
  s.frames_processed = static_cast<std::int64_t>(c.processed);
  s.frames_dropped = static_cast<std::int64_t>(c.dropped);
  s.frames_rejected = static_cast<std::int64_t>(c.rejected);
  s.frames_dropped_at_door = static_cast<std::int64_t>(c.dropped_at_door);
  s.frames_dropped_in_pipeline = static_cast<std::int64_t>(c.dropped_in_pipeline);
  s.frames_dropped_at_shutdown = static_cast<std::int64_t>(c.dropped_at_shutdown);
  s.cpu_budget_cores = static_cast<float>(daemon_config_.max_cpu_cores);
  s.processing_threads = static_cast<std::int32_t>(processingThreads());
  s.window_s = daemon_config_.stats_window_s;

  const StageStats stages[] = {prepare_->stats(), segment_->stats(), publish_->stats()};
  auto add_latency = [&](const std::string& name, const LatencySummary& l) {
    s.stage_names.push_back(name);
    s.latency_p50_us.push_back(static_cast<std::int64_t>(l.p50_ms * 1000.0));
    s.latency_p95_us.push_back(static_cast<std::int64_t>(l.p95_ms * 1000.0));
    s.latency_max_us.push_back(static_cast<std::int64_t>(l.max_ms * 1000.0));
  };
  std::string last_error;
  std::uint64_t last_error_utime = 0;
  {
    std::lock_guard lock(stats_mutex_);
    s.input_fps = static_cast<float>(input_rate_.rate(now));
    s.output_fps = static_cast<float>(output_rate_.rate(now));
    for (const auto& st : stages) add_latency(st.name, st.latency);
    for (const auto& [name, field] : subStages()) add_latency(name, latency_.at(name).summary(now));
    add_latency("total", latency_.at("total").summary(now));
    last_error = last_error_;
    last_error_utime = last_error_utime_;
    s.cpu_used_cores = static_cast<float>(cpu_used_cores_);
  }
  s.num_stages = static_cast<std::int32_t>(s.stage_names.size());
  for (const auto& st : stages) {
    s.queue_names.push_back(st.name);
    s.queue_depths.push_back(static_cast<std::int32_t>(st.queue_depth));
    s.queue_capacities.push_back(static_cast<std::int32_t>(st.queue_capacity));
  }
  s.num_queues = static_cast<std::int32_t>(s.queue_names.size());
  s.model_id = model_id_;

  if (const io::FrameSource* source = source_.load()) {
    const io::SourceState state = source->state();
    const io::SourceStats stats = source->stats();
    s.source = source->describe();
    s.source_state = static_cast<std::int8_t>(state);
    s.source_state_name = std::string(io::sourceStateName(state));
    s.source_reconnects = static_cast<std::int64_t>(stats.reconnects);
    if (stats.last_error_utime > last_error_utime) {
      last_error = stats.last_error;
      last_error_utime = stats.last_error_utime;
    }
  } else {
    s.source = "(in-process)";
    s.source_state = static_cast<std::int8_t>(io::SourceState::Running);
    s.source_state_name = std::string(io::sourceStateName(io::SourceState::Running));
  }
  s.last_error = last_error;
  s.last_error_utime = static_cast<std::int64_t>(last_error_utime);
  return s;
}

void Pipeline::publishStatus() {
  {
    // The CPU the process used since the previous status, against the budget.
    const double cpu_s = processCpuSeconds();
    const auto now = Clock::now();
    std::lock_guard lock(stats_mutex_);
    const double wall_s = std::chrono::duration<double>(now - cpu_sample_time_).count();
    if (wall_s > 0.0) cpu_used_cores_ = (cpu_s - cpu_sample_s_) / wall_s;
    cpu_sample_s_ = cpu_s;
    cpu_sample_time_ = now;
  }
  const findmug_lcm::status_t status = makeStatus();
  std::lock_guard lcm_lock(lcm_mutex_);
  if (!lcm_) return;  // stopped: the final status has gone out already
  if (lcm_->publish(status_channel_, &status) != 0) {
    spdlog::warn("LCM publish on {} failed", status_channel_);
  }
}

}  // namespace findmug::daemon
