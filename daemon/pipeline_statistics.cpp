// The pipeline's rates, latencies and last error; see pipeline_statistics.hpp.
#include "findmug/daemon/pipeline_statistics.hpp"

namespace findmug::daemon {

const std::vector<std::pair<std::string, double StageTimings::*>>& reportedStepTimings() {
  static const std::vector<std::pair<std::string, double StageTimings::*>> all = {
      {"cloud", &StageTimings::cloud_ms},
      {"normals", &StageTimings::normals_ms},
      {"ground", &StageTimings::ground_ms},
      {"oversegmentation", &StageTimings::oversegmentation_ms},
      {"features", &StageTimings::features_ms},
      {"regions", &StageTimings::regions_ms},
      {"forest", &StageTimings::forest_ms},
      {"context", &StageTimings::context_ms},
      {"mrf", &StageTimings::mrf_ms},
      {"labels", &StageTimings::labels_ms},
      {"tables", &StageTimings::tables_ms},
      {"objects", &StageTimings::objects_ms}};
  return all;
}

std::uint64_t hostUtimeNow() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                        std::chrono::system_clock::now().time_since_epoch())
                                        .count());
}

PipelineStatistics::PipelineStatistics(Clock::duration window)
    : input_rate_(1000, window), output_rate_(1000, window) {
  for (const auto& [name, field] : reportedStepTimings())
    latency_.emplace(name, LatencyWindow(window));
  latency_.emplace("total", LatencyWindow(window));
}

void PipelineStatistics::frameIn(Clock::time_point now) {
  std::lock_guard lock(mutex_);
  input_rate_.tick(now);
}

void PipelineStatistics::framePublished(const StageTimings& timings, double latency_ms,
                                        Clock::time_point now) {
  std::lock_guard lock(mutex_);
  output_rate_.tick(now);
  for (const auto& [name, field] : reportedStepTimings())
    latency_.at(name).add(timings.*field, now);
  latency_.at("total").add(latency_ms, now);
}

void PipelineStatistics::recordError(const std::string& message) {
  const std::uint64_t utime = hostUtimeNow();
  std::lock_guard lock(mutex_);
  last_error_ = message;
  last_error_utime_ = utime;
}

void PipelineStatistics::fill(StatusSnapshot& s, Clock::time_point now) const {
  std::lock_guard lock(mutex_);
  s.input_fps = input_rate_.rate(now);
  s.output_fps = output_rate_.rate(now);
  for (const auto& [name, field] : reportedStepTimings()) {
    s.latencies.emplace_back(name, latency_.at(name).summary(now));
  }
  s.latencies.emplace_back("total", latency_.at("total").summary(now));
  s.last_error = last_error_;
  s.last_error_utime = last_error_utime_;
}

}  // namespace findmug::daemon
