// Tests of the objects standing on table tops (table_objects.hpp).
//
// Three groups: hand-built point sets laid out in an organized cloud, where
// the answer is known to the millimetre (steps 1-4, flags, colour,
// relabelling, settings and bad input); rendered synthetic rooms whose
// every mug, box and book is known (findmug_synth), with the renderer's true
// labels; and NYU Depth V2 frames with their ground-truth labels.
#include "findmug/objects/table_objects.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <numeric>
#include <set>
#include <string>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/common/error.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/ground/ground.hpp"
#include "findmug/labels/labels.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "findmug/settings/config.hpp"
#include "findmug/synth/synth.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

using ::testing::HasSubstr;

constexpr float kTop = 0.75f;  // the hand-built table's top height
constexpr float kPi = 3.14159265358979f;
constexpr Rgb8 kRed{255, 0, 0}, kBlue{0, 0, 255}, kGrey{128, 128, 128};

// An organized cloud filled block by block with hand-made point sets: the
// geometry is exact, the pixel layout arbitrary (the stage uses the grid
// only as a clustering shortcut, for its pixel lists and the border and hole
// flags). Empty pixels are NaN with the void label.
struct Frame {
  OrganizedCloud cloud;
  LabelImage labels;
  int next_row = 4;  // blocks go one below the other, 4 px from the left edge

  explicit Frame(int width = 320, int height = 320) {
    cloud.width = labels.width = width;
    cloud.height = labels.height = height;
    const auto n = static_cast<std::size_t>(width) * height;
    cloud.points.assign(n, Eigen::Vector3f::Constant(std::nanf("")));
    cloud.colors.assign(n, Rgb8{});
    labels.labels.assign(n, kVoidLabel);
    labels.confidence.assign(n, 0.0f);
  }
  // Puts `points` in rows of `cols` pixels starting at column `col`; returns their pixels.
  std::vector<int> add(const std::vector<Eigen::Vector3f>& points, int cols, Label label,
                       Rgb8 colour = kGrey, int col = 4) {
    std::vector<int> pixels;
    for (std::size_t k = 0; k < points.size(); ++k) {
      const int x = col + static_cast<int>(k) % cols;
      const int y = next_row + static_cast<int>(k) / cols;
      const int i = y * cloud.width + x;
      cloud.points[static_cast<std::size_t>(i)] = points[k];
      cloud.colors[static_cast<std::size_t>(i)] = colour;
      labels.labels[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(label);
      labels.confidence[static_cast<std::size_t>(i)] = 1.0f;
      pixels.push_back(i);
    }
    next_row += (static_cast<int>(points.size()) + cols - 1) / cols + 2;
    return pixels;
  }
};

// The table top: x in [0, 1.2], y in [-0.5, 0.5] at z = kTop, 1 cm apart (121 columns).
std::vector<Eigen::Vector3f> topPoints(float noise_m = 0.0f) {
  std::vector<Eigen::Vector3f> points;
  for (int j = 0; j <= 100; ++j) {
    for (int i = 0; i <= 120; ++i) {
      // A deterministic ripple of +-noise_m: depth noise on the top.
      const float dz = noise_m * std::sin(0.7f * static_cast<float>(i * 13 + j * 7));
      points.emplace_back(0.01f * static_cast<float>(i), -0.5f + 0.01f * static_cast<float>(j),
                          kTop + dz);
    }
  }
  return points;
}

TableCluster handBuiltTable() {
  TableCluster t;
  t.top_height = kTop;
  t.hull = {{0.0f, -0.5f}, {1.2f, -0.5f}, {1.2f, 0.5f}, {0.0f, 0.5f}};
  t.centroid = Eigen::Vector3f(0.6f, 0.0f, kTop);
  return t;
}

// The side of a vertical cylinder standing on the top: 72 columns (5°) by
// rows 5 mm apart from 1 mm above the top (clear of min_height_m's edge) up to
// `height` + 1 mm.
constexpr int kCylinderCols = 72;
std::vector<Eigen::Vector3f> cylinderPoints(Eigen::Vector2f centre, float radius, float height) {
  std::vector<Eigen::Vector3f> points;
  const int rows = static_cast<int>(std::lround(height / 0.005f));
  for (int r = 0; r <= rows; ++r) {
    for (int a = 0; a < kCylinderCols; ++a) {
      const float angle = 2.0f * kPi * static_cast<float>(a) / kCylinderCols;
      points.emplace_back(centre.x() + radius * std::cos(angle),
                          centre.y() + radius * std::sin(angle),
                          kTop + 0.001f + 0.005f * static_cast<float>(r));
    }
  }
  return points;
}

// A vertical panel along y (a wall, a chair back): x fixed, y in [y0, y1], z in [z0, z1], 1 cm.
std::vector<Eigen::Vector3f> panelPoints(float x, float y0, float y1, float z0, float z1,
                                         int& cols) {
  std::vector<Eigen::Vector3f> points;
  cols = static_cast<int>(std::lround((y1 - y0) / 0.01f)) + 1;
  const int rows = static_cast<int>(std::lround((z1 - z0) / 0.01f)) + 1;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      points.emplace_back(x, y0 + 0.01f * static_cast<float>(c),
                          z0 + 0.01f * static_cast<float>(r));
    }
  }
  return points;
}

// The mean of the points at least min_height above the top.
Eigen::Vector3f meanAbove(const std::vector<Eigen::Vector3f>& points, float min_height) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int n = 0;
  for (const auto& p : points) {
    if (p.z() < kTop + min_height) continue;
    sum += p.cast<double>();
    ++n;
  }
  return (sum / n).cast<float>();
}

// The hand-built blocks lay points out in the image without regard to their
// places in 3-D, so they are clustered exactly (point_stride 1), whatever
// `config` says; the sampled clustering, which links image neighbours, has
// its own tests below, on blocks laid out as a camera would see them.
TableObjectDetection run(const Frame& f, const TableObjectConfig& config = {}) {
  TableObjectConfig exact = config;
  exact.point_stride = 1;
  return findTableObjects(f.cloud, f.labels, {handBuiltTable()}, exact);
}

TableObjectDetection runSampled(const Frame& f, int stride) {
  TableObjectConfig config;
  config.point_stride = stride;
  return findTableObjects(f.cloud, f.labels, {handBuiltTable()}, config);
}

// ------------------------------------------------------------ hand-built ----

