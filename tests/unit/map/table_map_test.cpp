// Tests of the persistent table map (table_map.hpp): pose algebra, polygon
// helpers, association / confirmation / forgetting, and a rendered synthetic
// drive through an apartment.
#include "findmug/map/table_map.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/common/error.hpp"
#include "findmug/ground/ground.hpp"
#include "findmug/map/depth_view.hpp"
#include "findmug/map/semantic_map.hpp"
#include "findmug/synth/synth.hpp"
#include "table_scenes.hpp"

namespace findmug {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::vector<Eigen::Vector2f> rectangle(const Eigen::Vector2f& center, float yaw, float length,
                                       float width) {
  const Eigen::Vector2f ax(std::cos(yaw), std::sin(yaw)), ay(-std::sin(yaw), std::cos(yaw));
  const float a = 0.5f * length, b = 0.5f * width;
  return {center - a * ax - b * ay, center + a * ax - b * ay, center + a * ax + b * ay,
          center - a * ax + b * ay};
}

// A table as findTables would report it (base frame), from its outline in
// the map and the robot pose: what a perfect detector sees.
TableCluster observe(const std::vector<Eigen::Vector2f>& outline_map, float height,
                     const Pose2D& base_in_map, bool reachable = true) {
  const Pose2D map_to_base = inversePose(base_in_map);
  TableCluster t;
  for (const auto& p : outline_map) t.hull.push_back(transformPoint(map_to_base, p));
  t.hull = convexHull2d(t.hull);
  const Eigen::Vector2f a = t.hull[1] - t.hull[0], b = t.hull[2] - t.hull[1];
  const bool a_long = a.norm() >= b.norm();
  t.major_axis = (a_long ? a : b).normalized();
  if (t.major_axis.x() < 0) t.major_axis = -t.major_axis;
  t.minor_axis = Eigen::Vector2f(-t.major_axis.y(), t.major_axis.x());
  t.extents =
      Eigen::Vector2f(0.5f * std::max(a.norm(), b.norm()), 0.5f * std::min(a.norm(), b.norm()));
  Eigen::Vector2f c = Eigen::Vector2f::Zero();
  for (const auto& p : t.hull) c += p;
  t.center = c / static_cast<float>(t.hull.size());
  t.centroid = Eigen::Vector3f(t.center.x(), t.center.y(), height);
  t.top_height = height;
  t.point_count = 5000;
  t.mean_confidence = 0.9f;
  TableConfig config;
  t.search_positions = computeSearchPositions(t, config);
  for (auto& p : t.search_positions) {
    p.reachable = reachable;
    if (!reachable) p.reason = "obstacle within robot radius (9 points)";
  }
  return t;
}

// A pose at `distance` from `target` looking at it from direction `angle`.
Pose2D lookingAt(const Eigen::Vector2f& target, double angle, double distance) {
  Pose2D p;
  p.x = target.x() - distance * std::cos(angle);
  p.y = target.y() - distance * std::sin(angle);
  p.yaw = angle;
  return p;
}

// ------------------------------------------------------------------ algebra

TEST(Pose2D, InverseComposeAndWrap) {
  const Pose2D a{1.5, -2.0, 2.9};
  const Pose2D id = composePoses(a, inversePose(a));
  EXPECT_NEAR(id.x, 0.0, 1e-12);
  EXPECT_NEAR(id.y, 0.0, 1e-12);
  EXPECT_NEAR(id.yaw, 0.0, 1e-12);
  const Eigen::Vector2f p(0.3f, 0.7f);
  const Eigen::Vector2f q = transformPoint(a, p);
  EXPECT_LT((transformPoint(inversePose(a), q) - p).norm(), 1e-5f);
  // 90° turn then 1 m forward.
  const Eigen::Vector2f r = transformPoint({0, 0, kPi / 2}, {1, 0});
  EXPECT_LT((r - Eigen::Vector2f(0, 1)).norm(), 1e-6f);
  // The double-precision transform (map-frame messages) agrees with the float one.
  const Eigen::Vector2d q_double = transformPointD(a, p.cast<double>());
  EXPECT_LT((q_double.cast<float>() - q).norm(), 1e-5f);
  EXPECT_LT((transformPointD({0, 0, kPi / 2}, {1, 0}) - Eigen::Vector2d(0, 1)).norm(), 1e-12);
  EXPECT_NEAR(wrapAngle(3 * kPi), kPi, 1e-12);
  EXPECT_NEAR(wrapAngle(-kPi), kPi, 1e-12);
  EXPECT_NEAR(wrapAngle(-0.5), -0.5, 1e-12);
  EXPECT_NEAR(composePoses(a, {0, 0, 1.0}).yaw, wrapAngle(3.9), 1e-12);
}

TEST(TransformTable, MovesAllGeometryAndRoundTrips) {
  const Pose2D base_in_map{4.0, 1.0, 0.8};
  const TableCluster t = observe(rectangle({6.0f, 3.0f}, 0.3f, 1.2f, 0.7f), 0.74f, base_in_map);
  const TableCluster m = transformTable(t, base_in_map);
  // In the map the table is where we put it.
  EXPECT_LT((m.center - Eigen::Vector2f(6.0f, 3.0f)).norm(), 1e-4f);
  EXPECT_NEAR(std::abs(m.major_axis.dot(Eigen::Vector2f(std::cos(0.3f), std::sin(0.3f)))), 1.0f,
              1e-5f);
  EXPECT_EQ(m.top_height, t.top_height);
  EXPECT_EQ(m.extents, t.extents);
  ASSERT_EQ(m.search_positions.size(), t.search_positions.size());
  for (const auto& p : m.search_positions) {
    // Still facing the table centre, now in map coordinates.
    const Eigen::Vector2f to_table = (m.center - p.xy).normalized();
    EXPECT_GT(to_table.dot(Eigen::Vector2f(std::cos(p.yaw), std::sin(p.yaw))), 0.9999f);
  }
  const TableCluster back = transformTable(m, inversePose(base_in_map));
  EXPECT_LT((back.center - t.center).norm(), 1e-4f);
  for (std::size_t i = 0; i < t.hull.size(); ++i)
    EXPECT_LT((back.hull[i] - t.hull[i]).norm(), 1e-4f);
}

TEST(Polygons, AreaIntersectionAndGap) {
  const auto a = rectangle({0, 0}, 0.0f, 2.0f, 2.0f);
  const auto b = rectangle({1, 1}, 0.0f, 2.0f, 2.0f);
  EXPECT_NEAR(polygonArea(a), 4.0f, 1e-5f);
  EXPECT_NEAR(polygonArea(intersectConvex(a, b)), 1.0f, 1e-5f);
  EXPECT_EQ(convexGap(a, b), 0.0f);
  const auto c = rectangle({3.5f, 0}, 0.0f, 1.0f, 1.0f);  // 2 m to the right of a's edge
  EXPECT_TRUE(intersectConvex(a, c).empty());
  EXPECT_NEAR(convexGap(a, c), 2.0f, 1e-5f);
  const auto inner = rectangle({0, 0}, 0.4f, 0.5f, 0.5f);  // fully inside
  EXPECT_EQ(convexGap(a, inner), 0.0f);
  EXPECT_NEAR(polygonArea(intersectConvex(a, inner)), 0.25f, 1e-4f);
}

// ---------------------------------------------------------------------- map

TEST(TableMap, ConfirmsAfterSightingsWithOneStableId) {
  TableMap map;
  const auto outline = rectangle({5.0f, 2.0f}, 0.2f, 1.4f, 0.8f);
  int id = -1;
  for (int frame = 0; frame < 5; ++frame) {
    // The robot drives around: different poses, same table.
    const Pose2D pose = lookingAt({5.0f, 2.0f}, -1.2 + 0.3 * frame, 2.0 + 0.1 * frame);
    const auto update =
        map.update({observe(outline, 0.75f, pose)}, pose, 1000000u + 100000u * frame);
    ASSERT_EQ(update.assigned_ids.size(), 1u);
    if (frame == 0) {
      id = update.assigned_ids[0];
      EXPECT_EQ(update.created, std::vector<int>{id});
    }
    EXPECT_EQ(update.assigned_ids[0], id);
    EXPECT_EQ(map.tables().size(), 1u);
    const MappedTable& t = map.tables()[0];
    EXPECT_EQ(t.table.id, id);
    EXPECT_EQ(t.sightings, frame + 1);
    EXPECT_EQ(t.confirmed, frame + 1 >= map.config().confirm_sightings);
    if (frame + 1 == map.config().confirm_sightings) {
      EXPECT_EQ(update.confirmed, std::vector<int>{id});
    }
    EXPECT_EQ(map.confirmedTables().size(), t.confirmed ? 1u : 0u);
  }
  const TableCluster& t = map.tables()[0].table;
  EXPECT_LT((t.center - Eigen::Vector2f(5.0f, 2.0f)).norm(), 1e-3f);
  EXPECT_NEAR(t.extents.x(), 0.7f, 1e-3f);
  EXPECT_NEAR(t.extents.y(), 0.4f, 1e-3f);
  EXPECT_LT(
      std::abs(std::abs(t.major_axis.dot(Eigen::Vector2f(std::cos(0.2f), std::sin(0.2f)))) - 1),
      1e-4f);
  // Positions recomputed in the map: at d from the edge, reachable (observed so).
  ASSERT_EQ(t.search_positions.size(), 4u);
  for (const auto& p : t.search_positions) {
    EXPECT_TRUE(p.reachable) << p.reason;
    EXPECT_NEAR(std::abs((p.xy - t.center).dot(t.minor_axis)), 0.4f + 0.5f, 1e-3f);
  }
}

TEST(TableMap, DistinctTablesKeepTheirIdsAndIdsAreNeverReused) {
  TableMapConfig config;
  config.forget_misses = 1;
  TableMap map(config);
  const auto left = rectangle({3.0f, 3.0f}, 0.0f, 1.2f, 0.8f);
  const auto right = rectangle({3.0f, 1.0f}, 0.0f, 1.2f, 0.8f);  // 1.2 m apart
  const Pose2D pose = lookingAt({3.0f, 2.0f}, 0.0, 2.5);
  auto u = map.update({observe(left, 0.75f, pose), observe(right, 0.72f, pose)}, pose, 1);
  ASSERT_EQ(u.assigned_ids.size(), 2u);
  EXPECT_NE(u.assigned_ids[0], u.assigned_ids[1]);
  const int left_id = u.assigned_ids[0], right_id = u.assigned_ids[1];
  // Input order does not matter: association is geometric.
  u = map.update({observe(right, 0.72f, pose), observe(left, 0.75f, pose)}, pose, 2);
  EXPECT_EQ(u.assigned_ids, (std::vector<int>{right_id, left_id}));
  // A table of a different height at the same place is a different table.
  u = map.update({observe(left, 0.45f, pose), observe(right, 0.72f, pose)}, pose, 3);
  EXPECT_NE(u.assigned_ids[0], left_id);
  // The left table is in view but was not seen: forgotten (forget_misses = 1).
  EXPECT_EQ(u.forgotten, std::vector<int>{left_id});
  const int low_id = u.assigned_ids[0];
  EXPECT_GT(low_id, right_id);
  u = map.update({observe(left, 0.75f, pose)}, pose, 4);
  EXPECT_GT(u.assigned_ids[0], low_id) << "an id was reused";
}

TEST(TableMap, PartialViewsAddUpToTheWholeTop) {
  TableMap map;
  // A 2.4 m table seen one half at a time (as when its ends are out of view).
  const auto left_half = rectangle({2.4f, 1.0f}, 0.0f, 1.2f, 0.8f);
  const auto right_half = rectangle({3.6f, 1.0f}, 0.0f, 1.2f, 0.8f);
  const Pose2D pose_left = lookingAt({2.4f, 1.0f}, kPi / 2, 2.0);
  const Pose2D pose_right = lookingAt({3.6f, 1.0f}, kPi / 2, 2.0);
  auto u1 = map.update({observe(left_half, 0.75f, pose_left)}, pose_left, 1);
  auto u2 = map.update({observe(right_half, 0.75f, pose_right)}, pose_right, 2);
  ASSERT_EQ(map.tables().size(), 1u);
  EXPECT_EQ(u1.assigned_ids, u2.assigned_ids);  // touching footprints: the same table
  const TableCluster& t = map.tables()[0].table;
  EXPECT_NEAR(t.extents.x(), 1.2f, 1e-3f);
  EXPECT_NEAR(t.extents.y(), 0.4f, 1e-3f);
  EXPECT_LT((t.center - Eigen::Vector2f(3.0f, 1.0f)).norm(), 1e-3f);
  EXPECT_LT(std::abs(t.major_axis.y()), 1e-4f);
  // 2.4 m long, 0.8 m deep: from 0.5 m an arm of 0.8 m covers ±0.62 m of
  // edge, so two positions per side (the paper's one would leave the ends out).
  EXPECT_EQ(t.search_positions.size(), 4u);
}

// A map (forgetting after 3 misses) with one confirmed 1.2 x 0.8 m table centred at (5, 0),
// seen three times from `facing`, 2 m west of it; `t` is the next update's time.
class TableMapWithOneTable : public ::testing::Test {
 protected:
  TableMapWithOneTable() {
    const auto outline = rectangle({5.0f, 0.0f}, 0.0f, 1.2f, 0.8f);
    for (int i = 0; i < 3; ++i) map.update({observe(outline, 0.75f, facing)}, facing, t++);
  }
  TableMap map;
  const Pose2D facing = lookingAt({5.0f, 0.0f}, 0.0, 2.0);
  std::uint64_t t = 1;
};

TEST_F(TableMapWithOneTable, ForgetsOnlyWhenNotSeenWhereExpected) {
  ASSERT_EQ(map.confirmedTables().size(), 1u);
  // Looking the other way (the table is behind the robot): no evidence.
  const Pose2D away{3.0, 0.0, kPi};
  for (int i = 0; i < 10; ++i) {
    const auto u = map.update({}, away, t++);
    EXPECT_TRUE(u.forgotten.empty());
  }
  EXPECT_EQ(map.tables()[0].misses, 0);
  // Too far away to be expected either.
  const Pose2D far = lookingAt({5.0f, 0.0f}, 0.0, 8.0);
  map.update({}, far, t++);
  EXPECT_EQ(map.tables()[0].misses, 0);
  // In view and range, not seen: three misses and it is gone.
  for (int i = 1; i <= 3; ++i) {
    const auto u = map.update({}, facing, t++);
    if (i < 3) {
      EXPECT_TRUE(u.forgotten.empty());
      EXPECT_EQ(map.tables()[0].misses, i);
    } else {
      ASSERT_EQ(u.forgotten.size(), 1u);
      ASSERT_EQ(u.diagnostics.size(), 1u);
      EXPECT_NE(u.diagnostics[0].find("not seen where expected"), std::string::npos);
    }
  }
  EXPECT_TRUE(map.tables().empty());
}

// A table not detected in a frame is missed only when the frame's depth shows its top or
// the floor where it stood: behind a wall, or where the sensor measured nothing, it is out
// of sight, and the map keeps it however long the robot looks that way.
TEST_F(TableMapWithOneTable, ATableHiddenFromViewIsNotMissedAndOneGoneIs) {
  ASSERT_EQ(map.confirmedTables().size(), 1u);
  const TableCluster table = map.confirmedTables()[0];

  const Eigen::Isometry3d camera = test::headCamera(facing);
  RgbdFrame wall = test::depthOfTops({}, camera);
  std::fill(wall.depth_mm.begin(), wall.depth_mm.end(), std::uint16_t{1000});  // 1 m away
  RgbdFrame no_depth = wall;
  std::fill(no_depth.depth_mm.begin(), no_depth.depth_mm.end(), std::uint16_t{0});
  for (const RgbdFrame* frame : {&wall, &no_depth}) {
    const DepthView view(*frame, camera);
    for (int i = 0; i < 6; ++i) {
      const auto u = map.update({}, facing, t++, &view);
      EXPECT_TRUE(u.forgotten.empty());
    }
    ASSERT_EQ(map.tables().size(), 1u);
    EXPECT_EQ(map.tables()[0].misses, 0);
  }

  // The top in plain view but not detected (a frame the segmenter got wrong) is a miss,
  // and so is the floor where the table stood.
  const RgbdFrame top = test::depthOfTops({table}, camera, 0.75);
  const DepthView top_view(top, camera);
  map.update({}, facing, t++, &top_view);
  EXPECT_EQ(map.tables()[0].misses, 1);
  const RgbdFrame floor = test::depthOfTops({}, camera);
  const DepthView floor_view(floor, camera);
  map.update({}, facing, t++, &floor_view);
  const auto u = map.update({}, facing, t++, &floor_view);
  ASSERT_EQ(u.forgotten.size(), 1u);
  EXPECT_TRUE(map.tables().empty());
}

TEST(TableMap, HiddenMarginIsASetting) {
  TableMapConfig c;
  tableMapSettings().set(c, "table_map.hidden_margin_m", "0.5");
  EXPECT_FLOAT_EQ(c.hidden_margin_m, 0.5f);
  c.hidden_margin_m = -0.1f;
  EXPECT_THROW(validateTableMapConfig(c), Error);
}

TEST(TableMap, SeeingItAgainResetsMisses) {
  TableMap map;
  const auto outline = rectangle({5.0f, 0.0f}, 0.0f, 1.2f, 0.8f);
  const Pose2D facing = lookingAt({5.0f, 0.0f}, 0.0, 2.0);
  std::uint64_t t = 1;
  map.update({observe(outline, 0.75f, facing)}, facing, t++);
  for (int round = 0; round < 4; ++round) {
    map.update({}, facing, t++);
    map.update({}, facing, t++);  // two misses (a person walking past)
    map.update({observe(outline, 0.75f, facing)}, facing, t++);
    ASSERT_EQ(map.tables().size(), 1u);
    EXPECT_EQ(map.tables()[0].misses, 0);
  }
}

TEST(TableMap, TentativeTablesTimeOut) {
  TableMapConfig config;
  config.tentative_timeout_s = 2.0;
  TableMap map(config);
  const auto outline = rectangle({5.0f, 0.0f}, 0.0f, 1.2f, 0.8f);
  const Pose2D facing = lookingAt({5.0f, 0.0f}, 0.0, 2.0);
  const Pose2D away{3.0, 0.0, kPi};
  map.update({observe(outline, 0.75f, facing)}, facing, 1000000);  // one sighting: tentative
  auto u = map.update({}, away, 2500000);
  EXPECT_TRUE(u.forgotten.empty());
  u = map.update({}, away, 3100000);  // 2.1 s later, still unconfirmed
  ASSERT_EQ(u.forgotten.size(), 1u);
  EXPECT_NE(u.diagnostics[0].find("not confirmed"), std::string::npos);
}

TEST(TableMap, ReachabilityComesFromTheNewestObservationOfThatSpot) {
  TableMap map;
  const Eigen::Vector2f centre(4.0f, 0.0f);
  const auto outline = rectangle(centre, kPi / 2, 1.2f, 0.8f);  // long along y
  const Pose2D west = lookingAt(centre, 0.0, 2.0);
  map.update({observe(outline, 0.75f, west, true)}, west, 1);
  for (const auto& p : map.tables()[0].table.search_positions) EXPECT_TRUE(p.reachable);
  map.update({observe(outline, 0.75f, west, false)}, west, 2);  // now a chair stands there
  for (const auto& p : map.tables()[0].table.search_positions) {
    EXPECT_FALSE(p.reachable);
    EXPECT_NE(p.reason.find("obstacle"), std::string::npos) << p.reason;
  }
  // A longer observation (the table really is 2.4 m) adds positions nobody
  // has evaluated: they are not claimed reachable.
  const auto longer = rectangle({4.0f, 0.6f}, kPi / 2, 2.4f, 0.8f);
  TableCluster seen = observe(longer, 0.75f, west, true);
  seen.search_positions.clear();  // as if every position had been out of view
  map.update({seen}, west, 3);
  int not_observed = 0;
  for (const auto& p : map.tables()[0].table.search_positions) {
    if (p.reason == "not observed yet") {
      EXPECT_FALSE(p.reachable);
      ++not_observed;
    }
  }
  EXPECT_GT(not_observed, 0);
}

TEST(TableMap, OverlappingTablesAreMerged) {
  TableMapConfig config;
  config.match_gap_m = 0.0f;  // only overlapping footprints associate
  TableMap map(config);
  const Pose2D pose = lookingAt({3.0f, 0.0f}, 0.0, 2.5);
  // Two separate partial views of one table (0.3 m apart)...
  auto u = map.update({observe(rectangle({3.0f, -0.55f}, 0.0f, 1.0f, 0.5f), 0.75f, pose),
                       observe(rectangle({3.0f, 0.55f}, 0.0f, 1.0f, 0.5f), 0.75f, pose)},
                      pose, 1);
  ASSERT_EQ(map.tables().size(), 2u);
  const int first = u.assigned_ids[0];
  // ...then a view of the whole table overlaps both: they become one.
  u = map.update({observe(rectangle({3.0f, 0.0f}, 0.0f, 1.0f, 1.6f), 0.75f, pose)}, pose, 2);
  ASSERT_EQ(map.tables().size(), 1u);
  EXPECT_EQ(map.tables()[0].table.id, first);
  EXPECT_EQ(u.assigned_ids, std::vector<int>{first});
  EXPECT_EQ(u.forgotten.size(), 1u);
}

TEST(TableMap, BadInputThrows) {
  TableMap map;
  EXPECT_THROW(map.update({}, {std::nan(""), 0, 0}, 1), Error);
  EXPECT_THROW(map.update({}, {0, 0, std::numeric_limits<double>::infinity()}, 1), Error);
  map.update({}, {0, 0, 0}, 100);
  EXPECT_THROW(map.update({}, {0, 0, 0}, 99), Error);  // time going backwards
  TableMapConfig bad;
  bad.view_max_range_m = 0.5f;  // below view_min_range_m
  try {
    TableMap m(bad);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("table_map.view_max_range_m"), std::string::npos);
  }
  bad = TableMapConfig{};
  bad.confirm_sightings = 0;
  EXPECT_THROW(TableMap{bad}, Error);
  TableConfig bad_tables;
  bad_tables.arm_reach_m = -1.0f;
  EXPECT_THROW((TableMap{TableMapConfig{}, bad_tables}), Error);
}

