// Tests of table clusters and search positions (tables.hpp).
//
// Four groups: the geometric building blocks against brute force / known
// shapes; findTables on hand-built clouds (bad input, reachability);
// rendered synthetic scenes with known tables (findmug_synth); and real data
// (PCL's table_scene_mug_stereo_textured.pcd and NYU Depth V2 frames with
// ground-truth labels).
#include "findmug/tables/tables.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/common/error.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/ground/ground.hpp"
#include "findmug/labels/labels.hpp"
#include "findmug/synth/synth.hpp"
#include "tables/tables_internal.hpp"  // internal: clusterPoints with the image shortcut
#include "test_data.hpp"

namespace findmug {
namespace {

constexpr float kPi = 3.14159265358979f;
constexpr std::uint8_t kTable = static_cast<std::uint8_t>(Label::Table);
constexpr std::uint8_t kFloor = static_cast<std::uint8_t>(Label::Floor);
constexpr std::uint8_t kChair = static_cast<std::uint8_t>(Label::Chair);
constexpr std::uint8_t kUnknown = static_cast<std::uint8_t>(Label::Unknown);
const float kNaN = std::numeric_limits<float>::quiet_NaN();

// Angle between two directions in the floor plane, ignoring sign (axes), degrees.
float axisAngleDeg(const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
  const float c = std::abs(a.normalized().dot(b.normalized()));
  return std::acos(std::min(1.0f, c)) * 180.0f / kPi;
}

// Angle between two directions, with sign (vectors), degrees.
float directionAngleDeg(const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
  const float c = a.normalized().dot(b.normalized());
  return std::acos(std::clamp(c, -1.0f, 1.0f)) * 180.0f / kPi;
}

float pointSegmentDistance(const Eigen::Vector2f& p, const Eigen::Vector2f& a,
                           const Eigen::Vector2f& b) {
  const Eigen::Vector2f ab = b - a;
  const float t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0f, 1.0f);
  return (a + t * ab - p).norm();
}

// Distance from a point outside a polygon to its boundary.
float distanceToPolygon(const Eigen::Vector2f& p, const std::vector<Eigen::Vector2f>& polygon) {
  float best = std::numeric_limits<float>::max();
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    best = std::min(best, pointSegmentDistance(p, polygon[i], polygon[(i + 1) % polygon.size()]));
  }
  return best;
}

bool insidePolygon(const Eigen::Vector2f& p, const std::vector<Eigen::Vector2f>& polygon,
                   float margin) {
  // Convex, counter-clockwise; `margin` metres of slack outside.
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2f a = polygon[i], b = polygon[(i + 1) % polygon.size()];
    const Eigen::Vector2f edge = (b - a).normalized();
    const float side = edge.x() * (p - a).y() - edge.y() * (p - a).x();
    if (side < -margin) return false;
  }
  return true;
}

std::vector<Eigen::Vector2f> rectangle(const Eigen::Vector2f& center, float yaw, float length,
                                       float width) {
  const Eigen::Vector2f ax(std::cos(yaw), std::sin(yaw)), ay(-std::sin(yaw), std::cos(yaw));
  const float a = 0.5f * length, b = 0.5f * width;
  return {center - a * ax - b * ay, center + a * ax - b * ay, center + a * ax + b * ay,
          center - a * ax + b * ay};
}

bool hasDiagnostic(const TableDetection& detection, const std::string& part) {
  for (const auto& d : detection.diagnostics) {
    if (d.find(part) != std::string::npos) return true;
  }
  return false;
}

std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const auto& l : lines) out += "\n  " + l;
  return out;
}

// ----------------------------------------------------------- building blocks

TEST(ConvexHull, SquareWithInteriorAndCollinearPoints) {
  std::vector<Eigen::Vector2f> pts;
  for (int i = 0; i <= 10; ++i) {
    for (int j = 0; j <= 10; ++j)
      pts.emplace_back(0.1f * i, 0.1f * j);  // edges hold collinear points
  }
  const auto hull = convexHull2d(pts);
  ASSERT_EQ(hull.size(), 4u);
  // Counter-clockwise: positive signed area of 1 m².
  float area2 = 0.0f;
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const auto& p = hull[i];
    const auto& q = hull[(i + 1) % hull.size()];
    area2 += p.x() * q.y() - q.x() * p.y();
  }
  EXPECT_NEAR(0.5f * area2, 1.0f, 1e-5f);
  for (const auto& corner : {Eigen::Vector2f(0, 0), Eigen::Vector2f(1, 0), Eigen::Vector2f(1, 1),
                             Eigen::Vector2f(0, 1)}) {
    EXPECT_TRUE(std::any_of(hull.begin(), hull.end(),
                            [&](const Eigen::Vector2f& h) { return (h - corner).norm() < 1e-5f; }))
        << "corner " << corner.transpose() << " missing";
  }
}

TEST(ConvexHull, DegenerateInputs) {
  EXPECT_TRUE(convexHull2d({}).empty());
  EXPECT_EQ(convexHull2d({Eigen::Vector2f(1, 2), Eigen::Vector2f(1, 2)}).size(), 1u);
  // Collinear points: the two ends only.
  const auto line = convexHull2d({{0, 0}, {1, 1}, {2, 2}, {3, 3}});
  EXPECT_LE(line.size(), 2u);
}

// Brute-force reference: connected components of the "within tolerance" graph.
std::vector<int> bruteForceClusters(const std::vector<Eigen::Vector3f>& pts, float tol) {
  std::vector<int> label(pts.size(), -1);
  int next = 0;
  for (std::size_t s = 0; s < pts.size(); ++s) {
    if (label[s] >= 0) continue;
    std::vector<std::size_t> stack{s};
    label[s] = next;
    while (!stack.empty()) {
      const std::size_t i = stack.back();
      stack.pop_back();
      for (std::size_t j = 0; j < pts.size(); ++j) {
        if (label[j] < 0 && (pts[i] - pts[j]).norm() <= tol) {
          label[j] = next;
          stack.push_back(j);
        }
      }
    }
    ++next;
  }
  return label;
}

TEST(EuclideanClusters, SamePartitionAsBruteForce) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> centre(-2.0f, 2.0f);
  std::normal_distribution<float> spread(0.0f, 0.06f);
  for (float tol : {0.02f, 0.05f, 0.1f}) {
    std::vector<Eigen::Vector3f> pts;
    for (int c = 0; c < 12; ++c) {
      const Eigen::Vector3f mid(centre(rng), centre(rng), 0.5f + 0.2f * centre(rng));
      for (int k = 0; k < 120; ++k) {
        pts.push_back(mid + Eigen::Vector3f(spread(rng), spread(rng), spread(rng)));
      }
    }
    const auto ours = euclideanClusterLabels(pts, tol);
    const auto reference = bruteForceClusters(pts, tol);
    ASSERT_EQ(ours.size(), reference.size());
    // Same partition: a bijection between the label sets.
    std::map<int, int> forward, backward;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      auto f = forward.emplace(ours[i], reference[i]);
      auto b = backward.emplace(reference[i], ours[i]);
      ASSERT_EQ(f.first->second, reference[i]) << "tolerance " << tol << ", point " << i;
      ASSERT_EQ(b.first->second, ours[i]) << "tolerance " << tol << ", point " << i;
    }
    EXPECT_GT(forward.size(), 1u) << "test needs more than one cluster";
  }
}

// detectTables passes the points' pixels to the clustering, which then links
// image neighbours without a search. Only a shortcut: on an organized cloud
// with depth steps just below and above the tolerance, noise, holes and
// pixels far apart (a coarse camera), the clusters are those without it and
// those of brute force. With tables.point_stride 2 the points sit at every
// other pixel of every other row of an image twice as wide, and the shortcut
// links points two pixels apart: the same cloud must give the same clusters.
TEST(EuclideanClusters, ImageNeighbourShortcutGivesTheSamePartition) {
  std::mt19937 rng(23);
  std::normal_distribution<float> noise(0.0f, 0.01f);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  const int width = 80, height = 60;  // sampled pixels
  const float focal = 60.0f;          // about 2.5 cm between sampled pixels at 1.5 m
  for (int stride : {1, 2}) {
    for (float tol : {0.03f, 0.05f}) {
      for (int trial = 0; trial < 3; ++trial) {
        std::vector<Eigen::Vector3f> pts;
        std::vector<int> pixels;
        for (int y = 0; y < height; ++y) {
          for (int x = 0; x < width; ++x) {
            if (unit(rng) > 0.8f) continue;  // holes
            float depth = 1.2f + 0.01f * x + 0.005f * y;
            if (x > 20 && x < 40) depth += 0.04f;               // step below the tolerance
            if (y > 30 && x > 45) depth += 0.07f;               // step above it
            if (x > 60 && y < 15) depth += 0.3f * (trial + 1);  // a far patch
            depth += noise(rng);
            pts.emplace_back((x - width / 2) * depth / focal, depth,
                             0.7f + (height / 2 - y) * depth / focal * 0.1f);
            pixels.push_back(y * stride * width * stride + x * stride);
          }
        }
        const auto plain = tables_detail::clusterPoints(pts, tol);
        const auto shortcut = tables_detail::clusterPoints(
            pts, tol, tables_detail::PointGrid{&pixels, width * stride, stride});
        // Ids are dense in order of first appearance: same partition = same ids.
        ASSERT_EQ(shortcut, plain)
            << "stride " << stride << ", tolerance " << tol << ", trial " << trial;
        const auto reference = bruteForceClusters(pts, tol);
        std::map<int, int> forward;
        for (std::size_t i = 0; i < pts.size(); ++i) {
          const auto f = forward.emplace(plain[i], reference[i]);
          ASSERT_EQ(f.first->second, reference[i]) << "tolerance " << tol << ", point " << i;
        }
        EXPECT_EQ(forward.size(), static_cast<std::size_t>(
                                      *std::max_element(reference.begin(), reference.end()) + 1));
        EXPECT_GT(forward.size(), 1u) << "test needs more than one cluster";
      }
    }
  }
}

