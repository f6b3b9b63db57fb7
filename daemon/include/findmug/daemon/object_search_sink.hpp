// findmug/daemon/object_search_sink.hpp — the objects on the tables, named, mapped and found.
//
// A sink after the TableMapSink (result_sinks.hpp). On the publish thread, consume()
// only copies what the object work needs: the frame's table-top candidates with their
// points (not the frame's cloud), its tables without their pixel lists, the table map
// ids the TableMapSink gave them, the pose, seq and utime, and the table map's
// confirmed tables, copied again only when TableMapSink::revision moved. It hands that
// job to the sink's own worker (a Stage, thread "findmug-objects") through a bounded
// drop-oldest queue (daemon.objects_queue): when matching falls behind, the oldest job
// is dropped (counted, status_t.object_frames_skipped), the label stream never waits.
// The worker, in frame order, for each job:
//   1. every daemon.objects_refresh_s it re-reads daemon.objects_dir (the
//      taught objects, ObjectLibrary): a new or changed file is picked up, a
//      corrupt one refused with its reason (logged, last_error, counted);
//   2. it names the frame's table-top candidates with the taught-object
//      matcher (objects/object_matcher.hpp), counting each refusal by its
//      reason; why the nearest taught object was refused for a candidate is
//      logged at debug level, at most once a second;
//   3. with a robot pose for a frame that was labelled (the table map's rule),
//      it updates the object map (map/object_map.hpp) with the candidates, the
//      table map ids and the names, and (daemon.publish_object_map) publishes
//      the map on FINDMUG_OBJECT_MAP (objects_t, CONTENT_MAP), with the frame's
//      utime and seq: the table_id of each object indexes the confirmed tables
//      of the table map at that frame (FINDMUG_TABLE_MAP of the same seq, when
//      the semantic map is off), -1 when its table is not among them;
//   4. it notes the tables at whose search positions the robot stands as
//      searched for the latest find request, and when that request's answer
//      changed (seen now, another place first, a table searched) it publishes
//      it again on FINDMUG_FIND_RESULT.
// A "find" command (command_t, from the command thread) is answered at once
// from what the sink holds (requestFind): where the object was seen, or the
// places to look (map/object_search.hpp), or a refusal with the reason (no
// pose input, so no map; a name not taught, listing the taught ones). The
// worker holds the sink's lock only to update the map, never while matching.
//
// In ExecutionMode::Sequential there is no thread: consume() does the work itself.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "findmug/daemon/object_library.hpp"
#include "findmug/daemon/result_sinks.hpp"
#include "findmug/daemon/stage.hpp"
#include "findmug/io/bus.hpp"
#include "findmug/io/lcm_codec_find.hpp"
#include "findmug/map/object_map.hpp"
#include "findmug/map/object_search.hpp"
#include "findmug/objects/object_matcher.hpp"

namespace findmug::daemon {

struct ObjectSearchSettings {
  std::string objects_dir;         // daemon.objects_dir ("" = no taught objects)
  double refresh_period_s = 1.0;   // how often the folder is looked at again
  bool map_objects = true;         // false without a pose input: no map, no places
  bool publish_map = true;         // daemon.publish_object_map
  ExecutionMode mode = ExecutionMode::Threaded;
  int queue_capacity = 2;          // daemon.objects_queue: jobs waiting for the worker
  ObjectMapConfig object_map;
  ObjectSearchConfig object_search;
  ObjectMatcherConfig matcher;
  // Runs on the worker before each job (tests: hold it, to show the publish thread
  // does not wait for it).
  std::function<void()> before_job;
};

// Where the sink's table map comes from (TableMapSink): the confirmed tables (map
// frame, stable ids) and a revision that moves whenever they may have changed.
struct TableMapSource {
  std::function<std::uint64_t()> revision;
  std::function<std::vector<TableCluster>()> confirmed_tables;
};

class ObjectSearchSink final : public ResultSink {
 public:
  using OnError = std::function<void(const std::string& what)>;
  using Clock = std::chrono::steady_clock;

  struct Channels {
    std::string find_result;  // FINDMUG_FIND_RESULT (the bus applies the suffix)
    std::string object_map;   // FINDMUG_OBJECT_MAP
  };

  struct Counters {
    std::uint64_t frames_queued = 0;   // jobs handed to the worker
    std::uint64_t frames_skipped = 0;  // of them dropped from its full queue
    std::uint64_t frames_failed = 0;   // jobs whose work threw (reported)
    std::uint64_t frames_matched = 0;  // frames whose candidates went through the matcher
    std::uint64_t candidates = 0;      // candidates put to the matcher
    std::uint64_t matches = 0;         // candidates named
    // Candidates refused, by the reason the nearest taught object gave (object_matcher.hpp).
    std::uint64_t refused_too_big = 0, refused_too_small = 0, refused_colour = 0,
                  refused_not_round = 0, refused_shape = 0, refused_few_points = 0;
    std::uint64_t object_files_refused = 0;
    std::uint64_t find_requests = 0;
    std::uint64_t find_answers = 0;    // find_result_t published (first answers and updates)
    std::uint64_t map_publishes = 0;   // object map messages published
    std::uint64_t table_map_copies = 0;  // times the table map's tables were copied in
    std::uint64_t mapped_objects = 0;  // now
    std::size_t queue_depth = 0, queue_capacity = 0;
    LatencySummary latency;  // the worker's time per job (match, map, publish)
  };

