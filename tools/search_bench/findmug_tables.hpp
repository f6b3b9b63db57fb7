// findmug_tables.hpp — findmug's perception for the search benchmark: the daemon's own
// Pipeline (ExecutionMode::Sequential) fed with the simulated camera's frames and the
// robot's pose, its table map read back from FINDMUG_TABLE_MAP.
//
// Why the daemon's path and not the Segmenter alone: the search strategy should act only
// on what a robot would receive from findmugd — the confirmed tables of the persistent
// map and their search positions, decoded from tables_t (CONTENT_MAP) by the io codecs.
// The pose goes in as robot_pose_t on FINDMUG_ROBOT_POSE through the pipeline's pose bus.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "findmug/daemon/daemon_config.hpp"
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

// One episode's daemon: a fresh pipeline (and so an empty table map).
class FindmugTables {
 public:
  explicit FindmugTables(const FindmugModel& model);
  ~FindmugTables();
  FindmugTables(const FindmugTables&) = delete;
  FindmugTables& operator=(const FindmugTables&) = delete;

  // Publishes the pose, waits until the pose input has it, then submits the frame; reads
  // any table map the daemon published for it.
  void feed(const synth::RenderedFrame& frame, const Eigen::Vector2d& xy, double yaw,
            double time_s);
  // Search positions of the confirmed tables in the last published map.
  const std::vector<MapSearchPosition>& positions() const { return positions_; }
  int tables() const { return tables_; }
  int frames() const { return frames_; }

 private:
  std::shared_ptr<io::MemoryBus> out_, poses_, commands_;
  std::unique_ptr<daemon::Pipeline> pipeline_;
  std::vector<MapSearchPosition> positions_;
  int tables_ = 0;
  int frames_ = 0;
};

}  // namespace findmug::search
