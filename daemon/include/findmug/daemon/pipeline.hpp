// findmug/daemon/pipeline.hpp — frames in, label images / tables / status out over LCM.
//
//   submit(frame) ─▶ [prepare queue] ─▶ prepare ─▶ [segment queue] ─▶ segment ×N
//                     the door:          1 thread,   one place          reorder ▼
//                     drop oldest        waits for                  [publish queue]
//                                        that place                   drop-oldest ─▶ publish
//                                                                    (1 thread: the sinks,
//                                                                     also sends status)
//
// Each stage runs one step class of frame_steps.hpp (PrepareStep, SegmentStep,
// PublishStep) on its thread(s). The Pipeline only wires them (makeSinks, makeStages,
// makeCommandInput, makePoseInput); the figures live in their own types
// (PipelineStatistics: rates, step latencies, last error; ProcessUsage: CPU and heap;
// the stages' own StageStats: queues, drops, stage latencies).
//
//   prepare   Segmenter::prepare: cloud, normals, ground plane
//   segment   Segmenter::oversegment + classify (oversegmentation, features, forest,
//             MRF, labels, tables): the bottleneck, run on N workers; results
//             leave in frame order (ReorderBuffer)
//   publish   hands each result, in frame order, to the sinks registered on
//             the pipeline (result_sinks.hpp): the TableMapSink (the map
//             update rule), then the LcmPublisherSink (label_image_t on
//             FINDMUG_LABELS, tables_t on FINDMUG_TABLES, the map on
//             FINDMUG_TABLE_MAP), then the ObjectSearchSink, which copies what
//             the object work needs and hands it to a worker thread of its own
//             (taught objects named among the table-top candidates, the object
//             map on FINDMUG_OBJECT_MAP, answers to "find" on
//             FINDMUG_FIND_RESULT; a drop-oldest queue, daemon.objects_queue),
//             then any added with addSink(); and, every
//             daemon.status_period_s, status_t on FINDMUG_STATUS, built by
//             StatusBuilder (status_builder.hpp) from statusSnapshot().
//             Each sink declares which slots of the FrameResult it adds and
//             reads (ResultSink::slots); addSink refuses an order that breaks them.
//
// Map frame (pose_input.hpp): when robot poses arrive on FINDMUG_ROBOT_POSE,
// the publish stage looks up the pose closest in time to each frame (within
// daemon.pose_max_age_s). With one, the frame's tables_t carries it and the
// map-frame copies of every table, and the TableMapSink decides whether the
// frame updates the persistent TableMap (result_sinks.hpp); after each update
// the map's confirmed tables go out on FINDMUG_TABLE_MAP (tables_t, content
// CONTENT_MAP, ids stable). The map is touched by the publish thread only, in
// frame order, as TableMap::update requires. Table diagnostics (why a cluster
// was dropped) and map changes (created / confirmed / forgotten) are logged
// at debug level.
//
// The newest frame wins. A navigation client acts on where things are now: a label image
// of a frame that waited behind a newer one is out of date before it is made, and the work
// spent on it delays the newer frame too. So no frame waits behind another once work has
// been spent on it: the prepare stage takes a frame only when the one place in the segment
// queue is free, and a daemon source loop calls waitForRoom() before taking a frame from
// its source, which waits until nothing waits at the door and that place is free; so under
// overload frames wait, and the oldest are dropped, in the source before decoding (or, for
// a caller that submits without waiting, at the door, which drops its oldest when full). Nothing blocks a
// worker handing a result on (BoundedQueue::push never waits): when the sinks fall behind,
// the publish queue drops its oldest result, so a slow sink never stalls the segmentation
// workers. Drops are counted by reason (PipelineCounters).
//
// CPU budget (daemon.max_cpu_cores): the daemon runs the pipeline
// sequentially on its source thread below 2 cores, threaded with at most
// floor(budget) - 1 segmentation workers from 2; status_t reports the
// process's CPU use against the budget.
// Each published label image is exactly Segmenter::process of its frame.
//
// Model reload (model_reload.hpp): the steps take the Segmenter from a ModelSlot
// once per frame; requestModelReload() (SIGHUP, or a reload_model command_t on
// FINDMUG_COMMAND through the CommandInput, command_input.hpp) has the
// ModelReloader's own thread load and check daemon.model_path again and swap
// it in between frames; no frame waits and none is dropped for it. A refused
// model leaves the running one; status_t reports the outcome (last_reload_*).
//
// Collection (daemon.collect_dir, frame_collector.hpp): a FrameCollector sink
// after the publisher saves frames worth labelling (save_frame command, low
// confidence, table flicker) on a writer thread of its own.
//
// In ExecutionMode::Sequential every submit() runs all stages on the
// caller's thread and returns after publishing, deterministically.
//
// The output bus (an io::LcmBus on daemon.lcm_url, or PipelineHooks::output_bus)
// is only published on (Bus::publish is thread-safe: the publish thread, and
// the status from the sequential caller or stop()); nobody handles it. The
// pose input's bus is owned by the pose thread.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "findmug/daemon/command_input.hpp"
#include "findmug/daemon/daemon_config.hpp"
#include "findmug/daemon/frame_collector.hpp"
#include "findmug/daemon/frame_steps.hpp"
#include "findmug/daemon/frame_trace.hpp"
#include "findmug/daemon/model_reload.hpp"
#include "findmug/daemon/object_search_sink.hpp"
#include "findmug/daemon/object_teacher.hpp"
#include "findmug/daemon/pipeline_statistics.hpp"
#include "findmug/daemon/pose_input.hpp"
#include "findmug/daemon/process_usage.hpp"
#include "findmug/daemon/result_sinks.hpp"
#include "findmug/daemon/semantic_map_sink.hpp"
#include "findmug/daemon/service.hpp"
#include "findmug/daemon/stage.hpp"
#include "findmug/daemon/status_snapshot.hpp"
#include "findmug/frame/frame.hpp"
#include "findmug/io/bus.hpp"
#include "findmug/learner/forest.hpp"
#include "findmug/map/table_map.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "findmug/settings/config.hpp"

