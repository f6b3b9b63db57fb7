// Tests of the label-layout prior (mrf.pairwise = layout): its file is read
// back as written and refused with file and line when corrupt, unlikely label
// pairs cost most, edges get the table their heights ask for, and a strong
// prior changes the MRF's answer the way it says.
#include "findmug/mrf/layout_prior.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "findmug/common/error.hpp"
#include "mrf/mrf_internal.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

constexpr int L = kNumLabels;
constexpr std::size_t at(Label a, Label b) {
  return static_cast<std::size_t>(static_cast<int>(a) * L + static_cast<int>(b));
}

// Every boundary seen 10 times, except those set otherwise.
LayoutCounts uniformCounts() {
  LayoutCounts c;
  for (int a = 0; a < L; ++a)
    for (int b = 0; b < L; ++b)
      if (a != b) c.vertical[a * L + b] = c.horizontal[a * L + b] = 10;
  c.smoothing = 1;
  c.offset_px = 10;
  c.frames = 3;
  return c;
}

std::string errorOf(const std::string& text) {
  try {
    parseLayoutCounts(text, "prior.csv");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(LayoutPrior, FileRoundTrips) {
  LayoutCounts c = uniformCounts();
  c.vertical[at(Label::Table, Label::Floor)] = 12345;
  c.horizontal[at(Label::Chair, Label::Table)] = 0.5;
  const std::string text = formatLayoutCounts(c, {"a comment"});
  EXPECT_EQ(text.rfind("# a comment\n", 0), 0u);
  const LayoutCounts back = parseLayoutCounts(text, "x");
  EXPECT_EQ(back.vertical, c.vertical);
  EXPECT_EQ(back.horizontal, c.horizontal);
  EXPECT_EQ(back.smoothing, 1);
  EXPECT_EQ(back.offset_px, 10);
  EXPECT_EQ(back.frames, 3);
}

TEST(LayoutPrior, CorruptFileNamesFileAndLine) {
  const std::string good = formatLayoutCounts(uniformCounts(), {});
  // Line numbers: 1 magic, 2 smoothing, 3 offset, 4 frames, 5.. pairs.
  auto replaceLine = [&](int line, const std::string& with) {
    std::string out;
    std::istringstream in(good);
    std::string l;
    for (int k = 1; std::getline(in, l); ++k) out += (k == line ? with : l) + "\n";
    return out;
  };
  EXPECT_NE(errorOf(replaceLine(1, "findmug-model,1")).find("prior.csv: line 1"), std::string::npos);
  EXPECT_NE(errorOf(replaceLine(2, "smoothing,-1")).find("prior.csv: line 2: smoothing"),
            std::string::npos);
  EXPECT_NE(errorOf(replaceLine(6, "vertical,unknown,sofa,3")).find("line 6: unknown label 'sofa'"),
            std::string::npos);
  EXPECT_NE(errorOf(replaceLine(7, "vertical,unknown,wall,x")).find("line 7: count 'x'"),
            std::string::npos);
  EXPECT_NE(errorOf(replaceLine(8, "vertical,unknown,floor,3")).find("line 8: vertical pair unknown,floor listed twice"),
            std::string::npos);
  EXPECT_NE(errorOf(replaceLine(9, "vertical,wall,wall,3")).find("line 9: a pair of the same label"),
            std::string::npos);
  EXPECT_NE(errorOf(replaceLine(10, "diagonal,wall,floor,3")).find("line 10: unknown row"),
            std::string::npos);
  EXPECT_NE(errorOf(replaceLine(11, "vertical,wall")).find("line 11: expected"), std::string::npos);
  // A row missing (cut off file).
  const std::string cut = good.substr(0, good.rfind("horizontal,object"));
  EXPECT_NE(errorOf(cut).find("missing horizontal pair object,cabinet"), std::string::npos) << errorOf(cut);
  EXPECT_NE(errorOf("").find("prior.csv: empty"), std::string::npos);
  EXPECT_EQ(errorOf(good), "");

  // From a file: the path is in the message.
  test::TempDir dir;
  const std::string path = (dir.path() / "bad-prior.csv").string();
  std::ofstream(path) << replaceLine(7, "vertical,unknown,wall,-4");
  try {
    loadLayoutPrior(path);
    FAIL() << "a negative count was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": line 7"), std::string::npos) << e.what();
  }
  EXPECT_THROW(loadLayoutPrior((dir.path() / "absent.csv").string()), Error);
}

TEST(LayoutPrior, RareBoundariesCostMost) {
  LayoutCounts c = uniformCounts();
  c.vertical[at(Label::Floor, Label::Table)] = 0;     // floor above table: never
  c.vertical[at(Label::Table, Label::Floor)] = 1000;  // table above floor: often
  const LayoutPrior p = layoutPriorFromCounts(c);
  float lo = 1, hi = 0;
  for (int a = 0; a < L; ++a) {
    EXPECT_EQ(p.vertical[a * L + a], 0.0f);
    for (int b = 0; b < L; ++b) {
      if (a == b) continue;
      lo = std::min(lo, p.vertical[a * L + b]);
      hi = std::max(hi, p.vertical[a * L + b]);
    }
  }
  EXPECT_FLOAT_EQ(lo, 0.0f);  // scaled to [0, 1]
  EXPECT_FLOAT_EQ(hi, 1.0f);
  EXPECT_GT(p.vertical[at(Label::Floor, Label::Table)], p.vertical[at(Label::Table, Label::Floor)] + 0.3f);
  EXPECT_GT(p.vertical[at(Label::Floor, Label::Table)], p.vertical[at(Label::Wall, Label::Chair)]);
  // By hand, smoothing 0, three labels meeting only as unknown-floor 30,
  // unknown-wall 10, floor-wall 10, wall-floor 10 (others 0, so unseen: cost 1):
  // total 60; P(unknown, floor) = 1/2, row(unknown) = 2/3, col(floor) = 2/3,
  // so cost -log(9/8); P(unknown, wall) = 1/6, col(wall) = 1/3: -log(3/4);
  // P(floor, wall) = 1/6, row(floor) = 1/6: -log(3); P(wall, floor) = 1/6,
  // row(wall) 1/6: -log(3/2). Scaled over [-log 3, -log(3/4)].
  LayoutCounts h;
  h.smoothing = 0;
  h.horizontal = uniformCounts().horizontal;
  h.vertical[at(Label::Unknown, Label::Floor)] = 30;
  h.vertical[at(Label::Unknown, Label::Wall)] = 10;
  h.vertical[at(Label::Floor, Label::Wall)] = 10;
  h.vertical[at(Label::Wall, Label::Floor)] = 10;
  const LayoutPrior q = layoutPriorFromCounts(h);
  const double lo_cost = -std::log(3.0), hi_cost = -std::log(0.75);
  auto scaled = [&](double c) { return static_cast<float>((c - lo_cost) / (hi_cost - lo_cost)); };
  EXPECT_NEAR(q.vertical[at(Label::Unknown, Label::Floor)], scaled(-std::log(9.0 / 8)), 1e-6);
  EXPECT_NEAR(q.vertical[at(Label::Unknown, Label::Wall)], 1.0f, 1e-6);
  EXPECT_NEAR(q.vertical[at(Label::Floor, Label::Wall)], 0.0f, 1e-6);
  EXPECT_NEAR(q.vertical[at(Label::Wall, Label::Floor)], scaled(-std::log(1.5)), 1e-6);
  EXPECT_EQ(q.vertical[at(Label::Table, Label::Chair)], 1.0f);  // never seen
  // Uniform counts: every boundary equally likely, so all cost the same (0).
  const LayoutPrior flat = layoutPriorFromCounts(uniformCounts());
  for (float v : flat.horizontal) EXPECT_EQ(v, 0.0f);
  // Smoothing 0 and an empty table cannot be made a distribution.
  LayoutCounts empty;
  empty.smoothing = 0;
  EXPECT_THROW(layoutPriorFromCounts(empty), Error);
}

TEST(LayoutPrior, EdgesGetTheTableTheirHeightsAsk) {
  LayoutPrior p;
  p.vertical[at(Label::Floor, Label::Table)] = 1.0f;
  p.horizontal[at(Label::Wall, Label::Chair)] = 0.5f;
  const std::vector<float> heights = {0.0f, 0.75f, 0.05f, std::nanf("")};
  const std::vector<std::pair<int, int>> edges = {{0, 1}, {1, 0}, {0, 2}, {2, 3}};
  MrfPairFactors f;
  layoutPairFactorsInto(p, 2.0f, 0.1f, heights, edges, f);
  ASSERT_EQ(f.table_of_edge.size(), 4u);
  // Edge (0, 1): node 1 is above; its label is the upper one (the column here).
  const MrfPairTable& t01 = f.tables[f.table_of_edge[0]];
  EXPECT_FLOAT_EQ(t01[at(Label::Table, Label::Floor)], 3.0f);  // first=table (lower) under floor
  EXPECT_FLOAT_EQ(t01[at(Label::Floor, Label::Table)], 1.0f);
  const MrfPairTable& t10 = f.tables[f.table_of_edge[1]];
  EXPECT_FLOAT_EQ(t10[at(Label::Floor, Label::Table)], 3.0f);  // first=floor above table
  // 0.05 m apart: side by side.
  EXPECT_FLOAT_EQ(f.tables[f.table_of_edge[2]][at(Label::Wall, Label::Chair)], 2.0f);
  EXPECT_FLOAT_EQ(f.tables[f.table_of_edge[2]][at(Label::Floor, Label::Table)], 1.0f);
  // No height: plain Potts.
  EXPECT_EQ(f.tables[f.table_of_edge[3]], pottsPairTable());
  EXPECT_THROW(layoutPairFactorsInto(p, -1.0f, 0.1f, heights, edges, f), Error);
  EXPECT_THROW(layoutPairFactorsInto(p, 1.0f, 0.1f, heights, {{0, 4}}, f), Error);
}

TEST(LayoutPrior, ImageDirectionUsesMeanRows) {
  // 2x3 image: segment 0 in row 0, segment 1 in rows 1-2, one pixel in none.
  const std::vector<int> pixel_segment = {0, 0, 1, -1, 1, 1};
  std::vector<float> heights;
  segmentImageHeightsInto(pixel_segment, 2, 3, heights);
  ASSERT_EQ(heights.size(), 3u);
  EXPECT_FLOAT_EQ(heights[0], 0.0f);
  EXPECT_FLOAT_EQ(heights[1], -(1 + 2 + 2) / 3.0f);
  EXPECT_TRUE(std::isnan(heights[2]));  // no pixels: Potts
  EXPECT_THROW(segmentImageHeightsInto({0, 5}, 2, 3, heights), Error);
  EXPECT_THROW(segmentImageHeightsInto({0, 0, 0}, 2, 3, heights), Error);

  // layoutHeightsInto picks rows or centroid heights, and the threshold that goes with them.
  std::vector<FeatureVector> features(3);
  features[0][3] = 0.2f;
  features[1][3] = 0.9f;  // higher in the room, lower in the image
  features[2][3] = 0.5f;
  MrfParams params;
  params.layout_height_threshold = 0.25f;
  params.layout_image_threshold_px = 7.0f;
  EXPECT_FLOAT_EQ(layoutHeightsInto(params, {&pixel_segment, 2, &features}, heights), 0.25f);
  EXPECT_FLOAT_EQ(heights[1], 0.9f);
  params.layout_direction = LayoutDirection::Image;
  EXPECT_FLOAT_EQ(layoutHeightsInto(params, {&pixel_segment, 2, &features}, heights), 7.0f);
  EXPECT_GT(heights[0], heights[1]);
}

// Two patches: the lower one (node 1) is surely a table, the upper one
// (node 0) leans a little to floor over table. With Potts they part (floor
// over table costs one Potts weight, less than the unary difference would);
// a strong prior that a floor above a table never happens makes node 0 a
// table as well.
TEST(LayoutPrior, StrongPriorFlipsAPatch) {
  ClassProbabilities upper{}, lower{};
  upper[static_cast<int>(Label::Floor)] = 0.6f;
  upper[static_cast<int>(Label::Table)] = 0.4f;
  lower[static_cast<int>(Label::Table)] = 1.0f;
  const std::vector<ClassProbabilities> unaries = {upper, lower};
  // 0.05 m apart: Potts weight exp(-0.5) = 0.61 > 0.2 would already join
  // them; 0.3 m apart: exp(-3) = 0.05 < 0.2 parts them.
  const std::vector<Eigen::Vector3f> centroids = {{0, 0, 0.9f}, {0, 0, 0.6f}};
  const std::vector<std::pair<int, int>> edges = {{0, 1}};
  const std::vector<float> heights = {0.9f, 0.6f};
  MrfParams params;
  const MrfResult potts = solveMrf(unaries, centroids, edges, params);
  ASSERT_EQ(potts.labels[0], static_cast<int>(Label::Floor));

  LayoutPrior prior;  // every boundary likely but a floor above a table
  prior.vertical[at(Label::Floor, Label::Table)] = 1.0f;
  MrfPairFactors f;
  layoutPairFactorsInto(prior, 100.0f, 0.1f, heights, edges, f);
  MrfResult layout;
  solveMrfWithFactorsInto(unaries, centroids, edges, f, params, layout);
  EXPECT_EQ(layout.labels[0], static_cast<int>(Label::Table));
  EXPECT_EQ(layout.labels[1], static_cast<int>(Label::Table));
  // The same prior with the heights swapped (table above floor: likely)
  // leaves the Potts answer.
  layoutPairFactorsInto(prior, 100.0f, 0.1f, {0.6f, 0.9f}, edges, f);
  solveMrfWithFactorsInto(unaries, centroids, edges, f, params, layout);
  EXPECT_EQ(layout.labels[0], static_cast<int>(Label::Floor));
  // Weight 0: the Potts answer and the same beliefs.
  layoutPairFactorsInto(prior, 0.0f, 0.1f, heights, edges, f);
  solveMrfWithFactorsInto(unaries, centroids, edges, f, params, layout);
  EXPECT_EQ(layout.labels, potts.labels);
  for (std::size_t i = 0; i < 2; ++i) EXPECT_NEAR(layout.confidence[i], potts.confidence[i], 1e-5f);
}

TEST(LayoutPrior, PottsTableGivesThePottsSolver) {
  // A loopy graph: the factor path with the Potts table must match the O(L) path.
  std::vector<ClassProbabilities> unaries;
  std::vector<Eigen::Vector3f> centroids;
  for (int i = 0; i < 6; ++i) {
    ClassProbabilities p{};
    p[i % L] = 0.5f;
    p[(i + 3) % L] = 0.3f;
    p[(i + 5) % L] = 0.2f;
    unaries.push_back(p);
    centroids.emplace_back(0.05f * i, 0.02f * (i % 2), 0);
  }
  const std::vector<std::pair<int, int>> edges = {{0, 1}, {1, 2}, {2, 3}, {3, 4}, {4, 5}, {5, 0}, {1, 4}};
  MrfParams params;
  const MrfResult potts = solveMrf(unaries, centroids, edges, params);
  MrfPairFactors f;
  f.tables = {pottsPairTable()};
  f.table_of_edge.assign(edges.size(), 0);
  MrfResult factors;
  solveMrfWithFactorsInto(unaries, centroids, edges, f, params, factors);
  EXPECT_EQ(factors.labels, potts.labels);
  EXPECT_EQ(factors.iterations, potts.iterations);
  for (std::size_t i = 0; i < unaries.size(); ++i)
    EXPECT_NEAR(factors.confidence[i], potts.confidence[i], 1e-5f);
  f.table_of_edge[2] = 1;  // no such table
  EXPECT_THROW(solveMrfWithFactorsInto(unaries, centroids, edges, f, params, factors), Error);
  f.table_of_edge[2] = 0;
  f.tables[0][3] = -1.0f;
  EXPECT_THROW(solveMrfWithFactorsInto(unaries, centroids, edges, f, params, factors), Error);
}

// The committed prior loads and says what the rooms say.
TEST(LayoutPrior, CommittedPriorLoads) {
  const LayoutPrior p =
      loadLayoutPrior((test::sourceDir() / "models/nyu-layout-prior.csv").string());
  // Walls stand under ceilings, not over them; a ceiling next to a floor is
  // about the least likely boundary.
  EXPECT_LT(p.vertical[at(Label::Ceiling, Label::Wall)], p.vertical[at(Label::Wall, Label::Ceiling)]);
  EXPECT_GT(p.horizontal[at(Label::Ceiling, Label::Floor)], 0.9f);
}

}  // namespace
}  // namespace findmug
