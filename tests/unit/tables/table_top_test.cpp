// Tests of the table-top test of detectTables (tables.hpp, step 3b): a large
// top whose near-horizontal normals are mostly not flat (a bed, a sofa) is
// not a table, and relabelSoftTops labels its pixels Unknown.
//
// Two groups: hand-built tops with known normals (a flat table passes, an
// undulating bed-sized top fails, the boundaries of both thresholds), and
// NYU frames with their true beds and tables labelled Table.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <tuple>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/common/error.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/frame/image_io.hpp"
#include "findmug/labels/labels.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "findmug/tables/tables.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

constexpr std::uint8_t kTable = static_cast<std::uint8_t>(Label::Table);
constexpr std::uint8_t kUnknownLabel = static_cast<std::uint8_t>(Label::Unknown);
constexpr float kDeg = 3.14159265358979f / 180.0f;

std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const auto& l : lines) out += "\n  " + l;
  return out;
}

// Table-labelled points with their normals, as a 1-row organized image.
struct Top {
  OrganizedCloud cloud;
  NormalImage normals;
  LabelImage labels;
  void add(const Eigen::Vector3f& p, const Eigen::Vector3f& n) {
    cloud.points.push_back(p);
    normals.normals.push_back(n.normalized());
    labels.labels.push_back(kTable);
    cloud.width = normals.width = labels.width = static_cast<int>(cloud.points.size());
    cloud.height = normals.height = labels.height = 1;
  }
};

// A normal tilted `tilt_deg` from vertical towards `azimuth` (radians).
Eigen::Vector3f tilted(float tilt_deg, float azimuth) {
  const float t = tilt_deg * kDeg;
  return {std::sin(t) * std::cos(azimuth), std::sin(t) * std::sin(azimuth), std::cos(t)};
}

// A flat rectangular top `length` x `width` at `height`, points every 1 cm;
// the normals of the points with x below `tilted_below_x` (relative to the
// top's start) are tilted by `steep_deg`, the others by `shallow_deg`, their
// azimuth turning from point to point (depth noise has no direction).
Top flatTop(float length, float width, float height, float shallow_deg = 2.0f,
            float steep_deg = 15.0f, float tilted_below_x = 0.0f) {
  Top top;
  int k = 0;
  for (float x = 0.0f; x <= length + 1e-6f; x += 0.01f) {
    for (float y = 0.0f; y <= width + 1e-6f; y += 0.01f, ++k) {
      const float tilt = x < tilted_below_x ? steep_deg : shallow_deg;
      top.add({1.0f + x, y - 0.5f * width, height}, tilted(tilt, 0.7f * static_cast<float>(k)));
    }
  }
  return top;
}

// A bed: a low, large top whose surface undulates by +-2 cm over 30 cm
// (a blanket), with the normals of that surface (up to 23 degrees of tilt).
Top undulatingTop(float length, float width, float height) {
  Top top;
  constexpr float kAmplitude = 0.02f, kWave = 0.3f;
  const float w = 2.0f * 3.14159265358979f / kWave;
  for (float x = 0.0f; x <= length + 1e-6f; x += 0.01f) {
    for (float y = 0.0f; y <= width + 1e-6f; y += 0.01f) {
      const float z = height + kAmplitude * std::sin(w * x) * std::sin(w * y);
      const float dzdx = kAmplitude * w * std::cos(w * x) * std::sin(w * y);
      const float dzdy = kAmplitude * w * std::sin(w * x) * std::cos(w * y);
      top.add({1.0f + x, y - 0.5f * width, z}, {-dzdx, -dzdy, 1.0f});
    }
  }
  return top;
}