namespace findmug::io {
class FrameSource;
}

namespace findmug::daemon {

struct PipelineHooks {
  // Called by a segment worker before it starts on a frame (tests use it to
  // make the bottleneck artificially slow or to hold it).
  std::function<void(const RgbdFrame&)> before_segment;
  // Publish on this bus instead of opening daemon.lcm_url (tests: an
  // io::MemoryBus, or an io::FaultyBus around one).
  std::shared_ptr<io::Bus> output_bus;
  // Listen for robot poses on this bus instead of daemon.pose_url.
  std::shared_ptr<io::Bus> pose_bus;
  // Listen for commands (command_t) on this bus instead of daemon.command_url.
  std::shared_ptr<io::Bus> command_bus;
  // Called by the object worker before each frame's object work (tests hold it there).
  std::function<void()> before_object_job;
};

class Pipeline {
 public:
  using Clock = std::chrono::steady_clock;

  // Opens the output bus (effectiveLcmUrl) and, when effectivePoseUrl
  // gives one, the pose input (its own bus and thread); throws
  // findmug::Error naming the key when either cannot be opened. `forest`
  // must be trained; `model_id` goes into status_t.
  Pipeline(const SegmenterConfig& segmenter_config, const DaemonConfig& daemon_config,
           std::shared_ptr<const RandomForest> forest, std::string model_id,
           ExecutionMode mode = ExecutionMode::Threaded, PipelineHooks hooks = {});
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  // The source whose description, state and counters go into status_t
  // (not owned; must outlive the pipeline or be detached with nullptr).
  void attachSource(const io::FrameSource* source);

  // Adds a sink after the built-in ones (before start()); it sees every
  // published frame on the publish thread.
  void addSink(std::shared_ptr<ResultSink> sink);

  void start();
  // Threaded: never blocks (drop-oldest). Sequential: returns after publishing.
  // Returns false after stop().
  bool submit(RgbdFrame frame);
  // Threaded: waits at most `timeout` until a submitted frame would be
  // accepted without dropping one and prepared at once (nothing waits at the
  // door and the segment queue's place is free; false on timeout or after stop()). A
  // source loop that calls this before taking its next frame leaves frames
  // waiting in the source, where overload drops them before they are even
  // decoded, and takes each when it can be worked on. Sequential: true at once.
  bool waitForRoom(Clock::duration timeout);
  // Sequential mode: publish a status now (threaded mode does it periodically).
  void publishStatusNow();
  // Sequential mode: publish a status if daemon.status_period_s has passed
  // since the last one (submit() does this; an idle caller may too, from any
  // thread). Threaded mode: no-op.
  void publishStatusIfDue();
  // Threads that process frames: 1 in sequential mode (the caller's),
  // prepare + segmentation workers + publish in threaded mode.
  int processingThreads() const;
  // Drain: finish every queued frame; Discard: drop queued frames and wait
  // for those in flight at most daemon.shutdown_grace_s (the rest are
  // abandoned, counted as dropped). Then publishes a final status and
  // releases the output bus (closing an LcmBus flushes a file:// log). Idempotent.
  void stop(StopMode mode);