// The table stage's voxel and grid cells and the scene features' height bins
// use floorToInt instead of std::floor: it must give the same cell for every
// coordinate, on both sides of zero and at and next to integers, where a
// truncation alone would be one cell off for negative values.
TEST(FloorToInt, MatchesStdFloor) {
  std::vector<float> values = {0.0f, -0.0f, 1.0f, -1.0f, 0.5f, -0.5f, 1e-30f, -1e-30f,
                               2147483520.0f, -2147483648.0f};
  for (int k = -2000; k <= 2000; ++k) {
    const float v = static_cast<float>(k) * 0.25f;
    values.push_back(v);
    values.push_back(std::nextafter(v, -1e9f));
    values.push_back(std::nextafter(v, 1e9f));
  }
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> wide(-2.0e5f, 2.0e5f);
  for (int k = 0; k < 10000; ++k) values.push_back(wide(rng));
  for (const float v : values) {
    ASSERT_EQ(detail::floorToInt(v), static_cast<int>(std::floor(v))) << v;
  }
}

TEST(EuclideanClusters, ChainsLinkAndGapsSplit) {
  std::vector<Eigen::Vector3f> chain, gaps;
  for (int i = 0; i < 50; ++i) {
    chain.emplace_back(0.045f * i, 0.0f,
                       0.7f);                   // steps below the tolerance: one cluster 2.2 m long
    gaps.emplace_back(0.055f * i, 0.0f, 0.7f);  // steps above it: all apart
  }
  const auto one = euclideanClusterLabels(chain, 0.05f);
  EXPECT_EQ(*std::max_element(one.begin(), one.end()), 0);
  const auto many = euclideanClusterLabels(gaps, 0.05f);
  EXPECT_EQ(*std::max_element(many.begin(), many.end()), 49);
}

TEST(EuclideanClusters, RejectsBadInput) {
  EXPECT_THROW(euclideanClusterLabels({Eigen::Vector3f(0, kNaN, 0)}, 0.05f), Error);
  EXPECT_THROW(euclideanClusterLabels({Eigen::Vector3f(500, 0, 0)}, 0.05f), Error);
  EXPECT_THROW(euclideanClusterLabels({Eigen::Vector3f(0, 0, 0)}, 0.0f), Error);
  EXPECT_TRUE(euclideanClusterLabels({}, 0.05f).empty());
}

TableCluster boxTable(const Eigen::Vector2f& center, float yaw, float length, float width) {
  TableCluster t;
  t.center = center;
  t.major_axis = Eigen::Vector2f(std::cos(yaw), std::sin(yaw));
  t.minor_axis = Eigen::Vector2f(-std::sin(yaw), std::cos(yaw));
  t.extents = Eigen::Vector2f(0.5f * length, 0.5f * width);
  t.top_height = 0.75f;
  return t;
}

TEST(SearchPositions, PaperPositionsOnSecondAxisFacingTheTable) {
  TableConfig config;  // d = 0.5, r = 0.8
  const TableCluster t = boxTable({2.0f, 1.0f}, 0.4f, 1.0f, 0.8f);
  const auto positions = computeSearchPositions(t, config);
  ASSERT_EQ(positions.size(), 2u);
  const auto outline = rectangle(t.center, 0.4f, 1.0f, 0.8f);
  EXPECT_NE(positions[0].side, positions[1].side);
  for (const auto& p : positions) {
    EXPECT_NEAR(distanceToPolygon(p.xy, outline), config.safety_distance_m, 1e-4f);
    EXPECT_LT(axisAngleDeg(p.xy - t.center, t.minor_axis), 0.01f);
    EXPECT_NEAR(p.along_m, 0.0f, 1e-6f);
    // Facing the table: heading points from the position to the centre.
    EXPECT_LT(directionAngleDeg({std::cos(p.yaw), std::sin(p.yaw)}, t.center - p.xy), 0.01f);
    EXPECT_TRUE(p.reachable);
  }
}

TEST(SearchPositions, LongNarrowTableIsWithinArmReachEverywhere) {
  TableConfig config;
  config.safety_distance_m = 0.5f;
  config.arm_reach_m = 0.8f;  // reaches the midline of a 0.5 m deep top (0.75 m away)
  const float yaw = -0.3f;
  const TableCluster t = boxTable({1.0f, -2.0f}, yaw, 3.0f, 0.5f);
  const auto positions = computeSearchPositions(t, config);
  ASSERT_GT(positions.size(), 2u);
  const auto outline = rectangle(t.center, yaw, 3.0f, 0.5f);
  for (const auto& p : positions) {
    EXPECT_NEAR(distanceToPolygon(p.xy, outline), 0.5f, 1e-4f);
    EXPECT_LT(axisAngleDeg({std::cos(p.yaw), std::sin(p.yaw)}, t.minor_axis), 0.01f);
  }
  // Every point of the top (sampled on a 2 cm grid) is within reach of a position.
  for (float a = -1.5f; a <= 1.5f; a += 0.02f) {
    for (float b = -0.25f; b <= 0.25f; b += 0.02f) {
      const Eigen::Vector2f q = t.center + a * t.major_axis + b * t.minor_axis;
      float nearest = std::numeric_limits<float>::max();
      for (const auto& p : positions) nearest = std::min(nearest, (p.xy - q).norm());
      ASSERT_LE(nearest, config.arm_reach_m + 1e-4f) << "top point (" << a << ", " << b << ")";
    }
  }
  // Not more positions than needed: one fewer per side leaves a gap.
  const int per_side = static_cast<int>(positions.size()) / 2;
  const float h = std::sqrt(0.8f * 0.8f - 0.75f * 0.75f);
  EXPECT_EQ(per_side, static_cast<int>(std::ceil(1.5f / h)));
}

TEST(SearchPositions, DeepTableHasItsEdgesWithinReach) {
  TableConfig config;  // d = 0.5, r = 0.8: a 1 m deep top's midline is out of reach
  const TableCluster t = boxTable({0.0f, 0.0f}, 0.0f, 2.5f, 1.0f);
  const auto positions = computeSearchPositions(t, config);
  EXPECT_GT(positions.size(), 2u);
  for (int side : {1, -1}) {
    for (float a = -1.25f; a <= 1.25f; a += 0.01f) {
      const Eigen::Vector2f edge_point(a, 0.5f * side);
      float nearest = std::numeric_limits<float>::max();
      for (const auto& p : positions) nearest = std::min(nearest, (p.xy - edge_point).norm());
      ASSERT_LE(nearest, config.arm_reach_m + 1e-4f) << "edge point " << edge_point.transpose();
    }
  }
}

TEST(SearchPositions, NoExtraPositionsWhenTheArmIsShorterThanTheSafetyDistance) {
  TableConfig config;
  config.safety_distance_m = 0.6f;
  config.arm_reach_m = 0.5f;
  const auto positions = computeSearchPositions(boxTable({0, 0}, 0.0f, 4.0f, 0.8f), config);
  EXPECT_EQ(positions.size(), 2u);
}

// ------------------------------------------------- hand-built labelled clouds

// A cloud of listed points as a 1-row organized grid with their labels.
struct Scene {
  OrganizedCloud cloud;
  LabelImage labels;
  void add(const Eigen::Vector3f& p, std::uint8_t label, float confidence = 0.9f) {
    cloud.points.push_back(p);
    labels.labels.push_back(label);
    labels.confidence.push_back(confidence);
    cloud.width = labels.width = static_cast<int>(cloud.points.size());
    cloud.height = labels.height = 1;
  }
  // Floor points on a grid over [x0,x1]x[y0,y1], except inside `hole`.
  void addFloor(float x0, float x1, float y0, float y1, float step = 0.05f) {
    for (float x = x0; x <= x1; x += step) {
      for (float y = y0; y <= y1; y += step) add({x, y, 0.0f}, kFloor);
    }
  }
  // A table top: points on a rotated rectangle at `height`.
  void addTop(const Eigen::Vector2f& center, float yaw, float length, float width, float height,
              float step = 0.01f, float confidence = 0.9f) {
    const Eigen::Vector2f ax(std::cos(yaw), std::sin(yaw)), ay(-std::sin(yaw), std::cos(yaw));
    for (float a = -0.5f * length; a <= 0.5f * length + 1e-6f; a += step) {
      for (float b = -0.5f * width; b <= 0.5f * width + 1e-6f; b += step) {
        const Eigen::Vector2f xy = center + a * ax + b * ay;
        add({xy.x(), xy.y(), height}, kTable, confidence);
      }
    }
  }
};

