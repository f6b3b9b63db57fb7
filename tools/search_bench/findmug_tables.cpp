// findmug's tables for the search benchmark: findmugd's Pipeline on the simulated frames
// (see findmug_tables.hpp).
#include "findmug_tables.hpp"

#include <chrono>
#include <cmath>
#include <algorithm>
#include <sstream>
#include <thread>

#include "findmug/common/error.hpp"
#include "findmug/daemon/daemon.hpp"
#include "findmug/daemon/pipeline.hpp"
#include "findmug/io/bus.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/lcm_codec.hpp"

namespace findmug::search {

const std::vector<std::string>& simDomainSettings() {
  static const std::vector<std::string> settings{"learner.classes=labels",
                                                 "features.objects=false", "mrf.pairwise=potts"};
  return settings;
}

FindmugModel loadFindmugModel(const std::string& config_path, const std::string& model_path,
                              const std::vector<std::string>& overrides) {
  std::vector<std::string> args{"--config", config_path, "--model", model_path};
  for (const std::string& o : overrides) {
    args.push_back("--set");
    args.push_back(o);
  }
  FindmugModel model;
  model.loaded = daemon::loadDaemonConfig(daemon::parseCommandLine(args));
  model.forest = daemon::loadModel(model.loaded.daemon.model_path, &model.model_id);
  return model;
}

namespace {
// The request id of every find of an episode (a navigation client's one search).
constexpr std::int64_t kFindRequestId = 1;
}  // namespace

FindmugTables::FindmugTables(const FindmugModel& model, const std::string& objects_dir)
    : out_(std::make_shared<io::MemoryBus>(100000)),
      poses_(std::make_shared<io::MemoryBus>()),
      commands_(std::make_shared<io::MemoryBus>()) {
  // Every bus in memory: nothing leaves the process (the daemon would otherwise listen for
  // commands on its LCM URL).
  daemon::PipelineHooks hooks;
  hooks.output_bus = out_;
  hooks.pose_bus = poses_;
  hooks.command_bus = commands_;
  daemon::DaemonConfig config = model.loaded.daemon;
  config.channel_suffix.clear();
  config.objects_dir = objects_dir;
  pipeline_ =
      std::make_unique<daemon::Pipeline>(model.loaded.config.segmenter, config, model.forest,
                                         model.model_id, daemon::ExecutionMode::Sequential, hooks);
  if (pipeline_->poseInput() == nullptr)
    throw Error("search: the daemon's pose input is off (daemon.pose_input must be true)");
  out_->subscribe(
      std::string(io::kTableMapChannel),
      [this](const std::string& channel, const std::uint8_t* data, std::size_t size) {
        const io::TablesMessage map = io::decodeTables(data, size, channel);
        positions_.clear();
        map_tables_.clear();
        tables_ = static_cast<int>(map.tables.size());
        for (std::size_t t = 0; t < map.tables.size(); ++t) {
          if (t < map.map_info.size() && !map.map_info[t].confirmed) continue;
          // The table in the map frame: the map_ fields, the base frame's top height.
          const io::MapFrameTable& in_map = map.map_tables[t];
          TableCluster table;
          table.id = map.tables[t].id;
          table.top_height = map.tables[t].top_height;
          table.centroid = in_map.centroid.cast<float>();
          table.center = in_map.center.cast<float>();
          for (const Eigen::Vector2d& p : in_map.hull) table.hull.push_back(p.cast<float>());
          table.search_positions = in_map.search_positions;
          map_tables_.push_back(std::move(table));
          for (const SearchPosition& p : map.map_tables[t].search_positions)
            positions_.push_back({map.tables[t].id, p.xy.cast<double>(), p.yaw, p.reachable});
        }
      });
  out_->subscribe(std::string(io::kFindResultChannel),
                  [this](const std::string& channel, const std::uint8_t* data, std::size_t size) {
                    io::FindResultMessage answer = io::decodeFindResult(data, size, channel);
                    if (answer.request_id != kFindRequestId) return;
                    last_answer_ = std::move(answer);
                    ++answers_;
                  });
  pipeline_->start();
}

FindmugTables::~FindmugTables() {
  pipeline_->stop(daemon::StopMode::Drain);
  pipeline_.reset();
}

void FindmugTables::feed(const synth::RenderedFrame& frame, const Eigen::Vector2d& xy, double yaw,
                         double time_s) {
  // Simulated time as the host clock, from 1 s so that no stamp is zero.
  const auto utime = static_cast<std::uint64_t>(std::llround((time_s + 1.0) * 1e6)) +
                     static_cast<std::uint64_t>(frames_);
  const std::uint64_t before = pipeline_->poseInput()->received();
  io::publishMessage(*poses_, std::string(io::kRobotPoseChannel),
                     io::encodeRobotPose({utime, {xy.x(), xy.y(), yaw}}));
  // The pose thread takes it off the bus; the frame must not be published before it has.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (pipeline_->poseInput()->received() == before) {
    if (std::chrono::steady_clock::now() > deadline)
      throw Error("search: the daemon's pose input did not take a pose within 10 s");
    std::this_thread::sleep_for(std::chrono::microseconds(100));
  }
  RgbdFrame f = frame.labeled.frame;
  f.utime = utime;
  f.seq = frames_++;
  last_utime_ = utime;
  pipeline_->submit(std::move(f));
  while (out_->handle(std::chrono::milliseconds(0)) == io::HandleResult::Handled) {
  }
}

io::FindResultMessage FindmugTables::find(const std::string& name) {
  if (pipeline_->commandInput() == nullptr)
    throw Error("search: the daemon's command input is off (daemon.command_input must be true)");
  // In sequential mode the object work of every frame fed is done and its answers handled
  // (feed drains the bus), so the next answer to this request is the one to this command.
  while (out_->handle(std::chrono::milliseconds(0)) == io::HandleResult::Handled) {
  }
  const std::uint64_t before = answers_;
  io::publishMessage(*commands_, std::string(io::kCommandChannel),
                     io::encodeCommand(io::CommandMessage{last_utime_, kFindRequestId, "find",
                                                          name}));
  ++find_requests_;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (answers_ == before) {
    if (std::chrono::steady_clock::now() > deadline)
      throw Error("search: no answer to \"find " + name + "\" on " +
                  std::string(io::kFindResultChannel) + " within 10 s");
    out_->handle(std::chrono::milliseconds(20));
  }
  return last_answer_;
}

daemon::ObjectSearchSink::Counters FindmugTables::objectCounters() const {
  return pipeline_->objectSearch().counters();
}

std::vector<int> FindmugTables::lookCloserTables(const io::FindResultMessage& answer) {
  std::vector<int> ids;
  if (answer.result != io::FindResult::LookAt) return ids;
  for (const PlaceToLook& p : answer.places)
    if (p.look_closer && std::find(ids.begin(), ids.end(), p.table_id) == ids.end())
      ids.push_back(p.table_id);
  return ids;
}

}  // namespace findmug::search
