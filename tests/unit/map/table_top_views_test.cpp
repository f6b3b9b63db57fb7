// TableTopViews (findmug/map/table_top_views.hpp): which cells of the mapped table tops a
// view showed from within the recogniser's reach, unhidden; a table's seen share.
#include "findmug/map/table_top_views.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "findmug/common/error.hpp"
#include "findmug/ground/ground.hpp"
#include "findmug/map/semantic_map.hpp"
#include "table_scenes.hpp"

namespace findmug {
namespace {

constexpr float kTop = 0.75f;

// A 0.8 x 0.8 m table top in the map frame, x in [1.0, 1.8], y in [-0.4, 0.4].
TableCluster squareTable(int id) {
  TableCluster t;
  t.id = id;
  t.top_height = kTop;
  t.center = {1.4f, 0.0f};
  t.centroid = {1.4f, 0.0f, kTop};
  t.hull = {{1.0f, -0.4f}, {1.8f, -0.4f}, {1.8f, 0.4f}, {1.0f, 0.4f}};
  return t;
}

TEST(TableTopViews, ATopInFullViewWithinReachIsSeenWhole) {
  const TableCluster table = squareTable(3);
  const Eigen::Isometry3d camera = test::headCamera(Pose2D{0.0, 0.0, 0.0});
  TableTopViews views;
  EXPECT_EQ(views.seenShare(table), 0.0);
  const int added = views.observe({table}, test::depthOfTops({table}, camera), camera);
  EXPECT_EQ(added, 256);  // 16 x 16 cells of 5 cm
  EXPECT_DOUBLE_EQ(views.seenShare(table), 1.0);
  // Seeing it again adds nothing.
  EXPECT_EQ(views.observe({table}, test::depthOfTops({table}, camera), camera), 0);
}

TEST(TableTopViews, ATopBehindTheCameraIsNotSeen) {
  const TableCluster table = squareTable(3);
  const Eigen::Isometry3d away = test::headCamera(Pose2D{0.0, 0.0, M_PI});
  TableTopViews views;
  views.observe({table}, test::depthOfTops({table}, away), away);
  EXPECT_EQ(views.seenShare(table), 0.0);
}

TEST(TableTopViews, OnlyCellsWithinTheRecognisersReachCount) {
  const TableCluster table = squareTable(3);
  const Eigen::Isometry3d camera = test::headCamera(Pose2D{0.0, 0.0, 0.0});
  TableTopViewsConfig near;
  near.range_m = 1.5f;  // the top spans 1.15-1.9 m from the camera
  TableTopViews views(near);
  views.observe({table}, test::depthOfTops({table}, camera), camera);
  const double share = views.seenShare(table);
  EXPECT_GT(share, 0.2);
  EXPECT_LT(share, 0.8);
  // From 4 m back, nothing is within 2 m.
  TableTopViews far_views;
  const Eigen::Isometry3d far_camera = test::headCamera(Pose2D{-2.6, 0.0, 0.0});
  far_views.observe({table}, test::depthOfTops({table}, far_camera), far_camera);
  EXPECT_EQ(far_views.seenShare(table), 0.0);
}

TEST(TableTopViews, SomethingInFrontHidesTheTopAndMissingDepthShowsNothing) {
  const TableCluster table = squareTable(3);
  const Eigen::Isometry3d camera = test::headCamera(Pose2D{0.0, 0.0, 0.0});
  RgbdFrame wall = test::depthOfTops({table}, camera);
  std::fill(wall.depth_mm.begin(), wall.depth_mm.end(), std::uint16_t{500});  // 0.5 m away
  TableTopViews views;
  views.observe({table}, wall, camera);
  EXPECT_EQ(views.seenShare(table), 0.0);
  RgbdFrame holes = test::depthOfTops({table}, camera);
  std::fill(holes.depth_mm.begin(), holes.depth_mm.end(), std::uint16_t{0});
  views.observe({table}, holes, camera);
  EXPECT_EQ(views.seenShare(table), 0.0);
  // An object 10 cm tall on the top is within the occlusion margin: the top counts.
  RgbdFrame object = test::depthOfTops({table}, camera);
  for (auto& d : object.depth_mm)
    if (d > 0 && d < 2500) d = static_cast<std::uint16_t>(d - 100);
  views.observe({table}, object, camera);
  EXPECT_DOUBLE_EQ(views.seenShare(table), 1.0);
}

TEST(TableTopViews, ViewsAddUpAndTheMemoryIsKeyedByPlaceNotId) {
  const TableCluster table = squareTable(3);
  const Eigen::Isometry3d camera = test::headCamera(Pose2D{0.0, 0.0, 0.0});
  RgbdFrame left = test::depthOfTops({table}, camera), right = left;
  for (int v = 0; v < 480; ++v)
    for (int u = 0; u < 640; ++u) (u < 320 ? left : right).depth_mm[v * 640 + u] = 0;
  TableTopViews views;
  views.observe({table}, left, camera);
  const double half = views.seenShare(table);
  EXPECT_GT(half, 0.3);
  EXPECT_LT(half, 0.7);
  views.observe({table}, right, camera);
  EXPECT_DOUBLE_EQ(views.seenShare(table), 1.0);
  // The map renumbered the table, or merged it into a bigger one: what was seen stays.
  TableCluster renamed = squareTable(9);
  EXPECT_DOUBLE_EQ(views.seenShare(renamed), 1.0);
  TableCluster grown = squareTable(9);
  grown.hull = {{1.0f, -0.4f}, {2.6f, -0.4f}, {2.6f, 0.4f}, {1.0f, 0.4f}};
  EXPECT_NEAR(views.seenShare(grown), 0.5, 0.01);
  views.clear();
  EXPECT_EQ(views.seenShare(table), 0.0);
  EXPECT_EQ(views.seenShare(TableCluster{}), 0.0);  // no hull
}

TEST(TableTopViews, BadSettingsAndFramesAreRefusedByName) {
  TableTopViewsConfig c;
  c.range_m = 0.0f;
  EXPECT_THROW({ TableTopViews v(c); }, Error);
  c = {};
  c.cell_m = 0.001f;
  EXPECT_THROW({ TableTopViews v(c); }, Error);
  c = {};
  c.border_px = -1;
  EXPECT_THROW({ TableTopViews v(c); }, Error);
  TableTopViews views;
  RgbdFrame broken;
  broken.width = 640;
  broken.height = 480;
  broken.source = "short.png";
  broken.depth_mm.assign(10, 0);
  try {
    views.observe({squareTable(1)}, broken, test::headCamera(Pose2D{0, 0, 0}));
    FAIL() << "a depth image of the wrong size was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("short.png"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace findmug