TEST(FindTables, BoxTopGeometry) {
  Scene s;
  s.addFloor(-1.0f, 5.0f, -3.0f, 3.0f);
  const float yaw = 0.5f;
  s.addTop({2.0f, 0.3f}, yaw, 1.2f, 0.7f, 0.74f, 0.01f, 0.8f);
  const TableDetection d = detectTables(s.cloud, s.labels, TableConfig{});
  ASSERT_EQ(d.tables.size(), 1u) << joined(d.diagnostics);
  const TableCluster& t = d.tables[0];
  EXPECT_EQ(t.id, 0);
  EXPECT_NEAR(t.top_height, 0.74f, 1e-4f);
  EXPECT_NEAR(t.centroid.z(), 0.74f, 1e-4f);
  EXPECT_LT((t.center - Eigen::Vector2f(2.0f, 0.3f)).norm(), 0.01f);
  EXPECT_LT(axisAngleDeg(t.major_axis, {std::cos(yaw), std::sin(yaw)}), 1.0f);
  EXPECT_NEAR(t.major_axis.norm(), 1.0f, 1e-5f);
  EXPECT_NEAR(t.major_axis.dot(t.minor_axis), 0.0f, 1e-5f);
  // minor = major turned +90° (right-handed floor frame).
  EXPECT_NEAR(t.major_axis.x() * t.minor_axis.y() - t.major_axis.y() * t.minor_axis.x(), 1.0f,
              1e-5f);
  EXPECT_NEAR(t.extents.x(), 0.6f, 0.01f);
  EXPECT_NEAR(t.extents.y(), 0.35f, 0.01f);
  EXPECT_EQ(t.point_count, d.table_points);
  EXPECT_NEAR(t.mean_confidence, 0.8f, 1e-4f);
  // The hull is the rectangle: four corners, counter-clockwise.
  const auto outline = rectangle({2.0f, 0.3f}, yaw, 1.2f, 0.7f);
  ASSERT_GE(t.hull.size(), 4u);
  for (const auto& h : t.hull) EXPECT_LT(distanceToPolygon(h, outline), 0.01f);
  for (const auto& corner : outline) {
    float nearest = std::numeric_limits<float>::max();
    for (const auto& h : t.hull) nearest = std::min(nearest, (h - corner).norm());
    EXPECT_LT(nearest, 0.015f) << "corner " << corner.transpose();
  }
  // Floor everywhere, nothing in the way: both positions reachable.
  ASSERT_EQ(t.search_positions.size(), 2u);
  for (const auto& p : t.search_positions) {
    EXPECT_TRUE(p.reachable) << p.reason;
    EXPECT_NEAR(distanceToPolygon(p.xy, outline), 0.5f, 0.015f);
  }
}

TEST(FindTables, SeparateTablesSmallClustersAndSizeLimits) {
  Scene s;
  s.addFloor(-1.0f, 6.0f, -3.0f, 3.0f);
  s.addTop({2.0f, -1.0f}, 0.0f, 1.6f, 0.6f, 0.72f);   // y in [-1.3, -0.7], ~9800 points
  s.addTop({2.0f, -0.45f}, 0.0f, 1.6f, 0.3f, 0.72f);  // y in [-0.6, -0.3]: 0.1 m gap, ~5000
  s.addTop({4.5f, 1.5f}, 0.0f, 0.1f, 0.1f, 0.9f);     // ~120 points: below min_cluster_points
  TableConfig config;
  TableDetection d = detectTables(s.cloud, s.labels, config);
  ASSERT_EQ(d.tables.size(), 2u) << joined(d.diagnostics);
  EXPECT_GT(d.tables[0].point_count, d.tables[1].point_count);  // sorted, ids in that order
  EXPECT_EQ(d.tables[0].id, 0);
  EXPECT_EQ(d.tables[1].id, 1);
  EXPECT_TRUE(hasDiagnostic(d, "below tables.min_cluster_points")) << joined(d.diagnostics);
  EXPECT_EQ(d.clusters_rejected, 1);

  config.max_cluster_points = 8000;  // now the large one is too large
  d = detectTables(s.cloud, s.labels, config);
  ASSERT_EQ(d.tables.size(), 1u);
  EXPECT_NEAR(d.tables[0].extents.y(), 0.15f, 0.01f);
  EXPECT_TRUE(hasDiagnostic(d, "above tables.max_cluster_points")) << joined(d.diagnostics);

  config = TableConfig{};
  config.cluster_tolerance_m = 0.15f;  // now the gap is bridged: one table
  d = detectTables(s.cloud, s.labels, config);
  ASSERT_EQ(d.tables.size(), 1u);
  EXPECT_NEAR(d.tables[0].extents.x(), 0.8f, 0.02f);
  EXPECT_NEAR(d.tables[0].extents.y(), 0.5f, 0.02f);
}

// Every field of two detections, bit for bit.
void expectSameDetection(const TableDetection& got, const TableDetection& want,
                         const std::string& what) {
  SCOPED_TRACE(what);
  EXPECT_EQ(got.diagnostics, want.diagnostics);
  EXPECT_EQ(got.table_points, want.table_points);
  EXPECT_EQ(got.nonfinite_points, want.nonfinite_points);
  EXPECT_EQ(got.implausible_points, want.implausible_points);
  EXPECT_EQ(got.clusters_rejected, want.clusters_rejected);
  EXPECT_EQ(got.unsampled_points, want.unsampled_points);
  ASSERT_EQ(got.tables.size(), want.tables.size());
  for (std::size_t k = 0; k < got.tables.size(); ++k) {
    const TableCluster& a = got.tables[k];
    const TableCluster& b = want.tables[k];
    EXPECT_EQ(a.id, b.id);
    EXPECT_EQ(a.centroid, b.centroid);
    EXPECT_EQ(a.top_height, b.top_height);
    EXPECT_EQ(a.major_axis, b.major_axis);
    EXPECT_EQ(a.minor_axis, b.minor_axis);
    EXPECT_EQ(a.extents, b.extents);
    EXPECT_EQ(a.center, b.center);
    EXPECT_EQ(a.hull, b.hull);
    EXPECT_EQ(a.top_area_m2, b.top_area_m2);
    EXPECT_EQ(std::isnan(a.horizontal_share), std::isnan(b.horizontal_share));
    if (!std::isnan(b.horizontal_share)) {
      EXPECT_EQ(a.horizontal_share, b.horizontal_share);
    }
    EXPECT_EQ(a.point_count, b.point_count);
    EXPECT_EQ(a.pixels, b.pixels);
    EXPECT_EQ(a.mean_confidence, b.mean_confidence);
    ASSERT_EQ(a.search_positions.size(), b.search_positions.size());
    for (std::size_t j = 0; j < a.search_positions.size(); ++j) {
      const SearchPosition& p = a.search_positions[j];
      const SearchPosition& q = b.search_positions[j];
      EXPECT_EQ(p.xy, q.xy);
      EXPECT_EQ(p.yaw, q.yaw);
      EXPECT_EQ(p.reachable, q.reachable);
      EXPECT_EQ(p.reason, q.reason);
      EXPECT_EQ(p.side, q.side);
      EXPECT_EQ(p.along_m, q.along_m);
    }
  }
}

// detectTablesInto reuses the tables of the detection it writes into (their
// pixel lists and hulls): whatever that detection held (more tables, fewer,
// larger ones, rejected clusters and their reasons, nothing), the result is
// the fresh one's, field for field.
TEST(FindTables, IntoAUsedDetectionEqualsAFreshOne) {
  Scene two;  // two tables, a small cluster and its reason
  two.addFloor(-1.0f, 6.0f, -3.0f, 3.0f);
  two.addTop({2.0f, -1.0f}, 0.0f, 1.6f, 0.6f, 0.72f);
  two.addTop({2.0f, -0.45f}, 0.0f, 1.6f, 0.3f, 0.72f);
  two.addTop({4.5f, 1.5f}, 0.0f, 0.1f, 0.1f, 0.9f);
  Scene one;  // one table, rotated, fewer points than the larger of `two`
  one.addFloor(-1.0f, 5.0f, -3.0f, 3.0f);
  one.addTop({2.0f, 0.3f}, 0.5f, 1.2f, 0.7f, 0.74f, 0.01f, 0.8f);
  Scene big;  // one table with more points than any table above
  big.addFloor(-1.0f, 5.0f, -3.0f, 3.0f);
  big.addTop({2.5f, 0.0f}, -0.2f, 2.0f, 1.0f, 0.70f, 0.008f);
  Scene none;  // floor only
  none.addFloor(-1.0f, 4.0f, -2.0f, 2.0f);
  Scene no_ground;  // no ground plane: an empty cloud
  no_ground.labels = one.labels;
  const std::vector<std::pair<const Scene*, std::string>> stream = {
      {&two, "two tables"}, {&one, "one table"},  {&big, "a big table"},
      {&two, "two tables"}, {&none, "no table"},  {&two, "two tables"},
      {&no_ground, "no ground"}, {&big, "a big table"}, {&one, "one table"}};
  const TableConfig config;
  TableDetection used;
  for (const auto& [scene, what] : stream) {
    const TableDetection fresh = detectTables(scene->cloud, scene->labels, config);
    detectTablesInto(scene->cloud, scene->labels, config, nullptr, used);
    expectSameDetection(used, fresh, what);
  }
  // And a detection's own contents are not kept by mistake: every field is
  // replaced, also those the function only counts.
  used.table_points = used.clusters_rejected = 12345;
  used.diagnostics = {"stale"};
  used.tables.emplace_back();
  detectTablesInto(none.cloud, none.labels, config, nullptr, used);
  expectSameDetection(used, detectTables(none.cloud, none.labels, config), "stale fields");
}