TEST(TableTopTest, FlatTableTopPasses) {
  const Top top = flatTop(1.2f, 0.8f, 0.74f);
  const TableDetection d = detectTables(top.cloud, top.labels, TableConfig{}, &top.normals);
  ASSERT_EQ(d.tables.size(), 1u) << joined(d.diagnostics);
  EXPECT_GE(d.tables[0].top_area_m2, TableConfig{}.soft_top_min_area_m2);
  EXPECT_FLOAT_EQ(d.tables[0].flat_share, 1.0f);
  EXPECT_EQ(d.soft_tops, 0);
  EXPECT_TRUE(d.soft_top_pixels.empty());
}

TEST(TableTopTest, UndulatingBedSizedLowTopFailsAndIsRelabelled) {
  Top bed = undulatingTop(2.0f, 1.4f, 0.55f);
  TableDetection d = detectTables(bed.cloud, bed.labels, TableConfig{}, &bed.normals);
  EXPECT_TRUE(d.tables.empty()) << joined(d.diagnostics);
  EXPECT_EQ(d.soft_tops, 1);
  EXPECT_EQ(d.clusters_rejected, 1);
  bool reason = false;
  for (const auto& line : d.diagnostics) reason |= line.find("soft top") != std::string::npos;
  EXPECT_TRUE(reason) << joined(d.diagnostics);
  // Every point of the cluster is listed once, in pixel order.
  ASSERT_EQ(d.soft_top_pixels.size(), bed.cloud.points.size());
  for (std::size_t k = 0; k < d.soft_top_pixels.size(); ++k)
    EXPECT_EQ(d.soft_top_pixels[k], static_cast<int>(k));
  EXPECT_EQ(relabelSoftTops(d, bed.labels), static_cast<int>(bed.cloud.points.size()));
  for (const std::uint8_t l : bed.labels.labels) EXPECT_EQ(l, kUnknownLabel);
  // Relabelled once, nothing is left to change.
  EXPECT_EQ(relabelSoftTops(d, bed.labels), 0);

  // The same bed with the test off is a table with search positions: the
  // test, not another filter, is what drops it.
  TableConfig off;
  off.min_flat_share = 0.0f;
  d = detectTables(bed.cloud, bed.labels, off, &bed.normals);
  EXPECT_TRUE(d.tables.empty());  // relabelled above: no table points left
  const Top again = undulatingTop(2.0f, 1.4f, 0.55f);
  d = detectTables(again.cloud, again.labels, off, &again.normals);
  ASSERT_EQ(d.tables.size(), 1u) << joined(d.diagnostics);
  EXPECT_FALSE(d.tables[0].search_positions.empty());
  EXPECT_EQ(d.soft_tops, 0);
}

TEST(TableTopTest, SmallUndulatingTopIsNotTested) {
  // 0.6 x 0.6 m: below tables.soft_top_min_area_m2 (0.5 m²), so a small
  // table seen with noisy normals keeps its search positions.
  const Top small = undulatingTop(0.6f, 0.6f, 0.55f);
  const TableDetection d = detectTables(small.cloud, small.labels, TableConfig{}, &small.normals);
  ASSERT_EQ(d.tables.size(), 1u) << joined(d.diagnostics);
  EXPECT_LT(d.tables[0].top_area_m2, TableConfig{}.soft_top_min_area_m2);
  EXPECT_TRUE(std::isnan(d.tables[0].flat_share));
  // With the area limit lowered below it, the same top fails.
  TableConfig config;
  config.soft_top_min_area_m2 = 0.3f;
  const TableDetection tested = detectTables(small.cloud, small.labels, config, &small.normals);
  EXPECT_TRUE(tested.tables.empty()) << joined(tested.diagnostics);
  EXPECT_EQ(tested.soft_tops, 1);
}

TEST(TableTopTest, WithoutNormalsNothingIsTested) {
  const Top bed = undulatingTop(2.0f, 1.4f, 0.55f);
  const TableDetection d = detectTables(bed.cloud, bed.labels, TableConfig{});
  ASSERT_EQ(d.tables.size(), 1u) << joined(d.diagnostics);
  EXPECT_TRUE(std::isnan(d.tables[0].flat_share));
}

