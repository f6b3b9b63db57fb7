// status_t from a StatusSnapshot; see status_builder.hpp.
#include "findmug/daemon/status_builder.hpp"

namespace findmug::daemon {

findmug_lcm::status_t StatusBuilder::build(const StatusSnapshot& in) {
  findmug_lcm::status_t s{};
  s.utime = static_cast<std::int64_t>(in.utime);
  s.uptime_us = in.uptime_us;
  const PipelineCounters& c = in.counters;
  s.frames_received = static_cast<std::int64_t>(c.received);
  s.frames_processed = static_cast<std::int64_t>(c.processed);
  s.frames_dropped = static_cast<std::int64_t>(c.dropped);
  s.frames_rejected = static_cast<std::int64_t>(c.rejected);
  s.frames_dropped_at_door = static_cast<std::int64_t>(c.dropped_at_door);
  s.frames_dropped_in_pipeline = static_cast<std::int64_t>(c.dropped_in_pipeline);
  s.frames_dropped_at_shutdown = static_cast<std::int64_t>(c.dropped_at_shutdown);
  s.cpu_budget_cores = static_cast<float>(in.cpu_budget_cores);
  s.cpu_used_cores = static_cast<float>(in.cpu_used_cores);
  s.processing_threads = static_cast<std::int32_t>(in.processing_threads);
  s.window_s = in.window_s;
  s.input_fps = static_cast<float>(in.input_fps);
  s.output_fps = static_cast<float>(in.output_fps);

  for (const auto& [name, l] : in.latencies) {
    s.stage_names.push_back(name);
    s.latency_p50_us.push_back(static_cast<std::int64_t>(l.p50_ms * 1000.0));
    s.latency_p95_us.push_back(static_cast<std::int64_t>(l.p95_ms * 1000.0));
    s.latency_max_us.push_back(static_cast<std::int64_t>(l.max_ms * 1000.0));
  }
  s.num_stages = static_cast<std::int32_t>(s.stage_names.size());
  for (const auto& q : in.queues) {
    s.queue_names.push_back(q.name);
    s.queue_depths.push_back(static_cast<std::int32_t>(q.depth));
    s.queue_capacities.push_back(static_cast<std::int32_t>(q.capacity));
  }
  s.num_queues = static_cast<std::int32_t>(s.queue_names.size());
  s.model_id = in.model_id;
  s.publish_failures = static_cast<std::int64_t>(in.publish_failures);
  s.heap_in_use_bytes = in.heap_in_use_bytes;
  s.semantic_map_frames = static_cast<std::int64_t>(in.semantic_map_frames);
  s.semantic_map_skipped = static_cast<std::int64_t>(in.semantic_map_skipped);
  s.semantic_map_voxels = static_cast<std::int64_t>(in.semantic_map_voxels);
  s.model_reloads = static_cast<std::int64_t>(in.reload.reloads);
  s.model_reloads_refused = static_cast<std::int64_t>(in.reload.refused);
  s.last_reload_ok = in.reload.last_ok;
  s.last_reload_result = in.reload.last_result;
  s.last_reload_utime = static_cast<std::int64_t>(in.reload.last_utime);
  s.last_reload_request_id = in.reload.last_request_id;
  s.commands_accepted = static_cast<std::int64_t>(in.commands_accepted);
  s.commands_rejected = static_cast<std::int64_t>(in.commands_rejected);
  s.frames_collected = static_cast<std::int64_t>(in.frames_collected);
  s.frames_collect_refused = static_cast<std::int64_t>(in.frames_collect_refused);
  s.last_collected_frame = in.last_collected_frame;
  s.objects_taught = static_cast<std::int64_t>(in.teach.taught);
  s.teach_refused = static_cast<std::int64_t>(in.teach.refused);
  s.last_teach_ok = in.teach.last_ok;
  s.last_teach_result = in.teach.last_result;
  s.last_teach_request_id = in.teach.last_request_id;
  const StatusSnapshot::Objects& o = in.objects;
  s.object_frames = static_cast<std::int64_t>(o.frames);
  s.object_frames_skipped = static_cast<std::int64_t>(o.frames_skipped);
  s.object_candidates = static_cast<std::int64_t>(o.candidates);
  s.objects_named = static_cast<std::int64_t>(o.named);
  s.objects_refused_too_big = static_cast<std::int64_t>(o.refused_too_big);
  s.objects_refused_too_small = static_cast<std::int64_t>(o.refused_too_small);
  s.objects_refused_colour = static_cast<std::int64_t>(o.refused_colour);
  s.objects_refused_not_round = static_cast<std::int64_t>(o.refused_not_round);
  s.objects_refused_shape = static_cast<std::int64_t>(o.refused_shape);
  s.objects_refused_few_points = static_cast<std::int64_t>(o.refused_few_points);
  s.object_files_refused = static_cast<std::int64_t>(o.files_refused);
  s.find_requests = static_cast<std::int64_t>(o.find_requests);
  s.find_answers = static_cast<std::int64_t>(o.find_answers);
  s.mapped_objects = static_cast<std::int64_t>(o.mapped);
  s.object_map_publishes = static_cast<std::int64_t>(o.map_publishes);

  std::string last_error = in.last_error;
  std::uint64_t last_error_utime = in.last_error_utime;
  if (in.source) {
    s.source = in.source->description;
    s.source_state = static_cast<std::int8_t>(in.source->state);
    s.source_state_name = std::string(io::sourceStateName(in.source->state));
    s.source_reconnects = static_cast<std::int64_t>(in.source->reconnects);
    s.frames_lost_in_transit = static_cast<std::int64_t>(in.source->lost_in_transit);
    if (in.source->last_error_utime > last_error_utime) {
      last_error = in.source->last_error;
      last_error_utime = in.source->last_error_utime;
    }
  } else {
    s.source = "(in-process)";
    s.source_state = static_cast<std::int8_t>(io::SourceState::Running);
    s.source_state_name = std::string(io::sourceStateName(io::SourceState::Running));
  }
  s.last_error = last_error;
  s.last_error_utime = static_cast<std::int64_t>(last_error_utime);
  return s;
}

}  // namespace findmug::daemon