  PipelineCounters counters() const;
  ProgressSnapshot progress() const;  // source_heartbeat left for the caller
  // The figures status_t reports (StatusBuilder::build / makeStatus turn them into one).
  StatusSnapshot statusSnapshot() const;
  std::string modelId() const { return model_.modelId(); }
  // Loads daemon.model_path again in the background and swaps it in between
  // frames if it passes the start-up checks (model_reload.hpp). Never blocks on
  // the load; thread-safe. `request_id`: the command's, -1 for SIGHUP.
  void requestModelReload(std::int64_t request_id, const std::string& origin);
  ReloadStatus reloadStatus() const { return reloader_->status(); }
  // The floor the frame stream follows (ground.reestimate_every_frames), kept across model
  // reloads: the prepare stage's, so read it only once the pipeline has stopped.
  const GroundTracker& groundTracker() const { return prepare_step_.ground(); }
  // Saves the next published frame for labelling (daemon.collect_dir); throws
  // findmug::Error when collection is off or the note is not fit for frames.csv.
  void requestFrameSave(std::int64_t request_id, const std::string& note);
  // The objects on the tables: taught ones named, mapped and found (object_search_sink.hpp).
  const ObjectSearchSink& objectSearch() const { return *object_search_; }
  // Teaching from the live view, the command "teach" (object_teacher.hpp).
  const ObjectTeacher& objectTeacher() const { return *object_teacher_; }
  // The command input, or nullptr when there is none (see effectiveCommandUrl).
  const CommandInput* commandInput() const { return command_input_.get(); }
  int workers() const { return workers_; }
  // The pose input, or nullptr when there is none (see effectivePoseUrl).
  const PoseInput* poseInput() const { return pose_input_.get(); }
  // Tables in the map now, tentative ones included (thread-safe copy).
  std::vector<MappedTable> mappedTables() const;
  // The semantic map sink's counters (daemon.semantic_map), or nullopt when it is off.
  std::optional<SemanticMapSink::Counters> semanticMapCounters() const;
  // The semantic map's tables at its last publish (empty when it is off).
  std::vector<FusedTable> semanticMapTables() const;
  // Publishes refused by the output bus (frames' messages and status).
  std::uint64_t publishFailures() const { return publisher_->publishFailures(); }

 private:
  struct Published {};

  // The constructor's steps, in order.
  void makeSinks(const SegmenterConfig& segmenter_config, std::shared_ptr<io::Bus> bus);
  void makeStages();
  void makeCommandInput();
  void makePoseInput();
  // PublishStep on one result, then the output rate and latency statistics.
  void publishResult(ResultJob& job);
  void publishStatus();
  void recordError(const std::string& message);
  void recordErrorQuietly(const std::string& message);  // last_error only (logged elsewhere)

  // The stages' workers are joined by the destructor before any member dies (~Pipeline), so
  // the order below only matters to construction: what a member's constructor uses comes
  // before it.
  DaemonConfig daemon_config_;
  ModelSlot model_;  // the Segmenter (and model) frames run with
  ExecutionMode mode_;
  PipelineHooks hooks_;
  int workers_;
  PipelineStatistics statistics_;  // rates, step latencies, last error (status_t)
  ProcessUsage process_usage_;     // CPU cores used between statuses, heap in use
  std::unique_ptr<FrameTraceWriter> trace_;  // nullptr unless daemon.frame_trace_file
  std::shared_ptr<TableMapSink> table_map_sink_;
  std::shared_ptr<SemanticMapSink> semantic_map_;  // nullptr unless daemon.semantic_map
  std::shared_ptr<LcmPublisherSink> publisher_;
  std::unique_ptr<PoseInput> pose_input_;  // nullptr: no pose input
  std::unique_ptr<ModelReloader> reloader_;
  std::unique_ptr<CommandInput> command_input_;  // nullptr: no command input
  std::shared_ptr<FrameCollector> collector_;    // nullptr unless daemon.collect_dir
  std::shared_ptr<ObjectSearchSink> object_search_;  // taught objects, object map, "find"
  std::shared_ptr<ObjectTeacher> object_teacher_;    // "teach": the last frames' candidates
  // The three steps (frame_steps.hpp), each run by its Stage below.
  PrepareStep prepare_step_;
  SegmentStep segment_step_;
  PublishStep publish_step_;  // holds the sinks, in the order they see a result
  Clock::time_point started_;
  Clock::time_point last_sequential_status_;
  std::mutex sequential_status_mutex_;  // guards last_sequential_status_
  std::atomic<const io::FrameSource*> source_{nullptr};
  std::atomic<std::uint64_t> received_{0}, processed_{0}, abandoned_{0};
  std::atomic<bool> finalized_{false};

  std::unique_ptr<Stage<ResultJob, Published>> publish_;
  std::unique_ptr<Stage<PreparedJob, ResultJob>> segment_;
  std::unique_ptr<Stage<FrameJob, PreparedJob>> prepare_;
  bool stopped_ = false;
  std::mutex stop_mutex_;
};

}  // namespace findmug::daemon
