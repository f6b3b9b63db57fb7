// findmug/daemon/frame_collector.hpp — saving frames worth labelling (daemon.collect_*).
//
// FrameCollector is a ResultSink (result_sinks.hpp) after the publisher. On the
// publish thread it decides whether a frame is saved:
//   * asked for: a save_frame command (requestSave) takes the next published frame;
//   * low confidence: the frame's mean confidence over its labelled pixels is
//     below daemon.collect_low_confidence;
//   * table flicker: the number of tables changed daemon.collect_flicker_changes
//     times within daemon.collect_flicker_window_s (then the count starts again).
// Automatic saves are rate-limited to one per daemon.collect_min_interval_s of
// capture time (the frames' utime, so a replay behaves as it did live); a request
// is not. The frame (colour, depth, camera) is copied into the bounded queue of
// a one-worker Stage (stage.hpp, thread findmug-collect) that encodes and
// writes it: the publish thread never waits for the disk. A save is refused, logged and counted when
// the folder has reached its bound (daemon.collect_max_frames frames or
// daemon.collect_max_mb of rgb/ and depth/ PNGs, what was there at start
// included; at most one frame past the bytes), when the writer's queue is full,
// or when the write fails (the half-written frame is removed).
//
// The folder is in the dataset layout findmug-train, findmug-eval and
// findmug-web read (dataset.hpp): rgb/NAME.png, depth/NAME.png (mm),
// intrinsics.yaml (one camera per folder: a frame of another camera is
// refused), extrinsics.csv / gravity.csv rows when the frame has them, and a
// row in frames.csv: frame,scene,utime,trigger,mean_confidence,tables,model_id,note
// (scene: this daemon run, so cross-validation keeps a run's frames together).
// NAME is "<utime>_<seq>". No label8/: that is for the person labelling them.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "findmug/daemon/daemon_config.hpp"
#include "findmug/daemon/result_sinks.hpp"
#include "findmug/daemon/stage.hpp"
#include "findmug/frame/frame.hpp"

namespace findmug::daemon {

class FrameCollector final : public ResultSink {
 public:
  struct Options {
    std::string dir;
    std::uint64_t max_frames = 500;
    std::uint64_t max_bytes = 2000ull << 20;
    double min_interval_s = 10.0;
    double low_confidence = 0.0;  // 0: off
    int flicker_changes = 0;      // 0: off
    double flicker_window_s = 5.0;
    std::size_t queue_capacity = 2;
    std::string scene;  // frames.csv scene of this run
  };
  struct Counters {
    std::uint64_t saved = 0;    // frames written
    std::uint64_t refused = 0;  // saves refused (bound, queue full, write failed)
    std::string last_saved;     // NAME of the last frame written, "" before any
  };
  using OnError = std::function<void(const std::string& what)>;

  static Options fromConfig(const DaemonConfig& config);

  // Creates the folder and counts what it holds; throws findmug::Error naming
  // daemon.collect_dir when it cannot. Starts the writer stage. `model_id`
  // names the model in use (frames.csv); `on_error` gets each refusal.
  FrameCollector(Options options, std::function<std::string()> model_id, OnError on_error);
  ~FrameCollector() override;
  FrameCollector(const FrameCollector&) = delete;
  FrameCollector& operator=(const FrameCollector&) = delete;

  // The next published frame is saved, with `note` in frames.csv. Throws
  // findmug::Error for a note with a comma, quote or control character.
  void requestSave(std::int64_t request_id, const std::string& note);
  std::string name() const override { return "FrameCollector"; }
  void consume(FrameResult& result) override;
  // Writes what is queued, then ends the writer. Idempotent.
  void stop();
  Counters counters() const;

  // Mean confidence over the pixels the model labelled (the depth holes filled
  // from their neighbours, confidence 0, are left out); nullopt when none is.
  static std::optional<double> meanConfidence(const LabelImage& labels);

 private:
  struct Job {
    std::string name;
    RgbdFrame frame;  // colour, depth, camera (copied off the publish thread's frame)
    std::string row;  // frames.csv columns after `frame`
  };
  // What the writer did with a job.
  struct Written {
    std::string name;
    std::uint64_t bytes = 0;  // of its two PNGs
    std::string error;        // "" = written
  };

  std::optional<std::string> automaticTrigger(const LabelledFrame& labelled);
  void enqueue(const LabelledFrame& labelled, const std::string& trigger,
               const std::string& note, std::optional<double> confidence);
  void refuse(const std::string& what);
  Written writeJob(const Job& job);  // on the writer's thread
  void recordWritten(Written&& written);
  void write(const Job& job);  // throws findmug::Error

  Options options_;
  std::function<std::string()> model_id_;
  OnError on_error_;
  // Publish thread only.
  std::optional<std::size_t> last_table_count_;
  std::deque<std::uint64_t> table_changes_;  // utimes of the count's changes in the window
  std::optional<std::uint64_t> last_automatic_utime_;

  mutable std::mutex mutex_;  // guards everything below but the stage
  std::deque<std::pair<std::int64_t, std::string>> requests_;  // (request id, note)
  std::uint64_t queued_ = 0;  // handed to the writer, not yet written (against the bounds)
  std::uint64_t frames_ = 0, bytes_ = 0;  // in the folder (written + there at start)
  Counters counters_;
  // Last member: its worker uses everything above and is joined first (~FrameCollector).
  std::unique_ptr<Stage<Job, Written>> writer_;
};

}  // namespace findmug::daemon
