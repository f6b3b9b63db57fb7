// findmug-search-bench (tools/search_bench, issue 51): the simulated robot's motion model
// and time accounting, the oracle's shortest path, findmug's table map driving the search
// to the mug on a table, and the program's output not depending on its worker count.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "findmug/common/error.hpp"
#include "report.hpp"
#include "search_sim.hpp"
#include "strategies.hpp"
#include "test_data.hpp"

namespace findmug::search {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A world in an empty 6 x 4 m room with the mug on the floor at (5, 2).
World emptyRoomWorld(const SimParams& params) {
  World w;
  w.apartment.scene = synth::makeEmptyRoom({6.0, 4.0, 2.6});
  w.apartment.rooms.push_back({synth::RoomKind::Living, {0, 0}, {6, 4}});
  w.mug.object = synth::addObject(w.apartment.scene, "target_mug", Label::Object, {});
  w.mug.position = {5.0, 2.0, 0.0};
  w.grid = Grid(w.apartment.scene, params.robot_radius_m, params.cell_m);
  w.start = w.grid.center(w.grid.cellAt({1.0, 2.0}));
  w.start_yaw = 0.0;
  return w;
}

TEST(SearchSim, DrivingAndTurningTimeFollowTheBaseModel) {
  const SimParams params;
  const World w = emptyRoomWorld(params);
  Robot robot(w, params);
  const Eigen::Vector2d goal = w.grid.center(w.grid.cellAt({4.0, 2.0}));
  ASSERT_TRUE(robot.driveTo(goal));
  // Straight ahead in free space: no turn, distance / 0.3 m/s.
  const double d = (goal - w.start).norm();
  EXPECT_NEAR(robot.stats().path_m, d, 1e-9);
  EXPECT_NEAR(robot.stats().drive_s, d / 0.3, 1e-9);
  EXPECT_NEAR(robot.stats().turn_s, 0.0, 1e-9);
  robot.turnTo(M_PI / 2);  // 90 deg at 45 deg/s
  EXPECT_NEAR(robot.stats().turn_s, 2.0, 1e-9);
  robot.lookAround();  // 12 views, 11 turns of 30 deg, 0.1 s each view
  EXPECT_EQ(robot.stats().views, 12);
  EXPECT_NEAR(robot.stats().turn_s, 2.0 + 11 * (M_PI / 6) / (M_PI / 4), 1e-9);
  EXPECT_NEAR(robot.stats().process_s, 1.2, 1e-9);
  EXPECT_NEAR(robot.stats().time_s,
              robot.stats().drive_s + robot.stats().turn_s + robot.stats().process_s, 1e-9);
  EXPECT_FALSE(robot.stats().found);  // the mug has no primitive: nothing to see
}

TEST(SearchSim, PlannerGoesAroundObstaclesAndTheBudgetStopsTheRobot) {
  SimParams params;
  World w = emptyRoomWorld(params);
  // A wall across the room with a gap at the top: the path must bend through it.
  w.apartment.scene.obstacles.push_back({{{2.9, 0.0}, {3.1, 0.0}, {3.1, 2.8}, {2.9, 2.8}}, 2.6, 6});
  w.grid = Grid(w.apartment.scene, params.robot_radius_m, params.cell_m);
  const int from = w.grid.cellAt({1.0, 1.0}), to = w.grid.cellAt({5.0, 1.0});
  const std::vector<double> dist = w.grid.distancesFrom(from);
  ASSERT_TRUE(std::isfinite(dist[to]));
  // At least via the gap's lower corner (3, 3.1), where the inflated wall ends: 2 x 2.9 m.
  EXPECT_GT(dist[to], 2 * std::hypot(2.0, 2.1) - 0.05);
  const std::vector<Eigen::Vector2d> path = w.grid.path(from, to);
  ASSERT_GE(path.size(), 3u);
  for (std::size_t i = 1; i < path.size(); ++i) EXPECT_TRUE(w.grid.lineFree(path[i - 1], path[i]));
  params.time_budget_s = 5.0;
  w.start = w.grid.center(from);
  Robot robot(w, params);
  robot.driveTo(w.grid.center(to));
  EXPECT_FALSE(robot.active());
  EXPECT_GE(robot.stats().time_s, 5.0);
  EXPECT_LT(robot.stats().path_m, dist[to]);  // stopped on the way, after the leg it was on
  EXPECT_FALSE(robot.look());                 // and does nothing more
  EXPECT_EQ(robot.stats().views, 0);
}

TEST(SearchBench, OracleDrivesTheShortestPathAndSeesTheMug) {
  const SimParams params;
  for (int e = 0; e < 2; ++e) {
    const World w = makeWorld({0, e, 11, 1100 + static_cast<std::uint64_t>(e)}, params);
    ASSERT_TRUE(std::isfinite(w.shortest_path_m));
    EXPECT_TRUE(mugRecognisable(w, params, w.best_view, w.best_view_yaw));
    const EpisodeResult r = runStrategy("oracle", w, params, nullptr);
    EXPECT_TRUE(r.stats.found);
    EXPECT_NEAR(r.stats.path_m, w.shortest_path_m, 1e-6);
    EXPECT_EQ(r.stats.views, 1);
    // The start is outside the mug's room.
    EXPECT_NE(w.apartment.roomAt(w.start), w.mug.room);
  }
}

TEST(SearchBench, FindmugStrategyFindsTheMugOnTablesFromTheDaemonsTableMap) {
  const std::string root = FINDMUG_SOURCE_DIR;
  const FindmugModel model =
      loadFindmugModel(root + "/daemon/findmugd.yaml", root + "/models/findmug-nyu-synth.fmf",
                       {"learner.classes=labels", "features.objects=false", "mrf.pairwise=potts"});
  SimParams params;
  params.prior = {1.0, 0.0, 0.0};  // table episodes only
  int positions = 0, tables = 0;
  for (int e = 0; e < 2; ++e) {
    const World w = makeWorld({1, e, 21 + static_cast<std::uint64_t>(e), 2100u + e}, params);
    ASSERT_EQ(w.mug.place, synth::MugPlace::Table);
    const EpisodeResult r = runStrategy("findmug", w, params, &model);
    EXPECT_TRUE(r.stats.found) << "episode " << e;
    EXPECT_LE(r.stats.found_time_s, params.time_budget_s);
    EXPECT_EQ(r.frames_processed, r.stats.views);  // every view went through the daemon
    positions += r.positions_visited;
    tables += r.tables_mapped;
  }
  // The table map filled and its search positions were driven to.
  EXPECT_GT(tables, 0);
  EXPECT_GT(positions, 0);
}

TEST(SearchBench, ProgramOutputDoesNotDependOnTheWorkers) {
  const fs::path tmp = fs::temp_directory_path() /
                       ("search_bench_test_" + std::to_string(static_cast<long>(::getpid())));
  fs::remove_all(tmp);
  const std::string root = FINDMUG_SOURCE_DIR;
  auto run = [&](int jobs) {
    const fs::path out = tmp / ("jobs" + std::to_string(jobs));
    const std::string command =
        std::string(FINDMUG_SEARCH_BENCH_EXE) +
        " --apartments 2 --episodes-per-apartment 1 --strategies findmug,coverage,oracle" +
        " --jobs " + std::to_string(jobs) + " --config " + root + "/daemon/findmugd.yaml" +
        " --model " + root + "/models/findmug-nyu-synth.fmf --quiet --out " + out.string() + " > " +
        (tmp / "stdout").string() + " 2>&1";
    EXPECT_EQ(std::system(command.c_str()), 0) << slurp(tmp / "stdout");
    return out;
  };
  fs::create_directories(tmp);
  const fs::path one = run(1), two = run(2);
  const std::string csv = slurp(one / "episodes.csv");
  EXPECT_EQ(csv, slurp(two / "episodes.csv"));
  EXPECT_EQ(slurp(one / "summary.md"), slurp(two / "summary.md"));
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 2 * 3);
  EXPECT_NE(slurp(one / "success_curve.svg").find("<polyline"), std::string::npos);
  fs::remove_all(tmp);
}

