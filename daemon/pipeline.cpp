// The daemon's threaded pipeline; see pipeline.hpp for the picture.
#include "findmug/daemon/pipeline.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <thread>

#include "findmug/common/error.hpp"
#include "findmug/daemon/status_builder.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/frame_source.hpp"
#include "findmug/io/udpm.hpp"

namespace findmug::daemon {

namespace {

Pipeline::Clock::duration statsWindow(const DaemonConfig& config) {
  return std::chrono::duration_cast<Pipeline::Clock::duration>(
      std::chrono::duration<double>(config.stats_window_s));
}

}  // namespace

Pipeline::Pipeline(const SegmenterConfig& segmenter_config, const DaemonConfig& daemon_config,
                   std::shared_ptr<const RandomForest> forest, std::string model_id,
                   ExecutionMode mode, PipelineHooks hooks)
    : daemon_config_(daemon_config),
      model_(segmenter_config, forest, std::move(model_id)),
      mode_(mode),
      hooks_(std::move(hooks)),
      workers_(daemon_config.effectiveWorkers()),
      statistics_(statsWindow(daemon_config)),
      prepare_step_([this] { return model_.segmenter(); }),
      segment_step_([this] { return model_.segmenter(); }, hooks_.before_segment),
      publish_step_(
          static_cast<std::uint64_t>(std::llround(daemon_config.pose_max_age_s * 1e6))),
      started_(Clock::now()),
      last_sequential_status_(started_) {
  if (!forest || forest->empty()) throw Error("findmugd: the model has no trees");
  if (!daemon_config_.frame_trace_file.empty()) {
    trace_ = std::make_unique<FrameTraceWriter>(daemon_config_.frame_trace_file);
  }
  std::shared_ptr<io::Bus> bus = hooks_.output_bus;
  if (!bus) bus = std::make_shared<io::LcmBus>(effectiveLcmUrl(daemon_config_), "daemon.lcm_url");
  // Every bus of the daemon applies daemon.channel_suffix: channels are named by base name.
  makeSinks(segmenter_config, io::withChannelSuffix(std::move(bus), daemon_config_.channel_suffix));
  makeStages();
  // Last (with the inputs below): their threads report through recordError,
  // so everything they may touch must exist already.
  reloader_ = std::make_unique<ModelReloader>(
      daemon_config_.model_path, model_,
      [this](const std::string& what) { recordErrorQuietly(what); });
  makeCommandInput();
  makePoseInput();
}

// The sinks, in the order they see a result (PublishStep::addSink checks that no sink reads
// a slot of the FrameResult that a sink after it writes: result_sinks.hpp).
void Pipeline::makeSinks(const SegmenterConfig& segmenter_config, std::shared_ptr<io::Bus> bus) {
  auto on_error = [this](const std::string& what) { recordError(what); };
  // The map first, as the frame's tables_t carries what the map made of it.
  // With the semantic map on, FINDMUG_TABLE_MAP carries the map's tables instead.
  table_map_sink_ = std::make_shared<TableMapSink>(
      daemon_config_.table_map, segmenter_config.tables,
      daemon_config_.publish_table_map && !daemon_config_.semantic_map, on_error);
  if (daemon_config_.semantic_map) {
    SemanticMapSink::Options options;
    options.map = daemon_config_.semantic_map_config;
    options.tables = segmenter_config.tables;
    options.threaded = mode_ == ExecutionMode::Threaded;
    options.queue_capacity = daemon_config_.semantic_map_queue;
    options.publish_period_s = daemon_config_.semantic_map_publish_s;
    options.fused_labels = daemon_config_.semantic_map_fused_labels;
    options.file = daemon_config_.semantic_map_file;
    options.save_period_s = daemon_config_.semantic_map_save_s;
    options.map_channel = io::kSemanticMapChannel;
    options.table_map_channel = io::kTableMapChannel;
    semantic_map_ = std::make_shared<SemanticMapSink>(std::move(options), bus, on_error);
  }
  ObjectSearchSettings object_search;
  object_search.objects_dir = daemon_config_.objects_dir;
  object_search.map_objects =
      hooks_.pose_bus != nullptr || effectivePoseUrl(daemon_config_).has_value();
  object_search.object_map = daemon_config_.object_map;
  object_search.object_search = daemon_config_.object_search;
  object_search.matcher = daemon_config_.object_matcher;
  object_search.publish_map = daemon_config_.publish_object_map;
  object_search.mode = mode_;
  object_search.queue_capacity = daemon_config_.objects_queue;
  object_search.before_job = hooks_.before_object_job;
  object_search_ = std::make_shared<ObjectSearchSink>(
      std::move(object_search), bus,
      ObjectSearchSink::Channels{std::string(io::kFindResultChannel),
                                 std::string(io::kObjectMapChannel)},
      TableMapSource{[sink = table_map_sink_] { return sink->revision(); },
                     [sink = table_map_sink_] { return sink->confirmedTables(); }},
      on_error);
  publisher_ = std::make_shared<LcmPublisherSink>(
      std::move(bus),
      LcmPublisherSink::Channels{std::string(io::kLabelsChannel), std::string(io::kTablesChannel),
                                 std::string(io::kObjectsChannel),
                                 std::string(io::kTableMapChannel),
                                 std::string(io::kStatusChannel)},
      daemon_config_.publish_confidence, daemon_config_.publish_tables);
  if (daemon_config_.publish_color) publisher_->publishColor(daemon_config_.color_jpeg_quality);
  publish_step_.addSink(table_map_sink_);
  if (semantic_map_) publish_step_.addSink(semantic_map_);  // may set the published labels
  // Before the publisher: a client that saw a frame's objects_t may name one of its
  // candidates at once, so the teacher holds them before they go out.
  object_teacher_ = std::make_shared<ObjectTeacher>(daemon_config_.objects_dir);
  publish_step_.addSink(object_teacher_);
  publish_step_.addSink(publisher_);
  publish_step_.addSink(object_search_);  // after the table map and the frame's messages
  if (!daemon_config_.collect_dir.empty()) {
    collector_ = std::make_shared<FrameCollector>(
        FrameCollector::fromConfig(daemon_config_), [this] { return model_.modelId(); },
        on_error);
    publish_step_.addSink(collector_);
  }
}

// The three stages, last first (each hands its results to the next). The rules that keep
// latency bounded live here:
//   - a frame never waits behind another frame once work has been spent on it (a
//     navigation client acts on where things are now; a label image of a frame that waited
//     behind a newer one is out of date before it is made, and working on it delays the
//     newer one too): the segment queue is one place, and the prepare step runs only when
//     that place is free (the gate), so under overload frames wait, and the oldest are
//     dropped, in the source (Pipeline::waitForRoom) or at the door, before any work;
//   - nothing blocks a worker that hands a result on: the publish queue (daemon.queue_capacity
//     + one place per worker) drops its oldest result (counted) when the sinks fall behind,
//     so a slow sink never stalls the segmentation workers, whose emit runs under their
//     stage's release lock.
void Pipeline::makeStages() {
  const auto window = statsWindow(daemon_config_);
  const auto capacity = static_cast<std::size_t>(daemon_config_.queue_capacity);
  auto on_error = [this](const std::string& what) { recordError(what); };

  // Room for a whole run the reorder buffer releases at once (one result per worker) on top
  // of daemon.queue_capacity: only sinks that fall behind make it drop.
  StageOptions publish_options{"publish",
                               mode_,
                               1,
                               capacity + static_cast<std::size_t>(workers_),
                               DropPolicy::DropOldest,
                               window,
                               std::chrono::duration_cast<Clock::duration>(
                                   std::chrono::duration<double>(daemon_config_.status_period_s))};
  publish_ = std::make_unique<Stage<ResultJob, Published>>(
      publish_options, StageCallbacks<ResultJob, Published>{
                           .work = [this](ResultJob& job) -> std::optional<Published> {
                             publishResult(job);
                             return Published{};
                           },
                           .emit = [](Published&&) {},
                           .on_drop =
                               [this](ResultJob& dropped) {
                                 spdlog::debug("publish queue full: dropped {}",
                                               frameName(dropped.labelled.segmented.prepared.frame));
                                 // Its buffers serve the next frames, as a published one's do.
                                 model_.segmenter()->recycle(std::move(dropped.labelled));
                               },
                           .on_error = on_error,
                           .tick = [this] { publishStatus(); },
                       });

  // One prepared frame waits for the next free worker, no more.
  StageOptions segment_options{"segment", mode_, workers_, 1, DropPolicy::DropOldest, window};
  segment_ = std::make_unique<Stage<PreparedJob, ResultJob>>(
      segment_options, StageCallbacks<PreparedJob, ResultJob>{
                           .work = [this](PreparedJob& job) -> std::optional<ResultJob> {
                             job.trace.segment_start = Clock::now();
                             ResultJob r = segment_step_(job);
                             r.trace.segment_end = Clock::now();
                             return r;
                           },
                           .emit =
                               [this](ResultJob&& r) {
                                 r.trace.released = Clock::now();
                                 if (!publish_->push(std::move(r)))
                                   abandoned_.fetch_add(1);  // only after stop()
                               },
                           .on_drop =
                               [](const PreparedJob& dropped) {
                                 spdlog::debug("segment queue full: dropped {}",
                                               frameName(dropped.prepared.frame));
                               },
                           .on_error = on_error,
                       });

  StageOptions prepare_options{"prepare", mode_, 1, capacity, DropPolicy::DropOldest, window};
  prepare_ = std::make_unique<Stage<FrameJob, PreparedJob>>(
      prepare_options, StageCallbacks<FrameJob, PreparedJob>{
                           .work = [this](FrameJob& job) -> std::optional<PreparedJob> {
                             job.trace.prepare_start = Clock::now();
                             PreparedJob p = prepare_step_(job);
                             p.trace.prepare_end = Clock::now();
                             return p;
                           },
                           .emit =
                               [this](PreparedJob&& p) {
                                 if (!segment_->push(std::move(p)))
                                   abandoned_.fetch_add(1);  // only after stop()
                               },
                           .on_drop =
                               [](const FrameJob& dropped) {
                                 spdlog::debug("pipeline entry full: dropped {} at the door",
                                               frameName(dropped.frame));
                               },
                           .on_error = on_error,
                           // The door: take the next frame only when the segment queue can accept
                           // it, so that under overload frames wait — and the oldest is dropped —
                           // here, before any work is spent on them.
                           .gate =
                               [this] {
                                 while (!segment_->waitForRoom(std::chrono::milliseconds(50))) {
                                   if (segment_->closed()) break;
                                   // Stopping: discarded (nothing left to take) or draining into a
                                   // live segment stage (waits for room like any frame).
                                   if (prepare_->closed() && prepare_->queueSize() == 0) break;
                                 }
                               },
                       });
}

// Commands on FINDMUG_COMMAND: one handler per command name.
void Pipeline::makeCommandInput() {
  const auto command_url = effectiveCommandUrl(daemon_config_);
  if (!hooks_.command_bus && !command_url) {
    spdlog::info("no command input ({}): reload the model with SIGHUP",
                 daemon_config_.command_input
                     ? "the output is a log file and daemon.command_url is empty"
                     : "daemon.command_input is off");
    return;
  }
  const std::string channel(io::kCommandChannel);
  std::map<std::string, CommandInput::Handler> handlers;
  handlers.emplace("reload_model", [this](const io::CommandMessage& c) {
    if (!c.argument.empty()) {
      throw Error("reload_model takes no argument (it loads daemon.model_path), got '" +
                  c.argument + "'");
    }
    requestModelReload(c.request_id, "command request " + std::to_string(c.request_id));
  });
  handlers.emplace("save_frame", [this](const io::CommandMessage& c) {
    requestFrameSave(c.request_id, c.argument);
  });
  handlers.emplace("find", [this](const io::CommandMessage& c) {
    object_search_->requestFind(c.request_id, c.argument, c.utime);
  });
  handlers.emplace("teach", [this](const io::CommandMessage& c) {
    object_teacher_->teach(c.request_id, c.argument);
  });
  auto on_command_error = [this](const std::string& what) { recordError(what); };
  std::shared_ptr<io::Bus> command_bus = hooks_.command_bus;
  if (!command_bus) {
    command_bus = io::openBus(*command_url, "daemon.command_url (commands on " + channel + ")");
  }
  command_input_ = std::make_unique<CommandInput>(
      io::withChannelSuffix(std::move(command_bus), daemon_config_.channel_suffix), channel,
      std::move(handlers), on_command_error);
  spdlog::info("commands from {} on {}", command_input_->describe(), channel);
}

// Robot poses on FINDMUG_ROBOT_POSE, looked up by the publish step.
void Pipeline::makePoseInput() {
  const auto pose_url = effectivePoseUrl(daemon_config_);
  if (!hooks_.pose_bus && !pose_url) {
    spdlog::info("no robot pose input ({}): tables in the base frame only, no table map",
                 daemon_config_.pose_input ? "the output is a log file and daemon.pose_url is empty"
                                           : "daemon.pose_input is off");
    return;
  }
  const std::string channel(io::kRobotPoseChannel);
  auto on_pose_error = [this](const std::string& what) { recordError(what); };
  std::shared_ptr<io::Bus> pose_bus = hooks_.pose_bus;
  if (!pose_bus) {
    pose_bus = io::openBus(*pose_url, "daemon.pose_url (robot poses on " + channel + ")");
  }
  pose_input_ = std::make_unique<PoseInput>(
      io::withChannelSuffix(std::move(pose_bus), daemon_config_.channel_suffix), channel,
      daemon_config_.pose_history_s, on_pose_error);
  publish_step_.setPoseInput(pose_input_.get());
  spdlog::info("robot poses from {} on {}: tables also in the map frame, table map on {}",
               hooks_.pose_bus     ? hooks_.pose_bus->describe()
               : pose_url->empty() ? std::string("the default LCM provider")
                                   : *pose_url,
               channel, publisher_->channels().table_map);
}

Pipeline::~Pipeline() {
  stop(StopMode::Discard);
  // A Discard stop does not wait for a segmentation past daemon.shutdown_grace_s: its worker
  // is joined here, upstream stage first, while everything a worker touches (the next
  // stage's queue, the steps, the statistics, the sinks) is still alive. So the order in
  // which the members are declared does not matter to the workers.
  prepare_.reset();
  segment_.reset();
  publish_.reset();
}

void Pipeline::requestModelReload(std::int64_t request_id, const std::string& origin) {
  reloader_->request(request_id, origin);
}

void Pipeline::requestFrameSave(std::int64_t request_id, const std::string& note) {
  if (!collector_) throw Error("save_frame: collection is off (daemon.collect_dir is empty)");
  collector_->requestSave(request_id, note);
}

void Pipeline::attachSource(const io::FrameSource* source) { source_.store(source); }

void Pipeline::addSink(std::shared_ptr<ResultSink> sink) { publish_step_.addSink(std::move(sink)); }

void Pipeline::start() {
  if (semantic_map_) semantic_map_->start();
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
  statistics_.frameIn();
  FrameTrace trace;
  trace.submit_utime = hostUtimeNow();
  const bool accepted = prepare_->push(FrameJob{std::move(frame), Clock::now(), trace});
  // No publish thread ticks in sequential mode: keep the status period here.
  publishStatusIfDue();
  return accepted;
}

bool Pipeline::waitForRoom(Clock::duration timeout) {
  if (mode_ == ExecutionMode::Sequential) return true;  // submit() runs the frame itself
  const auto deadline = Clock::now() + timeout;
  // Nothing waiting at the door, and the place after it free: a frame taken now is prepared
  // at once, instead of waiting at the door while newer frames arrive in the source.
  return prepare_->waitUntilEmpty(timeout) &&
         segment_->waitForRoom(std::max(deadline - Clock::now(), Clock::duration::zero()));
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
  if (trace_) trace_->close();
  if (collector_) collector_->stop();  // writes what it has queued
  // Nothing feeds the map any more: its last frames (Drain), last publish and save.
  if (semantic_map_) semantic_map_->stop(mode == StopMode::Drain);
  // Nothing feeds the object work any more: its last frames (Drain), before the final status.
  object_search_->stop(mode == StopMode::Drain);
  // Nobody looks poses up any more: stop the pose thread, close its handle.
  if (pose_input_) pose_input_->stop();
  // No more commands, no more reloads (a load in progress is finished first).
  if (command_input_) command_input_->stop();
  reloader_->stop();
  finalized_.store(true);
  // The publish thread is gone: the final status is the last message.
  publishStatus();
  // Release the bus: closing an LcmBus flushes a file:// log, leaves a udpm group.
  object_search_->close();  // before the publisher's: the last to let go of the bus closes it
  publisher_->close();
  const auto c = counters();
  spdlog::info("pipeline stopped: {} received, {} processed, {} dropped, {} rejected", c.received,
               c.processed, c.dropped, c.rejected);
}

void Pipeline::recordError(const std::string& message) {
  spdlog::warn("{}", message);
  recordErrorQuietly(message);
}

void Pipeline::recordErrorQuietly(const std::string& message) { statistics_.recordError(message); }

// The result goes to the sinks (PublishStep), then into the output statistics.
void Pipeline::publishResult(ResultJob& job) {
  const auto now = Clock::now();
  job.trace.publish_start = now;
  const std::int64_t latency_us = publish_step_(job, now);
  processed_.fetch_add(1);
  if (trace_) {
    const RgbdFrame& frame = job.labelled.segmented.prepared.frame;
    trace_->write(frame.seq, static_cast<std::int64_t>(frame.utime), job.arrival, job.trace,
                  Clock::now());
  }
  statistics_.framePublished(job.labelled.timings, static_cast<double>(latency_us) / 1000.0, now);
  // The sinks are done with it: its buffers serve the next frames (no
  // per-frame allocation of clouds, normals and segment lists once warm).
  // (Into the Segmenter in use now: after a model swap the old one's are freed.)
  model_.segmenter()->recycle(std::move(job.labelled));
}

std::optional<SemanticMapSink::Counters> Pipeline::semanticMapCounters() const {
  if (!semantic_map_) return std::nullopt;
  return semantic_map_->counters();
}

std::vector<FusedTable> Pipeline::semanticMapTables() const {
  return semantic_map_ ? semantic_map_->tables() : std::vector<FusedTable>{};
}

std::vector<MappedTable> Pipeline::mappedTables() const { return table_map_sink_->tables(); }

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

StatusSnapshot Pipeline::statusSnapshot() const {
  StatusSnapshot s;
  const auto now = Clock::now();
  s.utime = hostUtimeNow();
  s.uptime_us = std::chrono::duration_cast<std::chrono::microseconds>(now - started_).count();
  s.counters = counters();
  s.cpu_budget_cores = daemon_config_.max_cpu_cores;
  s.processing_threads = processingThreads();
  s.window_s = daemon_config_.stats_window_s;
  s.model_id = model_.modelId();
  s.reload = reloader_->status();
  if (collector_) {
    const FrameCollector::Counters c = collector_->counters();
    s.frames_collected = c.saved;
    s.frames_collect_refused = c.refused;
    s.last_collected_frame = c.last_saved;
  }
  s.teach = object_teacher_->status();
  if (command_input_) {
    s.commands_accepted = command_input_->accepted();
    s.commands_rejected = command_input_->rejected();
  }
  s.publish_failures = publishFailures();
  s.heap_in_use_bytes = ProcessUsage::heapInUseBytes();
  s.cpu_used_cores = process_usage_.lastCores();

  const StageStats stages[] = {prepare_->stats(), segment_->stats(), publish_->stats()};
  const ObjectSearchSink::Counters objects = object_search_->counters();
  // Report order: the stages, then the step timings and "total" (statistics_.fill).
  for (const auto& st : stages) s.latencies.emplace_back(st.name, st.latency);
  if (object_search_->active()) s.latencies.emplace_back("object_search", objects.latency);
  statistics_.fill(s, now);
  for (const auto& st : stages) s.queues.push_back({st.name, st.queue_depth, st.queue_capacity});
  if (object_search_->active()) {
    s.queues.push_back({"object_search", objects.queue_depth, objects.queue_capacity});
  }
  s.objects = {objects.frames_queued,     objects.frames_skipped,     objects.candidates,
               objects.matches,           objects.refused_too_big,    objects.refused_too_small,
               objects.refused_colour,    objects.refused_not_round,  objects.refused_shape,
               objects.refused_few_points, objects.object_files_refused, objects.find_requests,
               objects.find_answers,      objects.mapped_objects,     objects.map_publishes};
  if (semantic_map_) {
    const SemanticMapSink::Counters c = semantic_map_->counters();
    s.queues.push_back({"semantic_map", c.queue_depth, c.queue_capacity});
    s.semantic_map_frames = c.integrated;
    s.semantic_map_skipped = c.skipped;
    s.semantic_map_voxels = c.voxels;
  }

  if (const io::FrameSource* source = source_.load()) {
    const io::SourceStats stats = source->stats();
    s.source = StatusSnapshot::Source{source->describe(), source->state(), stats.last_error,
                                      stats.last_error_utime, stats.reconnects,
                                      stats.frames_lost_in_transit};
  }
  return s;
}

findmug_lcm::status_t makeStatus(const Pipeline& pipeline) {
  return StatusBuilder::build(pipeline.statusSnapshot());
}

void Pipeline::publishStatus() {
  // The CPU the process used since the previous status, against the budget.
  process_usage_.sampleCores();
  publisher_->publishStatus(statusSnapshot());
}

}  // namespace findmug::daemon