TEST(TableObjects, MugOnTheTopIsOneCandidateWithItsGeometry) {
  Frame f;
  f.add(topPoints(), 121, Label::Table);
  const auto mug = cylinderPoints({0.6f, 0.1f}, 0.04f, 0.10f);
  const std::vector<int> mug_pixels = f.add(mug, kCylinderCols, Label::Object, kRed);
  const TableObjectDetection d = run(f);
  ASSERT_EQ(d.objects.size(), 1u);
  const TableObject& o = d.objects[0];
  EXPECT_EQ(o.id, 0);
  EXPECT_EQ(o.table, 0);
  // Rows at 0 and 5 mm are below min_height_m (1 cm): 19 rows of 72.
  EXPECT_EQ(o.point_count, 19 * kCylinderCols);
  EXPECT_EQ(d.points_above_tops, 19 * kCylinderCols);
  const Eigen::Vector3f expected = meanAbove(mug, TableObjectConfig{}.min_height_m);
  EXPECT_NEAR(o.centroid.x(), 0.6f, 1e-3f);
  EXPECT_NEAR(o.centroid.y(), 0.1f, 1e-3f);
  EXPECT_NEAR(o.centroid.z(), expected.z(), 1e-3f);
  EXPECT_NEAR(o.centroid.z(), kTop + 0.056f, 1e-3f);
  EXPECT_NEAR(o.height_above_top, 0.101f, 1e-3f);
  // A circle's footprint box: the radius along both axes, centred on the axis.
  EXPECT_NEAR(o.extents.x(), 0.04f, 1e-3f);
  EXPECT_NEAR(o.extents.y(), 0.04f, 1e-3f);
  EXPECT_NEAR(o.center.x(), 0.6f, 1e-3f);
  EXPECT_NEAR(o.center.y(), 0.1f, 1e-3f);
  EXPECT_NEAR(o.major_axis.norm(), 1.0f, 1e-5f);
  EXPECT_EQ(o.truncation & (kTruncatedOutline | kTruncatedBorder), 0);
  // Its pixels, ascending: the mug's rows above 1 cm.
  const std::vector<int> expected_pixels(mug_pixels.begin() + 2 * kCylinderCols, mug_pixels.end());
  EXPECT_EQ(o.pixels, expected_pixels);
  EXPECT_TRUE(std::is_sorted(o.pixels.begin(), o.pixels.end()));
  // A red mug: mean colour and the red, saturated bin.
  EXPECT_NEAR((o.mean_rgb - Eigen::Vector3f(255, 0, 0)).norm(), 0.0f, 1e-3f);
  EXPECT_FLOAT_EQ(o.colour_histogram[1], 1.0f);
  EXPECT_EQ(d.clusters_too_small, 0);
  EXPECT_EQ(d.clusters_not_standing, 0);
}

// A box-like object's footprint: the axes follow its long side.
TEST(TableObjects, FootprintAxesFollowALongObject) {
  Frame f;
  f.add(topPoints(), 121, Label::Table);
  // A 30 cm x 6 cm book lying along the diagonal (45°), 4 cm high: its four sides.
  std::vector<Eigen::Vector3f> book;
  const Eigen::Vector2f c(0.5f, -0.1f), a(std::sqrt(0.5f), std::sqrt(0.5f)), b(-a.y(), a.x());
  for (int h = 0; h <= 8; ++h) {
    const float z = kTop + 0.005f * static_cast<float>(h);
    for (int s = -30; s <= 30; ++s) {
      const float u = 0.005f * static_cast<float>(s);
      for (const float v : {-0.03f, 0.03f}) {
        const Eigen::Vector2f p = c + u * a + v * b;
        book.emplace_back(p.x(), p.y(), z);
      }
    }
    for (int s = -6; s <= 6; ++s) {
      const float v = 0.005f * static_cast<float>(s);
      for (const float u : {-0.15f, 0.15f}) {
        const Eigen::Vector2f p = c + u * a + v * b;
        book.emplace_back(p.x(), p.y(), z);
      }
    }
  }
  f.add(book, 100, Label::Object);
  const TableObjectDetection d = run(f);
  ASSERT_EQ(d.objects.size(), 1u);
  const TableObject& o = d.objects[0];
  EXPECT_NEAR(std::abs(o.major_axis.dot(a)), 1.0f, 1e-3f);
  EXPECT_GE(o.major_axis.x(), 0.0f);  // one direction of the two
  EXPECT_NEAR(o.extents.x(), 0.15f, 1e-3f);
  EXPECT_NEAR(o.extents.y(), 0.03f, 1e-3f);
  EXPECT_NEAR((o.center - c).norm(), 0.0f, 1e-3f);
}

// An object half over the top's edge: its footprint hides the top under it,
// but it stands there; points within 1 cm of the grown outline flag it.
TEST(TableObjects, ObjectOverTheEdgeIsFoundAndFlagged) {
  Frame f;
  f.add(topPoints(), 121, Label::Table);
  // Centre 5 mm inside the edge x = 1.2; it reaches x = 1.245, the grown
  // outline is at 1.25.
  f.add(cylinderPoints({1.195f, 0.0f}, 0.05f, 0.1f), kCylinderCols, Label::Object);
  // And one well inside, for comparison.
  f.add(cylinderPoints({0.4f, 0.0f}, 0.05f, 0.08f), kCylinderCols, Label::Object);
  const TableObjectDetection d = run(f);
  ASSERT_EQ(d.objects.size(), 2u);
  const TableObject& edge = d.objects[0];  // the taller one has more points
  EXPECT_NEAR(edge.centroid.x(), 1.195f, 2e-3f);
  EXPECT_NE(edge.truncation & kTruncatedOutline, 0);
  EXPECT_EQ(d.objects[1].truncation & kTruncatedOutline, 0);
  // Without the margin the part beyond the top is cut off and it is flagged all the same.
  TableObjectConfig no_margin;
  no_margin.outline_margin_m = 0.0f;
  const TableObjectDetection cut = run(f, no_margin);
  ASSERT_EQ(cut.objects.size(), 2u);
  EXPECT_LT(cut.objects[1].point_count, edge.point_count);
}

// A wall rising through the grown outline behind the table stands on
// nothing: wall points are never looked at. The same points with another
// label would be (and are then rejected as too long).
TEST(TableObjects, WallBehindTheTableIsNoCandidate) {
  int cols = 0;
  const auto wall = panelPoints(1.23f, -0.6f, 0.6f, 0.0f, 1.6f, cols);
  Frame f;
  f.add(topPoints(), 121, Label::Table);
  f.add(wall, cols, Label::Wall);
  const TableObjectDetection d = run(f);
  EXPECT_TRUE(d.objects.empty());
  EXPECT_EQ(d.points_above_tops, 0);
  EXPECT_EQ(d.clusters_not_standing, 0);

  Frame unknown;
  unknown.add(topPoints(), 121, Label::Table);
  unknown.add(wall, cols, Label::Unknown);
  const TableObjectDetection u = run(unknown);
  EXPECT_TRUE(u.objects.empty());
  EXPECT_GT(u.points_above_tops, 0);
  EXPECT_EQ(u.clusters_not_standing, 1);
}

