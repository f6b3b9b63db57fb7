// lcm_samples.hpp — filled-in findmug_lcm messages for tests and the fuzz seed maker, so
// that one place says what a plausible daemon status (two stages, one queue) and a
// plausible objects message (two tables, a mug and a cut-off box, the map pose known)
// look like.
#pragma once

#include <findmug_lcm/objects_t.hpp>
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
  s.objects_taught = 2;
  s.teach_refused = 1;
  s.last_teach_ok = true;
  s.last_teach_result = "taught mug (2 views) from frame seq 41, candidate 0";
  s.last_teach_request_id = 77;
  s.object_frames = 120;
  s.object_frames_skipped = 2;
  s.object_candidates = 300;
  s.objects_named = 40;
  s.objects_refused_too_big = 100;
  s.objects_refused_too_small = 90;
  s.objects_refused_colour = 50;
  s.objects_refused_not_round = 10;
  s.objects_refused_shape = 5;
  s.objects_refused_few_points = 5;
  s.object_files_refused = 1;
  s.find_requests = 3;
  s.find_answers = 4;
  s.mapped_objects = 6;
  s.object_map_publishes = 118;
  return s;
}

// One candidate on table `table_id` (map id `table_map_id`) at `x`, `y` on a 0.75 m top.
inline findmug_lcm::table_object_t sampleTableObject(int id, int table_id, int table_map_id,
                                                     double x, double y) {
  findmug_lcm::table_object_t o{};
  o.id = id;
  o.table_id = table_id;
  o.table_map_id = table_map_id;
  o.centroid[0] = x;
  o.centroid[1] = y;
  o.centroid[2] = 0.81;
  // Robot at (2, 1), facing map +y (yaw pi/2): base (x, y) -> map (2 - y, 1 + x).
  o.map_centroid[0] = 2.0 - y;
  o.map_centroid[1] = 1.0 + x;
  o.map_centroid[2] = 0.81;
  o.height_above_top = 0.11;
  o.major_axis[0] = 0.6;
  o.major_axis[1] = 0.8;
  o.extents[0] = 0.045;
  o.extents[1] = 0.04;
  o.center[0] = x + 0.005;
  o.center[1] = y;
  o.point_count = 140;
  o.mean_rgb[0] = 190.0f;
  o.mean_rgb[1] = 35.0f;
  o.mean_rgb[2] = 30.0f;
  o.colour_histogram[0] = 0.625f;  // red, sums to 1 exactly in binary
  o.colour_histogram[1] = 0.25f;
  o.colour_histogram[27] = 0.125f;  // white highlights
  o.truncation = 0;
  return o;
}

inline findmug_lcm::objects_t sampleObjects() {
  findmug_lcm::objects_t m{};
  m.utime = 5550001;
  m.seq = 9;
  m.content = findmug_lcm::objects_t::CONTENT_FRAME;
  m.num_tables = 2;
  m.has_map_pose = true;
  m.map_pose.utime = 5550000;
  m.map_pose.x = 2.0;
  m.map_pose.y = 1.0;
  m.map_pose.yaw = 1.5707963267948966;
  m.objects = {sampleTableObject(0, 0, 4, 1.4, 0.1), sampleTableObject(1, 1, 0, 2.6, -0.7)};
  m.objects[1].truncation = findmug_lcm::table_object_t::TRUNCATED_BORDER |
                            findmug_lcm::table_object_t::TRUNCATED_DEPTH_HOLE;
  m.num_objects = 2;
  return m;
}

// An object map (FINDMUG_OBJECT_MAP, CONTENT_MAP): a mug named by the matcher on the
// table map's first confirmed table, and an unnamed object whose table is not confirmed
// (table_id -1).
inline findmug_lcm::objects_t sampleObjectMap() {
  findmug_lcm::objects_t m = sampleObjects();
  m.content = findmug_lcm::objects_t::CONTENT_MAP;
  for (std::size_t i = 0; i < m.objects.size(); ++i) {
    auto& o = m.objects[i];
    o.id = o.map_id = static_cast<std::int32_t>(i + 1);
    o.sightings = 12;
    o.last_seen_utime = 5550001 - static_cast<std::int64_t>(i) * 1000000;
    o.truncation = 0;
  }
  m.objects[0].name = "mug";
  m.objects[0].name_score = 0.8f;
  m.objects[1].table_id = -1;
  m.objects[1].table_map_id = 0;
  return m;
}

}  // namespace findmug::test