TEST(FindTables, ImplausibleHeightsAreNotTables) {
  Scene s;
  s.addFloor(-1.0f, 4.0f, -2.0f, 2.0f);
  s.addTop({2.0f, 0.0f}, 0.0f, 1.0f, 0.6f, 0.1f);  // "table" labels on the floor: wrong labels
  s.addTop({2.0f, 0.0f}, 0.0f, 1.0f, 0.6f, 2.0f);  // and above the head
  const TableDetection d = detectTables(s.cloud, s.labels, TableConfig{});
  EXPECT_TRUE(d.tables.empty());
  EXPECT_EQ(d.implausible_points,
            std::count(s.labels.labels.begin(), s.labels.labels.end(), kTable));
  EXPECT_TRUE(hasDiagnostic(d, "outside [0.3, 1.3] m height")) << joined(d.diagnostics);
}

TEST(FindTablesBadInput, NoGroundPlaneMeansNoTablesWithAReason) {
  const OrganizedCloud empty;  // what the segmenter passes when no ground plane was found
  LabelImage labels;
  labels.width = 4;
  labels.height = 2;
  labels.labels.assign(8, kTable);
  const TableDetection d = detectTables(empty, labels, TableConfig{});
  EXPECT_TRUE(d.tables.empty());
  EXPECT_TRUE(hasDiagnostic(d, "no ground plane")) << joined(d.diagnostics);
  EXPECT_TRUE(findTables(empty, labels, TableConfig{}).empty());
}

TEST(FindTablesBadInput, NanPointsAreSkippedWithAReason) {
  Scene s;
  s.addFloor(-1.0f, 4.0f, -2.0f, 2.0f);
  s.addTop({2.0f, 0.0f}, 0.0f, 1.0f, 0.6f, 0.75f);
  for (int i = 0; i < 300; ++i) {
    s.add({kNaN, kNaN, kNaN}, kTable);
    s.add({2.0f, kNaN, 0.75f}, kTable);  // a NaN in x or y alone is caught too
    s.add({kNaN, 0.0f, 0.75f}, kFloor);
  }
  const TableDetection d = detectTables(s.cloud, s.labels, TableConfig{});
  ASSERT_EQ(d.tables.size(), 1u);
  EXPECT_EQ(d.nonfinite_points, 600);
  EXPECT_TRUE(hasDiagnostic(d, "non-finite")) << joined(d.diagnostics);
  EXPECT_TRUE(std::isfinite(d.tables[0].centroid.x()));
  EXPECT_NEAR(d.tables[0].extents.x(), 0.5f, 0.01f);
}

TEST(FindTablesBadInput, LineOfPointsAndSinglePointAreDegenerate) {
  TableConfig config;
  config.min_cluster_points = 1;
  Scene line;
  line.addFloor(-1.0f, 4.0f, -2.0f, 2.0f);
  for (int i = 0; i < 100; ++i) line.add({1.0f + 0.01f * i, 0.5f, 0.8f}, kTable);
  TableDetection d = detectTables(line.cloud, line.labels, config);
  EXPECT_TRUE(d.tables.empty());
  EXPECT_TRUE(hasDiagnostic(d, "degenerate")) << joined(d.diagnostics);

  Scene single;
  single.addFloor(-1.0f, 4.0f, -2.0f, 2.0f);
  single.add({2.0f, 0.0f, 0.8f}, kTable);
  d = detectTables(single.cloud, single.labels, config);
  EXPECT_TRUE(d.tables.empty());
  EXPECT_TRUE(hasDiagnostic(d, "degenerate")) << joined(d.diagnostics);

  // Three points: a cluster, a hull of no width.
  Scene three;
  for (int i = 0; i < 3; ++i) three.add({2.0f + 0.02f * i, 0.0f, 0.8f}, kTable);
  d = detectTables(three.cloud, three.labels, config);
  EXPECT_TRUE(d.tables.empty());
  EXPECT_TRUE(hasDiagnostic(d, "degenerate")) << joined(d.diagnostics);
}

TEST(FindTablesBadInput, SizeMismatchAndBadSettingsThrow) {
  Scene s;
  s.addTop({2.0f, 0.0f}, 0.0f, 1.0f, 0.6f, 0.75f);
  LabelImage short_labels = s.labels;
  short_labels.labels.pop_back();
  EXPECT_THROW(detectTables(s.cloud, short_labels, TableConfig{}), Error);
  LabelImage bad_confidence = s.labels;
  bad_confidence.confidence.resize(3);
  EXPECT_THROW(detectTables(s.cloud, bad_confidence, TableConfig{}), Error);
  OrganizedCloud bad_cloud = s.cloud;
  bad_cloud.width += 1;
  EXPECT_THROW(detectTables(bad_cloud, s.labels, TableConfig{}), Error);

  auto expectSettingError = [&](TableConfig config, const std::string& key) {
    try {
      detectTables(s.cloud, s.labels, config);
      ADD_FAILURE() << "no error for " << key;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  };
  TableConfig c;
  c.cluster_tolerance_m = kNaN;
  expectSettingError(c, "tables.cluster_tolerance_m");
  c = TableConfig{};
  c.min_cluster_points = 10;
  c.max_cluster_points = 5;
  expectSettingError(c, "tables.max_cluster_points");
  c = TableConfig{};
  c.max_table_height_m = 0.2f;
  expectSettingError(c, "tables.max_table_height_m");
  c = TableConfig{};
  c.min_floor_observed_fraction = 1.5f;
  expectSettingError(c, "tables.min_floor_observed_fraction");
  c = TableConfig{};
  c.floor_cell_m = 0.0f;
  expectSettingError(c, "tables.floor_cell_m");
  for (int stride : {0, -1, 9}) {
    c = TableConfig{};
    c.point_stride = stride;
    expectSettingError(c, "tables.point_stride");
  }
}

TEST(FindTablesReachability, ObstacleAndUnseenFloorAreFlaggedNotDropped) {
  // Table along x at y = 0, 0.8 m deep: positions at y = ±0.9.
  Scene s;
  s.addFloor(0.0f, 4.0f, -3.0f, 0.0f);  // floor seen only on the -y side
  s.addTop({2.0f, 0.0f}, 0.0f, 1.0f, 0.8f, 0.75f);
  TableDetection d = detectTables(s.cloud, s.labels, TableConfig{});
  ASSERT_EQ(d.tables.size(), 1u);
  ASSERT_EQ(d.tables[0].search_positions.size(), 2u);
  for (const auto& p : d.tables[0].search_positions) {
    if (p.xy.y() > 0.0f) {
      EXPECT_FALSE(p.reachable);
      EXPECT_NE(p.reason.find("no observed floor"), std::string::npos) << p.reason;
    } else {
      EXPECT_TRUE(p.reachable) << p.reason;
      EXPECT_TRUE(p.reason.empty());
    }
  }

  // A chair (points 0.05..1 m high) within the robot radius of the -y position.
  for (float z = 0.1f; z <= 0.9f; z += 0.05f) {
    for (float x = 1.9f; x <= 2.1f; x += 0.05f) s.add({x, -0.8f, z}, kChair);
  }
  // Low clutter (below obstacle_min_height_m) and a few far points do not count.
  for (int i = 0; i < 50; ++i) s.add({2.0f, -0.9f, 0.02f}, kUnknown);
  d = detectTables(s.cloud, s.labels, TableConfig{});
  ASSERT_EQ(d.tables.size(), 1u);
  for (const auto& p : d.tables[0].search_positions) {
    EXPECT_FALSE(p.reachable);
    if (p.xy.y() < 0.0f) {
      EXPECT_NE(p.reason.find("obstacle within robot radius"), std::string::npos) << p.reason;
      EXPECT_EQ(p.reason.find("no observed floor"), std::string::npos) << p.reason;
    }
  }

  // A smaller robot clears the chair (0.1 m from the position).
  TableConfig small;
  small.robot_radius_m = 0.05f;
  d = detectTables(s.cloud, s.labels, small);
  for (const auto& p : d.tables[0].search_positions) {
    if (p.xy.y() < 0.0f) {
      EXPECT_TRUE(p.reachable) << p.reason;
    }
  }
}

// Step 1 of detectTables (the table points) has an AVX2 variant: the same
// points and pixels in the same order, and the same counts by reason, as the
// portable loop, whatever the labels' runs (image widths that leave tails of
// every length, runs across rows) and points (NaN, infinities, heights at
// and beyond the limits, beyond 100 m).
TEST(FindTables, VectorTablePointsMatchThePortableLoop) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> coord(-3.0f, 3.0f);
  std::uniform_real_distribution<float> height(0.0f, 1.5f);
  std::uniform_int_distribution<int> kind(0, 29);
  const TableConfig config;
  const float inf = std::numeric_limits<float>::infinity();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  int nonfinite = 0, implausible = 0, kept = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const int w = 1 + static_cast<int>(rng() % 90), h = 1 + static_cast<int>(rng() % 20);
    OrganizedCloud cloud;
    cloud.width = w;
    cloud.height = h;
    LabelImage labels;
    labels.width = w;
    labels.height = h;
    bool table = false;
    for (int i = 0; i < w * h; ++i) {
      if (rng() % 13 == 0) table = !table;  // runs of table labels
      Eigen::Vector3f p(coord(rng), coord(rng), height(rng));
      switch (kind(rng)) {
        case 0: p[static_cast<int>(rng() % 3)] = nan; break;
        case 1: p[static_cast<int>(rng() % 3)] = (rng() & 1) ? inf : -inf; break;
        case 2: p.z() = (rng() & 1) ? config.min_table_height_m : config.max_table_height_m; break;
        case 3: p.x() = (rng() & 1) ? 100.0f : -100.5f; break;
        case 4: p.y() = (rng() & 1) ? -100.0f : 1e30f; break;
        default: break;
      }
      cloud.points.push_back(p);
      labels.labels.push_back(table ? kTable : kFloor);
    }
    labels.confidence.assign(labels.labels.size(), 1.0f);
    std::vector<Eigen::Vector3f> points_simd, points_portable;
    std::vector<int> pixels_simd, pixels_portable;
    TableDetection simd, portable;
    tables_detail::collectTablePoints(cloud, labels, config, points_simd, pixels_simd, simd, true);
    tables_detail::collectTablePoints(cloud, labels, config, points_portable, pixels_portable,
                                      portable, false);
    ASSERT_EQ(pixels_simd, pixels_portable) << "trial " << trial;
    ASSERT_EQ(points_simd.size(), points_portable.size()) << "trial " << trial;
    for (std::size_t k = 0; k < points_simd.size(); ++k) {
      ASSERT_EQ(std::memcmp(points_simd[k].data(), points_portable[k].data(), 12), 0)
          << "trial " << trial << ", point " << k;
    }
    EXPECT_EQ(simd.table_points, portable.table_points) << "trial " << trial;
    EXPECT_EQ(simd.nonfinite_points, portable.nonfinite_points) << "trial " << trial;
    EXPECT_EQ(simd.implausible_points, portable.implausible_points) << "trial " << trial;
    // Both against the labels themselves: every table pixel is counted once,
    // and only table pixels are kept.
    EXPECT_EQ(portable.table_points, static_cast<int>(pixels_portable.size()));
    EXPECT_EQ(portable.table_points + portable.nonfinite_points + portable.implausible_points,
              std::count(labels.labels.begin(), labels.labels.end(), kTable))
        << "trial " << trial;
    for (const int pixel : pixels_portable) {
      ASSERT_EQ(labels.labels[static_cast<std::size_t>(pixel)], kTable) << "trial " << trial;
    }
    nonfinite += portable.nonfinite_points;
    implausible += portable.implausible_points;
    kept += portable.table_points;
  }
  // Every kind of point occurred.
  EXPECT_GT(nonfinite, 50);
  EXPECT_GT(implausible, 50);
  EXPECT_GT(kept, 1000);
}