// A chair back at the edge: too long a footprint. A lamp shade above the
// top: its base is too high. Both dropped, counted and explained.
TEST(TableObjects, ChairBackAndHoveringThingsAreRejectedAndCounted) {
  int cols = 0;
  Frame f;
  f.add(topPoints(), 121, Label::Table);
  const auto chair_back = panelPoints(1.15f, -0.35f, 0.35f, 0.45f, 1.1f, cols);
  f.add(chair_back, cols, Label::Chair);
  const TableObjectDetection d = run(f);
  EXPECT_TRUE(d.objects.empty());
  EXPECT_EQ(d.clusters_not_standing, 1);
  ASSERT_FALSE(d.diagnostics.empty());
  EXPECT_THAT(d.diagnostics[0], HasSubstr("table_objects.max_extent_m"));

  Frame lamp;
  lamp.add(topPoints(), 121, Label::Table);
  const auto shade = panelPoints(0.6f, -0.1f, 0.1f, kTop + 0.2f, kTop + 0.35f, cols);
  lamp.add(shade, cols, Label::Unknown);
  const TableObjectDetection l = run(lamp);
  EXPECT_TRUE(l.objects.empty());
  EXPECT_EQ(l.clusters_not_standing, 1);
  ASSERT_FALSE(l.diagnostics.empty());
  EXPECT_THAT(l.diagnostics[0], HasSubstr("table_objects.max_base_height_m"));
  // Allowed a higher base, the same panel is a candidate.
  TableObjectConfig high;
  high.max_base_height_m = 0.25f;
  EXPECT_EQ(run(lamp, high).objects.size(), 1u);
}

TEST(TableObjects, TwoObjectsTenCentimetresApartAreTwoCandidatesBySize) {
  Frame f;
  f.add(topPoints(), 121, Label::Table);
  // Gap between the sides: 0.18 - 2 x 0.04 = 0.10 m.
  const auto small_pixels =
      f.add(cylinderPoints({0.5f, 0.0f}, 0.04f, 0.06f), kCylinderCols, Label::Object);
  const auto big_pixels =
      f.add(cylinderPoints({0.68f, 0.0f}, 0.04f, 0.12f), kCylinderCols, Label::Object);
  const TableObjectDetection d = run(f);
  ASSERT_EQ(d.objects.size(), 2u);
  EXPECT_EQ(d.objects[0].id, 0);
  EXPECT_EQ(d.objects[1].id, 1);
  EXPECT_GT(d.objects[0].point_count, d.objects[1].point_count);
  EXPECT_NEAR(d.objects[0].centroid.x(), 0.68f, 1e-3f);
  EXPECT_NEAR(d.objects[1].centroid.x(), 0.5f, 1e-3f);
  EXPECT_EQ(d.objects[0].pixels.back(), big_pixels.back());
  EXPECT_EQ(d.objects[1].pixels.back(), small_pixels.back());
}

// Clutter: a mug touching a long unlabelled thing (a keyboard, a cable) is
// one cluster too long to stand; split by label, the mug stands on its own.
// The same with the long thing labelled Table: it is more of the table.
TEST(TableObjects, ClutterOfSeveralLabelsIsSplitByLabel) {
  int cols = 0;
  const auto keyboard = panelPoints(0.645f, -0.4f, 0.4f, kTop + 0.011f, kTop + 0.05f, cols);
  for (const Label other : {Label::Unknown, Label::Table}) {
    Frame f;
    f.add(topPoints(), 121, Label::Table);
    f.add(cylinderPoints({0.6f, 0.0f}, 0.04f, 0.1f), kCylinderCols, Label::Object);
    f.add(keyboard, cols, other);
    const TableObjectDetection d = run(f);
    ASSERT_EQ(d.objects.size(), 1u) << kLabelNames[static_cast<int>(other)];
    EXPECT_EQ(d.objects[0].point_count, 19 * kCylinderCols);
    EXPECT_NEAR(d.objects[0].centroid.x(), 0.6f, 1e-3f);
    EXPECT_EQ(d.clusters_not_standing, 1);
    ASSERT_FALSE(d.diagnostics.empty());
    EXPECT_THAT(d.diagnostics[0], HasSubstr("table_objects.max_extent_m"));
    // One label: no split, no candidate.
    Frame one;
    one.add(topPoints(), 121, Label::Table);
    one.add(cylinderPoints({0.6f, 0.0f}, 0.04f, 0.1f), kCylinderCols, Label::Object);
    one.add(keyboard, cols, Label::Object);
    EXPECT_TRUE(run(one).objects.empty());
  }
}

// A top seen tilted (here rising 4 cm over its 1.2 m, a gravity estimate 2°
// off): its far end rises above min_height_m. Above the local tops only the mug
// stands out; above the one top height the far end of the top is one more,
// huge cluster.
TEST(TableObjects, TiltedTopIsNotAnObject) {
  Frame f;
  std::vector<Eigen::Vector3f> top = topPoints(0.002f);
  for (auto& p : top) p.z() += 0.04f * p.x() / 1.2f;
  f.add(top, 121, Label::Table);
  auto mug = cylinderPoints({0.3f, 0.0f}, 0.04f, 0.1f);
  for (auto& p : mug) p.z() += 0.01f;  // the top is 1 cm higher there
  f.add(mug, kCylinderCols, Label::Object);
  TableObjectConfig cells;
  cells.top_cell_m = 0.1f;
  const TableObjectDetection local = run(f, cells);
  ASSERT_EQ(local.objects.size(), 1u);
  EXPECT_NEAR(local.objects[0].centroid.x(), 0.3f, 1e-3f);
  EXPECT_NEAR(local.objects[0].height_above_top, 0.1f, 0.01f);
  EXPECT_EQ(local.clusters_not_standing, 0);
  const TableObjectDetection d = run(f);
  EXPECT_EQ(d.clusters_not_standing, 1);
  EXPECT_GT(d.points_above_tops, local.points_above_tops + 3000);
}

// The top's own depth noise (5 mm) is below min_height_m; a few stray
// points above it form clusters too small to count.
TEST(TableObjects, TopNoiseAndStrayPointsAreNoCandidates) {
  Frame f;
  f.add(topPoints(0.005f), 121, Label::Table);
  EXPECT_TRUE(run(f).objects.empty());
  EXPECT_EQ(run(f).points_above_tops, 0);
  // 5 stray points 2 cm above the top, far apart.
  std::vector<Eigen::Vector3f> stray;
  for (int k = 0; k < 5; ++k) stray.emplace_back(0.1f + 0.2f * k, 0.2f, kTop + 0.02f);
  f.add(stray, 5, Label::Table);
  const TableObjectDetection d = run(f);
  EXPECT_TRUE(d.objects.empty());
  EXPECT_EQ(d.points_above_tops, 5);
  EXPECT_EQ(d.clusters_too_small, 5);
  ASSERT_EQ(d.diagnostics.size(), 1u);
  EXPECT_THAT(d.diagnostics[0], HasSubstr("table_objects.min_points"));
}

TEST(TableObjects, ObjectOnTheImageBorderIsFlagged) {
  Frame f;
  f.add(topPoints(), 121, Label::Table);
  f.add(cylinderPoints({0.3f, 0.0f}, 0.04f, 0.1f), kCylinderCols, Label::Object, kGrey, 0);
  f.add(cylinderPoints({0.9f, 0.0f}, 0.04f, 0.08f), kCylinderCols, Label::Object, kGrey, 40);
  const TableObjectDetection d = run(f);
  ASSERT_EQ(d.objects.size(), 2u);
  EXPECT_NE(d.objects[0].truncation & kTruncatedBorder, 0);  // column 0
  EXPECT_EQ(d.objects[1].truncation & kTruncatedBorder, 0);
}