TEST(TableTopTest, FlatShareBoundary) {
  // About the first half of the columns have normals tilted 15 degrees
  // (horizontal, not flat), the rest 2 degrees.
  const Top top = flatTop(1.2f, 0.8f, 0.74f, 2.0f, 15.0f, 0.595f);
  int flat = 0;
  for (const auto& n : top.normals.normals) flat += n.z() >= std::cos(10.0f * kDeg);
  const float expected = static_cast<float>(flat) / static_cast<float>(top.normals.normals.size());
  ASSERT_GT(expected, 0.45f);
  ASSERT_LT(expected, 0.55f);
  TableConfig measure;
  measure.min_flat_share = 1e-6f;  // measured, passes
  const TableDetection d = detectTables(top.cloud, top.labels, measure, &top.normals);
  ASSERT_EQ(d.tables.size(), 1u) << joined(d.diagnostics);
  const float share = d.tables[0].flat_share;
  EXPECT_FLOAT_EQ(share, expected);
  // At the limit the top passes ("below" fails), just above it it fails.
  TableConfig at = measure;
  at.min_flat_share = share;
  EXPECT_EQ(detectTables(top.cloud, top.labels, at, &top.normals).tables.size(), 1u);
  TableConfig above = measure;
  above.min_flat_share = std::nextafter(share, 1.0f);
  EXPECT_TRUE(detectTables(top.cloud, top.labels, above, &top.normals).tables.empty());
  // Normals steeper than tables.horizontal_tilt_deg (a front, a chair back)
  // do not count either way: tilted 30 degrees instead, the share is 1.
  const Top fronts = flatTop(1.2f, 0.8f, 0.74f, 2.0f, 30.0f, 0.595f);
  const TableDetection f = detectTables(fronts.cloud, fronts.labels, above, &fronts.normals);
  ASSERT_EQ(f.tables.size(), 1u) << joined(f.diagnostics);
  EXPECT_FLOAT_EQ(f.tables[0].flat_share, 1.0f);
}

TEST(TableTopTest, SoftTopPixelsOfAFrameDoNotLeakIntoTheNext) {
  const Top bed = undulatingTop(2.0f, 1.4f, 0.55f);
  const Top table = flatTop(1.2f, 0.8f, 0.74f);
  TableDetection d;
  detectTablesInto(bed.cloud, bed.labels, TableConfig{}, &bed.normals, d);
  EXPECT_EQ(d.soft_tops, 1);
  detectTablesInto(table.cloud, table.labels, TableConfig{}, &table.normals, d);
  EXPECT_EQ(d.soft_tops, 0);
  EXPECT_TRUE(d.soft_top_pixels.empty());
  EXPECT_EQ(d.tables.size(), 1u);
}

TEST(TableTopTest, BadSettingsAndPixelsAreRefused) {
  const Top top = flatTop(1.2f, 0.8f, 0.74f);
  auto refuses = [&](TableConfig c, const std::string& key) {
    try {
      detectTables(top.cloud, top.labels, c, &top.normals);
      ADD_FAILURE() << key << " accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("tables." + key), std::string::npos) << e.what();
    }
  };
  TableConfig c;
  c.min_flat_share = 1.5f;
  refuses(c, "min_flat_share");
  c = TableConfig{};
  c.min_flat_share = std::numeric_limits<float>::quiet_NaN();
  refuses(c, "min_flat_share");
  c = TableConfig{};
  c.flat_tilt_deg = c.horizontal_tilt_deg + 1.0f;  // flat must be within horizontal
  refuses(c, "flat_tilt_deg");
  c = TableConfig{};
  c.soft_top_min_area_m2 = -1.0f;
  refuses(c, "soft_top_min_area_m2");

  TableDetection bad;
  bad.soft_top_pixels = {0, static_cast<int>(top.labels.labels.size())};
  LabelImage labels = top.labels;
  EXPECT_THROW(relabelSoftTops(bad, labels), Error);
  EXPECT_EQ(labels.labels, top.labels.labels);  // unchanged
}

