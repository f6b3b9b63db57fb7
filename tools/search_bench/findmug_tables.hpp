// findmug_tables.hpp — findmug's perception for the search benchmark: the daemon's own
// Pipeline (ExecutionMode::Sequential) fed with the simulated camera's frames and the
// robot's pose, its table map read back from FINDMUG_TABLE_MAP.
//
// Why the daemon's path and not the Segmenter alone: the search strategy should act only
// on what a robot would receive from findmugd — the confirmed tables of the persistent
// map and their search positions, decoded from tables_t (CONTENT_MAP) by the io codecs.
// The pose goes in as robot_pose_t on FINDMUG_ROBOT_POSE through the pipeline's pose bus.
//
// With a folder of taught objects (daemon.objects_dir) the same pipeline names the table-top
// candidates and keeps its object map; find() then asks it "find NAME" as a navigation client
// would: command_t on FINDMUG_COMMAND, the answer find_result_t on FINDMUG_FIND_RESULT.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "findmug/daemon/daemon_config.hpp"
#include "findmug/daemon/object_search_sink.hpp"
#include "findmug/io/lcm_codec_find.hpp"
#include "findmug/learner/forest.hpp"
#include "findmug/synth/synth.hpp"

namespace findmug::daemon {
class Pipeline;
}
namespace findmug::io {
class MemoryBus;
}

namespace findmug::search {

// A search position of a mapped table, map (= world) frame.
struct MapSearchPosition {
  int table_id = 0;
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  double yaw = 0.0;
  bool reachable = true;
};

// The daemon's configuration and model, loaded once and shared by every episode.
struct FindmugModel {
  daemon::LoadedConfig loaded;
  std::shared_ptr<const RandomForest> forest;
  std::string model_id;
};

// Loads `config_path` with `overrides` ("key=value") and the model at `model_path`, as
// findmugd's command line would. Throws findmug::Error naming what is wrong.
FindmugModel loadFindmugModel(const std::string& config_path, const std::string& model_path,
                              const std::vector<std::string>& overrides);

// The settings the sim-domain model (models/findmug-apartments.fmf; the demo's
// models/findmug-nyu-synth.fmf too) runs with: it learned the 8 labels (findmug-synth
// writes no NYU-13 classes), without object features, for the Potts pairwise term.
const std::vector<std::string>& simDomainSettings();

// One episode's daemon: a fresh pipeline (and so an empty table and object map).
class FindmugTables {
 public:
  // `objects_dir` ("" = none) is the daemon's objects_dir: the taught objects it names.
  explicit FindmugTables(const FindmugModel& model, const std::string& objects_dir = "");
  ~FindmugTables();
  FindmugTables(const FindmugTables&) = delete;
  FindmugTables& operator=(const FindmugTables&) = delete;

  // Publishes the pose, waits until the pose input has it, then submits the frame; reads
  // any table map the daemon published for it.
  void feed(const synth::RenderedFrame& frame, const Eigen::Vector2d& xy, double yaw,
            double time_s);
  // Search positions of the confirmed tables in the last published map.
  const std::vector<MapSearchPosition>& positions() const { return positions_; }
  // The confirmed tables of the last published map (map frame, id = the stable id).
  const std::vector<TableCluster>& mapTables() const { return map_tables_; }
  int tables() const { return tables_; }
  int frames() const { return frames_; }

  // Sends "find NAME" on the command bus and returns the daemon's answer to it. Every call
  // of one FindmugTables carries the same request id: one search, asked again after each
  // frame, so that the daemon's tables searched for it accumulate. Throws findmug::Error
  // when no answer comes within 10 s.
  io::FindResultMessage find(const std::string& name);
  int findRequests() const { return find_requests_; }
  // What the daemon's object work counted: candidates put to the matcher, matches,
  // refusals by reason.
  daemon::ObjectSearchSink::Counters objectCounters() const;
  // Table map ids the last answer says may hold the object ("look closer" there), in its
  // order (find_result_t.place_look_closer).
  static std::vector<int> lookCloserTables(const io::FindResultMessage& answer);

 private:
  std::shared_ptr<io::MemoryBus> out_, poses_, commands_;
  std::unique_ptr<daemon::Pipeline> pipeline_;
  std::vector<MapSearchPosition> positions_;
  std::vector<TableCluster> map_tables_;
  int tables_ = 0;
  int frames_ = 0;
  std::uint64_t last_utime_ = 0;
  int find_requests_ = 0;
  std::uint64_t answers_ = 0;
  io::FindResultMessage last_answer_;
};

}  // namespace findmug::search