// A candidate whose outline runs along missing depth may be cut by it.
TEST(TableObjects, ObjectBesideMissingDepthIsFlagged) {
  Frame f;
  f.add(topPoints(), 121, Label::Table);
  // Laid out with the same pixels around it as a top: valid depth on every side ...
  const auto mug = cylinderPoints({0.6f, 0.0f}, 0.04f, 0.1f);
  const int first_row = f.next_row;
  f.add(mug, kCylinderCols, Label::Object);
  // ... made so by filling the block's surroundings with table points far away.
  for (int y = first_row - 1; y <= first_row + 21; ++y) {
    for (int x = 3; x <= 4 + kCylinderCols; ++x) {
      const auto i = static_cast<std::size_t>(y * f.cloud.width + x);
      if (std::isfinite(f.cloud.points[i].z())) continue;
      f.cloud.points[i] = Eigen::Vector3f(5.0f, 5.0f, 0.0f);
      f.labels.labels[i] = static_cast<std::uint8_t>(Label::Floor);
    }
  }
  const TableObjectDetection solid = run(f);
  ASSERT_EQ(solid.objects.size(), 1u);
  EXPECT_EQ(solid.objects[0].truncation & kTruncatedDepthHole, 0);
  // Holes along its left side and top: more than a quarter of its edge.
  for (int y = first_row - 1; y <= first_row + 21; ++y) {
    f.cloud.points[static_cast<std::size_t>(y * f.cloud.width + 3)] =
        Eigen::Vector3f::Constant(std::nanf(""));
  }
  for (int x = 3; x <= 4 + kCylinderCols; ++x) {
    f.cloud.points[static_cast<std::size_t>((first_row + 19) * f.cloud.width + x)] =
        Eigen::Vector3f::Constant(std::nanf(""));
  }
  const TableObjectDetection holed = run(f);
  ASSERT_EQ(holed.objects.size(), 1u);
  EXPECT_NE(holed.objects[0].truncation & kTruncatedDepthHole, 0);
}

TEST(TableObjects, ColourHistogramsOfRedAndBlueDifferInTheirHueBins) {
  const ObjectColourHistogram red = objectColourHistogram(std::vector<Rgb8>(50, kRed));
  const ObjectColourHistogram blue = objectColourHistogram(std::vector<Rgb8>(50, kBlue));
  // Hue 0° sector 0, hue 240° sector 8; fully saturated: the upper band.
  EXPECT_FLOAT_EQ(red[1], 1.0f);
  EXPECT_FLOAT_EQ(blue[17], 1.0f);
  EXPECT_FLOAT_EQ(std::accumulate(red.begin(), red.end(), 0.0f), 1.0f);
  EXPECT_FLOAT_EQ(std::accumulate(blue.begin(), blue.end(), 0.0f), 1.0f);
  // Pale red (saturation 0.3): the lower band of the same sector.
  EXPECT_FLOAT_EQ(objectColourHistogram({Rgb8{200, 140, 140}})[0], 1.0f);
  // Achromatic: black, dark grey, light grey, white.
  const auto grey = objectColourHistogram(
      {Rgb8{10, 10, 10}, Rgb8{100, 100, 100}, Rgb8{170, 170, 170}, Rgb8{250, 250, 250}});
  for (int b = 24; b < 28; ++b) EXPECT_FLOAT_EQ(grey[static_cast<std::size_t>(b)], 0.25f) << b;
  // Half and half.
  std::vector<Rgb8> mixed(10, kRed);
  mixed.insert(mixed.end(), 30, kBlue);
  const auto m = objectColourHistogram(mixed);
  EXPECT_FLOAT_EQ(m[1], 0.25f);
  EXPECT_FLOAT_EQ(m[17], 0.75f);
  const auto none = objectColourHistogram({});
  EXPECT_FLOAT_EQ(std::accumulate(none.begin(), none.end(), 0.0f), 0.0f);
}

TEST(TableObjects, RelabellingChangesOnlyTablePixels) {
  LabelImage labels;
  labels.width = 4;
  labels.height = 2;
  labels.labels = {4, 4, 5, 7, 4, 2, 4, 4};
  labels.confidence.assign(8, 1.0f);
  std::vector<TableObject> objects(2);
  objects[0].pixels = {0, 2, 3};
  objects[1].pixels = {4, 5};
  EXPECT_EQ(relabelTableObjects(objects, labels), 2);
  const std::vector<std::uint8_t> expected = {7, 4, 5, 7, 7, 2, 4, 4};
  EXPECT_EQ(labels.labels, expected);
  // A pixel outside the image: refused, and nothing changed.
  objects[1].pixels = {6, 8};
  EXPECT_THROW(relabelTableObjects(objects, labels), Error);
  EXPECT_EQ(labels.labels, expected);
}