// The reachability grid's pass over the cloud has an AVX2 variant: it must
// build the same grid as the portable loop, bit for bit, whatever the points
// (NaN, infinities, points on cell borders and on the region's edges, every
// label, heights at the band limits), and for cloud sizes that leave a tail
// of fewer than eight points.
TEST(FindTablesReachability, VectorPassBuildsTheSameGridAsThePortableOne) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> coord(-1.0f, 5.0f);
  std::uniform_real_distribution<float> height(-0.3f, 1.8f);
  std::uniform_int_distribution<int> label(0, 7);
  std::uniform_int_distribution<int> kind(0, 19);
  const TableConfig config;
  const float inf = std::numeric_limits<float>::infinity();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const Eigen::AlignedBox2f region(Eigen::Vector2f(0.25f, -0.5f), Eigen::Vector2f(3.5f, 3.0f));
  const std::vector<Eigen::Vector2f> positions = {{1.0f, 0.0f}, {3.4f, 2.9f}, {0.3f, 1.5f}};
  std::size_t obstacles = 0, floor_cells = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const int n = 1 + static_cast<int>(rng() % 3000);
    OrganizedCloud cloud;
    cloud.width = n;
    cloud.height = 1;
    LabelImage labels;
    labels.width = n;
    labels.height = 1;
    for (int i = 0; i < n; ++i) {
      Eigen::Vector3f p(coord(rng), coord(rng), height(rng));
      switch (kind(rng)) {
        case 0: p[static_cast<int>(rng() % 3)] = nan; break;
        case 1: p[static_cast<int>(rng() % 3)] = (rng() & 1) ? inf : -inf; break;
        case 2:  // on a cell border
          p.x() = region.min().x() + static_cast<float>(rng() % 70) * config.floor_cell_m;
          break;
        case 3: p.y() = region.min().y(); break;  // on the region's edge
        case 4: p.z() = (rng() & 1) ? config.obstacle_min_height_m : config.robot_height_m; break;
        case 5: p.z() = (rng() & 1) ? config.floor_tolerance_m : -config.floor_tolerance_m; break;
        case 6: p.z() = -0.0f; break;
        default: break;
      }
      cloud.points.push_back(p);
      labels.labels.push_back(kind(rng) < 6 ? kFloor : static_cast<std::uint8_t>(label(rng)));
    }
    labels.confidence.assign(labels.labels.size(), 1.0f);
    const tables_detail::ReachabilityGrid portable(cloud, labels, region, positions, config, false);
    const std::vector<std::uint8_t>& floor_seen = portable.floorSeen();
    const std::vector<int>& start = portable.obstacleStart();
    const std::vector<Eigen::Vector2f>& points = portable.obstaclePoints();
    const tables_detail::ReachabilityGrid vector(cloud, labels, region, positions, config, true);
    ASSERT_EQ(vector.floorSeen(), floor_seen) << "trial " << trial;
    ASSERT_EQ(vector.obstacleStart(), start) << "trial " << trial;
    ASSERT_EQ(vector.obstaclePoints().size(), points.size()) << "trial " << trial;
    for (std::size_t k = 0; k < points.size(); ++k) {
      ASSERT_EQ(std::memcmp(vector.obstaclePoints()[k].data(), points[k].data(), 8), 0)
          << "trial " << trial << ", obstacle point " << k;
    }
    obstacles += points.size();
    floor_cells += static_cast<std::size_t>(std::count(floor_seen.begin(), floor_seen.end(), 1));
  }
  // The cases above must have exercised both kinds of point.
  EXPECT_GT(obstacles, 100u);
  EXPECT_GT(floor_cells, 100u);
}

// ------------------------------------------------- rendered synthetic scenes

struct View {
  synth::RenderedFrame rendered;
  OrganizedCloud cloud_ground;
  LabelImage labels;
};

View renderView(const synth::SynthScene& scene, const synth::CameraPose& pose,
                std::uint64_t noise_seed, bool noise = true) {
  synth::RenderOptions options;
  options.noise.enabled = noise;
  View v;
  v.rendered = synth::render(scene, pose, options, noise_seed);
  const RgbdFrame& frame = v.rendered.labeled.frame;
  const GroundPlane ground = groundFromExtrinsics(frame.extrinsics.value());
  v.cloud_ground = transformCloud(frameToCloud(frame), ground.camera_to_ground);
  v.labels.width = frame.width;
  v.labels.height = frame.height;
  v.labels.labels = v.rendered.labeled.labels;
  return v;
}

// A rectangular table (top and four legs) with its ground truth.
synth::TableTruth addRectTable(synth::SynthScene& scene, const Eigen::Vector2d& center, double yaw,
                               double length, double width, double height) {
  const double top = 0.03;
  std::vector<synth::Primitive> parts;
  synth::Primitive slab;
  slab.center = Eigen::Vector3d(center.x(), center.y(), height - 0.5 * top);
  slab.yaw = yaw;
  slab.half_extent = Eigen::Vector3d(0.5 * length, 0.5 * width, 0.5 * top);
  slab.material.color = {150, 110, 70};
  parts.push_back(slab);
  const Eigen::Vector2d ax(std::cos(yaw), std::sin(yaw)), ay(-std::sin(yaw), std::cos(yaw));
  for (int sx : {-1, 1}) {
    for (int sy : {-1, 1}) {
      synth::Primitive leg = slab;
      const Eigen::Vector2d xy =
          center + sx * (0.5 * length - 0.06) * ax + sy * (0.5 * width - 0.06) * ay;
      leg.center = Eigen::Vector3d(xy.x(), xy.y(), 0.5 * (height - top));
      leg.half_extent = Eigen::Vector3d(0.025, 0.025, 0.5 * (height - top));
      parts.push_back(leg);
    }
  }
  synth::TableTruth truth;
  truth.id = static_cast<int>(scene.tables.size());
  truth.object = synth::addObject(scene, "table", Label::Table, parts);
  truth.shape = synth::TableShape::Rectangular;
  truth.kind = "dining";
  truth.center_xy = center;
  truth.yaw = yaw;
  truth.size = Eigen::Vector2d(length, width);
  truth.height = height;
  for (const auto& p : rectangle(center.cast<float>(), static_cast<float>(yaw),
                                 static_cast<float>(length), static_cast<float>(width))) {
    truth.top_polygon.push_back(p.cast<double>());
  }
  scene.tables.push_back(truth);
  return truth;
}

std::vector<Eigen::Vector2f> polygonOf(const synth::TableTruth& t) {
  std::vector<Eigen::Vector2f> out;
  for (const auto& p : t.top_polygon) out.push_back(p.cast<float>());
  return out;
}

