// Tests for the searchable-table figures of table_metrics.hpp (tables a robot
// can search: visible top >= 0.15 m2, matched by top overlap, false tables per
// frame), on hand-made ground-frame clouds and hand-made table tops whose
// answers follow from their construction.
#include <gtest/gtest.h>

#include <cmath>

#include "findmug/error.hpp"
#include "findmug/labels.hpp"
#include "findmug/table_map.hpp"
#include "findmug/table_metrics.hpp"
#include "findmug/tables.hpp"

namespace findmug {
namespace {

constexpr std::uint8_t kTable = static_cast<std::uint8_t>(Label::Table);
constexpr std::uint8_t kFloor = static_cast<std::uint8_t>(Label::Floor);
constexpr std::uint8_t kObject = static_cast<std::uint8_t>(Label::Object);

// A top-down "scene" in the ground frame: pixel (u, v) is the point
// (0.01 u, 0.01 v, height), so pixel rectangles are tops of known size.
struct Scene {
  static constexpr int kW = 200, kH = 100;
  OrganizedCloud cloud;
  std::vector<std::uint8_t> truth;
  Scene() {
    cloud.width = kW;
    cloud.height = kH;
    for (int v = 0; v < kH; ++v)
      for (int u = 0; u < kW; ++u) cloud.points.emplace_back(0.01f * u, 0.01f * v, 0.0f);
    cloud.colors.assign(cloud.points.size(), Rgb8{0, 0, 0});
    truth.assign(cloud.points.size(), kFloor);
  }
  void box(int u0, int u1, int v0, int v1, float height, std::uint8_t label) {
    for (int v = v0; v < v1; ++v) {
      for (int u = u0; u < u1; ++u) {
        const auto i = static_cast<std::size_t>(v * kW + u);
        cloud.points[i].z() = height;
        truth[i] = label;
      }
    }
  }
  static void paint(std::vector<std::uint8_t>& labels, int u0, int u1, int v0, int v1,
                    std::uint8_t label) {
    for (int v = v0; v < v1; ++v)
      for (int u = u0; u < u1; ++u) labels[static_cast<std::size_t>(v * kW + u)] = label;
  }
  LabelImage image(const std::vector<std::uint8_t>& labels) const {
    return LabelImage{kW, kH, labels, {}};
  }
};

// Desk A: 1.2 x 0.4 m = 0.48 m2 at 0.75 m (searchable); side table C:
// 0.35 x 0.35 m = 0.1225 m2 at 0.45 m (an instance, 1225 points, too small to
// search); a box (object) 0.5 x 0.35 m at 0.6 m, large enough to be detected.
Scene deskSideTableAndBox() {
  Scene s;
  s.box(10, 130, 10, 50, 0.75f, kTable);
  s.box(150, 185, 10, 45, 0.45f, kTable);
  s.box(150, 200, 60, 95, 0.6f, kObject);
  return s;
}

// A hand-made top: the axis-aligned rectangle [x0, x1] x [y0, y1] at `height`.
TableCluster top(float x0, float x1, float y0, float y1, float height) {
  TableCluster t;
  t.hull = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
  t.top_area_m2 = (x1 - x0) * (y1 - y0);
  t.top_height = height;
  return t;
}

TEST(SearchableTables, PolygonOverlapHasItsKnownArea) {
  const std::vector<Eigen::Vector2f> unit = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  const std::vector<Eigen::Vector2f> shifted = {{0.5f, 0.25f}, {1.5f, 0.25f}, {1.5f, 1.25f},
                                                {0.5f, 1.25f}};
  EXPECT_NEAR(polygonArea(unit), 1.0, 1e-12);
  EXPECT_NEAR(convexOverlapArea(unit, shifted), 0.5 * 0.75, 1e-6);
  // Clockwise order gives the same area.
  const std::vector<Eigen::Vector2f> clockwise(shifted.rbegin(), shifted.rend());
  EXPECT_NEAR(convexOverlapArea(unit, clockwise), 0.375, 1e-6);
  // A triangle over the square's diagonal: half of it.
  const std::vector<Eigen::Vector2f> triangle = {{0, 0}, {2, 0}, {0, 2}};
  EXPECT_NEAR(convexOverlapArea(unit, triangle), 1.0, 1e-6);
  const std::vector<Eigen::Vector2f> diagonal = {{0, 0}, {1, 0}, {0, 1}};
  EXPECT_NEAR(convexOverlapArea(unit, diagonal), 0.5, 1e-6);
  // Apart: nothing in common; degenerate: nothing.
  const std::vector<Eigen::Vector2f> far = {{3, 3}, {4, 3}, {4, 4}};
  EXPECT_EQ(convexOverlapArea(unit, far), 0.0);
  EXPECT_EQ(convexOverlapArea(unit, {{0, 0}, {1, 1}}), 0.0);
}

TEST(SearchableTables, GroundTruthAsPredictionFindsEverySearchableTable) {
  const Scene s = deskSideTableAndBox();
  const TableConfig tables;
  const TableMetricsConfig config;
  const auto truth = groundTruthTables(s.cloud, s.truth, tables, config);
  ASSERT_EQ(truth.size(), 2u);
  EXPECT_NEAR(truth[0].top_area_m2, 0.48f, 0.03f);
  EXPECT_LT(truth[1].top_area_m2, config.searchable_min_top_area_m2);
  const auto detected = detectTables(s.cloud, s.image(s.truth), tables).tables;
  const SearchableFrame frame = measureSearchableTables(truth, detected, config);
  EXPECT_EQ(frame.searchable, 1);
  EXPECT_EQ(frame.searchable_matched, 1);
  EXPECT_EQ(frame.detected, static_cast<int>(detected.size()));
  EXPECT_EQ(frame.detected_small, frame.detected - 1);  // the side table, if detected
  EXPECT_EQ(frame.false_tables, 0);
  SearchableMetrics metrics;
  metrics.add(frame);
  EXPECT_DOUBLE_EQ(metrics.precision(), 1.0);
  EXPECT_DOUBLE_EQ(metrics.recall(), 1.0);
  EXPECT_DOUBLE_EQ(metrics.falseTableFrameShare(), 0.0);
}

TEST(SearchableTables, HalfADeskMatchesAndABoxIsAFalseTable) {
  const Scene s = deskSideTableAndBox();
  const TableConfig tables;
  const TableMetricsConfig config;
  const auto truth = groundTruthTables(s.cloud, s.truth, tables, config);
  // The desk's left half (inside the desk's top: overlap 1 of the smaller
  // hull), the box called table, the side table missed.
  std::vector<std::uint8_t> predicted(s.truth.size(), kFloor);
  Scene::paint(predicted, 10, 65, 10, 50, kTable);
  Scene::paint(predicted, 150, 200, 60, 95, kTable);
  const auto detected = detectTables(s.cloud, s.image(predicted), tables).tables;
  ASSERT_EQ(detected.size(), 2u);
  const SearchableFrame frame = measureSearchableTables(truth, detected, config);
  EXPECT_EQ(frame.searchable, 1);
  EXPECT_EQ(frame.searchable_matched, 1);
  EXPECT_EQ(frame.detected, 2);
  EXPECT_EQ(frame.detected_small, 0);
  EXPECT_EQ(frame.false_tables, 1);
  // The instance metric (image IoU 0.5) does not match the half desk.
  EXPECT_TRUE(matchTables(truth, detected, config.min_iou).empty());

  // With a frame of nothing detected and nothing true: a false table in one
  // frame of two; precision 1 of 2 detections, recall 1 of 1.
  SearchableMetrics metrics;
  metrics.add(frame);
  metrics.add(measureSearchableTables({}, {}, config));
  EXPECT_EQ(metrics.frames(), 2);
  EXPECT_EQ(metrics.framesWithFalseTable(), 1);
  EXPECT_DOUBLE_EQ(metrics.falseTableFrameShare(), 0.5);
  EXPECT_DOUBLE_EQ(metrics.precision(), 0.5);
  EXPECT_DOUBLE_EQ(metrics.recall(), 1.0);

  // Requiring a larger top makes the desk unsearchable too: no recall to
  // measure, and the half desk then matches a small table (left out).
  TableMetricsConfig strict = config;
  strict.searchable_min_top_area_m2 = 0.5f;
  const SearchableFrame none = measureSearchableTables(truth, detected, strict);
  EXPECT_EQ(none.searchable, 0);
  EXPECT_EQ(none.detected_small, 1);
  SearchableMetrics strict_metrics;
  strict_metrics.add(none);
  EXPECT_TRUE(std::isnan(strict_metrics.recall()));
  EXPECT_DOUBLE_EQ(strict_metrics.precision(), 0.0);
}

TEST(SearchableTables, OverlapHeightAndOneToOneDecideAMatch) {
  const TableMetricsConfig config;
  const std::vector<TableCluster> truth = {top(0, 1, 0, 1, 0.75f)};  // 1 m2
  // Overlap 0.4 of the smaller (0.4 of a 1 m2 detection): no match.
  EXPECT_EQ(measureSearchableTables(truth, {top(0.6f, 1.6f, 0, 1, 0.75f)}, config).false_tables,
            1);
  // Overlap 0.6: a match.
  EXPECT_EQ(
      measureSearchableTables(truth, {top(0.4f, 1.4f, 0, 1, 0.75f)}, config).searchable_matched, 1);
  // Same top, 0.2 m higher (a shelf above the table): no match.
  EXPECT_EQ(measureSearchableTables(truth, {top(0, 1, 0, 1, 0.95f)}, config).false_tables, 1);
  // 0.1 m higher: a match.
  EXPECT_EQ(measureSearchableTables(truth, {top(0, 1, 0, 1, 0.85f)}, config).searchable_matched,
            1);
  // Two pieces of one table: the better one matches, the other is false.
  const SearchableFrame split = measureSearchableTables(
      truth, {top(0, 0.3f, 0, 1, 0.75f), top(0.2f, 1, 0, 1, 0.75f)}, config);
  EXPECT_EQ(split.searchable_matched, 1);
  EXPECT_EQ(split.false_tables, 1);
  TableMetricsConfig bad = config;
  bad.searchable_min_overlap = 0.0f;
  EXPECT_THROW(measureSearchableTables(truth, {}, bad), Error);
}

}  // namespace
}  // namespace findmug