TEST(TableObjects, BadSettingsAreRefusedByName) {
  auto refusal = [](auto change) {
    TableObjectConfig c;
    change(c);
    try {
      validateTableObjectConfig(c);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_THAT(refusal([](auto& c) { c.min_height_m = -0.1f; }),
              HasSubstr("table_objects.min_height_m"));
  EXPECT_THAT(refusal([](auto& c) { c.max_height_m = 5.0f; }),
              HasSubstr("table_objects.max_height_m"));
  EXPECT_THAT(refusal([](auto& c) {
                c.min_height_m = 0.5f;
                c.max_height_m = 0.4f;
              }),
              HasSubstr("table_objects.min_height_m"));
  EXPECT_THAT(refusal([](auto& c) { c.outline_margin_m = std::nanf(""); }),
              HasSubstr("table_objects.outline_margin_m"));
  EXPECT_THAT(refusal([](auto& c) { c.cluster_tolerance_m = 0.0f; }),
              HasSubstr("table_objects.cluster_tolerance_m"));
  EXPECT_THAT(refusal([](auto& c) { c.min_points = 0; }), HasSubstr("table_objects.min_points"));
  EXPECT_THAT(refusal([](auto& c) { c.max_base_height_m = 0.005f; }),
              HasSubstr("table_objects.max_base_height_m"));
  EXPECT_THAT(refusal([](auto& c) { c.max_extent_m = 0.0f; }),
              HasSubstr("table_objects.max_extent_m"));
  EXPECT_THAT(refusal([](auto& c) { c.top_cell_m = 0.001f; }),
              HasSubstr("table_objects.top_cell_m"));
  EXPECT_EQ(refusal([](auto&) {}), "accepted");
  // Through the settings file: the range, and the cross-key rule at validation.
  EXPECT_THROW(parseConfig("table_objects:\n  min_points: 0\n", "t.yaml"), Error);
  try {
    parseConfig("table_objects:\n  max_base_height_m: 0.005\n", "t.yaml");
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("table_objects.max_base_height_m"));
  }
  // findTableObjects refuses them too.
  Frame f;
  TableObjectConfig bad;
  bad.min_points = 0;
  EXPECT_THROW(findTableObjects(f.cloud, f.labels, {handBuiltTable()}, bad), Error);
}

// The settings are the segmenter's (read from the shared file) but no
// model records them: changing them never makes a model refused.
TEST(TableObjects, SettingsAreReadButNotRecordedInModels) {
  const Config c = parseConfig(
      "table_objects:\n  enabled: false\n  min_height_m: 0.02\n  max_height_m: 0.5\n"
      "  outline_margin_m: 0.03\n  cluster_tolerance_m: 0.03\n  min_points: 40\n"
      "  max_base_height_m: 0.06\n  max_extent_m: 0.7\n  top_cell_m: 0.2\n  relabel: true\n",
      "t.yaml");
  const TableObjectConfig& t = c.segmenter.table_objects;
  EXPECT_FALSE(t.enabled);
  EXPECT_FLOAT_EQ(t.min_height_m, 0.02f);
  EXPECT_FLOAT_EQ(t.max_height_m, 0.5f);
  EXPECT_FLOAT_EQ(t.outline_margin_m, 0.03f);
  EXPECT_FLOAT_EQ(t.cluster_tolerance_m, 0.03f);
  EXPECT_EQ(t.min_points, 40);
  EXPECT_FLOAT_EQ(t.max_base_height_m, 0.06f);
  EXPECT_FLOAT_EQ(t.max_extent_m, 0.7f);
  EXPECT_FLOAT_EQ(t.top_cell_m, 0.2f);
  EXPECT_TRUE(t.relabel);
  EXPECT_EQ(extractionSettings(c.segmenter), extractionSettings(SegmenterConfig{}));
  for (const auto& [key, value] : extractionSettings(c.segmenter)) {
    EXPECT_NE(key.rfind("table_objects.", 0), 0u) << key;
  }
  for (const auto& s : segmenterSettings().settings()) {
    if (s.key.rfind("table_objects.", 0) == 0) {
      EXPECT_FALSE(s.doc.empty()) << s.key;
    }
  }
}

TEST(TableObjects, DisabledNoTablesOrEmptyCloudGiveNothing) {
  Frame f;
  f.add(topPoints(), 121, Label::Table);
  f.add(cylinderPoints({0.6f, 0.0f}, 0.04f, 0.1f), kCylinderCols, Label::Object);
  TableObjectConfig off;
  off.enabled = false;
  EXPECT_TRUE(run(f, off).objects.empty());
  EXPECT_EQ(run(f, off).points_above_tops, 0);
  EXPECT_TRUE(findTableObjects(f.cloud, f.labels, {}, {}).objects.empty());
  EXPECT_TRUE(
      findTableObjects(OrganizedCloud{}, LabelImage{}, {handBuiltTable()}, {}).objects.empty());
  // A table without a usable outline is reported, not searched.
  TableCluster line = handBuiltTable();
  line.hull = {{0.0f, 0.0f}, {1.0f, 0.0f}};
  const auto d = findTableObjects(f.cloud, f.labels, {line}, {});
  EXPECT_TRUE(d.objects.empty());
  ASSERT_EQ(d.diagnostics.size(), 1u);
  EXPECT_THAT(d.diagnostics[0], HasSubstr("outline"));
}

TEST(TableObjects, SizeMismatchIsRefused) {
  Frame f;
  f.add(topPoints(), 121, Label::Table);
  LabelImage small = f.labels;
  small.height -= 1;
  small.labels.resize(static_cast<std::size_t>(small.width) * small.height);
  EXPECT_THROW(findTableObjects(f.cloud, small, {handBuiltTable()}, {}), Error);
  OrganizedCloud broken = f.cloud;
  broken.points.pop_back();
  EXPECT_THROW(findTableObjects(broken, f.labels, {handBuiltTable()}, {}), Error);
}

// A point above two tables' outlines belongs to the first table (by index) that holds it.
TEST(TableObjects, APointGoesToTheFirstTableThatHoldsIt) {
  Frame f;
  f.add(topPoints(), 121, Label::Table);
  f.add(cylinderPoints({0.6f, 0.0f}, 0.04f, 0.1f), kCylinderCols, Label::Object);
  TableCluster beside = handBuiltTable();  // its outline ends before the mug
  beside.hull = {{0.0f, -0.5f}, {0.3f, -0.5f}, {0.3f, 0.5f}, {0.0f, 0.5f}};
  const auto d =
      findTableObjects(f.cloud, f.labels, {beside, handBuiltTable(), handBuiltTable()}, {});
  ASSERT_EQ(d.objects.size(), 1u);
  EXPECT_EQ(d.objects[0].table, 1);
  EXPECT_EQ(d.objects[0].point_count, 19 * kCylinderCols);
}

void expectSame(const TableObjectDetection& a, const TableObjectDetection& b) {
  ASSERT_EQ(a.objects.size(), b.objects.size());
  EXPECT_EQ(a.diagnostics, b.diagnostics);
  EXPECT_EQ(a.points_above_tops, b.points_above_tops);
  EXPECT_EQ(a.clusters_too_small, b.clusters_too_small);
  EXPECT_EQ(a.clusters_not_standing, b.clusters_not_standing);
  for (std::size_t k = 0; k < a.objects.size(); ++k) {
    const TableObject &x = a.objects[k], &y = b.objects[k];
    EXPECT_EQ(x.id, y.id);
    EXPECT_EQ(x.table, y.table);
    EXPECT_EQ(x.centroid, y.centroid);
    EXPECT_EQ(x.height_above_top, y.height_above_top);
    EXPECT_EQ(x.major_axis, y.major_axis);
    EXPECT_EQ(x.extents, y.extents);
    EXPECT_EQ(x.center, y.center);
    EXPECT_EQ(x.point_count, y.point_count);
    EXPECT_EQ(x.mean_rgb, y.mean_rgb);
    EXPECT_EQ(x.colour_histogram, y.colour_histogram);
    EXPECT_EQ(x.truncation, y.truncation);
    EXPECT_EQ(x.pixels, y.pixels);
  }
}

TEST(TableObjects, RecycledOutputGivesTheSameResult) {
  Frame a;
  a.add(topPoints(), 121, Label::Table);
  a.add(cylinderPoints({0.3f, 0.2f}, 0.04f, 0.1f), kCylinderCols, Label::Object, kRed);
  a.add(cylinderPoints({0.8f, -0.2f}, 0.05f, 0.15f), kCylinderCols, Label::Object, kBlue);
  a.add(cylinderPoints({0.8f, 0.3f}, 0.03f, 0.05f), kCylinderCols, Label::Object);
  Frame b;
  b.add(topPoints(), 121, Label::Table);
  b.add(cylinderPoints({0.6f, 0.0f}, 0.04f, 0.1f), kCylinderCols, Label::Object, kBlue, 20);
  TableObjectDetection out = findTableObjects(a.cloud, a.labels, {handBuiltTable()}, {});
  ASSERT_EQ(out.objects.size(), 3u);
  out.diagnostics.push_back("stale");
  findTableObjectsInto(b.cloud, b.labels, {handBuiltTable()}, {}, out);
  expectSame(out, findTableObjects(b.cloud, b.labels, {handBuiltTable()}, {}));
  // And back to the bigger frame, with more objects than the last.
  findTableObjectsInto(a.cloud, a.labels, {handBuiltTable()}, {}, out);
  expectSame(out, findTableObjects(a.cloud, a.labels, {handBuiltTable()}, {}));
}

// ------------------------------------------------- sampled clustering ----
// The cylinder blocks are laid out as a camera sees a mug: neighbouring
// columns and rows are neighbouring points (3.5 mm and 5 mm apart), so the
// image grid the sampled clustering links holds the object together.

TEST(TableObjectsSampled, EveryStrideFindsTheSameMugWithAllItsPoints) {
  Frame f;
  f.add(topPoints(), 121, Label::Table);
  const auto mug = f.add(cylinderPoints({0.6f, 0.1f}, 0.04f, 0.1f), kCylinderCols, Label::Object);
  const TableObjectDetection exact = run(f);
  ASSERT_EQ(exact.objects.size(), 1u);
  for (const int stride : {2, 3, 4}) {
    const TableObjectDetection d = runSampled(f, stride);
    ASSERT_EQ(d.objects.size(), 1u) << "stride " << stride;
    // Every point joins it (each lies within the tolerance of a sampled
    // neighbour), so the fields are the exact clustering's.
    EXPECT_EQ(d.objects[0].pixels, exact.objects[0].pixels) << "stride " << stride;
    EXPECT_EQ(d.objects[0].point_count, exact.objects[0].point_count);
    EXPECT_EQ(d.objects[0].centroid, exact.objects[0].centroid);
    EXPECT_EQ(d.objects[0].extents, exact.objects[0].extents);
  }
}

TEST(TableObjectsSampled, TwoMugsTenCentimetresApartStayTwoAndAStrayPointJoinsNeither) {
  Frame f;
  f.add(topPoints(), 121, Label::Table);
  // Side by side in the image too (one block, two column ranges), as a
  // camera sees two mugs next to each other: image neighbours across the
  // gap are 10 cm apart in 3-D, beyond the tolerance.
  auto left = cylinderPoints({0.5f, 0.0f}, 0.04f, 0.08f);
  auto right = cylinderPoints({0.68f, 0.0f}, 0.04f, 0.08f);
  std::vector<Eigen::Vector3f> both;
  const int rows = static_cast<int>(left.size()) / kCylinderCols;
  for (int r = 0; r < rows; ++r) {
    for (int a = 0; a < kCylinderCols; ++a) both.push_back(left[r * kCylinderCols + a]);
    for (int a = 0; a < kCylinderCols; ++a) both.push_back(right[r * kCylinderCols + a]);
  }
  // One point in the left mug's rows sits 5 cm off everything: sampled or
  // not, it links to nothing and joins no candidate.
  both[5 * 2 * kCylinderCols + 11] = Eigen::Vector3f(0.3f, 0.3f, kTop + 0.05f);
  f.add(both, 2 * kCylinderCols, Label::Object);
  const TableObjectDetection exact = run(f);
  const TableObjectDetection d = runSampled(f, 2);
  ASSERT_EQ(exact.objects.size(), 2u);
  ASSERT_EQ(d.objects.size(), 2u);
  // The right mug whole, the left one without the stray point.
  EXPECT_EQ(exact.objects[0].point_count, exact.objects[1].point_count + 1);
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(d.objects[k].pixels, exact.objects[k].pixels) << k;
    EXPECT_EQ(d.objects[k].point_count, exact.objects[k].point_count) << k;
  }
}

