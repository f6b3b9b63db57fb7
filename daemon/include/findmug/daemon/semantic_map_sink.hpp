// findmug/daemon/semantic_map_sink.hpp — the fused 3-D semantic map as a result sink with
// its own thread.
//
// A ResultSink on the publish thread (after TableMapSink, before LcmPublisherSink) that
// hands every labelled frame with a robot pose (TableMapSink::isEvidence and a pose within
// daemon.pose_max_age_s) to the map's own thread through a bounded drop-oldest queue
// (daemon.semantic_map_queue): the map may skip frames under load (counted), the label
// stream never waits for it. The map thread fuses each frame (SemanticMap::integrate, the
// camera pose = robot pose ∘ the frame's camera mount, GroundPlane::camera_to_ground) and,
// at most every daemon.semantic_map_publish_s and only when the map changed, publishes
// the map's tables on FINDMUG_TABLE_MAP (tables_t, CONTENT_MAP; map_id the map's stable
// id, sightings the frames supporting it) and the map on FINDMUG_SEMANTIC_MAP
// (semantic_map_t). The map is loaded from daemon.semantic_map_file at start (a file
// that cannot be read is logged and renamed to FILE.refused) and saved there every
// daemon.semantic_map_save_s and at stop.
//
// With daemon.semantic_map_fused_labels, consume() also projects the map's labels into
// the frame (SemanticMap::projectLabels) for LcmPublisherSink to publish instead of the
// frame's own; when the map thread holds the map at that moment the frame keeps its own
// labels (counted as fused_busy), so that the label stream never waits.
//
// The map thread is a Stage (stage.hpp) of one worker, named "findmug-semmap" (top -H;
// tests/bench/daemon_bench.sh reads its CPU time from /proc/PID/task/*/stat), whose
// periodic tick publishes and saves when due even while no frame comes.
//
// In sequential mode (daemon.max_cpu_cores < 2) the Stage runs inline: consume() fuses the
// frame itself, and publishes when due.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "findmug/daemon/result_sinks.hpp"
#include "findmug/daemon/stage.hpp"
#include "findmug/io/bus.hpp"
#include "findmug/map/semantic_map.hpp"

namespace findmug::daemon {

class SemanticMapSink final : public ResultSink {
 public:
  using Clock = std::chrono::steady_clock;

  struct Options {
    SemanticMapConfig map;
    TableConfig tables;
    bool threaded = true;
    int queue_capacity = 2;
    double publish_period_s = 2.0;
    bool fused_labels = false;
    std::string file;  // "" = not kept
    double save_period_s = 60.0;
    std::string map_channel;        // FINDMUG_SEMANTIC_MAP (the bus applies the suffix)
    std::string table_map_channel;  // FINDMUG_TABLE_MAP
    // Runs before each frame is fused, on the map thread (tests: hold it).
    std::function<void()> before_fuse;
  };

  struct Counters {
    std::uint64_t queued = 0;      // frames handed to the map
    std::uint64_t skipped = 0;     // of them dropped from the full queue (the map fell behind)
    std::uint64_t integrated = 0;  // frames fused into the map
    std::uint64_t failed = 0;      // frames the map refused (logged)
    std::uint64_t publishes = 0;   // map messages sent
    std::uint64_t fused_frames = 0;  // frames published with the map's labels
    std::uint64_t fused_busy = 0;    // frames that kept their own labels: the map was busy
    std::size_t voxels = 0;
    std::size_t memory_bytes = 0;
    std::size_t queue_depth = 0, queue_capacity = 0;
  };

  using OnError = std::function<void(const std::string& what)>;

  // Loads Options::file when it exists (see above). Throws findmug::Error for bad options.
  SemanticMapSink(Options options, std::shared_ptr<io::Bus> bus, OnError on_error);
  ~SemanticMapSink() override;
  SemanticMapSink(const SemanticMapSink&) = delete;
  SemanticMapSink& operator=(const SemanticMapSink&) = delete;

  void start();
  std::string name() const override { return "SemanticMapSink"; }
  SinkSlots slots() const override { return {kPublishedLabels, 0}; }
  void consume(FrameResult& result) override;
  // Drain: fuse every queued frame first; then a last publish (when changed) and save.
  // Releases the bus. Idempotent.
  void stop(bool drain);

  Counters counters() const;
  // The tables of the map's last publish (map frame).
  std::vector<FusedTable> tables() const;

 private:
  struct Job {
    OrganizedCloud cloud_camera;
    LabelImage labels;
    Eigen::Isometry3d camera_in_map = Eigen::Isometry3d::Identity();
    io::RobotPose pose;
    std::uint64_t utime = 0;
    std::int64_t seq = 0;
  };

  struct Fused {};

  void fuse(Job& job);
  void publishIfDue(bool force);
  void saveIfDue(bool force);

  Options options_;
  OnError on_error_;
  std::shared_ptr<io::Bus> bus_;
  std::atomic<bool> stopped_{false};

  mutable std::mutex map_mutex_;  // guards map_ and the members up to tables_
  SemanticMap map_;
  bool changed_ = false;           // since the last publish
  bool unsaved_ = false;           // since the last save
  io::RobotPose last_pose_;
  std::uint64_t last_utime_ = 0;
  std::int64_t last_seq_ = 0;
  std::vector<FusedTable> tables_;
  Clock::time_point last_publish_{};
  Clock::time_point last_save_;

  std::atomic<std::uint64_t> queued_{0}, skipped_{0}, integrated_{0}, failed_{0}, publishes_{0},
      fused_frames_{0}, fused_busy_{0};
  // The map thread: fuses each queued frame. Last, so that its worker (joined by stop(), or
  // by its own destructor first of all members) never outlives what it touches.
  std::unique_ptr<Stage<Job, Fused>> stage_;
};

}  // namespace findmug::daemon
