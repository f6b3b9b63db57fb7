// findmug/daemon/status_snapshot.hpp — the pipeline's figures at one instant, in
// plain types (no generated LCM type): the counters and the snapshot that
// StatusBuilder (status_builder.hpp) turns into status_t.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "findmug/daemon/object_teacher.hpp"
#include "findmug/daemon/stats.hpp"
#include "findmug/io/frame_source.hpp"

namespace findmug::daemon {

struct PipelineCounters {
  std::uint64_t received = 0;   // submitted frames
  std::uint64_t processed = 0;  // published label images
  std::uint64_t dropped = 0;  // evicted from a full queue / discarded at shutdown (+ source drops)
  std::uint64_t dropped_at_door = 0;      // of those: before any work (pipeline entry, source)
  std::uint64_t dropped_in_pipeline = 0;  // after some work (an internal queue was full)
  std::uint64_t dropped_at_shutdown = 0;  // queued or in flight at stop()
  std::uint64_t rejected = 0;             // failed in a stage (+ bad input the source skipped,
                                          // + bad robot pose messages)
  std::uint64_t pending = 0;              // inside the pipeline now
};

// Model reloads and commands (model_reload.hpp, command_input.hpp).
struct ReloadStatus {
  std::uint64_t reloads = 0;          // models swapped in
  std::uint64_t refused = 0;          // reloads refused (the running model kept)
  bool last_ok = false;
  std::string last_result;            // "" before any reload
  std::uint64_t last_utime = 0;       // host clock, microseconds; 0 before any
  std::int64_t last_request_id = -1;  // command_t.request_id; -1: SIGHUP or none
};

struct StatusSnapshot {
  struct Queue {
    std::string name;  // the pipeline stage it feeds
    std::size_t depth = 0, capacity = 0;
  };
  struct Source {
    std::string description;
    io::SourceState state = io::SourceState::Running;
    std::string last_error;
    std::uint64_t last_error_utime = 0;
    std::uint64_t reconnects = 0;  // times the source re-opened its device after a loss
    std::uint64_t lost_in_transit = 0;  // publisher's frames that never arrived (seq holes)
  };

  std::uint64_t utime = 0;     // host clock, microseconds
  std::int64_t uptime_us = 0;  // since the pipeline was made
  PipelineCounters counters;
  double window_s = 0.0;  // daemon.stats_window_s
  double input_fps = 0.0, output_fps = 0.0;
  // (name, latency) in report order: pipeline stages, sub-stages, "total".
  std::vector<std::pair<std::string, LatencySummary>> latencies;
  std::vector<Queue> queues;
  std::string model_id;
  double cpu_budget_cores = 0.0, cpu_used_cores = 0.0;
  int processing_threads = 0;
  std::uint64_t publish_failures = 0;  // refused publishes, every channel (status included)
  std::int64_t heap_in_use_bytes = -1;  // allocated and not freed (-1: unknown)
  // The semantic map sink (all 0 when daemon.semantic_map is off).
  std::uint64_t semantic_map_frames = 0, semantic_map_skipped = 0, semantic_map_voxels = 0;
  ReloadStatus reload;
  std::uint64_t commands_accepted = 0, commands_rejected = 0;
  // Frames saved for labelling (frame_collector.hpp; 0 / "" when off).
  std::uint64_t frames_collected = 0, frames_collect_refused = 0;
  std::string last_collected_frame;
  TeachStatus teach;  // the command "teach" (object_teacher.hpp)
  // The objects on the tables (object_search_sink.hpp; status_t's object_* fields).
  struct Objects {
    std::uint64_t frames = 0, frames_skipped = 0, candidates = 0, named = 0;
    std::uint64_t refused_too_big = 0, refused_too_small = 0, refused_colour = 0,
                  refused_not_round = 0, refused_shape = 0, refused_few_points = 0;
    std::uint64_t files_refused = 0, find_requests = 0, find_answers = 0;
    std::uint64_t mapped = 0, map_publishes = 0;
  } objects;
  std::string last_error;  // the pipeline's own
  std::uint64_t last_error_utime = 0;
  std::optional<Source> source;  // nullopt: frames submitted in-process
};

}  // namespace findmug::daemon