// ------------------------------------------------------------- rendered ----

// The renderer's true labels as a label image (void where the frame has no point).
LabelImage trueLabels(const synth::RenderedFrame& r, const OrganizedCloud& cloud) {
  LabelImage labels;
  labels.width = cloud.width;
  labels.height = cloud.height;
  labels.labels = r.labeled.labels;
  labels.confidence.assign(labels.labels.size(), 1.0f);
  for (std::size_t i = 0; i < labels.labels.size(); ++i) {
    if (!cloud.valid(i)) labels.labels[i] = kVoidLabel;
  }
  return labels;
}

bool nearBorder(int pixel, int width, int height) {
  const int x = pixel % width, y = pixel / width;
  return x < 2 || y < 2 || x >= width - 2 || y >= height - 2;
}

struct RenderedScore {
  int objects = 0, found = 0, candidates = 0, bad_candidates = 0;
  std::vector<float> centroid_errors;  // candidate centroid to its points' mean
  std::vector<float> centre_errors;    // footprint box centre to the true object's, on the floor
};

// Small objects (mug, box, book) on a detected table: at least 100 pixels with
// a point, none on the image border, most of their points above a detected
// table's top (within its hull grown by the margin). Found: a candidate holds
// half of those points or more.
void scoreRenderedFrame(const synth::SynthScene& scene, const synth::CameraPose& pose,
                        const synth::RenderedFrame& r, RenderedScore& score) {
  const OrganizedCloud cloud = frameToCloud(r.labeled.frame);
  const GroundPlane ground = groundFromExtrinsics(*r.labeled.frame.extrinsics);
  const OrganizedCloud cloud_ground = transformCloud(cloud, ground.camera_to_ground);
  const LabelImage labels = trueLabels(r, cloud);
  const std::vector<TableCluster> tables = findTables(cloud_ground, labels, TableConfig{});
  const TableObjectDetection d = findTableObjects(cloud_ground, labels, tables, {});
  std::vector<int> candidate_of(cloud.points.size(), -1);
  for (const TableObject& o : d.objects) {
    int object_pixels = 0, table_or_wall = 0;
    for (const int p : o.pixels) {
      candidate_of[static_cast<std::size_t>(p)] = o.id;
      const std::uint8_t l = labels.labels[static_cast<std::size_t>(p)];
      object_pixels += l == static_cast<std::uint8_t>(Label::Object);
      table_or_wall += l == static_cast<std::uint8_t>(Label::Table) ||
                       l == static_cast<std::uint8_t>(Label::Wall);
    }
    ++score.candidates;
    if (2 * table_or_wall > o.point_count || 2 * object_pixels < o.point_count)
      ++score.bad_candidates;
  }
  // Pixels with a point per true object.
  std::map<int, std::vector<int>> pixels_of;
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    if (!cloud.valid(i)) continue;
    const int obj = r.object[i];
    const std::string& kind = scene.objects[static_cast<std::size_t>(obj)].kind;
    if (kind == "mug" || kind == "box" || kind == "book")
      pixels_of[obj].push_back(static_cast<int>(i));
  }
  const float margin = TableObjectConfig{}.outline_margin_m;
  for (const auto& [obj, pixels] : pixels_of) {
    if (pixels.size() < 100) continue;
    if (std::any_of(pixels.begin(), pixels.end(),
                    [&](int p) { return nearBorder(p, cloud.width, cloud.height); })) {
      continue;
    }
    // Its points above a detected top (that table's band and grown hull).
    std::vector<int> above;
    for (const TableCluster& t : tables) {
      above.clear();
      for (const int p : pixels) {
        const Eigen::Vector3f& q = cloud_ground.points[static_cast<std::size_t>(p)];
        const float h = q.z() - t.top_height;
        if (h < TableObjectConfig{}.min_height_m || h > TableObjectConfig{}.max_height_m) continue;
        bool inside = true;
        for (std::size_t k = 0; k < t.hull.size() && inside; ++k) {
          const Eigen::Vector2f e = t.hull[(k + 1) % t.hull.size()] - t.hull[k];
          const Eigen::Vector2f v = q.head<2>() - t.hull[k];
          inside = (e.x() * v.y() - e.y() * v.x()) / e.norm() >= -margin;
        }
        if (inside) above.push_back(p);
      }
      if (2 * above.size() >= pixels.size()) break;
    }
    if (above.size() < 100 || 2 * above.size() < pixels.size()) continue;
    ++score.objects;
    std::map<int, int> votes;
    for (const int p : above) {
      if (candidate_of[static_cast<std::size_t>(p)] >= 0)
        ++votes[candidate_of[static_cast<std::size_t>(p)]];
    }
    const auto best =
        std::max_element(votes.begin(), votes.end(),
                         [](const auto& a, const auto& b) { return a.second < b.second; });
    if (best == votes.end() || 2 * best->second < static_cast<int>(above.size())) continue;
    ++score.found;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const int p : above)
      mean += cloud_ground.points[static_cast<std::size_t>(p)].cast<double>();
    mean /= static_cast<double>(above.size());
    const TableObject& o = d.objects[static_cast<std::size_t>(best->first)];
    score.centroid_errors.push_back(static_cast<float>((o.centroid.cast<double>() - mean).norm()));
    // The object's first part stands on its footprint's centre.
    for (const synth::Primitive& part : scene.primitives) {
      if (part.object != obj) continue;
      const Eigen::Vector2d truth = (synth::worldToGround(pose) * part.center).head<2>();
      score.centre_errors.push_back(static_cast<float>((o.center.cast<double>() - truth).norm()));
      break;
    }
  }
}

