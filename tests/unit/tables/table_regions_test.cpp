// Tests for the table decisions after the forest (perf-log §1f): the
// region vote and the table weight (table_regions.hpp), the visible-top
// filter of detectTables, and the precision/recall curve over a detection
// score (table_metrics.hpp). Hand-made inputs whose answers follow from
// their construction.
#include "findmug/tables/table_regions.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "findmug/common/error.hpp"
#include "findmug/offline/table_metrics.hpp"
#include "findmug/tables/tables.hpp"

namespace findmug {
namespace {

using ::testing::HasSubstr;

constexpr std::uint8_t kUnknown = static_cast<std::uint8_t>(Label::Unknown);
constexpr std::uint8_t kTable = static_cast<std::uint8_t>(Label::Table);
constexpr std::uint8_t kCabinet = static_cast<std::uint8_t>(Label::Cabinet);
constexpr std::uint8_t kObject = static_cast<std::uint8_t>(Label::Object);
constexpr std::uint8_t kFloor = static_cast<std::uint8_t>(Label::Floor);

ClassProbabilities dist(std::initializer_list<std::pair<Label, float>> entries) {
  ClassProbabilities p{};
  float rest = 1.0f;
  for (const auto& [label, value] : entries) {
    p[static_cast<int>(label)] = value;
    rest -= value;
  }
  p[static_cast<int>(Label::Unknown)] += rest;
  return p;
}

// Region features of a segment: area, extents, centroid height, max height, normal angle.
void setRegion(RegionFeatures& r, std::size_t segment, int region, float area, float height,
               float angle_rad) {
  r.segment_region[segment] = region;
  float* v = r.values.data() + segment * kRegionFeatureDim;
  v[0] = area;
  v[1] = std::sqrt(area);
  v[2] = std::sqrt(area);
  v[3] = height;
  v[4] = height + 0.01f;
  v[5] = angle_rad;
}

// Segments 0-3: one table top (0.5 m², 0.75 m, horizontal) that the MRF split
// between table, object and cabinet; 4-5: a cabinet front (vertical); 6: a
// horizontal patch of floor height; 7: a small horizontal patch (0.01 m²).
struct SplitTop {
  std::vector<std::uint8_t> labels{kTable, kObject, kCabinet, kTable,
                                   kCabinet, kCabinet, kFloor, kObject};
  std::vector<float> confidence = std::vector<float>(8, 0.5f);
  std::vector<ClassProbabilities> probabilities{
      dist({{Label::Table, 0.6f}, {Label::Object, 0.2f}}),
      dist({{Label::Table, 0.35f}, {Label::Object, 0.45f}}),
      dist({{Label::Table, 0.4f}, {Label::Cabinet, 0.45f}}),
      dist({{Label::Table, 0.7f}, {Label::Cabinet, 0.1f}}),
      dist({{Label::Cabinet, 0.6f}, {Label::Table, 0.3f}}),
      dist({{Label::Cabinet, 0.5f}, {Label::Table, 0.4f}}),
      dist({{Label::Floor, 0.9f}}),
      dist({{Label::Object, 0.6f}, {Label::Table, 0.35f}}),
  };
  std::vector<float> weights{100, 300, 200, 100, 400, 400, 500, 50};
  RegionFeatures regions;
  SplitTop() {
    regions.region_count = 4;
    regions.segment_region.assign(8, 0);
    regions.values.assign(8 * kRegionFeatureDim, 0.0f);
    for (std::size_t s = 0; s < 4; ++s) setRegion(regions, s, 0, 0.5f, 0.75f, 0.05f);
    for (std::size_t s = 4; s < 6; ++s) setRegion(regions, s, 1, 0.6f, 0.5f, 1.55f);
    setRegion(regions, 6, 2, 3.0f, 0.0f, 0.02f);
    setRegion(regions, 7, 3, 0.01f, 0.8f, 0.0f);
  }
};

TEST(TableRegionVote, TableTopSplitBetweenClassesBecomesOneTableRegion) {
  const SplitTop s;
  TableConfig config;
  const RegionVoteResult vote =
      voteTableRegions(s.labels, s.confidence, s.probabilities, s.weights, s.regions, config);
  // Area-weighted p(table) over the top: (60 + 105 + 80 + 70) / 700 = 0.45,
  // above object (20 + 135 + 0 + 0) / 700 and cabinet (0 + 0 + 90 + 10) / 700.
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(vote.labels[k], kTable) << "segment " << k;
    EXPECT_NEAR(vote.confidence[k], 315.0f / 700.0f, 1e-5f);
  }
  // The vertical front, the floor-height patch and the small patch keep theirs.
  EXPECT_EQ(vote.labels[4], kCabinet);
  EXPECT_EQ(vote.labels[5], kCabinet);
  EXPECT_EQ(vote.labels[6], kFloor);
  EXPECT_EQ(vote.labels[7], kObject);
  EXPECT_FLOAT_EQ(vote.confidence[4], 0.5f);
  EXPECT_EQ(vote.regions_voted, 1);
  EXPECT_EQ(vote.segments_changed, 2);
}

TEST(TableRegionVote, SettingsDecideWhichRegionsVote) {
  const SplitTop s;
  TableConfig config;
  // A steeper limit lets the cabinet front (89°) vote: cabinet wins there,
  // so nothing changes on it, but it counts as voted.
  config.region_max_tilt_deg = 90.0f;
  EXPECT_EQ(voteTableRegions(s.labels, s.confidence, s.probabilities, s.weights, s.regions, config)
                .regions_voted,
            2);
  // No minimum area: the small patch votes too, and object wins it.
  config = TableConfig{};
  config.region_min_area_m2 = 0.0f;
  const auto small =
      voteTableRegions(s.labels, s.confidence, s.probabilities, s.weights, s.regions, config);
  EXPECT_EQ(small.regions_voted, 2);
  EXPECT_EQ(small.labels[7], kObject);
  // The top above the height range: no vote.
  config = TableConfig{};
  config.max_table_height_m = 0.7f;
  const auto high =
      voteTableRegions(s.labels, s.confidence, s.probabilities, s.weights, s.regions, config);
  EXPECT_EQ(high.regions_voted, 0);
  EXPECT_EQ(high.labels, s.labels);
}

TEST(TableRegionVote, SizesThatDisagreeAreRefused) {
  SplitTop s;
  s.weights.pop_back();
  EXPECT_THAT(
      [&] {
        try {
          voteTableRegions(s.labels, s.confidence, s.probabilities, s.weights, s.regions, {});
        } catch (const Error& e) {
          throw std::runtime_error(e.what());
        }
      },
      ::testing::ThrowsMessage<std::runtime_error>(HasSubstr("7 weights")));
}

TEST(TableWeight, ScalesTableProbabilityAndRenormalises) {
  const std::vector<ClassProbabilities> p{dist({{Label::Table, 0.4f}, {Label::Object, 0.5f}})};
  const auto same = weightTableProbability(p, 1.0f);
  EXPECT_EQ(same[0], p[0]);
  const auto w = weightTableProbability(p, 1.5f);
  // 0.6 / 1.2 for table, 0.5 / 1.2 for object: the decision flips to table.
  EXPECT_NEAR(w[0][kTable], 0.5f, 1e-6f);
  EXPECT_NEAR(w[0][kObject], 0.5f / 1.2f, 1e-6f);
  EXPECT_NEAR(w[0][kUnknown], 0.1f / 1.2f, 1e-6f);
  float sum = 0;
  for (float v : w[0]) sum += v;
  EXPECT_NEAR(sum, 1.0f, 1e-6f);
  EXPECT_THROW(weightTableProbability(p, 0.0f), Error);
}

// A ground-frame cloud of `width` x `height` pixels; fill() places shapes.
struct GroundScene {
  OrganizedCloud cloud;
  LabelImage labels;
  GroundScene(int width, int height) {
    cloud.width = labels.width = width;
    cloud.height = labels.height = height;
    cloud.points.assign(static_cast<std::size_t>(width) * height,
                        Eigen::Vector3f::Constant(std::nanf("")));
    cloud.colors.assign(cloud.points.size(), Rgb8{});
    labels.labels.assign(cloud.points.size(), kVoidLabel);
  }
  // A horizontal square top of side `side_m` at `height`, 1 cm point spacing,
  // starting at image column u0.
  void top(int u0, float side_m, float height, float x0) {
    const int n = static_cast<int>(std::lround(side_m / 0.01f));
    for (int v = 0; v < n; ++v) {
      for (int u = 0; u < n; ++u) {
        const auto i = static_cast<std::size_t>(v * cloud.width + u0 + u);
        cloud.points[i] = Eigen::Vector3f(x0 + 0.01f * u, 0.01f * v, height);
        labels.labels[i] = kTable;
      }
    }
  }
  // A vertical panel (a desk front, a chair back) 0.6 m wide and 0.5 m high
  // from 0.4 m, in the plane x = x0 (2 cm thick), at image columns u0.. .
  void panel(int u0, float x0) {
    for (int v = 0; v < 50; ++v) {
      for (int u = 0; u < 60; ++u) {
        const auto i = static_cast<std::size_t>(v * cloud.width + u0 + u);
        // 2 cm of depth noise across the panel, as a sensor gives it.
        cloud.points[i] = Eigen::Vector3f(x0 + 0.02f * static_cast<float>((u + v) % 2),
                                          0.01f * u, 0.9f - 0.01f * v);
        labels.labels[i] = kTable;
      }
    }
  }
};

TEST(TableTopFilter, SmallHorizontalPatchBelowTheMinimumAreaIsNotATable) {
  GroundScene scene(200, 60);
  scene.top(0, 0.5f, 0.75f, 0.0f);     // 0.25 m²: a table
  scene.top(100, 0.3f, 0.75f, 2.0f);   // 0.09 m²: a stool, a box
  TableConfig config;
  config.min_cluster_points = 100;
  ASSERT_FLOAT_EQ(config.min_top_area_m2, 0.15f);
  const TableDetection d = detectTables(scene.cloud, scene.labels, config);
  ASSERT_EQ(d.tables.size(), 1u);
  EXPECT_NEAR(d.tables[0].top_area_m2, 0.25f, 0.03f);
  EXPECT_NEAR(d.tables[0].centroid.x(), 0.245f, 0.01f);
  EXPECT_EQ(d.clusters_rejected, 1);
  bool reported = false;
  for (const auto& line : d.diagnostics) reported |= line.find("min_top_area_m2") != std::string::npos;
  EXPECT_TRUE(reported);
  // Without the filter both are tables.
  config.min_top_area_m2 = 0.0f;
  EXPECT_EQ(detectTables(scene.cloud, scene.labels, config).tables.size(), 2u);
}

TEST(TableTopFilter, VerticalPanelHasAlmostNoTopAndIsDropped) {
  GroundScene scene(100, 60);
  scene.panel(0, 1.0f);  // 3000 table-labelled points, 0.6 m wide
  TableConfig config;
  config.min_table_width_m = 0.0f;  // the panel's top band is a line: keep it to see its area
  config.min_top_area_m2 = 0.0f;
  const TableDetection all = detectTables(scene.cloud, scene.labels, config);
  ASSERT_EQ(all.tables.size(), 1u);
  // The top band of a vertical panel seen from above: 0.6 m by one 5 cm cell.
  EXPECT_LT(all.tables[0].top_area_m2, 0.06f);
  config.min_top_area_m2 = 0.15f;
  EXPECT_TRUE(detectTables(scene.cloud, scene.labels, config).tables.empty());
}

TEST(TableTopFilter, ClustersWithFewHorizontalNormalsAreDroppedWhenNormalsAreGiven) {
  GroundScene scene(200, 60);
  scene.top(0, 0.5f, 0.75f, 0.0f);  // a table top: normals up
  scene.panel(100, 2.0f);           // a cabinet front: normals along x
  NormalImage normals;
  normals.width = scene.cloud.width;
  normals.height = scene.cloud.height;
  normals.normals.assign(scene.cloud.points.size(), Eigen::Vector3f::Constant(std::nanf("")));
  for (int v = 0; v < 60; ++v) {
    for (int u = 0; u < 200; ++u) {
      const auto i = static_cast<std::size_t>(v * 200 + u);
      if (!std::isfinite(scene.cloud.points[i].z())) continue;
      // The front's upper tenth is rounded: its normals tilt 10° from up.
      const bool rim = u >= 100 && v < 5;
      normals.normals[i] = u < 100  ? Eigen::Vector3f::UnitZ()
                           : rim    ? Eigen::Vector3f(std::sin(0.17f), 0.0f, std::cos(0.17f))
                                    : Eigen::Vector3f::UnitX();
    }
  }
  TableConfig config;
  config.min_top_area_m2 = 0.0f;
  config.min_table_width_m = 0.0f;
  ASSERT_FLOAT_EQ(config.min_horizontal_share, 0.2f);
  // Without normals both clusters are tables, the share unknown.
  const auto blind = detectTables(scene.cloud, scene.labels, config);
  ASSERT_EQ(blind.tables.size(), 2u);
  EXPECT_TRUE(std::isnan(blind.tables[0].horizontal_share));
  // With them the front (10 % horizontal) is dropped, the top (100 %) kept.
  const auto seen = detectTables(scene.cloud, scene.labels, config, &normals);
  ASSERT_EQ(seen.tables.size(), 1u);
  EXPECT_FLOAT_EQ(seen.tables[0].horizontal_share, 1.0f);
  EXPECT_NEAR(seen.tables[0].centroid.x(), 0.245f, 0.01f);
  bool reported = false;
  for (const auto& line : seen.diagnostics)
    reported |= line.find("tables.min_horizontal_share") != std::string::npos;
  EXPECT_TRUE(reported);
  // A lower bar keeps the front: 10 % of its points are within 20° of up.
  config.min_horizontal_share = 0.05f;
  const auto low = detectTables(scene.cloud, scene.labels, config, &normals);
  ASSERT_EQ(low.tables.size(), 2u);
  for (const auto& t : low.tables) {
    if (t.centroid.x() > 1.0f) {
      EXPECT_NEAR(t.horizontal_share, 0.1f, 1e-5f);
    }
  }
  normals.normals.pop_back();
  EXPECT_THROW(detectTables(scene.cloud, scene.labels, config, &normals), Error);
}

TEST(TableTopFilter, LowConfidenceClustersAreDropped) {
  GroundScene scene(200, 60);
  scene.top(0, 0.5f, 0.75f, 0.0f);
  scene.top(100, 0.5f, 0.75f, 2.0f);
  scene.labels.confidence.assign(scene.cloud.points.size(), 0.3f);
  for (int v = 0; v < 50; ++v)
    for (int u = 0; u < 50; ++u) scene.labels.confidence[static_cast<std::size_t>(v * 200 + u)] = 0.8f;
  TableConfig config;
  config.min_confidence = 0.5f;
  const auto d = detectTables(scene.cloud, scene.labels, config);
  ASSERT_EQ(d.tables.size(), 1u);
  EXPECT_NEAR(d.tables[0].mean_confidence, 0.8f, 1e-5f);
  EXPECT_NEAR(d.tables[0].centroid.x(), 0.245f, 0.01f);
}

TEST(TableDecisionSettings, OutOfRangeValuesNameTheSetting) {
  TableConfig c;
  c.table_weight = 0.0f;
  EXPECT_THAT([&] { validateTableConfig(c); },
              ::testing::Throws<Error>());
  try {
    validateTableConfig(c);
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("tables.table_weight"));
  }
  c = TableConfig{};
  c.min_confidence = 1.5f;
  try {
    validateTableConfig(c);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("tables.min_confidence"));
  }
  c = TableConfig{};
  c.min_horizontal_share = -0.1f;
  try {
    validateTableConfig(c);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("tables.min_horizontal_share"));
  }
  c = TableConfig{};
  c.region_max_tilt_deg = 95.0f;
  try {
    validateTableConfig(c);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("tables.region_max_tilt_deg"));
  }
}