// Checks one table found in view against the truth in the ground frame.
void expectMatchesTruth(const TableCluster& found, const synth::TableTruth& truth_ground,
                        const TableConfig& config, const std::string& what) {
  SCOPED_TRACE(what);
  const Eigen::Vector2f major(std::cos(static_cast<float>(truth_ground.yaw)),
                              std::sin(static_cast<float>(truth_ground.yaw)));
  const Eigen::Vector2f minor(-major.y(), major.x());
  const auto outline = polygonOf(truth_ground);
  EXPECT_NEAR(found.top_height, truth_ground.height, 0.02);
  EXPECT_LT(axisAngleDeg(found.minor_axis, minor), 5.0f);
  EXPECT_NEAR(found.extents.x(), 0.5 * truth_ground.size.x(), 0.03);
  EXPECT_NEAR(found.extents.y(), 0.5 * truth_ground.size.y(), 0.03);
  ASSERT_FALSE(found.search_positions.empty());
  const int per_side = static_cast<int>(found.search_positions.size()) / 2;
  for (const auto& p : found.search_positions) {
    EXPECT_NEAR(distanceToPolygon(p.xy, outline), config.safety_distance_m, 0.03)
        << "position " << p.xy.transpose();
    EXPECT_FALSE(insidePolygon(p.xy, outline, 0.0f));
    // Facing the table across its long side, i.e. along the true second axis.
    EXPECT_LT(axisAngleDeg({std::cos(p.yaw), std::sin(p.yaw)}, minor), 5.0f);
    if (per_side == 1) {
      // The paper's positions lie on the true second axis through the centre.
      EXPECT_LT(axisAngleDeg(p.xy - truth_ground.center_xy.cast<float>(), minor), 5.0f)
          << "position " << p.xy.transpose();
    }
  }
}

TEST(SynthTables, KnownTableFromSeveralViewpoints) {
  synth::SynthScene scene = synth::makeEmptyRoom({7.0, 6.0, 2.6});
  const synth::TableTruth truth = addRectTable(scene, {3.5, 3.0}, 0.35, 1.4, 0.8, 0.75);
  const TableConfig config;
  struct Case {
    Eigen::Vector2d xy;
    double pitch;
    bool facing_long_side;  // else looking along the table from one end
  };
  // From both long sides and both ends, 1.9 to 2.2 m from the table centre.
  int checked = 0;
  for (const Case& c : {Case{{2.9, 1.2}, 0.55, true}, Case{{1.5, 2.2}, 0.45, false},
                        Case{{5.6, 2.4}, 0.5, false}, Case{{3.9, 5.0}, 0.55, true}}) {
    synth::CameraPose pose;
    pose.xy = c.xy;
    pose.yaw = std::atan2(truth.center_xy.y() - c.xy.y(), truth.center_xy.x() - c.xy.x());
    pose.height_m = 1.2;
    pose.pitch_rad = c.pitch;
    const View v = renderView(scene, pose, 11 + checked);
    const TableDetection d = detectTables(v.cloud_ground, v.labels, config);
    const std::string what = "camera at " + std::to_string(c.xy.x()) + ", " +
                             std::to_string(c.xy.y()) + joined(d.diagnostics);
    ASSERT_EQ(d.tables.size(), 1u) << what;
    expectMatchesTruth(d.tables[0], synth::tableInGroundFrame(truth, pose), config, what);
    // Nothing stands in the empty room: no position is blocked, and the side
    // facing the camera has observed floor. (Behind the table the floor is
    // seen between the legs, under the top.)
    int reachable = 0;
    for (const auto& p : d.tables[0].search_positions) {
      EXPECT_EQ(p.reachable, p.reason.empty()) << p.reason;
      EXPECT_EQ(p.reason.find("obstacle"), std::string::npos) << what << ": " << p.reason;
      const bool near_side = p.xy.norm() < d.tables[0].center.norm();
      if (c.facing_long_side && near_side) {
        EXPECT_TRUE(p.reachable) << what << ": " << p.reason;
      }
      reachable += p.reachable;
    }
    if (c.facing_long_side) {
      EXPECT_GT(reachable, 0);
    }
    ++checked;
  }
}

TEST(SynthTables, LongTableGetsPositionsAlongItsLongSides) {
  synth::SynthScene scene = synth::makeEmptyRoom({7.0, 6.0, 2.6});
  const synth::TableTruth truth = addRectTable(scene, {3.5, 3.0}, -0.1, 2.0, 0.4, 0.72);
  synth::CameraPose pose;
  pose.xy = {3.5, 1.0};
  pose.yaw = kPi / 2;
  pose.pitch_rad = 0.5;
  const View v = renderView(scene, pose, 5);
  const TableConfig config;
  const TableDetection d = detectTables(v.cloud_ground, v.labels, config);
  ASSERT_EQ(d.tables.size(), 1u) << joined(d.diagnostics);
  // 2.0 m long, 0.4 m deep: from 0.5 m the arm (0.8 m) reaches the midline
  // (0.7 m away) over ±0.39 m of edge, so ceil(1.0 / 0.39) = 3 positions per side.
  EXPECT_EQ(d.tables[0].search_positions.size(), 6u);
  expectMatchesTruth(d.tables[0], synth::tableInGroundFrame(truth, pose), config, "long table");
}

// tables.point_stride 2: clustering and geometry on a quarter of the table
// points. Every table pixel but the few (flying pixels at the edge) with no
// sampled point within the tolerance still belongs to the table, and the
// geometry stays close to that of every point: the bounds below are what
// the approximation is documented to give (tables.hpp, perf-log §9j),
// a little looser than expectMatchesTruth's at stride 1.
TEST(SynthTables, PointStrideTwoKeepsThePixelsAndNearlyTheGeometry) {
  synth::SynthScene scene = synth::makeEmptyRoom({7.0, 6.0, 2.6});
  const synth::TableTruth truth = addRectTable(scene, {3.5, 3.0}, 0.35, 1.4, 0.8, 0.75);
  synth::CameraPose pose;
  pose.xy = {2.9, 1.2};
  pose.yaw = std::atan2(truth.center_xy.y() - 1.2, truth.center_xy.x() - 2.9);
  pose.height_m = 1.2;
  pose.pitch_rad = 0.55;
  View v = renderView(scene, pose, 11);
  v.labels.confidence.assign(v.labels.labels.size(), 0.7f);
  TableConfig exact, strided;
  strided.point_stride = 2;
  const TableDetection all = detectTables(v.cloud_ground, v.labels, exact);
  const TableDetection sampled = detectTables(v.cloud_ground, v.labels, strided);
  ASSERT_EQ(all.tables.size(), 1u) << joined(all.diagnostics);
  ASSERT_EQ(sampled.tables.size(), 1u) << joined(sampled.diagnostics);
  EXPECT_EQ(sampled.table_points, all.table_points);
  const TableCluster& a = all.tables[0];
  const TableCluster& b = sampled.tables[0];
  // Left-out points may also be noise outside the table (clusters of their own at stride 1).
  EXPECT_LE(b.point_count, a.point_count);
  EXPECT_GE(b.point_count + sampled.unsampled_points, a.point_count);
  EXPECT_LT(sampled.unsampled_points, a.point_count / 1000) << joined(sampled.diagnostics);
  EXPECT_EQ(b.point_count, static_cast<int>(b.pixels.size()));
  EXPECT_TRUE(std::includes(a.pixels.begin(), a.pixels.end(), b.pixels.begin(), b.pixels.end()));
  EXPECT_NEAR(b.mean_confidence, 0.7f, 1e-5f);
  EXPECT_NEAR(b.top_height, a.top_height, 0.005f);
  EXPECT_LT((b.center - a.center).norm(), 0.02f);
  EXPECT_LT(axisAngleDeg(b.major_axis, a.major_axis), 3.0f);
  EXPECT_NEAR(b.extents.x(), a.extents.x(), 0.02f);
  EXPECT_NEAR(b.extents.y(), a.extents.y(), 0.02f);
  EXPECT_NEAR(b.top_area_m2, a.top_area_m2, 0.1f * a.top_area_m2);
  ASSERT_EQ(b.search_positions.size(), a.search_positions.size());
  const auto outline = polygonOf(synth::tableInGroundFrame(truth, pose));
  for (std::size_t k = 0; k < b.search_positions.size(); ++k) {
    EXPECT_LT((b.search_positions[k].xy - a.search_positions[k].xy).norm(), 0.05f);
    EXPECT_NEAR(distanceToPolygon(b.search_positions[k].xy, outline), strided.safety_distance_m,
                0.05f);
  }
}

