// The daemon's threaded pipeline; see pipeline.hpp for the picture.
#include "findmug/daemon/pipeline.hpp"

#include <spdlog/spdlog.h>

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
      {"features", &StageTimings::features_ms}, {"forest", &StageTimings::forest_ms},
      {"mrf", &StageTimings::mrf_ms},           {"labels", &StageTimings::labels_ms},
      {"tables", &StageTimings::tables_ms}};
  return all;
}

std::uint64_t utimeNow() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                        std::chrono::system_clock::now().time_since_epoch())
                                        .count());
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
      segmenter_(segmenter_config, forest),
      model_id_(std::move(model_id)),
      mode_(mode),
      hooks_(std::move(hooks)),
      workers_(daemon_config.effectiveWorkers()),
      started_(Clock::now()),
      last_sequential_status_(started_) {
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
        spdlog::debug("prepare queue full: dropped {}", frameName(dropped.frame));
      },
      on_error);
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
  if (mode_ == ExecutionMode::Sequential) {
    // No publish thread ticks in sequential mode: keep the status period here.
    const auto now = Clock::now();
    if (now - last_sequential_status_ >=
        std::chrono::duration<double>(daemon_config_.status_period_s)) {
      publishStatus();
      last_sequential_status_ = now;
    }
  }
  return accepted;
}

void Pipeline::publishStatusNow() { publishStatus(); }

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
  finalized_.store(true);
  // The publish thread is gone: this thread may use the LCM handle now.
  publishStatus();
  // Close the handle: flushes a file:// log, leaves a udpm multicast group.
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
  const label_image_t label_msg = io::encodeLabelImage(labels, daemon_config_.publish_confidence);
  if (lcm_->publish(labels_channel_, &label_msg) != 0) {
    throw Error("LCM publish on " + labels_channel_ + " failed for " + frameName(frame));
  }
  if (daemon_config_.publish_tables) {
    io::TablesMessage tables;
    tables.utime = frame.utime;
    tables.seq = frame.seq;
    tables.tables = labelled.tables;
    const tables_t tables_msg = io::encodeTables(tables);
    if (lcm_->publish(tables_channel_, &tables_msg) != 0) {
      throw Error("LCM publish on " + tables_channel_ + " failed for " + frameName(frame));
    }
  }
  processed_.fetch_add(1);
  std::lock_guard lock(stats_mutex_);
  output_rate_.tick(now);
  for (const auto& [name, field] : subStages()) latency_.at(name).add(labelled.timings.*field, now);
  latency_.at("total").add(static_cast<double>(latency_us) / 1000.0, now);
}

PipelineCounters Pipeline::counters() const {
  PipelineCounters c;
  c.received = received_.load();
  c.processed = processed_.load();
  for (const StageStats& s : {prepare_->stats(), segment_->stats(), publish_->stats()}) {
    c.dropped += s.dropped;
    c.rejected += s.failed;
    c.pending += s.queue_depth + s.in_flight;
  }
  c.dropped += abandoned_.load();
  if (finalized_.load()) {
    // Stopped: whatever is still in a stage will never be published.
    c.dropped += c.pending;
    c.pending = 0;
  }
  if (const io::FrameSource* source = source_.load()) {
    const io::SourceStats s = source->stats();
    c.dropped += s.frames_dropped;
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

status_t Pipeline::makeStatus() const {
  status_t s{};
  const auto now = Clock::now();
  s.utime = static_cast<std::int64_t>(utimeNow());
  s.uptime_us = std::chrono::duration_cast<std::chrono::microseconds>(now - started_).count();
  const PipelineCounters c = counters();
  s.frames_received = static_cast<std::int64_t>(c.received);
  s.frames_processed = static_cast<std::int64_t>(c.processed);
  s.frames_dropped = static_cast<std::int64_t>(c.dropped);
  s.frames_rejected = static_cast<std::int64_t>(c.rejected);
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
  if (!lcm_) return;  // stopped: the final status has gone out already
  const status_t status = makeStatus();
  if (lcm_->publish(status_channel_, &status) != 0) {
    spdlog::warn("LCM publish on {} failed", status_channel_);
  }
}

}  // namespace findmug::daemon