// The sampled clustering (point_stride 2, shipped) against the exact one on
// rendered rooms: nearly every exact candidate of an object (mostly Object
// pixels, 100 or more) has a sampled one holding at least 75 % of its pixels.
// Not all: on small far objects a sampled point on the silhouette or across a
// depth step links to no sampled neighbour, and the pixels that join it are
// lost with it (seeds 1-3: of 53 such candidates 46 keep 90 % or more, 6
// keep 80-88 %, one 35 %).
TEST(TableObjectsRendered, SampledClusteringFindsTheExactClusteringsObjects) {
  int exact_objects = 0, kept = 0;
  for (const std::uint64_t seed : {1u, 2u, 3u}) {
    const synth::SynthScene scene = synth::makeApartment(seed);
    const auto poses = synth::cameraPath(scene, 8, 1.0);
    for (std::size_t f = 0; f < poses.size(); f += 2) {
      const synth::RenderedFrame r = synth::render(scene, poses[f], synth::RenderOptions{}, f);
      const OrganizedCloud cloud = frameToCloud(r.labeled.frame);
      const GroundPlane ground = groundFromExtrinsics(*r.labeled.frame.extrinsics);
      const OrganizedCloud cloud_ground = transformCloud(cloud, ground.camera_to_ground);
      const LabelImage labels = trueLabels(r, cloud);
      const std::vector<TableCluster> tables = findTables(cloud_ground, labels, TableConfig{});
      TableObjectConfig exact_config, sampled_config;
      exact_config.point_stride = 1;
      sampled_config.point_stride = 2;
      const auto exact = findTableObjects(cloud_ground, labels, tables, exact_config);
      const auto sampled = findTableObjects(cloud_ground, labels, tables, sampled_config);
      std::vector<int> sampled_of(labels.labels.size(), -1);
      for (const TableObject& o : sampled.objects) {
        for (const int p : o.pixels) sampled_of[static_cast<std::size_t>(p)] = o.id;
      }
      for (const TableObject& o : exact.objects) {
        const auto object_pixels = std::count_if(o.pixels.begin(), o.pixels.end(), [&](int p) {
          return labels.labels[static_cast<std::size_t>(p)] ==
                 static_cast<std::uint8_t>(Label::Object);
        });
        if (o.pixels.size() < 100 || 2 * object_pixels < static_cast<long>(o.pixels.size())) {
          continue;
        }
        ++exact_objects;
        std::map<int, int> votes;
        for (const int p : o.pixels) {
          const int id = sampled_of[static_cast<std::size_t>(p)];
          if (id >= 0) ++votes[id];
        }
        int best = 0;
        for (const auto& [id, n] : votes) best = std::max(best, n);
        if (4 * best >= 3 * static_cast<int>(o.pixels.size())) ++kept;
      }
    }
  }
  std::printf("sampled clustering: %d of %d exact object candidates kept (75 %% of pixels)\n",
              kept, exact_objects);
  ASSERT_GE(exact_objects, 20);
  EXPECT_GE(kept, 0.95 * exact_objects);
}

TEST(TableObjectsRendered, SmallObjectsOnVisibleTablesAreFound) {
  RenderedScore score;
  for (const std::uint64_t seed : {1u, 2u, 3u, 4u, 5u, 6u}) {
    const synth::SynthScene scene = synth::makeApartment(seed);
    const auto poses = synth::cameraPath(scene, 8, 1.0);
    for (std::size_t f = 0; f < poses.size(); f += 2) {
      scoreRenderedFrame(scene, poses[f], synth::render(scene, poses[f], synth::RenderOptions{}, f),
                         score);
    }
  }
  auto median = [](std::vector<float> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 1.0f : v[v.size() / 2];
  };
  std::printf(
      "rendered: %d objects on tables, %d found; %d candidates, %d mostly not objects; "
      "median error of the centroid %.4f m (to its points' mean), of the footprint "
      "centre %.4f m (to the true object's)\n",
      score.objects, score.found, score.candidates, score.bad_candidates,
      median(score.centroid_errors), median(score.centre_errors));
  ASSERT_GE(score.objects, 20);
  EXPECT_GE(score.found, 0.85 * score.objects);
  EXPECT_LE(score.bad_candidates, score.candidates / 10);
  EXPECT_LT(median(score.centroid_errors), 0.005f);
  EXPECT_LT(median(score.centre_errors), 0.03f);
}

// ------------------------------------------------------------ real data ----

