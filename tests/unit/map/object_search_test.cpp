// ObjectSearch (findmug/map/object_search.hpp): the answer to "find my mug" —
// where it was seen and where to stand, or the places to look in order, with
// tables seen before first and searched tables last; unknown names refused.
#include "findmug/map/object_search.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "findmug/common/error.hpp"
#include "findmug/ground/ground.hpp"
#include "findmug/map/semantic_map.hpp"
#include "table_scenes.hpp"

namespace findmug {
namespace {

// A mapped table with a search position on each long side.
TableCluster mappedTable(int id, float cx, float cy) {
  return test::withSearchPositions(test::tableAt(cx, cy, id));
}

TableObject mugOn(int table, float x, float y) {
  TableObject o;
  o.table = table;
  o.centroid = {x, y, 0.80f};
  o.height_above_top = 0.1f;
  o.extents = {0.05f, 0.05f};
  o.colour_histogram[2] = 1.0f;
  return o;
}

const std::vector<std::string> kTaught = {"book", "mug"};

// A map that names an object from one match at any range: the tests of the
// answers below are not about the evidence a name needs (object_map_test is).
ObjectMapConfig oneMatchNames() {
  ObjectMapConfig config;
  config.name_after_matches = 1;
  config.max_name_range_m = 100.0f;
  return config;
}

TEST(ObjectSearch, AMugSeenOnATableIsReportedWithWhereToStand) {
  const std::vector<TableCluster> tables = {mappedTable(1, 0.0f, 0.0f), mappedTable(2, 4.0f, 0.0f)};
  ObjectMap objects(oneMatchNames());
  // Seen from the map origin (pose = identity, so base = map) on table 2, near its north side.
  objects.update({mugOn(0, 4.1f, 0.3f)}, {tables[1]}, {2}, Pose2D{}, 5'000'000, {{"mug", 0.8f}});
  ObjectSearch search;
  const FindAnswer answer =
      search.answer(7, "mug", kTaught, objects, tables, Pose2D{0, 0, 0}, 17'000'000);
  ASSERT_EQ(answer.kind, FindAnswer::Kind::Seen);
  ASSERT_TRUE(answer.object.has_value());
  EXPECT_EQ(answer.object->table_id, 2);
  ASSERT_TRUE(answer.stand_here.has_value());
  EXPECT_NEAR(answer.stand_here->xy.y(), 0.9f, 1e-6f);  // the north side, nearer the mug
  EXPECT_NE(answer.summary.find("12.0 s ago"), std::string::npos) << answer.summary;
  EXPECT_NE(answer.summary.find("table 2"), std::string::npos) << answer.summary;
}

TEST(ObjectSearch, UnseenObjectGetsPlacesSeenBeforeFirstSearchedLast) {
  std::vector<TableCluster> tables = {mappedTable(1, 1.0f, 0.0f), mappedTable(2, 3.0f, 0.0f),
                                      mappedTable(3, 8.0f, 0.0f)};
  // Table 1's south side is blocked.
  tables[0].search_positions[1].reachable = false;
  ObjectMapConfig forgetful = oneMatchNames();
  forgetful.forget_misses = 1;
  ObjectMap objects(forgetful);
  // The mug was once seen on table 3, then its place was seen empty.
  objects.update({mugOn(0, 8.0f, 0.0f)}, {tables[2]}, {3}, Pose2D{}, 1, {{"mug", 0.9f}});
  objects.update({}, {tables[2]}, {3}, Pose2D{}, 2);
  ASSERT_TRUE(objects.objects().empty());

  ObjectSearch search;
  const Pose2D robot{0.0, 0.0, 0.0};
  FindAnswer answer = search.answer(1, "mug", kTaught, objects, tables, robot, 10);
  ASSERT_EQ(answer.kind, FindAnswer::Kind::LookAt);
  ASSERT_EQ(answer.places.size(), 5u);  // 2 + 2 + 2 positions, one unreachable
  EXPECT_EQ(answer.places[0].table_id, 3);
  EXPECT_EQ(answer.places[1].table_id, 3);
  EXPECT_TRUE(answer.places[0].seen_here_before);
  // Then, from table 3, the tour goes back over table 2 before table 1.
  EXPECT_EQ(answer.places[2].table_id, 2);
  EXPECT_EQ(answer.places[4].table_id, 1);
  for (const PlaceToLook& p : answer.places) EXPECT_TRUE(p.position.reachable);

  // The robot stands at table 3's north position facing it: table 3 is searched
  // and goes last; a pose near a position but facing away marks nothing.
  EXPECT_TRUE(search.observeRobot(Pose2D{8.0, 0.95, 0.0}, tables).empty());
  EXPECT_EQ(search.observeRobot(Pose2D{8.0, 0.95, -M_PI / 2}, tables), std::vector<int>{3});
  answer = search.answer(1, "mug", kTaught, objects, tables, robot, 20);
  ASSERT_EQ(answer.places.size(), 5u);
  EXPECT_EQ(answer.places[0].table_id, 1);  // nearest of the unsearched from the robot
  EXPECT_EQ(answer.places[3].table_id, 3);
  EXPECT_TRUE(answer.places[3].searched);
  // A new request starts with nothing searched.
  answer = search.answer(2, "mug", kTaught, objects, tables, robot, 30);
  EXPECT_EQ(answer.places[0].table_id, 3);
  EXPECT_TRUE(search.searchedTables().empty());
}

// A match from too far (the shipped max_name_range_m, 2 m) or only one
// match does not make the mug "seen": the answer is the places to look, its
// table first, searched or not, with "look closer" in the summary.
TEST(ObjectSearch, AMugMatchedOnlyFromFarIsLookCloserWithItsTableFirst) {
  const std::vector<TableCluster> tables = {mappedTable(1, 1.0f, 0.0f), mappedTable(2, 4.0f, 0.0f)};
  ObjectMap objects;
  // Twice from the map origin, 4 m away: never near enough to confirm.
  for (std::uint64_t t : {1u, 2u}) {
    objects.update({mugOn(0, 4.1f, 0.3f)}, {tables[1]}, {2}, Pose2D{}, t, {{"mug", 0.8f}});
  }
  ASSERT_EQ(objects.objects().size(), 1u);
  EXPECT_EQ(objects.objects()[0].name, "");
  EXPECT_EQ(objects.objects()[0].pending_name, "mug");
  ObjectSearch search;
  EXPECT_EQ(search.observeRobot(Pose2D{4.0, 0.95, -M_PI / 2}, tables), std::vector<int>{2});
  FindAnswer answer = search.answer(1, "mug", kTaught, objects, tables, Pose2D{}, 10);
  ASSERT_EQ(answer.kind, FindAnswer::Kind::LookAt);
  ASSERT_EQ(answer.places.size(), 4u);
  // Table 2 first although it is farther and was searched.
  EXPECT_EQ(answer.places[0].table_id, 2);
  EXPECT_EQ(answer.places[1].table_id, 2);
  EXPECT_TRUE(answer.places[0].look_closer);
  EXPECT_FALSE(answer.places[2].look_closer);
  EXPECT_NE(answer.summary.find("look closer"), std::string::npos) << answer.summary;
  // Two near sightings (the robot 1 m from it) confirm it: seen.
  const Pose2D near{4.0, 1.3, -M_PI / 2};  // facing -y: the mug 1 m ahead, 0.1 m left
  for (std::uint64_t t : {3u, 4u}) {
    objects.update({mugOn(0, 1.0f, 0.1f)}, {mappedTable(2, 1.3f, 0.0f)}, {2}, near, t,
                   {{"mug", 0.9f}});
  }
  ASSERT_EQ(objects.objects().size(), 1u);
  answer = search.answer(1, "mug", kTaught, objects, tables, Pose2D{}, 10);
  EXPECT_EQ(answer.kind, FindAnswer::Kind::Seen) << answer.summary;
}

TEST(ObjectSearch, ATopSeenNearEnoughWhileDrivingByIsSearched) {
  const std::vector<TableCluster> tables = {mappedTable(1, 1.0f, 0.0f), mappedTable(2, 6.0f, 0.0f)};
  ObjectMap objects(oneMatchNames());
  ObjectSearchConfig reach;
  reach.top_seen_range_m = 2.5f;
  ObjectSearch search(reach);
  const Pose2D robot{-0.5, 0.0, 0.0};
  FindAnswer answer = search.answer(1, "mug", kTaught, objects, tables, robot, 10);
  ASSERT_EQ(answer.places.size(), 4u);
  EXPECT_EQ(answer.places[0].table_id, 1);
  // The head camera (1.2 m up, 0.5 rad down) 0.9 m behind table 1's near edge, facing it:
  // its whole top in view within 2.5 m. Table 2 is far out of reach.
  CameraExtrinsics mount;
  mount.height_m = 1.2;
  mount.pitch_rad = 0.5;
  const Eigen::Isometry3d camera =
      cameraInMap(robot, groundFromExtrinsics(mount).camera_to_ground);
  EXPECT_EQ(search.observeView(tables, test::depthOfTops({tables[0]}, camera), camera),
            std::vector<int>{1});
  answer = search.answer(1, "mug", kTaught, objects, tables, robot, 20);
  EXPECT_EQ(answer.places[0].table_id, 2);
  EXPECT_TRUE(answer.places[3].searched);
  EXPECT_EQ(answer.places[3].table_id, 1);
  // Something in front (a wall 0.3 m away) shows nothing, for a new request.
  answer = search.answer(2, "mug", kTaught, objects, tables, robot, 30);
  RgbdFrame wall = test::depthOfTops({tables[0]}, camera);
  std::fill(wall.depth_mm.begin(), wall.depth_mm.end(), std::uint16_t{300});
  EXPECT_TRUE(search.observeView(tables, wall, camera).empty());
  // With top_seen_share 0, views never search a table.
  ObjectSearchConfig standing_only = reach;
  standing_only.top_seen_share = 0.0f;
  ObjectSearch strict(standing_only);
  strict.answer(1, "mug", kTaught, objects, tables, robot, 10);
  EXPECT_TRUE(strict.observeView(tables, test::depthOfTops({tables[0]}, camera), camera).empty());
}

TEST(ObjectSearch, AnUntaughtNameIsRefusedListingTheTaughtOnes) {
  ObjectMap objects;
  ObjectSearch search;
  const FindAnswer answer =
      search.answer(1, "teapot", kTaught, objects, {mappedTable(1, 1, 0)}, std::nullopt, 0);
  EXPECT_EQ(answer.kind, FindAnswer::Kind::UnknownName);
  EXPECT_TRUE(answer.places.empty());
  EXPECT_NE(answer.summary.find("teapot"), std::string::npos);
  EXPECT_NE(answer.summary.find("book, mug"), std::string::npos) << answer.summary;
}

TEST(ObjectSearch, WithoutAPoseTheTourStartsAtTheFirstPlace) {
  ObjectMap objects;
  ObjectSearch search;
  const std::vector<TableCluster> tables = {mappedTable(1, 0.0f, 0.0f)};
  const FindAnswer answer = search.answer(1, "mug", kTaught, objects, tables, std::nullopt, 0);
  ASSERT_EQ(answer.places.size(), 2u);
  EXPECT_NE(answer.summary.find("not seen yet"), std::string::npos);
}

TEST(ObjectSearch, SettingsAreCheckedAndParsed) {
  ObjectSearchConfig parsed;
  objectSearchSettings().set(parsed, "object_search.position_tolerance_m", "0.5");
  EXPECT_FLOAT_EQ(parsed.position_tolerance_m, 0.5f);
  EXPECT_THROW(objectSearchSettings().set(parsed, "object_search.tolerance", "1"), Error);
  objectSearchSettings().set(parsed, "object_search.top_seen_share", "0.9");
  EXPECT_FLOAT_EQ(parsed.top_seen_share, 0.9f);
  EXPECT_THROW(objectSearchSettings().set(parsed, "object_search.top_seen_share", "1.5"), Error);
  EXPECT_THROW(objectSearchSettings().set(parsed, "object_search.top_seen_range_m", "0"), Error);
  ObjectSearchConfig config;
  config.heading_tolerance_rad = 4.0f;
  try {
    ObjectSearch search(config);
    FAIL() << "accepted heading_tolerance_rad 4";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("object_search.heading_tolerance_rad"),
              std::string::npos);
  }
}

}  // namespace
}  // namespace findmug
