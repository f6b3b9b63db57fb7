// Segmenter: the table-top object stage (table_objects.*) inside process(),
// on a rendered room whose forest calls the objects on the tables "table" (the
// case table_objects.relabel is for).
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "findmug/segmenter/segmenter.hpp"
#include "findmug/synth/synth.hpp"
#include "small_forest.hpp"

namespace findmug {
namespace {

constexpr auto kTable = static_cast<std::uint8_t>(Label::Table);
constexpr auto kObject = static_cast<std::uint8_t>(Label::Object);

SegmenterConfig fastConfig() {
  SegmenterConfig config;
  config.oversegmentation.kind = OversegmenterKind::Organized;
  return config;
}

// A rendered frame with many object pixels, and its true labels with every
// Object made Table.
struct Rendered {
  RgbdFrame frame;
  std::vector<std::uint8_t> truth;
};

Rendered frameWithObjectsOnATable() {
  const synth::SynthScene scene = synth::makeApartment(3);
  const auto poses = synth::cameraPath(scene, 8, 1.0);
  Rendered best;
  long most = -1;
  for (std::size_t f = 0; f < poses.size(); ++f) {
    synth::RenderedFrame r = synth::render(scene, poses[f], synth::RenderOptions{}, f);
    const long objects = std::count(r.labeled.labels.begin(), r.labeled.labels.end(), kObject);
    if (objects <= most) continue;
    most = objects;
    best.frame = std::move(r.labeled.frame);
    best.truth = r.labeled.labels;
  }
  for (auto& l : best.truth) l = l == kObject ? kTable : l;
  return best;
}

TEST(SegmenterTableObjects, ProcessFindsThemAndRelabelsTheirTablePixels) {
  const Rendered r = frameWithObjectsOnATable();
  const Segmenter untrained(fastConfig(), nullptr);
  const auto forest = test::trainSmallForest(untrained, r.frame, r.truth);

  const Segmenter plain(fastConfig(), forest);
  const LabelledFrame off = plain.process(r.frame);
  ASSERT_FALSE(off.tables.empty());
  ASSERT_FALSE(off.table_objects.objects.empty());
  EXPECT_GT(off.table_objects.points_above_tops, 0);
  EXPECT_GT(off.cpu_timings.objects_ms, 0.0);
  EXPECT_GT(off.timings.objects_ms, 0.0);
  for (const TableObject& o : off.table_objects.objects) {
    EXPECT_LT(o.table, static_cast<int>(off.tables.size()));
  }
  // relabel off (the default): the label image is the MRF's, with no Object
  // anywhere (the forest never learned it).
  EXPECT_EQ(std::count(off.labels.labels.begin(), off.labels.labels.end(), kObject), 0);

  SegmenterConfig config = fastConfig();
  config.table_objects.relabel = true;
  const Segmenter relabelling(config, forest);
  const LabelledFrame on = relabelling.process(r.frame);
  ASSERT_EQ(on.table_objects.objects.size(), off.table_objects.objects.size());
  std::set<int> candidate;
  int changed = 0;
  for (std::size_t k = 0; k < on.table_objects.objects.size(); ++k) {
    EXPECT_EQ(on.table_objects.objects[k].pixels, off.table_objects.objects[k].pixels);
    for (const int p : off.table_objects.objects[k].pixels) {
      candidate.insert(p);
      const auto i = static_cast<std::size_t>(p);
      if (off.labels.labels[i] == kTable) {
        EXPECT_EQ(on.labels.labels[i], kObject) << p;
        ++changed;
      } else {
        EXPECT_EQ(on.labels.labels[i], off.labels.labels[i]) << p;
      }
    }
  }
  EXPECT_GT(changed, 100);
  // Every other pixel with a point keeps its label (holes may be filled from Object).
  const OrganizedCloud& cloud = off.segmented.prepared.cloud_camera;
  for (std::size_t i = 0; i < off.labels.labels.size(); ++i) {
    if (!cloud.valid(i) || candidate.count(static_cast<int>(i))) continue;
    ASSERT_EQ(on.labels.labels[i], off.labels.labels[i]) << i;
  }
  // The tables are those of the unchanged labels.
  ASSERT_EQ(on.tables.size(), off.tables.size());
  for (std::size_t t = 0; t < on.tables.size(); ++t) {
    EXPECT_EQ(on.tables[t].pixels, off.tables[t].pixels);
  }
}

// A recycled frame lends its candidates' buffers; the answer is the same.
// table_objects.enabled = false: none.
TEST(SegmenterTableObjects, RecycledFramesGiveTheSameCandidatesAndDisabledNone) {
  const Rendered r = frameWithObjectsOnATable();
  const Segmenter untrained(fastConfig(), nullptr);
  const auto forest = test::trainSmallForest(untrained, r.frame, r.truth);
  const Segmenter segmenter(fastConfig(), forest);
  const LabelledFrame first = segmenter.process(r.frame);
  ASSERT_FALSE(first.table_objects.objects.empty());
  LabelledFrame copy = first;
  segmenter.recycle(std::move(copy));
  const LabelledFrame again = segmenter.process(r.frame);
  ASSERT_EQ(again.table_objects.objects.size(), first.table_objects.objects.size());
  for (std::size_t k = 0; k < first.table_objects.objects.size(); ++k) {
    EXPECT_EQ(again.table_objects.objects[k].pixels, first.table_objects.objects[k].pixels);
    EXPECT_EQ(again.table_objects.objects[k].centroid, first.table_objects.objects[k].centroid);
  }
  SegmenterConfig config = fastConfig();
  config.table_objects.enabled = false;
  const LabelledFrame none = Segmenter(config, forest).process(r.frame);
  EXPECT_FALSE(none.tables.empty());
  EXPECT_TRUE(none.table_objects.objects.empty());
}

}  // namespace
}  // namespace findmug
