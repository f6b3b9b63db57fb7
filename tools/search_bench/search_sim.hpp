// search_sim.hpp — the simulated robot of findmug-search-bench (issue 51): a multi-room
// apartment with a target mug (findmug_synth), a 2-D occupancy grid with shortest paths, a
// differential-drive base and a head camera rendered by the project's renderer.
//
// Why a simulator: the project claims that looking on tables first finds the mug sooner.
// That is a claim about time spent by a robot, so every strategy runs on the same seeded
// episodes with the same motion model, recogniser and time accounting:
//   time = path / speed + |turns| / turn rate + stop views * per-view processing time.
// Frames taken while the base drives or turns (drive_frames_hz) cost no time: the daemon
// processes them in parallel to the motion. The recogniser is either an oracle on the
// rendered frame (the mug counts as seen when enough of its pixels are visible within
// range), so that strategies differ only in where they look, or findmugd's own taught-object
// matcher asked "find mug" after every frame (strategies.hpp), whose "seen" may be wrong.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "findmug/synth/synth.hpp"

namespace findmug::search {

struct SimParams {
  double robot_radius_m = 0.3;
  double cell_m = 0.05;
  double speed_mps = 0.3;
  double turn_rate_rad_s = 0.785398163397448;  // 45 deg/s
  double view_processing_s = 0.1;              // per view, fixed (stated in the report)
  int look_around_views = 12;                  // 30 deg steps
  // A look-around turns only through the headings whose view would show at least this much
  // floor plan (within look_coverage_range_m, in line of sight) that no earlier frame of the
  // robot showed: a small table top (0.5 m^2). Headings below it are skipped and the turn
  // takes the short way through the rest. full_look_arounds: every heading, always.
  double look_unseen_min_m2 = 0.5;
  double look_coverage_range_m = 3.0;  // the oracle's top-seen range (a mug shows from 3.5 m)
  bool full_look_arounds = false;
  double camera_height_m = 1.2;
  double camera_pitch_rad = 0.5;  // 28.6 deg down: table tops and the floor from 0.9 m
  double recognise_range_m = 3.5;
  int recognise_min_pixels = 150;  // of the mug, at 640x480
  double time_budget_s = 600.0;
  // Frames while driving or turning, per second of motion (0: views at stops only).
  double drive_frames_hz = 1.0;
  // A matcher's "seen" counts as found when its position is this near the mug (on the floor).
  double found_tolerance_m = 0.3;
  // Coverage counts floor within this range of a view as searched: nearer than the
  // recogniser's range, because a mug at 3.5 m shows 150 px only when seen whole and
  // head-on (tables, chairs and other objects hide it more often the further it is).
  double coverage_range_m = 2.0;
  // The findmug strategy skips a table once this share of its top was in view within the
  // recogniser's reach (findmug's TableTopViews; 0: visit every table's search position).
  double top_seen_share = 0.8;
  double top_seen_range_oracle_m = 3.0;   // the oracle's 150 px of mug: 3.5 m head-on
  double top_seen_range_matcher_m = 1.5;  // the matcher names the mug from 1.0-1.5 m
  // A room counts as explored (the findmug and places strategies' room exploring) once the
  // robot looked around in it, or once its frames have shown this share of its floor plan
  // (ViewCoverage; 1: only a look-around in it).
  double room_seen_share = 0.8;
  // Exploring a room drives to its centre before the look-around, also when a look-around
  // from a spot passed on the way (its doorway) would show as much of it (the behaviour
  // before exploring looked from the first such spot).
  bool explore_to_room_centres = false;
  // The findmug strategy stops exploring a room when the map shows a new table to look at.
  bool replan_on_new_tables = true;
  // The findmug strategy drives only to the search positions findmugd marks reachable
  // (the behaviour before it also tried the others its own occupancy grid can reach once
  // every room was explored: the daemon marks a spot unreachable when its frames did not
  // show the floor there, which a robot's navigation map decides better).
  bool only_daemon_reachable = false;
  // The findmug strategy, when coverage has left nothing and the mug is not seen: it looks at
  // every footprint of the occupancy grid from beside it, nearest first.
  bool furniture_after_coverage = true;
  synth::MultiRoomParams apartment;
  synth::MugPrior prior;
  // Other mugs as red as the target: recoloured (default) or kept (--keep-look-alikes).
  synth::LookAlikes look_alikes = synth::LookAlikes::Recolour;
  // Keep a line per action (time, pose, what and why) for --trace: where an episode's time went.
  bool trace = false;
};

// Occupancy grid of the apartment's floor: a cell is free when a round robot of the
// given radius centred there clears every wall and obstacle footprint.
class Grid {
 public:
  Grid() : cell_(0.05), nx_(0), ny_(0) {}
  Grid(const synth::SynthScene& scene, double robot_radius, double cell);
  int nx() const { return nx_; }
  int ny() const { return ny_; }
  int size() const { return nx_ * ny_; }
  double cell() const { return cell_; }
  bool free(int i) const { return free_[i] != 0; }
  int cellAt(const Eigen::Vector2d& xy) const;  // -1 outside
  Eigen::Vector2d center(int i) const { return {(i % nx_ + 0.5) * cell_, (i / nx_ + 0.5) * cell_}; }
  // The free cell nearest to `xy` within `max_m` (straight-line), or -1.
  int nearestFree(const Eigen::Vector2d& xy, double max_m) const;
  // Shortest 8-connected path lengths (metres) from `start` to every cell (infinity when
  // unreachable): one Dijkstra answers "which of these is nearest by planned path".
  std::vector<double> distancesFrom(int start) const;
  // A* from cell to cell, shortened by line of sight; the polyline from the first cell's
  // centre to the last's, empty when unreachable.
  std::vector<Eigen::Vector2d> path(int from, int to) const;
  bool lineFree(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const;

 private:
  double cell_;
  int nx_, ny_;
  std::vector<std::uint8_t> free_;
};

inline constexpr double kInfinity = std::numeric_limits<double>::infinity();

// The benchmark's seed mixer (SplitMix64, the same mix the renderer uses: the same on every
// platform): every seed it derives (episodes, start
// cells, frame noise, random poses, teaching views) goes through this one function.
inline std::uint64_t mix(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// One episode: an apartment, the mug, where the robot starts, and what the best could do.
struct Episode {
  int apartment = 0;  // index among the benchmark's apartments
  int index = 0;      // episode index within the apartment
  std::uint64_t apartment_seed = 0, episode_seed = 0;
};

struct World {
  Episode episode;
  synth::MultiRoomApartment apartment;
  synth::TargetMug mug;
  Grid grid;
  Eigen::Vector2d start = Eigen::Vector2d::Zero();
  double start_yaw = 0.0;
  // The nearest pose (by planned path from the start) from which the mug is recognised:
  // the shortest path of SPL and the oracle strategy's goal.
  Eigen::Vector2d best_view = Eigen::Vector2d::Zero();
  double best_view_yaw = 0.0;
  double shortest_path_m = kInfinity;
};

// Builds the episode's world: the apartment of `apartment_seed`, a mug by the prior and a
// start cell in the robot's free space outside the mug's room, all from the seeds. Mug placements
// that no pose can recognise are drawn again (up to 10 times; the episode is then "findable" by
// construction, stated in the report). Throws findmug::Error when none was.
World makeWorld(const Episode& episode, const SimParams& params);

// The camera of a robot standing at xy with heading yaw.
synth::CameraPose cameraAt(const SimParams& params, const Eigen::Vector2d& xy, double yaw);

// The oracle recogniser: the mug is seen from a view when the camera is within
// recognise_range_m of the mug's centre and at least recognise_min_pixels of the frame
// show it (the renderer's per-pixel object index).
int mugPixels(const World& world, const synth::RenderedFrame& frame);
bool mugInRange(const World& world, const SimParams& params, const Eigen::Vector2d& xy);
// Whether the oracle recogniser sees the mug from a pose: a cheap range and bearing test,
// then the mug's pixel count of the frame from there (synth::countObjectPixels, without
// rendering the frame).
bool mugRecognisable(const World& world, const SimParams& params, const Eigen::Vector2d& xy,
                     double yaw);

// What perception said after one frame: whether the robot now believes it found the mug,
// and where perception put it (the matcher's answer; the oracle's are the mug's own).
struct Sighting {
  bool claimed = false;
  Eigen::Vector3d reported = Eigen::Vector3d::Zero();
  // Lines for the trace (with SimParams::trace): what the frame changed in the daemon's map.
  std::vector<std::string> notes;
};

// The ground-truth check of a claimed find: true when the reported position is within
// `tolerance_m` of the mug's centre on the floor plane (x, y; the object map reports the
// candidate's centroid, whose height differs from the mug's base by design).
bool claimIsCorrect(const World& world, const Eigen::Vector3d& reported, double tolerance_m);

// What the robot's frames have shown of the floor plan: the cells within
// look_coverage_range_m inside a frame's horizontal field of view, in line of sight on the
// grid (obstacles taller than the camera less 0.2 m block the view; lower furniture, such
// as tables, is looked over). The robot knows its map and its past poses, so it can tell
// which headings of a look-around would show something new.
class ViewCoverage {
 public:
  ViewCoverage() = default;
  ViewCoverage(const World& world, const SimParams& params);
  // Marks what a frame from this pose shows.
  void markFrame(const Eigen::Vector2d& xy, double yaw);
  // The floor (m^2) a frame from this pose would show that no marked frame showed.
  double unseenM2(const Eigen::Vector2d& xy, double yaw) const;
  // The cells within `range_m` that a full turn at this spot would show (every heading, in
  // line of sight): the most a look-around there can show from that near.
  std::vector<int> cellsInViewAround(const Eigen::Vector2d& xy, double range_m) const;
  bool covered(int cell) const { return seen_[cell] != 0; }
  bool blocksView(int cell) const { return blocks_[cell] != 0; }

 private:
  // Calls visit(cell) once per cell a frame from this pose shows within `range_m`; a wider
  // half angle than the camera's (pi: all around) for what several frames from the spot show.
  template <typename Visit>
  void castFrame(const Eigen::Vector2d& xy, double yaw, double range_m, double half_angle,
                 Visit&& visit) const;
  static constexpr double kCameraHalfFov = 0.547;  // atan(320 / 525), horizontal
  const Grid* grid_ = nullptr;
  double range_m_ = 0.0;
  std::vector<std::uint8_t> seen_, blocks_;
  mutable std::vector<std::uint32_t> stamp_;  // per-cell mark of the last cast (once per cell)
  mutable std::uint32_t casts_ = 0;
};

// Everything a strategy spent, and whether it found the mug.
struct RunStats {
  bool found = false;        // a correct find (the episode's success)
  bool false_found = false;  // perception said "seen" with the mug elsewhere: the search ended
  double time_s = 0.0, path_m = 0.0, drive_s = 0.0, turn_s = 0.0, process_s = 0.0;
  int views = 0;             // stop views (each costs view_processing_s)
  int drive_frames = 0;      // frames taken while the base moved (cost no time)
  int recogniser_calls = 0;  // frames the recogniser judged (oracle tests or find requests)
  int look_around_views_skipped = 0;  // headings of look-arounds that showed too little new
  double found_time_s = kInfinity;  // when the search ended with a claim (true or false)
};

// The robot: pose, clock and perception. Every action checks the time budget; once it is
// spent (or the search has ended with a claim) actions do nothing and return false.
class Robot {
 public:
  // `on_frame`, when set, gets every frame (stop views and driving frames; noisy, 640x480)
  // with the base pose and the simulated time (findmug's perception listens here) and says
  // what the matcher concluded. With Recognition::Oracle its answer is ignored and the mug
  // counts as seen by the oracle test; with Recognition::Matcher its answer is the robot's
  // belief, checked against the ground truth (claimIsCorrect).
  enum class Recognition { Oracle, Matcher };
  using FrameHook = std::function<Sighting(const synth::RenderedFrame&, const Eigen::Vector2d& xy,
                                           double yaw, double time_s)>;
  Robot(const World& world, const SimParams& params, FrameHook on_frame = {},
        Recognition recognition = Recognition::Oracle);

  bool active() const {
    return !stats_.found && !stats_.false_found && stats_.time_s < params_.time_budget_s;
  }
  // Plans and drives to `goal` (the nearest free cell to it), turning on the way.
  // False when unreachable or inactive. `stop_when`, when set, is asked after every frame
  // taken on the way (after perception has seen it): true stops the robot there
  // (interrupted() then says so), as a robot re-plans when its map shows something new.
  bool driveTo(const Eigen::Vector2d& goal, const std::function<bool()>& stop_when = {});
  bool interrupted() const { return interrupted_; }
  // The caller took the last stop as arriving (its goal was reached on the way).
  void clearInterrupted() { interrupted_ = false; }
  void turnTo(double yaw);
  // Turns by `delta` rad (signed, not wrapped: a look-around's turns keep their direction).
  void turnBy(double delta);
  // One view at the current pose (processing time counted); true when the search ended
  // with it (the mug seen, or believed seen).
  bool look();
  // Views at look_around_views even yaw steps from the current heading. With `only_unseen`
  // (and not SimParams::full_look_arounds) only the headings whose view would show at least
  // look_unseen_min_m2 of floor plan no frame has shown yet, the turn through them the
  // shortest way (one way, or one way and back); a heading that the frames while turning
  // covered by the time it is reached gets no stop view. True when the search ended.
  bool lookAround(bool only_unseen = true);
  const ViewCoverage& viewCoverage() const { return coverage_; }

  const Eigen::Vector2d& xy() const { return xy_; }
  double yaw() const { return yaw_; }
  // The grid cell the robot plans from: its own, or, when the grid marks that one blocked,
  // the nearest free cell. A stop on a string-pulled leg (a driving frame's find, or a drive
  // stopped to re-plan) can fall in a cell the robot's radius marks blocked, at a corner the
  // leg cuts; planning from there found no path at all, and the search ended early.
  int cell() const;
  const RunStats& stats() const { return stats_; }
  // Every pose a stop view was taken from (coverage bookkeeping).
  const std::vector<std::pair<Eigen::Vector2d, double>>& viewPoses() const { return views_; }
  // With SimParams::trace: a line "time x y yaw: what" for the episode's trace (strategies
  // say why they go where they go); nothing otherwise.
  void note(const std::string& what);
  const std::vector<std::string>& trace() const { return trace_; }

 private:
  void spend(double seconds);
  // The motion from the current pose: `seconds` long, ending at `xy`, `yaw`, moving at a
  // constant rate; takes the driving frames that fall in it. Returns false when one of
  // them ended the search (the robot then stands at that frame's pose).
  bool move(double seconds, const Eigen::Vector2d& xy, double yaw, bool turning);
  // One frame at the current pose and time through perception; true when it ended the
  // search.
  bool perceive(bool stop_view);
  const World& world_;
  const SimParams& params_;
  FrameHook on_frame_;
  Recognition recognition_;
  Eigen::Vector2d xy_;
  double yaw_;
  double motion_s_ = 0.0;  // seconds of motion so far (driving frames fall on its multiples)
  int frames_ = 0;         // frames rendered (the noise seed of each)
  RunStats stats_;
  ViewCoverage coverage_;
  std::vector<std::pair<Eigen::Vector2d, double>> views_;
  std::vector<std::string> trace_;
  const std::function<bool()>* stop_when_ = nullptr;  // during driveTo
  bool interrupted_ = false;                           // the last driveTo stopped early
};

}  // namespace findmug::search