// A table point with no sampled point near it (a flying pixel between two
// sampled ones) is left out at stride 2 and counted, not silently dropped.
TEST(FindTables, PointStrideCountsTablePointsWithNoSampledNeighbour) {
  // A 200 x 100 pixel organized top, 1 cm apart, at 0.75 m; floor around it
  // is not needed to find the table (only to reach it).
  const int width = 200, height = 100;
  OrganizedCloud cloud;
  LabelImage labels;
  cloud.width = labels.width = width;
  cloud.height = labels.height = height;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      cloud.points.emplace_back(1.5f + 0.01f * y, -1.0f + 0.01f * x, 0.75f);
      labels.labels.push_back(kTable);
    }
  }
  // Pixel (51, 31) is odd in x and y: no sampled pixel of its own; lifted
  // 0.3 m it is no sampled corner's neighbour either.
  cloud.points[31 * width + 51].z() += 0.3f;
  TableConfig config;
  config.point_stride = 2;
  const TableDetection d = detectTables(cloud, labels, config);
  ASSERT_EQ(d.tables.size(), 1u) << joined(d.diagnostics);
  EXPECT_EQ(d.table_points, width * height);
  EXPECT_EQ(d.unsampled_points, 1);
  EXPECT_TRUE(hasDiagnostic(d, "no sampled point within tables.cluster_tolerance_m"))
      << joined(d.diagnostics);
  EXPECT_EQ(d.tables[0].point_count, width * height - 1);
  EXPECT_EQ(std::count(d.tables[0].pixels.begin(), d.tables[0].pixels.end(), 31 * width + 51), 0);
  EXPECT_TRUE(std::is_sorted(d.tables[0].pixels.begin(), d.tables[0].pixels.end()));
  // Table labels on odd rows only: no table point at a sampled pixel at all.
  LabelImage odd_rows = labels;
  for (int y = 0; y < height; y += 2) {
    std::fill_n(odd_rows.labels.begin() + y * width, width, kFloor);
  }
  const TableDetection none = detectTables(cloud, odd_rows, config);
  EXPECT_TRUE(none.tables.empty());
  EXPECT_EQ(none.table_points, width * height / 2);
  EXPECT_EQ(none.unsampled_points, none.table_points);
  EXPECT_TRUE(hasDiagnostic(none, "none at a sampled pixel")) << joined(none.diagnostics);
  // At stride 1 the same point is its own cluster, dropped as too small.
  config.point_stride = 1;
  const TableDetection exact = detectTables(cloud, labels, config);
  ASSERT_EQ(exact.tables.size(), 1u);
  EXPECT_EQ(exact.unsampled_points, 0);
  EXPECT_EQ(exact.tables[0].point_count, width * height - 1);
  EXPECT_TRUE(hasDiagnostic(exact, "below tables.min_cluster_points")) << joined(exact.diagnostics);
}

TEST(SynthTables, FloorHiddenBehindASolidTableIsNoObservedFloor) {
  // A kitchen island: one solid block labelled table, 0.9 m high. Its top
  // hides the floor behind it, its front face is table-labelled too.
  synth::SynthScene scene = synth::makeEmptyRoom({7.0, 6.0, 2.6});
  synth::Primitive block;
  block.center = Eigen::Vector3d(3.5, 3.0, 0.45);
  block.yaw = 0.2;
  block.half_extent = Eigen::Vector3d(0.8, 0.4, 0.45);
  block.material.color = {180, 160, 140};
  synth::TableTruth truth;
  truth.object = synth::addObject(scene, "table", Label::Table, {block});
  truth.center_xy = {3.5, 3.0};
  truth.yaw = 0.2;
  truth.size = {1.6, 0.8};
  truth.height = 0.9;
  for (const auto& p : rectangle({3.5f, 3.0f}, 0.2f, 1.6f, 0.8f)) {
    truth.top_polygon.push_back(p.cast<double>());
  }
  synth::CameraPose pose;
  pose.xy = {3.3, 1.0};
  pose.yaw = kPi / 2;
  pose.pitch_rad = 0.45;
  const View v = renderView(scene, pose, 21);
  const TableConfig config;
  const TableDetection d = detectTables(v.cloud_ground, v.labels, config);
  ASSERT_EQ(d.tables.size(), 1u) << joined(d.diagnostics);
  expectMatchesTruth(d.tables[0], synth::tableInGroundFrame(truth, pose), config, "island");
  int near_reachable = 0, far_unseen = 0;
  for (const auto& p : d.tables[0].search_positions) {
    if (p.xy.norm() < d.tables[0].center.norm()) {
      near_reachable += p.reachable;
    } else {
      EXPECT_FALSE(p.reachable);
      far_unseen += p.reason.find("no observed floor") != std::string::npos;
    }
  }
  EXPECT_EQ(near_reachable, static_cast<int>(d.tables[0].search_positions.size()) / 2);
  EXPECT_EQ(far_unseen, static_cast<int>(d.tables[0].search_positions.size()) / 2);
}

TEST(SynthTables, ObstacleAtASearchPositionMakesItUnreachable) {
  synth::SynthScene scene = synth::makeEmptyRoom({7.0, 6.0, 2.6});
  const synth::TableTruth truth = addRectTable(scene, {3.5, 3.0}, 0.0, 1.2, 0.8, 0.75);
  // A cabinet where the near-side (y = 3 - 0.4 - 0.5 = 2.1) position would be.
  synth::Primitive box;
  box.center = Eigen::Vector3d(3.5, 2.05, 0.4);
  box.half_extent = Eigen::Vector3d(0.2, 0.15, 0.4);
  box.material.color = {200, 200, 60};
  synth::addObject(scene, "cabinet", Label::Cabinet, {box});
  synth::CameraPose pose;
  pose.xy = {3.2, 0.3};
  pose.yaw = std::atan2(3.0 - 0.3, 3.5 - 3.2);
  pose.pitch_rad = 0.5;
  const View v = renderView(scene, pose, 3);
  const TableDetection d = detectTables(v.cloud_ground, v.labels, TableConfig{});
  ASSERT_EQ(d.tables.size(), 1u) << joined(d.diagnostics);
  const auto& t = d.tables[0];
  const Eigen::Vector2f cabinet_ground =
      (synth::worldToGround(pose) * Eigen::Vector3d(3.5, 2.05, 0.0)).head<2>().cast<float>();
  bool blocked = false;
  for (const auto& p : t.search_positions) {
    if ((p.xy - cabinet_ground).norm() < 0.4f) {
      blocked = true;
      EXPECT_FALSE(p.reachable);
      EXPECT_NE(p.reason.find("obstacle within robot radius"), std::string::npos) << p.reason;
    }
  }
  EXPECT_TRUE(blocked) << "no search position near the cabinet";
}

TEST(SynthTables, EveryTableInViewAndRangeIsFoundInApartments) {
  const TableConfig config;
  int frames = 0, tables_checked = 0;
  for (std::uint64_t seed : {1u, 2u, 3u, 4u}) {
    const synth::SynthScene scene = synth::makeApartment(seed);
    const auto path = synth::cameraPath(scene, 240, 10.0);
    for (std::size_t f = 0; f < path.size(); f += 40) {
      const synth::CameraPose& pose = path[f];
      const View v = renderView(scene, pose, seed * 1000 + f);
      const TableDetection d = detectTables(v.cloud_ground, v.labels, config);
      ++frames;
      const std::string what = "seed " + std::to_string(seed) + " frame " + std::to_string(f);
      // Every cluster is a real table (the labels are the truth).
      for (const auto& t : d.tables) {
        bool real = false;
        for (const auto& truth : scene.tables) {
          const auto g = synth::tableInGroundFrame(truth, pose);
          real |= insidePolygon(t.center, polygonOf(g), 0.05f) &&
                  std::abs(t.top_height - g.height) < 0.03;
        }
        EXPECT_TRUE(real) << what << ": cluster at " << t.center.transpose() << " h "
                          << t.top_height;
      }
      for (const auto& truth : scene.tables) {
        const auto g = synth::tableInGroundFrame(truth, pose);
        // In view and range: enough of its top has depth, centre within 4 m.
        // And its visible top covers at least tables.min_top_area_m2 (cells of
        // cluster_tolerance_m, as TableCluster::top_area_m2 counts them).
        int top_points = 0;
        std::set<std::pair<int, int>> top_cells;
        for (std::size_t i = 0; i < v.cloud_ground.points.size(); ++i) {
          const auto& p = v.cloud_ground.points[i];
          if (v.rendered.object[i] == truth.object && std::isfinite(p.z()) &&
              std::abs(p.z() - truth.height) < 0.03) {
            ++top_points;
            top_cells.emplace(static_cast<int>(std::floor(p.x() / config.cluster_tolerance_m)),
                              static_cast<int>(std::floor(p.y() / config.cluster_tolerance_m)));
          }
        }
        const float top_area = static_cast<float>(top_cells.size()) * config.cluster_tolerance_m *
                               config.cluster_tolerance_m;
        if (top_points < 2 * config.min_cluster_points || g.center_xy.norm() > 4.0 ||
            top_area < 1.2f * config.min_top_area_m2) {
          continue;
        }
        ++tables_checked;
        bool found = false;
        for (const auto& t : d.tables) {
          found |= insidePolygon(t.center, polygonOf(g), 0.05f) &&
                   std::abs(t.top_height - g.height) < 0.03;
        }
        EXPECT_TRUE(found) << what << ": table " << truth.id << " (" << truth.kind << ", "
                           << top_points << " top points) not found" << joined(d.diagnostics);
      }
    }
  }
  EXPECT_GE(tables_checked, 8) << "too few tables in view over " << frames << " frames";
}

TEST(SynthTables, RoomWithoutTablesGivesNone) {
  synth::SynthScene scene = synth::makeEmptyRoom({6.0, 5.0, 2.6});
  synth::Primitive cabinet;
  cabinet.center = Eigen::Vector3d(3.0, 4.5, 0.45);
  cabinet.half_extent = Eigen::Vector3d(0.6, 0.25, 0.45);
  synth::addObject(scene, "cabinet", Label::Cabinet, {cabinet});
  synth::Primitive seat;
  seat.center = Eigen::Vector3d(2.0, 3.0, 0.45);
  seat.half_extent = Eigen::Vector3d(0.22, 0.22, 0.02);
  synth::addObject(scene, "chair", Label::Chair, {seat});
  for (double yaw : {1.2, 1.57, 1.9}) {
    synth::CameraPose pose;
    pose.xy = {3.0, 0.5};
    pose.yaw = yaw;
    const View v = renderView(scene, pose, 9);
    const TableDetection d = detectTables(v.cloud_ground, v.labels, TableConfig{});
    EXPECT_TRUE(d.tables.empty());
    EXPECT_EQ(d.table_points, 0);
    EXPECT_TRUE(hasDiagnostic(d, "no table-labelled points")) << joined(d.diagnostics);
  }
}