// Ground-truth object instances above a frame's table tops: 4-connected
// components of Object pixels (neighbours within 5 cm in 3-D) with at least
// 100 points above a top (`above`), whose footprint there is within
// max_extent_m (NYU's "object" class also holds piles, monitors and shelves'
// contents, which the stage leaves out by design). Each instance: its points above the tops.
std::vector<std::vector<int>> objectInstancesAboveTops(const OrganizedCloud& cloud,
                                                       const LabelImage& labels,
                                                       const std::vector<std::uint8_t>& above) {
  const int w = cloud.width, h = cloud.height;
  const auto object = static_cast<std::uint8_t>(Label::Object);
  std::vector<int> component(cloud.points.size(), -1);
  std::vector<std::vector<int>> instances;
  int next = 0;
  for (int start = 0; start < w * h; ++start) {
    const auto s0 = static_cast<std::size_t>(start);
    if (component[s0] >= 0 || labels.labels[s0] != object || !cloud.valid(s0)) continue;
    std::vector<int> stack = {start}, members;
    component[s0] = next;
    while (!stack.empty()) {
      const int p = stack.back();
      stack.pop_back();
      members.push_back(p);
      const int x = p % w, y = p / w;
      const int around[4] = {x > 0 ? p - 1 : -1, x + 1 < w ? p + 1 : -1, y > 0 ? p - w : -1,
                             y + 1 < h ? p + w : -1};
      for (const int q : around) {
        if (q < 0) continue;
        const auto uq = static_cast<std::size_t>(q);
        if (component[uq] >= 0 || labels.labels[uq] != object || !cloud.valid(uq)) continue;
        if ((cloud.points[uq] - cloud.points[static_cast<std::size_t>(p)]).norm() > 0.05f) continue;
        component[uq] = next;
        stack.push_back(q);
      }
    }
    ++next;
    std::vector<int> on_top;
    Eigen::AlignedBox2f box;
    for (const int p : members) {
      if (!above[static_cast<std::size_t>(p)]) continue;
      on_top.push_back(p);
      box.extend(cloud.points[static_cast<std::size_t>(p)].head<2>());
    }
    if (on_top.size() < 100 || box.sizes().maxCoeff() > TableObjectConfig{}.max_extent_m) continue;
    instances.push_back(std::move(on_top));
  }
  return instances;
}

// NYU frames with their ground-truth labels: tables from the true labels, then
// the candidates. Most ground-truth object instances of a size the stage looks
// for that stand above the tops must be found (half of their points in one
// candidate's or more), and candidates must be mostly object pixels.
TEST(TableObjectsOnNyu, GroundTruthObjectsOnTableTopsAreFound) {
  FINDMUG_REQUIRE_DATA(root, "nyuv2_labeled");
  FINDMUG_REQUIRE_DATA(rotations_file, "nyuv2_meta/camera_rotations_NYU.txt");
  DatasetOptions options;
  options.nyu_rotations_file = rotations_file.string();
  const DatasetFolder folder(root.string(), options);
  SegmenterConfig config;
  config.ground.source = GroundSource::Gravity;
  const Segmenter segmenter(config, nullptr);
  long object_points = 0, in_candidates = 0, candidate_points = 0, candidate_object_points = 0;
  int frames_with_tables = 0, candidates = 0, instances = 0, found = 0;
  std::array<long, kNumLabels + 1> candidate_labels{};  // the last: void
  for (std::size_t i = 0; i < folder.size(); ++i) {
    LabeledFrame f = folder.load(i);
    const PreparedFrame p = segmenter.prepare(std::move(f.frame), &f.labels);
    ASSERT_TRUE(p.ground.has_value()) << f.name;
    LabelImage labels;
    labels.width = p.cloud_ground.width;
    labels.height = p.cloud_ground.height;
    labels.labels = f.labels;
    labels.confidence.assign(labels.labels.size(), 1.0f);
    const TableDetection tables =
        detectTables(p.cloud_ground, labels, TableConfig{}, &p.normals_ground);
    if (tables.tables.empty()) continue;
    ++frames_with_tables;
    TableObjectConfig probe;  // every point above the tops, whatever its cluster
    probe.point_stride = 1;
    probe.min_points = 1;
    probe.max_base_height_m = probe.max_height_m;
    probe.max_extent_m = 10.0f;
    const TableObjectDetection all = findTableObjects(p.cloud_ground, labels, tables.tables, probe);
    const TableObjectDetection d = findTableObjects(p.cloud_ground, labels, tables.tables, {});
    std::vector<int> candidate_of(labels.labels.size(), -1);
    for (const TableObject& o : d.objects) {
      ++candidates;
      for (const int q : o.pixels) {
        candidate_of[static_cast<std::size_t>(q)] = o.id;
        ++candidate_points;
        candidate_object_points += labels.labels[static_cast<std::size_t>(q)] == 7;
        ++candidate_labels[std::min<std::size_t>(labels.labels[static_cast<std::size_t>(q)],
                                                 kNumLabels)];
      }
    }
    std::vector<std::uint8_t> above(labels.labels.size(), 0);
    for (const TableObject& o : all.objects) {
      for (const int q : o.pixels) {
        above[static_cast<std::size_t>(q)] = 1;
        if (labels.labels[static_cast<std::size_t>(q)] != 7) continue;
        ++object_points;
        in_candidates += candidate_of[static_cast<std::size_t>(q)] >= 0;
      }
    }
    int frame_instances = 0, frame_found = 0;
    for (const auto& instance : objectInstancesAboveTops(p.cloud_ground, labels, above)) {
      ++frame_instances;
      std::map<int, int> votes;
      for (const int q : instance) {
        if (candidate_of[static_cast<std::size_t>(q)] >= 0)
          ++votes[candidate_of[static_cast<std::size_t>(q)]];
      }
      for (const auto& [id, n] : votes) {
        if (2 * n >= static_cast<int>(instance.size())) {
          ++frame_found;
          break;
        }
      }
    }
    std::printf("%s: %zu tables, %zu candidates, %d of %d object instances found\n", f.name.c_str(),
                tables.tables.size(), d.objects.size(), frame_found, frame_instances);
    instances += frame_instances;
    found += frame_found;
  }
  std::printf(
      "NYU: %d frames with tables, %d candidates; %d of %d object instances on the tops "
      "found; %ld of %ld object points above the tops in candidates; %ld of %ld "
      "candidate points are objects\n",
      frames_with_tables, candidates, found, instances, in_candidates, object_points,
      candidate_object_points, candidate_points);
  std::printf("candidate points by true label:");
  for (std::size_t l = 0; l <= kNumLabels; ++l) {
    std::printf(" %s %ld", l < kNumLabels ? kLabelNames[l].data() : "void", candidate_labels[l]);
  }
  std::printf("\n");
  ASSERT_GE(frames_with_tables, 5);
  ASSERT_GE(instances, 10);
  EXPECT_GE(found, 0.6 * instances);  // measured 26 of 34
  EXPECT_GE(static_cast<double>(candidate_object_points),
            0.5 * static_cast<double>(candidate_points));
}

}  // namespace
}  // namespace findmug