// ---------------------------------------------------------------- NYU frames

// NYU frames with their true beds (NYU-40 class 4) or tables (7 table, 12
// counter, 14 desk) labelled Table, the ground from NYU's gravity and the
// shipped depth fill, as findmug-eval prepares them. On the beds' frames
// the test leaves no table (each bed was a table without it); on the
// tables' frames it drops none. Fails when the rule is removed or loosened
// below the beds, or tightened into the tables.
struct NyuCase {
  std::string frame;
  std::vector<int> classes;  // NYU-40 classes labelled Table
};

TEST(TableTopTestOnNyu, BedsAreNoTablesAndTablesStay) {
  FINDMUG_REQUIRE_DATA(extra, "nyuv2_labeled_extra");
  FINDMUG_REQUIRE_DATA(labeled, "nyuv2_labeled");
  FINDMUG_REQUIRE_DATA(rotations_file, "nyuv2_meta/camera_rotations_NYU.txt");
  SegmenterConfig config;
  config.ground.source = GroundSource::Gravity;
  config.depth_holes.max_run_px = 40;  // the shipped cloud.fill_depth_max_run_px
  const Segmenter segmenter(config, nullptr);
  DatasetOptions options;
  options.nyu_rotations_file = rotations_file.string();
  const std::vector<NyuCase> beds = {{"0056", {4}}, {"0076", {4}}};
  const std::vector<NyuCase> tables = {{"0029", {7, 12, 14}}, {"0032", {7, 12, 14}},
                                       {"0039", {7, 12, 14}}, {"0031", {7, 12, 14}},
                                       {"0118", {7, 12, 14}}, {"0002", {7, 12, 14}}};
  int seen = 0;
  for (const auto& [root, cases, is_bed] :
       {std::tuple{extra, beds, true}, std::tuple{extra, tables, false},
        std::tuple{labeled, tables, false}}) {
    const DatasetFolder folder(root.string(), options);
    for (const NyuCase& c : cases) {
      std::size_t index = folder.size();
      for (std::size_t i = 0; i < folder.size(); ++i)
        if (folder.names()[i] == c.frame) index = i;
      if (index == folder.size()) continue;  // in the other folder
      ++seen;
      LabeledFrame f = folder.load(index);
      const Image<std::uint8_t> fine = readPng8((root / "label40" / (c.frame + ".png")).string());
      const PreparedFrame p = segmenter.prepare(std::move(f.frame), &f.labels);
      ASSERT_TRUE(p.ground.has_value()) << c.frame;
      LabelImage labels{p.cloud_ground.width,
                        p.cloud_ground.height,
                        std::vector<std::uint8_t>(fine.pixels.size(), kUnknownLabel),
                        {}};
      for (std::size_t q = 0; q < fine.pixels.size(); ++q)
        for (const int cls : c.classes)
          if (fine.pixels[q] == cls) labels.labels[q] = kTable;
      TableConfig off;
      off.min_flat_share = 0.0f;
      const TableDetection with = detectTables(p.cloud_ground, labels, {}, &p.normals_ground);
      const TableDetection without = detectTables(p.cloud_ground, labels, off, &p.normals_ground);
      if (is_bed) {
        EXPECT_GE(without.tables.size(), 1u) << c.frame << ": the bed is no table even without "
                                             << "the test" << joined(without.diagnostics);
        EXPECT_TRUE(with.tables.empty()) << c.frame << joined(with.diagnostics);
        EXPECT_GE(with.soft_tops, 1) << c.frame;
      } else {
        EXPECT_GE(without.tables.size(), 1u) << c.frame << joined(without.diagnostics);
        EXPECT_EQ(with.tables.size(), without.tables.size()) << c.frame << joined(with.diagnostics);
        EXPECT_EQ(with.soft_tops, 0) << c.frame;
      }
    }
  }
  EXPECT_EQ(seen, static_cast<int>(beds.size() + tables.size()));
}

}  // namespace
}  // namespace findmug