  // `bus` (may be null: nothing is published) for find_result_t and the object map;
  // `table_map` (its functions may be empty: no tables) where the places to look come
  // from. Threaded: the worker starts here, unless there is nothing it could do (no
  // objects_dir and no map).
  ObjectSearchSink(ObjectSearchSettings settings, std::shared_ptr<io::Bus> bus,
                   Channels channels, TableMapSource table_map, OnError on_error);
  ~ObjectSearchSink() override;
  ObjectSearchSink(const ObjectSearchSink&) = delete;
  ObjectSearchSink& operator=(const ObjectSearchSink&) = delete;

  std::string name() const override { return "ObjectSearchSink"; }
  SinkSlots slots() const override { return {0, kMapInfo}; }
  void consume(FrameResult& result) override;

  // The command "find NAME" with its request id; answers on the find channel
  // (thread-safe, returns quickly). Throws findmug::Error for a name that is
  // not a taught-object name (the command input counts it as refused).
  void requestFind(std::int64_t request_id, const std::string& name, std::uint64_t utime);

  // No more jobs: drain finishes the queued ones, else they are dropped; joins the
  // worker. Idempotent.
  void stop(bool drain);
  // Lets go of the bus (the pipeline's stop: the last holder closes it, which
  // flushes a file:// log); later answers are not sent. Thread-safe, idempotent.
  void close();

  // Threaded: waits at most `timeout` until every job handed over is done (tests).
  bool waitIdle(Clock::duration timeout) const;
  // Whether there is object work at all: taught objects to look for or a map to keep
  // (otherwise no worker, no job; status then leaves its queue and time out).
  bool active() const { return !settings_.objects_dir.empty() || settings_.map_objects; }

  Counters counters() const;
  std::vector<MappedObject> mappedObjects() const;  // thread-safe copy
  std::vector<std::string> taughtNames() const;

 private:
  // What the worker needs of one frame, copied on the publish thread.
  struct Job {
    std::uint64_t utime = 0;
    std::int64_t seq = 0;
    std::string frame_name;
    // The candidates, their pixels renumbered to index `points` (only their points).
    std::vector<TableObject> candidates;
    OrganizedCloud points;
    std::vector<TableCluster> tables;  // the frame's, base frame, without pixel lists
    std::vector<int> table_ids;        // their table map ids; empty: the map did not take it
    std::optional<io::RobotPose> pose;
    bool evidence = false;  // labelled (TableMapSink::isEvidence)
    std::shared_ptr<const std::vector<TableCluster>> map_tables;  // confirmed, map frame
    // While a find request is open: the frame's depth image (no colour) and the camera's
    // pose in the map, for the tables whose tops the view searched (ObjectSearch::observeView).
    std::optional<RgbdFrame> view_depth;
    Eigen::Isometry3d camera_in_map = Eigen::Isometry3d::Identity();
  };
  struct Done {};

  Job makeJob(const FrameResult& result);
  void work(Job& job);
  void refreshLibrary();
  std::vector<ObjectIdentity> nameCandidates(const Job& job);
  void countRefusal(const std::string& rejection);
  io::FindResultMessage answerLocked(std::uint64_t utime);
  void publish(const io::FindResultMessage& message);
  void publishMap(const std::vector<std::uint8_t>& bytes, std::int64_t seq);
  // Depth buffers of finished or dropped jobs, reused by the next ones: a 640x480 image is
  // 600 KB, which a fresh allocation maps and faults in page by page every frame.
  std::vector<std::uint16_t> takeDepthBuffer();
  void recycle(Job& job);

  ObjectSearchSettings settings_;
  mutable std::mutex bus_mutex_;  // guards bus_ (worker, command thread, stop)
  std::mutex spare_depth_mutex_;  // guards spare_depth_ (frame thread, worker)
  std::vector<std::vector<std::uint16_t>> spare_depth_;
  std::shared_ptr<io::Bus> bus_;
  Channels channels_;
  TableMapSource table_map_;
  OnError on_error_;
  ObjectLibrary library_;
  std::atomic<bool> has_models_{false};  // the library holds a model (worker sets it)
  Clock::time_point next_refresh_{};
  Clock::time_point next_rejection_log_{};
  // Publish thread only: the table map revision copied last and that copy.
  std::optional<std::uint64_t> table_map_revision_;
  std::shared_ptr<const std::vector<TableCluster>> table_map_copy_;

  mutable std::mutex mutex_;  // guards everything below (worker and command thread)
  ObjectMap map_;
  ObjectSearch search_;
  std::shared_ptr<const std::vector<TableCluster>> map_tables_;  // confirmed, map frame
  std::optional<Pose2D> robot_;           // the newest frame pose
  std::vector<std::string> taught_;       // names in the library, sorted
  std::optional<std::string> request_name_;
  std::string last_answer_;  // summary + places of the last answer published, to spot changes
  Counters counters_;
  std::atomic<bool> stopped_{false};

  // Last: destroyed (its worker joined) before the members its work uses.
  std::unique_ptr<Stage<Job, Done>> stage_;
};

}  // namespace findmug::daemon
