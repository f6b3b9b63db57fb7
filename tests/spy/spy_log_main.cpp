// findmug-test-spy-log LOG — writes an LCM log with one message of every findmug type on its
// channel (rgbd_frame_t, label_image_t, tables_t on FINDMUG_TABLES and FINDMUG_TABLE_MAP,
// objects_t on FINDMUG_OBJECTS and FINDMUG_OBJECT_MAP, status_t, robot_pose_t, semantic_map_t, command_t; table_t and search_position_t
// inside the tables, table_object_t inside the objects), encoded by
// findmug_io's codecs, for spy_test.sh to replay into findmug-spy.
#include <cmath>
#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <vector>

#include "findmug/io/channels.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/lcm_codec_objects.hpp"
#include "findmug/io/semantic_map_codec.hpp"
#include "findmug_lcm/status_t.hpp"

using namespace findmug;

namespace {

void write(lcm::LogFile& log, std::string_view channel, std::vector<std::uint8_t> data,
           std::int64_t utime) {
  lcm::LogEvent event{};
  event.timestamp = utime;
  event.channel = std::string(channel);
  event.datalen = static_cast<std::int32_t>(data.size());
  event.data = data.data();
  if (log.writeEvent(&event) != 0) throw std::runtime_error("cannot write " + event.channel);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: findmug-test-spy-log LOG\n");
    return 2;
  }
  try {
    lcm::LogFile log(argv[1], "w");
    if (!log.good()) throw std::runtime_error(std::string(argv[1]) + ": cannot open");
    const std::int64_t t = 1'000'000;
    const int w = 64, h = 48;

    RgbdFrame frame;
    frame.width = w;
    frame.height = h;
    frame.depth_mm.assign(w * h, 1500);
    frame.rgb.assign(w * h, Rgb8{120, 80, 40});
    frame.intrinsics = CameraIntrinsics{50, 50, 32, 24};
    frame.extrinsics = CameraExtrinsics{1.2, 0.5, 0.0};
    frame.utime = t;
    write(log, io::kRgbdChannel, io::encodeMessage(io::encodeRgbdFrame(frame)), t);

    io::LabelImageMessage labels;
    labels.image.width = w;
    labels.image.height = h;
    labels.image.labels.assign(w * h, 1);
    labels.image.confidence.assign(w * h, 0.8f);
    labels.utime = t;
    // With the camera and colour fields filled in, so that lcm-spy decodes them too.
    auto label_message = io::encodeLabelImage(labels);
    Eigen::Isometry3d camera_to_base = Eigen::Isometry3d::Identity();
    camera_to_base.translation() = Eigen::Vector3d(0, 0, 1.2);
    io::setCameraView(label_message, frame.intrinsics, camera_to_base);
    io::setColorJpeg(label_message, frame.rgb, 80);
    write(log, io::kLabelsChannel, io::encodeMessage(label_message), t + 1);

    io::TablesMessage tables;
    tables.utime = t;
    TableCluster table;
    table.top_height = 0.75f;
    table.hull = {{1.0f, -0.5f}, {2.0f, -0.5f}, {2.0f, 0.5f}, {1.0f, 0.5f}};
    table.center = {1.5f, 0.0f};
    table.extents = {0.5f, 0.5f};
    table.centroid = {1.5f, 0.0f, 0.75f};
    table.point_count = 900;
    SearchPosition position;
    position.xy = {0.5f, 0.0f};
    table.search_positions = {position};
    tables.tables = {table};
    write(log, io::kTablesChannel, io::encodeMessage(io::encodeTables(tables)), t + 2);

    // A mug on that table, seen with the robot's pose known (map_centroid filled in).
    TableObjectDetection objects;
    TableObject mug;
    mug.centroid = {1.4f, 0.1f, 0.82f};
    mug.height_above_top = 0.1f;
    mug.extents = {0.04f, 0.04f};
    mug.center = {1.4f, 0.1f};
    mug.point_count = 150;
    mug.mean_rgb = {180.0f, 40.0f, 30.0f};
    mug.colour_histogram[0] = 0.75f;
    mug.colour_histogram[27] = 0.25f;
    mug.truncation = kTruncatedDepthHole;
    objects.objects = {mug};
    write(log, io::kObjectsChannel,
          io::encodeMessage(io::encodeObjects(
              static_cast<std::uint64_t>(t), 0, objects, tables.tables,
              io::RobotPose{static_cast<std::uint64_t>(t), {2.0, 1.0, 0.3}}, {})),
          t + 2);

    io::TablesMessage map = tables;
    map.content = io::TablesContent::Map;
    map.map_pose = io::RobotPose{static_cast<std::uint64_t>(t), {2.0, 1.0, 0.3}};
    map.map_info = {io::TableMapInfo{1, true, 3, 2}};
    map.tables[0].id = 1;
    write(log, io::kTableMapChannel, io::encodeMessage(io::encodeTables(map)), t + 3);

    MappedObject mapped;
    mapped.id = 1;
    mapped.centroid = {3.3f, 1.5f, 0.82f};
    mapped.extents = {0.04f, 0.04f};
    mapped.height_above_top = 0.1f;
    mapped.mean_rgb = {180.0f, 40.0f, 30.0f};
    mapped.colour_histogram[0] = 0.75f;
    mapped.colour_histogram[27] = 0.25f;
    mapped.point_count = 150;
    mapped.table_id = 1;
    mapped.name = "mug";
    mapped.name_score = 0.8f;
    mapped.sightings = 4;
    mapped.last_seen_utime = static_cast<std::uint64_t>(t);
    const std::vector<MappedObject> object_map = {mapped};
    const std::vector<TableCluster> map_tables = {map.tables[0]};
    write(log, io::kObjectMapChannel,
          io::encodeMessage(io::encodeObjectMap(static_cast<std::uint64_t>(t), 0, object_map,
                                                map_tables, *map.map_pose)),
          t + 3);

    write(log, io::kRobotPoseChannel, io::encodeMessage(io::encodeRobotPose(*map.map_pose)), t + 4);

    findmug_lcm::status_t status{};
    status.utime = t + 5;
    status.model_id = "findmug.fmf:test";
    status.source = "dataset:/test";
    status.source_state_name = "running";
    status.source_state = findmug_lcm::status_t::SOURCE_RUNNING;
    status.model_reloads = 1;
    status.last_reload_ok = true;
    status.last_reload_result = "loaded findmug.fmf:test";
    status.last_reload_request_id = 7;
    write(log, io::kStatusChannel, io::encodeMessage(status), t + 5);

    write(log, io::kCommandChannel,
          io::encodeMessage(io::encodeCommand(
              io::CommandMessage{static_cast<std::uint64_t>(t), 7, "reload_model", ""})),
          t + 7);

    io::SemanticMapMessage semantic;
    semantic.utime = static_cast<std::uint64_t>(t);
    semantic.frames = 3;
    // A 3 x 2.5 m floor with the table map's table standing on it (its top at 0.75 m, the
    // same place as map.tables[0] in the map frame): web_browser_test.sh replays these two
    // channels into findmug-web and checks the live page's map panel draws them.
    const double yaw = map.map_pose->pose.yaw;
    const Eigen::Vector2d robot(map.map_pose->pose.x, map.map_pose->pose.y);
    for (std::int16_t i = 30; i < 90; ++i) {
      for (std::int16_t j = 0; j < 50; ++j) {
        semantic.voxels.push_back({i, j, 0, 1, 230});
        // Into the base frame of the table's hull: inside its 1..2 x -0.5..0.5 m.
        const Eigen::Vector2d d = Eigen::Vector2d(i * 0.05, j * 0.05) - robot;
        const double bx = std::cos(yaw) * d.x() + std::sin(yaw) * d.y();
        const double by = -std::sin(yaw) * d.x() + std::cos(yaw) * d.y();
        if (bx > 1.0 && bx < 2.0 && by > -0.5 && by < 0.5) {
          semantic.voxels.push_back({i, j, 15, 4, 200});
        }
      }
    }
    write(log, io::kSemanticMapChannel, io::encodeMessage(io::encodeSemanticMap(semantic)), t + 6);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "findmug-test-spy-log: %s\n", e.what());
    return 1;
  }
  return 0;
}
