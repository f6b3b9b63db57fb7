// lcm_samples.hpp — a filled-in findmug_lcm message for tests and the fuzz seed maker, so
// that one place says what a plausible daemon status looks like (two stages, one queue).
#pragma once

#include <findmug_lcm/status_t.hpp>

namespace findmug::test {

inline findmug_lcm::status_t sampleStatus() {
  findmug_lcm::status_t s{};
  s.utime = 99;
  s.uptime_us = 1000000;
  s.frames_received = 10;
  s.frames_processed = 8;
  s.frames_dropped = 1;
  s.frames_rejected = 1;
  s.window_s = 5.0;
  s.input_fps = 30.0f;
  s.output_fps = 4.0f;
  s.num_stages = 2;
  s.stage_names = {"cloud", "total"};
  s.latency_p50_us = {1000, 200000};
  s.latency_p95_us = {1500, 250000};
  s.latency_max_us = {2000, 300000};
  s.num_queues = 1;
  s.queue_names = {"frames"};
  s.queue_depths = {1};
  s.queue_capacities = {2};
  s.model_id = "forest.fmf";
  s.source = "openni2";
  s.source_state_name = "running";
  s.source_state = findmug_lcm::status_t::SOURCE_RUNNING;
  s.last_error = "";
  s.last_error_utime = 0;
  s.model_reloads = 1;
  s.model_reloads_refused = 1;
  s.last_reload_ok = false;
  s.last_reload_result = "refused /var/lib/findmug/model.fmf: cloud.max_depth_m differs";
  s.last_reload_utime = 98;
  s.last_reload_request_id = 7;
  s.commands_accepted = 2;
  s.commands_rejected = 1;
  s.frames_collected = 3;
  s.frames_collect_refused = 1;
  s.last_collected_frame = "1700000000000000_42";
  return s;
}

}  // namespace findmug::test