TEST(SearchReport, SplAndPairedRatios) {
  std::vector<EpisodeRow> rows;
  for (int e = 0; e < 4; ++e) {
    for (const char* name : {"findmug", "coverage"}) {
      EpisodeRow row;
      row.episode = {0, e, 1, static_cast<std::uint64_t>(e)};
      row.shortest_path_m = 2.0;
      row.result.strategy = name;
      const bool ours = std::string(name) == "findmug";
      row.result.stats.found = ours || e < 2;
      row.result.stats.path_m = ours ? 4.0 : 1.0;
      row.result.stats.found_time_s = row.result.stats.found ? (ours ? 10.0 : 30.0) : kInfinity;
      rows.push_back(row);
    }
  }
  EXPECT_DOUBLE_EQ(rows[0].spl(), 0.5);  // 2 / max(4, 2)
  EXPECT_DOUBLE_EQ(rows[1].spl(), 1.0);  // a path shorter than the shortest counts as it
  const StrategySummary s = summarise("coverage", rows);
  EXPECT_EQ(s.found, 2);
  EXPECT_DOUBLE_EQ(s.success, 0.5);
  EXPECT_DOUBLE_EQ(s.spl, 0.5);
  // Ratios 3, 3, 60, 60 (failures at the 600 s budget): median 31.5.
  const PairedRatio p = pairedTimeRatio("findmug", "coverage", rows, 600.0);
  EXPECT_EQ(p.pairs, 4);
  EXPECT_DOUBLE_EQ(p.median, 31.5);
  EXPECT_LE(p.lo, p.median);
  EXPECT_GE(p.hi, p.median);
}

}  // namespace
}  // namespace findmug::search
