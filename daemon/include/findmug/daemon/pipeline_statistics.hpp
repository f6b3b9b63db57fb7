// findmug/daemon/pipeline_statistics.hpp — the pipeline's rates, per-step latencies and last
// error, as status_t reports them; and the one table of the step timings it reports.
//
// The Pipeline calls frameIn() at submit, framePublished() after the sinks, recordError()
// from any thread; statusSnapshot() copies the figures into a StatusSnapshot. Thread-safe.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "findmug/daemon/stats.hpp"
#include "findmug/daemon/status_snapshot.hpp"
#include "findmug/segmenter/segmenter.hpp"

namespace findmug::daemon {

// The step timings status_t reports (stage_names, latency_*), in frame order, with the
// StageTimings field each comes from. A new timing of the Segmenter is reported by adding
// its row here (and its field to StageTimings); nothing else in the daemon names them.
const std::vector<std::pair<std::string, double StageTimings::*>>& reportedStepTimings();

class PipelineStatistics {
 public:
  using Clock = std::chrono::steady_clock;

  // `window`: daemon.stats_window_s, the span rates and percentiles cover.
  explicit PipelineStatistics(Clock::duration window);

  void frameIn(Clock::time_point now = Clock::now());
  // A published frame: its step timings and its latency from arrival to published.
  void framePublished(const StageTimings& timings, double latency_ms, Clock::time_point now);
  // The pipeline's own last error (status_t.last_error), host clock.
  void recordError(const std::string& message);

  // Input and output fps, the step timings then "total" appended to `s.latencies`, last error.
  void fill(StatusSnapshot& s, Clock::time_point now) const;

 private:
  mutable std::mutex mutex_;  // guards everything below
  RateMeter input_rate_, output_rate_;
  std::map<std::string, LatencyWindow> latency_;  // per reported step timing, and "total"
  std::string last_error_;
  std::uint64_t last_error_utime_ = 0;
};

// Host clock, microseconds since the epoch (status_t's utime fields).
std::uint64_t hostUtimeNow();

}  // namespace findmug::daemon