// ----------------------------------------------------------------- real data

// Minimal reader for the PCD files of PCL's test data: organized,
// `FIELDS x y z rgba`, `DATA binary_compressed` (LZF, fields stored one
// after the other). Test-only: the product reads PCDs through findmug_io.
std::vector<std::uint8_t> lzfDecompress(const std::uint8_t* in, std::size_t in_size,
                                        std::size_t out_size) {
  std::vector<std::uint8_t> out;
  out.reserve(out_size);
  std::size_t i = 0;
  while (i < in_size) {
    const unsigned ctrl = in[i++];
    if (ctrl < 32) {  // literal run of ctrl + 1 bytes
      if (i + ctrl + 1 > in_size) throw Error("LZF literal overruns the input");
      out.insert(out.end(), in + i, in + i + ctrl + 1);
      i += ctrl + 1;
    } else {  // back reference
      std::size_t length = ctrl >> 5;
      if (length == 7) {
        if (i >= in_size) throw Error("LZF truncated");
        length += in[i++];
      }
      if (i >= in_size) throw Error("LZF truncated");
      const std::size_t back = ((ctrl & 0x1f) << 8) + in[i++] + 1;
      if (back > out.size()) throw Error("LZF reference before the start");
      const std::size_t from = out.size() - back;
      for (std::size_t k = 0; k < length + 2; ++k) out.push_back(out[from + k]);
    }
  }
  if (out.size() != out_size) throw Error("LZF size mismatch");
  return out;
}

OrganizedCloud readPcdXyz(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open");
  std::string line;
  int width = 0, height = 0;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string key;
    words >> key;
    if (key == "FIELDS" && line != "FIELDS x y z rgba") throw Error(path + ": fields " + line);
    if (key == "WIDTH") words >> width;
    if (key == "HEIGHT") words >> height;
    if (key == "DATA") {
      if (line != "DATA binary_compressed") throw Error(path + ": " + line);
      break;
    }
  }
  std::uint32_t sizes[2];
  in.read(reinterpret_cast<char*>(sizes), sizeof(sizes));
  std::vector<std::uint8_t> packed(sizes[0]);
  in.read(reinterpret_cast<char*>(packed.data()), sizes[0]);
  if (!in || width <= 0 || height <= 0) throw Error(path + ": truncated");
  const std::size_t n = static_cast<std::size_t>(width) * height;
  if (sizes[1] != n * 16) throw Error(path + ": unexpected payload size");
  const auto raw = lzfDecompress(packed.data(), packed.size(), sizes[1]);
  OrganizedCloud cloud;
  cloud.width = width;
  cloud.height = height;
  cloud.points.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (int axis = 0; axis < 3; ++axis) {
      std::memcpy(&cloud.points[i][axis], raw.data() + (axis * n + i) * 4, 4);
    }
  }
  return cloud;
}

TEST(RealDataTables, PclTableSceneMugGivesOneTable) {
  FINDMUG_REQUIRE_DATA(path, "pcl_test_clouds/table_scene_mug_stereo_textured.pcd");
  const OrganizedCloud cloud = readPcdXyz(path.string());
  // The file has no labels and shows no floor (a table top seen from 0.5 m,
  // a wall behind). Labels from geometry: the dominant plane (RANSAC, fixed
  // seed) is the table; the floor is put a nominal 0.75 m below it. What is
  // tested is clustering and shape on real stereo points with holes, noise
  // and a mug standing on the top.
  std::vector<std::size_t> valid;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (cloud.valid(i)) valid.push_back(i);
  }
  ASSERT_GT(valid.size(), 100000u);
  std::mt19937 rng(3);
  std::uniform_int_distribution<std::size_t> pick(0, valid.size() - 1);
  Eigen::Vector3f best_normal = Eigen::Vector3f::UnitZ();
  float best_offset = 0.0f;
  int best_support = 0;
  for (int iteration = 0; iteration < 200; ++iteration) {
    const Eigen::Vector3f a = cloud.points[valid[pick(rng)]];
    const Eigen::Vector3f b = cloud.points[valid[pick(rng)]];
    const Eigen::Vector3f c = cloud.points[valid[pick(rng)]];
    Eigen::Vector3f normal = (b - a).cross(c - a);
    if (normal.norm() < 1e-6f) continue;
    normal.normalize();
    const float offset = -normal.dot(a);
    int support = 0;
    for (std::size_t k = 0; k < valid.size(); k += 7) {
      support += std::abs(normal.dot(cloud.points[valid[k]]) + offset) < 0.01f;
    }
    if (support > best_support) {
      best_support = support;
      best_normal = normal;
      best_offset = offset;
    }
  }
  if (best_offset < 0.0f) {  // normal towards the camera, i.e. up from the top
    best_normal = -best_normal;
    best_offset = -best_offset;
  }
  LabelImage labels;
  labels.width = cloud.width;
  labels.height = cloud.height;
  labels.labels.assign(cloud.size(), kVoidLabel);
  int top_points = 0;
  for (std::size_t i : valid) {
    const bool on_top = std::abs(best_normal.dot(cloud.points[i]) + best_offset) < 0.015f;
    labels.labels[i] = on_top ? kTable : kUnknown;
    top_points += on_top;
  }
  const float table_height = 0.75f;
  const GroundPlane ground = groundFromPlane(best_normal, best_offset + table_height, 0);
  const OrganizedCloud cloud_ground = transformCloud(cloud, ground.camera_to_ground);
  const TableDetection d = detectTables(cloud_ground, labels, TableConfig{});
  ASSERT_EQ(d.tables.size(), 1u) << joined(d.diagnostics);
  const TableCluster& t = d.tables[0];
  EXPECT_NEAR(t.top_height, table_height, 0.01f);
  // Nearly all of the plane's points are one connected top.
  EXPECT_GT(t.point_count, 0.95 * top_points);
  // The visible part of the top is about 0.5 m across (see the file's extent).
  EXPECT_GT(t.extents.minCoeff(), 0.1f);
  EXPECT_LT(t.extents.maxCoeff(), 1.0f);
  EXPECT_GE(t.hull.size(), 4u);
  EXPECT_EQ(t.search_positions.size(), 2u);
}

// NYU Depth V2 frames (ground-truth labels mapped to findmug's 8 classes,
// ground plane fitted to the floor-labelled points as in the paper). Listed:
// the frames whose ground truth has a table of useful size (>= 1000 table
// pixels with depth) and enough floor for the ground plane, with the number
// of clusters our defaults give there; and frames without table pixels,
// which must give none. The counts were taken when this test was written and
// checked against the images: e.g. 0009 has the desk in front and the
// reception counter at the back (2); 0031 the desk, its left part cut off
// behind the chair, and a small table-labelled surface 13 cm below the top
// (3); in 0016 a 9 cm wide sliver of a second desk is dropped as too narrow. A changed count means
// clustering or the ground fit behaves differently: look at the frame before updating it.
TEST(RealDataTables, NyuFramesWithTablesGiveTableClusters) {
  FINDMUG_REQUIRE_DATA(dir, "nyuv2_labeled");
  const DatasetFolder dataset(dir.string());
  const std::map<std::string, int> expected = {
      {"0001", 1}, {"0009", 2}, {"0016", 1}, {"0017", 1}, {"0018", 1},
      {"0021", 1}, {"0030", 1}, {"0031", 3}, {"0118", 1},               // with tables
      {"0015", 0}, {"0037", 0}, {"0060", 0}, {"0090", 0}, {"0433", 0},  // without
  };
  int seen = 0;
  for (std::size_t i = 0; i < dataset.size(); ++i) {
    const auto it = expected.find(dataset.names()[i]);
    if (it == expected.end()) continue;
    ++seen;
    const LabeledFrame frame = dataset.load(i);
    const OrganizedCloud cloud = frameToCloud(frame.frame);
    const auto ground = fitGroundToLabels(cloud, frame.labels, GroundConfig{});
    ASSERT_TRUE(ground.has_value()) << frame.name;
    LabelImage labels;
    labels.width = cloud.width;
    labels.height = cloud.height;
    labels.labels = frame.labels;
    // The counts are those of the clustering: the visible-top filter
    // (tables.min_top_area_m2, table_regions_test) is off.
    TableConfig config;
    config.min_top_area_m2 = 0.0f;
    const TableDetection d =
        detectTables(transformCloud(cloud, ground->camera_to_ground), labels, config);
    EXPECT_EQ(static_cast<int>(d.tables.size()), it->second)
        << "frame " << frame.name << joined(d.diagnostics);
    for (const auto& t : d.tables) {
      EXPECT_GT(t.top_height, 0.4f) << frame.name;
      EXPECT_LT(t.top_height, 1.2f) << frame.name;
      EXPECT_GE(t.point_count, config.min_cluster_points);
      EXPECT_GE(t.search_positions.size(), 2u);
      for (const auto& p : t.search_positions) {
        EXPECT_EQ(p.reachable, p.reason.empty()) << frame.name << ": " << p.reason;
      }
    }
  }
  EXPECT_EQ(seen, static_cast<int>(expected.size())) << "frames missing from " << dir;
}

}  // namespace
}  // namespace findmug