// ------------------------------------------------ rendered synthetic drive

TEST(TableMapSynth, DriveThroughApartmentsMapsEachTableOnce) {
  int confirmed_total = 0;
  for (std::uint64_t seed : {2u, 5u}) {
    const synth::SynthScene scene = synth::makeApartment(seed);
    const auto path = synth::cameraPath(scene, 360, 10.0);
    TableMap map;
    synth::RenderOptions options;
    for (std::size_t f = 0; f < path.size(); f += 12) {
      const synth::CameraPose& pose = path[f];
      const auto rendered = synth::render(scene, pose, options, seed * 7919 + f);
      const RgbdFrame& frame = rendered.labeled.frame;
      const GroundPlane ground = groundFromExtrinsics(frame.extrinsics.value());
      LabelImage labels;
      labels.width = frame.width;
      labels.height = frame.height;
      labels.labels = rendered.labeled.labels;
      const auto tables =
          findTables(transformCloud(frameToCloud(frame), ground.camera_to_ground), labels, {});
      map.update(tables, Pose2D{pose.xy.x(), pose.xy.y(), pose.yaw},
                 static_cast<std::uint64_t>(pose.time_s * 1e6));
    }
    // Every confirmed table is a real table (world frame = map frame here),
    // and no real table has two confirmed entries.
    std::map<int, int> entries_per_truth;
    for (const TableCluster& t : map.confirmedTables()) {
      int match = -1;
      for (const auto& truth : scene.tables) {
        bool inside = true;
        const auto& poly = truth.top_polygon;
        for (std::size_t i = 0; i < poly.size(); ++i) {
          const Eigen::Vector2d e = poly[(i + 1) % poly.size()] - poly[i];
          const Eigen::Vector2d q = t.center.cast<double>() - poly[i];
          inside &= e.x() * q.y() - e.y() * q.x() >= -0.1 * e.norm();
        }
        if (inside && std::abs(t.top_height - truth.height) < 0.05) match = truth.id;
      }
      EXPECT_GE(match, 0) << "seed " << seed << ": confirmed table " << t.id << " at "
                          << t.center.transpose() << " is not a real table";
      if (match >= 0) ++entries_per_truth[match];
      // Map-frame search positions face the table across its long side.
      for (const auto& p : t.search_positions) {
        const Eigen::Vector2f heading(std::cos(p.yaw), std::sin(p.yaw));
        EXPECT_GT(heading.dot(t.center - p.xy), 0.0f);
        EXPECT_GT(std::abs(heading.dot(t.minor_axis)), 0.999f);
      }
    }
    for (const auto& [truth, entries] : entries_per_truth) {
      EXPECT_EQ(entries, 1) << "seed " << seed << ": table " << truth << " mapped " << entries
                            << " times";
    }
    confirmed_total += static_cast<int>(map.confirmedTables().size());
  }
  EXPECT_GE(confirmed_total, 2);
}

}  // namespace
}  // namespace findmug