TEST(PrecisionRecallCurve, HandMadeScoredDetections) {
  // 4 true instances; detections by score: 0.9 hit, 0.8 hit, 0.8 miss, 0.6 miss, 0.5 hit.
  const std::vector<ScoredDetection> d{
      {0.6f, false}, {0.9f, true}, {0.8f, true}, {0.5f, true}, {0.8f, false}};
  const auto curve = precisionRecallCurve(d, 4);
  ASSERT_EQ(curve.size(), 4u);  // the two 0.8 scores are one threshold
  EXPECT_FLOAT_EQ(curve[0].threshold, 0.9f);
  EXPECT_EQ(curve[0].detected, 1);
  EXPECT_DOUBLE_EQ(curve[0].precision, 1.0);
  EXPECT_DOUBLE_EQ(curve[0].recall, 0.25);
  EXPECT_FLOAT_EQ(curve[1].threshold, 0.8f);
  EXPECT_EQ(curve[1].detected, 3);
  EXPECT_EQ(curve[1].matched, 2);
  EXPECT_DOUBLE_EQ(curve[1].precision, 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(curve[1].recall, 0.5);
  EXPECT_DOUBLE_EQ(curve[2].precision, 0.5);
  EXPECT_DOUBLE_EQ(curve[3].precision, 0.6);
  EXPECT_DOUBLE_EQ(curve[3].recall, 0.75);

  const PrecisionRecallPoint* at80 = operatingPoint(curve, 0.8);
  ASSERT_NE(at80, nullptr);
  EXPECT_FLOAT_EQ(at80->threshold, 0.9f);
  const PrecisionRecallPoint* at60 = operatingPoint(curve, 0.6);
  ASSERT_NE(at60, nullptr);
  EXPECT_FLOAT_EQ(at60->threshold, 0.5f);  // recall 0.75 at precision 0.6
  EXPECT_DOUBLE_EQ(at60->recall, 0.75);
  EXPECT_EQ(operatingPoint(curve, 1.01), nullptr);
  EXPECT_TRUE(precisionRecallCurve({}, 3).empty());
  EXPECT_THROW(precisionRecallCurve({{std::nanf(""), true}}, 1), Error);
}

}  // namespace
}  // namespace findmug
