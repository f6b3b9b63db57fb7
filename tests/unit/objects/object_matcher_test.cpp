// The taught-object matcher (object_matcher.hpp) on rendered table tops: the
// taught mug found on a view it was not taught from, look-alikes refused with
// the gate and the numbers that refused them, and its settings.
#include "findmug/objects/object_matcher.hpp"

#include <gtest/gtest.h>

#include "expect_error.hpp"
#include "object_scenes.hpp"

namespace findmug {
namespace {

using test::errorOf;

const Rgb8 kRed{200, 40, 40};
const Rgb8 kBlue{40, 90, 200};

// One table, its objects in a row across it (no one hides another from the
// camera bearings used here, -40..40 degrees).
class TableTop : public ::testing::Test {
 protected:
  void SetUp() override {
    scene_ = test::makeTableScene();
    const Eigen::Vector2d c = scene_.table_center;
    mug_ = test::addMug(scene_, c + Eigen::Vector2d(0, -0.45), 0.04, 0.10, 2.0, kRed);
    blue_mug_ = test::addMug(scene_, c + Eigen::Vector2d(0, -0.15), 0.04, 0.10, 2.0, kBlue);
    big_box_ =
        test::addBox(scene_, "box", c + Eigen::Vector2d(0, 0.18), 0.3, {0.10, 0.08, 0.09}, kRed);
    small_mug_ = test::addMug(scene_, c + Eigen::Vector2d(0, 0.45), 0.03, 0.04, 2.0, kRed);
  }

  test::RenderedTable view(double bearing_deg, double distance, std::uint64_t noise) const {
    return test::renderTable(scene_, test::cameraAround(scene_, bearing_deg * M_PI / 180, distance),
                             noise);
  }
  TableObject candidate(const test::RenderedTable& r, int object) const {
    return test::candidateOf(r, object, static_cast<float>(scene_.top_z), object);
  }
  ObjectModel teach(const std::string& name, int object) const {
    ObjectModel m{name, {}};
    int noise = 1;
    for (double bearing : {-35.0, 0.0, 35.0}) {
      const auto r = view(bearing, 1.3, noise++);
      m.views.push_back(makeObjectView(r.cloud_ground, candidate(r, object)));
    }
    return m;
  }

