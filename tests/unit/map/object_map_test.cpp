// ObjectMap (findmug/map/object_map.hpp): table-top candidates of many frames
// under stable ids; matched by place and colour, forgotten when their place
// is seen empty, kept while it is out of view.
#include "findmug/map/object_map.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "findmug/common/error.hpp"

namespace findmug {
namespace {

ObjectColourHistogram histogramAt(int bin) {
  ObjectColourHistogram h{};
  h[bin] = 1.0f;
  return h;
}

constexpr int kRedBin = 1;   // any chromatic bin
constexpr int kBlueBin = 17;

// A 1.2 x 0.8 m table top at 0.75 m, centred at (cx, cy) in the frame's base frame.
TableCluster tableAt(float cx, float cy) {
  TableCluster t;
  t.top_height = 0.75f;
  t.centroid = {cx, cy, 0.75f};
  t.center = {cx, cy};
  t.extents = {0.6f, 0.4f};
  t.hull = {{cx - 0.6f, cy - 0.4f}, {cx + 0.6f, cy - 0.4f}, {cx + 0.6f, cy + 0.4f},
            {cx - 0.6f, cy + 0.4f}};
  return t;
}

// A mug-sized candidate at (x, y) of the base frame on table 0.
TableObject mugAt(float x, float y, int colour_bin = kRedBin) {
  TableObject o;
  o.table = 0;
  o.centroid = {x, y, 0.80f};
  o.height_above_top = 0.10f;
  o.extents = {0.05f, 0.04f};
  o.point_count = 200;
  o.mean_rgb = {200, 30, 30};
  o.colour_histogram = histogramAt(colour_bin);
  return o;
}

TEST(ObjectMap, TheSameMugFromTwoPosesIsOneObjectAtItsMeanPlace) {
  ObjectMap map;
  // Pose 1: the robot at the map origin; the mug 2 m ahead, 0.1 m left.
  const Pose2D first{0.0, 0.0, 0.0};
  auto update = map.update({mugAt(2.0f, 0.1f)}, {tableAt(2.0f, 0.0f)}, {7}, first, 1000);
  ASSERT_EQ(update.created.size(), 1u);
  const int id = update.object_ids[0];
  // Pose 2: the robot at (1, 1) facing -y (yaw -90°): the same map point
  // (2.02, 0.1) is 0.9 m ahead and 1.02 m to the left... in base coordinates:
  // x = -(0.1 - 1) = 0.9, y = (2.02 - 1) = 1.02.
  const Pose2D second{1.0, 1.0, -M_PI / 2};
  TableCluster table2 = tableAt(0.9f, 1.0f);
  update = map.update({mugAt(0.9f, 1.02f)}, {table2}, {7}, second, 2000);
  EXPECT_TRUE(update.created.empty());
  ASSERT_EQ(update.object_ids.size(), 1u);
  EXPECT_EQ(update.object_ids[0], id);
  ASSERT_EQ(map.objects().size(), 1u);
  const MappedObject& mug = map.objects()[0];
  EXPECT_EQ(mug.sightings, 2);
  EXPECT_EQ(mug.table_id, 7);
  EXPECT_EQ(mug.first_seen_utime, 1000u);
  EXPECT_EQ(mug.last_seen_utime, 2000u);
  EXPECT_NEAR(mug.centroid.x(), 2.01f, 1e-4f);  // mean of 2.00 and 2.02
  EXPECT_NEAR(mug.centroid.y(), 0.1f, 1e-4f);
}

TEST(ObjectMap, ABlueMugWhereTheRedOneStoodIsAnotherObject) {
  ObjectMap map;
  const Pose2D pose{};
  map.update({mugAt(2.0f, 0.0f, kRedBin)}, {tableAt(2.0f, 0.0f)}, {}, pose, 1);
  const auto update = map.update({mugAt(2.0f, 0.0f, kBlueBin)}, {tableAt(2.0f, 0.0f)}, {}, pose, 2);
  EXPECT_EQ(update.created.size(), 1u);
  EXPECT_NE(update.object_ids[0], map.objects().front().id);
  // The red one's place was seen without it (its match was refused): one miss.
  EXPECT_EQ(map.objects().front().misses, 1);
}

TEST(ObjectMap, AMugWhosePlaceIsSeenEmptyIsForgottenOneOutOfViewIsKept) {
  ObjectMapConfig config;
  config.forget_misses = 3;
  ObjectMap map(config);
  const Pose2D pose{};
  TableObject far = mugAt(5.0f, 3.0f);
  far.table = 1;
  map.update({mugAt(2.0f, 0.1f), far}, {tableAt(2.0f, 0.0f), tableAt(5.0f, 3.0f)}, {}, pose, 1);
  ASSERT_EQ(map.objects().size(), 2u);
  const int near_id = map.objects()[0].id;
  const int far_id = map.objects()[1].id;
  // Now only the first table is in view, empty.
  for (int frame = 0; frame < 2; ++frame) {
    const auto update = map.update({}, {tableAt(2.0f, 0.0f)}, {}, pose, 10 + frame);
    EXPECT_TRUE(update.forgotten.empty());
  }
  const auto update = map.update({}, {tableAt(2.0f, 0.0f)}, {}, pose, 20);
  ASSERT_EQ(update.forgotten.size(), 1u);
  EXPECT_EQ(update.forgotten[0], near_id);
  ASSERT_EQ(map.objects().size(), 1u);
  EXPECT_EQ(map.objects()[0].id, far_id);
  EXPECT_EQ(map.objects()[0].misses, 0);
  EXPECT_EQ(map.objects()[0].last_seen_utime, 1u);
}

TEST(ObjectMap, ASightingInBetweenResetsTheMisses) {
  ObjectMap map;
  const Pose2D pose{};
  map.update({mugAt(2.0f, 0.1f)}, {tableAt(2.0f, 0.0f)}, {}, pose, 1);
  map.update({}, {tableAt(2.0f, 0.0f)}, {}, pose, 2);
  map.update({}, {tableAt(2.0f, 0.0f)}, {}, pose, 3);
  EXPECT_EQ(map.objects()[0].misses, 2);
  map.update({mugAt(2.0f, 0.1f)}, {tableAt(2.0f, 0.0f)}, {}, pose, 4);
  EXPECT_EQ(map.objects()[0].misses, 0);
  map.update({}, {tableAt(2.0f, 0.0f)}, {}, pose, 5);
  EXPECT_EQ(map.objects().size(), 1u);
}

TEST(ObjectMap, NearestCandidateTakesTheMappedObjectTheOtherIsNew) {
  ObjectMap map;
  const Pose2D pose{};
  map.update({mugAt(2.0f, 0.0f)}, {tableAt(2.0f, 0.0f)}, {}, pose, 1);
  const int id = map.objects()[0].id;
  const auto update =
      map.update({mugAt(2.08f, 0.0f), mugAt(2.02f, 0.0f)}, {tableAt(2.0f, 0.0f)}, {}, pose, 2);
  EXPECT_EQ(update.object_ids[1], id);
  EXPECT_NE(update.object_ids[0], id);
  EXPECT_EQ(update.created, std::vector<int>{update.object_ids[0]});
  // The next id in order of creation.
  EXPECT_EQ(update.object_ids[0], id + 1);
}

TEST(ObjectMap, ANamedSightingNamesTheObjectAndItsTablesAreRemembered) {
  ObjectMapConfig config;
  config.forget_misses = 1;
  ObjectMap map(config);
  const Pose2D pose{};
  map.update({mugAt(2.0f, 0.1f)}, {tableAt(2.0f, 0.0f)}, {4}, pose, 1, {{"mug", 0.9f}});
  ASSERT_EQ(map.objects().size(), 1u);
  EXPECT_EQ(map.objects()[0].name, "mug");
  EXPECT_FLOAT_EQ(map.objects()[0].name_score, 0.9f);
  // Seen again without a name: it keeps its name.
  map.update({mugAt(2.0f, 0.1f)}, {tableAt(2.0f, 0.0f)}, {4}, pose, 2, {{"", 0.0f}});
  EXPECT_EQ(map.objects()[0].name, "mug");
  // Its place seen empty: forgotten, but where it stood is remembered.
  const auto update = map.update({}, {tableAt(2.0f, 0.0f)}, {4}, pose, 3);
  EXPECT_EQ(update.forgotten.size(), 1u);
  EXPECT_TRUE(map.objects().empty());
  EXPECT_EQ(map.seenOnTables("mug"), std::vector<int>{4});
  EXPECT_TRUE(map.seenOnTables("book").empty());
  EXPECT_TRUE(map.seenOnTables("").empty());
  EXPECT_THROW(map.update({mugAt(2.0f, 0.1f)}, {tableAt(2.0f, 0.0f)}, {4}, pose, 4,
                          {{"mug", 1.0f}, {"cup", 1.0f}}),
               Error);
}

TEST(ObjectMap, ColourDistanceIsZeroForEqualAndOneForDisjointOrEmptyHistograms) {
  EXPECT_NEAR(colourHistogramDistance(histogramAt(3), histogramAt(3)), 0.0f, 1e-6f);
  EXPECT_NEAR(colourHistogramDistance(histogramAt(3), histogramAt(4)), 1.0f, 1e-6f);
  EXPECT_NEAR(colourHistogramDistance(ObjectColourHistogram{}, histogramAt(4)), 1.0f, 1e-6f);
  ObjectColourHistogram half{};
  half[3] = 0.5f;
  half[4] = 0.5f;
  EXPECT_NEAR(colourHistogramDistance(half, histogramAt(3)), 1.0f - std::sqrt(0.5f), 1e-6f);
}

TEST(ObjectMap, InputsThatDoNotFitTheFrameAreRefused) {
  ObjectMap map;
  TableObject stray = mugAt(2.0f, 0.0f);
  stray.table = 1;
  EXPECT_THROW(map.update({stray}, {tableAt(2.0f, 0.0f)}, {}, Pose2D{}, 1), Error);
  EXPECT_THROW(map.update({}, {tableAt(2.0f, 0.0f)}, {1, 2}, Pose2D{}, 1), Error);
  TableObject nan = mugAt(2.0f, 0.0f);
  nan.centroid.x() = std::nanf("");
  EXPECT_THROW(map.update({nan}, {tableAt(2.0f, 0.0f)}, {}, Pose2D{}, 1), Error);
  EXPECT_TRUE(map.objects().empty());
}

TEST(ObjectMap, SettingsAreRangeCheckedAndNamed) {
  ObjectMapConfig config;
  config.match_colour_distance = 1.5f;
  try {
    validateObjectMapConfig(config);
    FAIL() << "accepted match_colour_distance 1.5";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("object_map.match_colour_distance"), std::string::npos);
  }
  config = {};
  config.forget_misses = 0;
  EXPECT_THROW(ObjectMap{config}, Error);
  ObjectMapConfig parsed;
  objectMapSettings().set(parsed, "object_map.match_distance_m", "0.2");
  EXPECT_FLOAT_EQ(parsed.match_distance_m, 0.2f);
  EXPECT_THROW(objectMapSettings().set(parsed, "object_map.match_distance", "0.2"), Error);
  EXPECT_EQ(objectMapSettings().settings().size(), 6u);
}

}  // namespace
}  // namespace findmug
