// findmug/daemon/pipeline.hpp — frames in, label images / tables / status out over LCM.
//
//   submit(frame) ─▶ [prepare queue] ─▶ prepare ─▶ [segment queue] ─▶ segment ×N
//                     drop oldest        1 thread    drop oldest       reorder ▼
//                                                   [publish queue] ◀──────────┘
//                                                     blocking  ─▶ publish (1 thread: owns the LCM
//                                                                  handle, also sends status)
//
//   prepare   Segmenter::prepare: cloud, normals, ground plane
//   segment   Segmenter::oversegment + classify (supervoxels, features, forest,
//             MRF, labels, tables): the bottleneck, run on N workers; results
//             leave in frame order (ReorderBuffer)
//   publish   label_image_t on FINDMUG_LABELS, tables_t on FINDMUG_TABLES, and
//             status_t on FINDMUG_STATUS every daemon.status_period_s
//
// Frames are perishable, results are not: the two input queues drop their
// oldest frame when full (counted), the publish queue applies back-pressure.
// Each published label image is exactly Segmenter::process of its frame.
//
// In ExecutionMode::Sequential every submit() runs all stages on the
// caller's thread and returns after publishing, deterministically.
//
// Thread use of LCM: the output handle is used only by the publish stage's
// thread (and by stop(), after that thread has been joined).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "findmug/config.hpp"
#include "findmug/daemon/daemon_config.hpp"
#include "findmug/daemon/service.hpp"
#include "findmug/daemon/stage.hpp"
#include "findmug/forest.hpp"
#include "findmug/frame.hpp"
#include "findmug/segmenter.hpp"
#include "findmug/status_t.hpp"

namespace lcm {
class LCM;
}

namespace findmug::io {
class FrameSource;
}

namespace findmug::daemon {

struct PipelineHooks {
  // Called by a segment worker before it starts on a frame (tests use it to
  // make the bottleneck artificially slow or to hold it).
  std::function<void(const RgbdFrame&)> before_segment;
};

struct PipelineCounters {
  std::uint64_t received = 0;   // submitted frames
  std::uint64_t processed = 0;  // published label images
  std::uint64_t dropped = 0;   // evicted from a full queue / discarded at shutdown (+ source drops)
  std::uint64_t rejected = 0;  // failed in a stage (+ bad input the source skipped)
  std::uint64_t pending = 0;   // inside the pipeline now
};

class Pipeline {
 public:
  using Clock = std::chrono::steady_clock;

  // Opens the output LCM handle (effectiveLcmUrl); throws findmug::Error when
  // it cannot. `forest` must be trained; `model_id` goes into status_t.
  Pipeline(const SegmenterConfig& segmenter_config, const DaemonConfig& daemon_config,
           std::shared_ptr<const RandomForest> forest, std::string model_id,
           ExecutionMode mode = ExecutionMode::Threaded, PipelineHooks hooks = {});
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  // The source whose description, state and counters go into status_t
  // (not owned; must outlive the pipeline or be detached with nullptr).
  void attachSource(const io::FrameSource* source);

  void start();
  // Threaded: never blocks (drop-oldest). Sequential: returns after publishing.
  // Returns false after stop().
  bool submit(RgbdFrame frame);
  // Sequential mode: publish a status now (threaded mode does it periodically).
  void publishStatusNow();
  // Drain: finish every queued frame; Discard: drop queued frames and wait
  // for those in flight at most daemon.shutdown_grace_s (the rest are
  // abandoned, counted as dropped). Then publishes a final status and closes
  // the LCM handle. Idempotent.
  void stop(StopMode mode);

  PipelineCounters counters() const;
  ProgressSnapshot progress() const;  // source_heartbeat left for the caller
  status_t makeStatus() const;
  const std::string& modelId() const { return model_id_; }
  int workers() const { return workers_; }

 private:
  struct FrameJob;
  struct PreparedJob;
  struct ResultJob;
  struct Published {};

  void publishResult(ResultJob& job);
  void publishStatus();
  void recordError(const std::string& message);

  DaemonConfig daemon_config_;
  std::string labels_channel_, tables_channel_, status_channel_;
  Segmenter segmenter_;
  std::string model_id_;
  ExecutionMode mode_;
  PipelineHooks hooks_;
  int workers_;
  std::unique_ptr<lcm::LCM> lcm_;
  Clock::time_point started_;
  Clock::time_point last_sequential_status_;
  std::atomic<const io::FrameSource*> source_{nullptr};

  std::atomic<std::uint64_t> received_{0}, processed_{0}, abandoned_{0};
  std::atomic<bool> finalized_{false};
  mutable std::mutex stats_mutex_;  // guards the members below
  RateMeter input_rate_, output_rate_;
  std::map<std::string, LatencyWindow> latency_;  // per named stage/sub-stage
  std::string last_error_;
  std::uint64_t last_error_utime_ = 0;

  std::unique_ptr<Stage<ResultJob, Published>> publish_;
  std::unique_ptr<Stage<PreparedJob, ResultJob>> segment_;
  std::unique_ptr<Stage<FrameJob, PreparedJob>> prepare_;
  bool stopped_ = false;
  std::mutex stop_mutex_;
};

}  // namespace findmug::daemon