  test::TableScene scene_;
  int mug_ = 0, blue_mug_ = 0, big_box_ = 0, small_mug_ = 0;
};

TEST_F(TableTop, FindsTheTaughtMugOnAnUnseenViewAndRefusesTheLookAlikes) {
  const ObjectModel mug = teach("mug", mug_);
  const auto r = view(18.0, 1.6, 99);  // another bearing, distance and noise
  const std::vector<TableObject> candidates = {candidate(r, mug_), candidate(r, blue_mug_),
                                               candidate(r, big_box_), candidate(r, small_mug_)};
  for (const auto& c : candidates) ASSERT_GE(c.point_count, 30) << "object " << c.id;
  const auto matches = matchObjects(r.cloud_ground, candidates, {mug}, ObjectMatcherConfig{});
  ASSERT_EQ(matches.size(), 4u);

  EXPECT_TRUE(matches[0].matched()) << matches[0].rejection;
  EXPECT_EQ(matches[0].name, "mug");
  EXPECT_GT(matches[0].score, 0.0f);
  EXPECT_LE(matches[0].score, 1.0f);

  // Same shape and size, another colour.
  EXPECT_EQ(matches[1].name, "mug");
  EXPECT_EQ(matches[1].score, 0.0f);
  EXPECT_EQ(matches[1].rejection.rfind("wrong colour: distance ", 0), 0u) << matches[1].rejection;
  EXPECT_CONTAINS(matches[1].rejection, "> 0.200");

  // Same colour, twice the mug's footprint.
  EXPECT_EQ(matches[2].rejection.rfind("too big: footprint length ", 0), 0u)
      << matches[2].rejection;
  EXPECT_CONTAINS(matches[2].rejection, "taught 0.");

  // Same colour and shape, 40 % of the height.
  EXPECT_EQ(matches[3].rejection.rfind("too small: height ", 0), 0u) << matches[3].rejection;

  // Deterministic: the same frame gives the same verdicts and scores.
  const auto again = matchObjects(r.cloud_ground, candidates, {mug}, ObjectMatcherConfig{});
  for (std::size_t i = 0; i < matches.size(); ++i) {
    EXPECT_EQ(again[i].name, matches[i].name);
    EXPECT_EQ(again[i].score, matches[i].score);
    EXPECT_EQ(again[i].rejection, matches[i].rejection);
  }
}

TEST_F(TableTop, WrongShapeIsRefusedWithTheDistance) {
  // The mug's size and colour with a flat object's shape in every view.
  ObjectModel flat = teach("flat_mug", mug_);
  std::vector<Eigen::Vector3f> plane;
  for (int i = 0; i < 400; ++i) plane.emplace_back(0.004f * (i % 20), 0.005f * (i / 20), 0.0f);
  for (auto& v : flat.views) v.shape = objectShapeDescriptor(plane);
  const auto r = view(10.0, 1.4, 5);
  const auto matches = matchObjects(r.cloud_ground, {candidate(r, mug_)}, {flat}, {});
  EXPECT_EQ(matches[0].name, "flat_mug");
  EXPECT_EQ(matches[0].rejection.rfind("wrong shape: distance ", 0), 0u) << matches[0].rejection;
  EXPECT_CONTAINS(matches[0].rejection, "> 0.250");
}

TEST_F(TableTop, EachCandidateTakesItsBestModelAndTheNearestRefusalOtherwise) {
  const std::vector<ObjectModel> models = {teach("red_mug", mug_), teach("blue_mug", blue_mug_)};
  const auto r = view(-15.0, 1.5, 11);
  const auto matches = matchObjects(
      r.cloud_ground, {candidate(r, mug_), candidate(r, blue_mug_), candidate(r, big_box_)}, models,
      {});
  EXPECT_EQ(matches[0].name, "red_mug");
  EXPECT_TRUE(matches[0].matched()) << matches[0].rejection;
  EXPECT_EQ(matches[1].name, "blue_mug");
  EXPECT_TRUE(matches[1].matched()) << matches[1].rejection;
  // Too big for both; the red mug's model is nearer (the same colour does not
  // matter to the size gate, so the order decides only on a tie).
  EXPECT_FALSE(matches[2].matched());
  EXPECT_EQ(matches[2].rejection.rfind("too big", 0), 0u) << matches[2].rejection;
}

TEST_F(TableTop, ATruncatedCandidateIsNotRefusedAsTooSmall) {
  const ObjectModel mug = teach("mug", mug_);
  const auto r = view(5.0, 1.4, 3);
  TableObject part = candidate(r, mug_);
  part.height_above_top *= 0.5f;  // as if the image border cut off its top
  auto matches = matchObjects(r.cloud_ground, {part}, {mug}, {});
  EXPECT_EQ(matches[0].rejection.rfind("too small: height", 0), 0u) << matches[0].rejection;
  part.truncation = kTruncatedBorder;
  matches = matchObjects(r.cloud_ground, {part}, {mug}, {});
  EXPECT_EQ(matches[0].rejection.find("too small"), std::string::npos) << matches[0].rejection;
  // ... but a part can still be too big.
  part.height_above_top = 0.5f;
  matches = matchObjects(r.cloud_ground, {part}, {mug}, {});
  EXPECT_EQ(matches[0].rejection.rfind("too big: height 0.500 m", 0), 0u) << matches[0].rejection;
}

// The mug and a box of its colour and size side by side: ESF does not tell
// them apart (object_recognition_eval), the roundness gate does.
class MugAndBox : public ::testing::Test {
 protected:
  void SetUp() override {
    scene_ = test::makeTableScene();
    const Eigen::Vector2d c = scene_.table_center;
    mug_ = test::addMug(scene_, c + Eigen::Vector2d(0, -0.2), 0.04, 0.10, 2.0, kRed);
    box_ =
        test::addBox(scene_, "box", c + Eigen::Vector2d(0, 0.2), 0.5, {0.042, 0.042, 0.05}, kRed);
  }
  test::RenderedTable view(double bearing_deg, double distance, std::uint64_t noise) const {
    return test::renderTable(scene_, test::cameraAround(scene_, bearing_deg * M_PI / 180, distance),
                             noise);
  }
  TableObject candidate(const test::RenderedTable& r, int object) const {
    return test::candidateOf(r, object, static_cast<float>(scene_.top_z), object);
  }
  ObjectModel teach(const std::string& name, int object) const {
    ObjectModel m{name, {}};
    int noise = 1;
    for (double bearing : {-35.0, 0.0, 35.0}) {
      const auto r = view(bearing, 1.3, noise++);
      m.views.push_back(makeObjectView(r.cloud_ground, candidate(r, object)));
    }
    return m;
  }

  test::TableScene scene_;
  int mug_ = 0, box_ = 0;
};

TEST_F(MugAndBox, TheBoxIsRefusedAsNotRoundAndTheMugIsFound) {
  const ObjectModel mug = teach("mug", mug_);
  for (const auto& v : mug.views) ASSERT_LE(v.roundness, 0.08f) << "the taught mug is round";
  for (const auto& [bearing, distance] : {std::pair{20.0, 1.6}, std::pair{-25.0, 1.4}}) {
    const auto r = view(bearing, distance, 42);  // views it was not taught from
    const std::vector<TableObject> candidates = {candidate(r, mug_), candidate(r, box_)};
    for (const auto& c : candidates) ASSERT_GE(c.point_count, 30) << "object " << c.id;
    const auto matches = matchObjects(r.cloud_ground, candidates, {mug}, ObjectMatcherConfig{});
    EXPECT_TRUE(matches[0].matched()) << bearing << ": " << matches[0].rejection;
    EXPECT_EQ(matches[1].name, "mug");
    EXPECT_EQ(matches[1].rejection.rfind("wrong shape: not round: roundness residual ", 0), 0u)
        << bearing << ": " << matches[1].rejection;
    EXPECT_CONTAINS(matches[1].rejection, "> 0.080 (taught 0.0");
  }
}

TEST_F(MugAndBox, ATaughtBoxIsNotAskedToBeRound) {
  const ObjectModel box = teach("box", box_);
  for (const auto& v : box.views) ASSERT_GT(v.roundness, 0.08f);
  const auto r = view(15.0, 1.5, 8);
  const auto matches = matchObjects(r.cloud_ground, {candidate(r, box_)}, {box}, {});
  EXPECT_EQ(matches[0].rejection.find("not round"), std::string::npos) << matches[0].rejection;
}

TEST(ObjectMatcher, WithoutModelsOrWithBadInputs) {
  OrganizedCloud cloud;
  cloud.width = 2;
  cloud.height = 1;
  cloud.points.assign(2, Eigen::Vector3f(0, 0, 1));
  cloud.colors.assign(2, Rgb8{});
  TableObject c;
  c.pixels = {0, 1};
  auto matches = matchObjects(cloud, {c}, {}, {});
  ASSERT_EQ(matches.size(), 1u);
  EXPECT_EQ(matches[0].name, "");
  EXPECT_EQ(matches[0].rejection, "no models");
  EXPECT_TRUE(matchObjects(cloud, {}, {}, {}).empty());
  c.pixels = {0, 2};
  EXPECT_CONTAINS(errorOf([&] { matchObjects(cloud, {c}, {}, {}); }),
                  "pixel 2 outside the 2x1 cloud");
  ObjectMatcherConfig bad;
  bad.max_shape_distance = std::numeric_limits<float>::quiet_NaN();
  EXPECT_CONTAINS(errorOf([&] { matchObjects(cloud, {}, {}, bad); }),
                  "object_matcher.max_shape_distance = nan");
  bad = {};
  bad.max_roundness_residual = 1.5f;
  EXPECT_CONTAINS(errorOf([&] { matchObjects(cloud, {}, {}, bad); }),
                  "object_matcher.max_roundness_residual = 1.5: must be in [0, 1]");
}

TEST(ObjectMatcher, TooFewPointsForAShapeIsSaid) {
  // Size and colour pass (the model's view is this candidate's), then the
  // shape needs 20 points.
  const ObjectModel model = test::sampleObjectModel("mug", 1);
  OrganizedCloud cloud;
  cloud.width = 10;
  cloud.height = 1;
  for (int i = 0; i < 10; ++i) cloud.points.emplace_back(0.01f * i, 0.0f, 0.01f * (i % 3));
  cloud.colors.assign(10, Rgb8{});
  TableObject c;
  for (int i = 0; i < 10; ++i) c.pixels.push_back(i);
  c.height_above_top = 0.10f;
  c.extents = {0.045f, 0.025f};
  c.colour_histogram = model.views[0].colour_histogram;
  const auto m = matchObjects(cloud, {c}, {model}, {});
  EXPECT_EQ(m[0].rejection, "too few points: 10 with depth, need 20");
}

TEST(ObjectMatcherSettings, EachKeyHasARangeAndADocLine) {
  ObjectMatcherConfig config;
  const auto& table = objectMatcherSettings();
  EXPECT_EQ(table.settings().size(), 5u);
  for (const auto& s : table.settings()) EXPECT_FALSE(s.doc.empty()) << s.key;
  table.set(config, "object_matcher.max_shape_distance", "0.2");
  EXPECT_FLOAT_EQ(config.max_shape_distance, 0.2f);
  table.set(config, "object_matcher.size_tolerance_m", "0.05");
  EXPECT_FLOAT_EQ(config.size_tolerance_m, 0.05f);
  table.set(config, "object_matcher.max_roundness_residual", "0.07");
  EXPECT_FLOAT_EQ(config.max_roundness_residual, 0.07f);
  EXPECT_CONTAINS(errorOf([&] { table.set(config, "object_matcher.max_colour_distance", "1.5"); }),
                  "object_matcher.max_colour_distance");
  EXPECT_THROW(table.set(config, "object_matcher.shape", "0.2"), Error);
  EXPECT_NO_THROW(validateObjectMatcherConfig(ObjectMatcherConfig{}));
  ObjectMatcherConfig negative;
  negative.size_tolerance = -0.1f;
  EXPECT_CONTAINS(errorOf([&] { validateObjectMatcherConfig(negative); }),
                  "object_matcher.size_tolerance = -0.1");
}

}  // namespace
}  // namespace findmug
