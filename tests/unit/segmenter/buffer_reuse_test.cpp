// Reused buffers (issue 13): the stages that write into memory recycled from
// an earlier frame (Segmenter::recycle, Oversegmenter::segmentInto, the
// `out` variants of the cloud functions, finalizeOversegmentation on a used
// Oversegmentation) must give exactly what fresh buffers give, whatever the
// earlier frame was (another scene, another image size, a frame without a
// ground plane). And once warm they must not allocate: this program counts
// heap allocations with its own operator new.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "../bench/counting_new.hpp"  // this program's operator new counts allocations
#include "findmug/cloud/cloud.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/offline/training.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "findmug/oversegmentation/oversegmentation.hpp"
#include "small_forest.hpp"

namespace findmug {
namespace {

// A camera `height` m above a chequered floor, pitched 30 degrees down,
// facing a striped wall `wall_x` m ahead: enough texture for a few hundred
// segments. Colours follow world position, so two scenes differ everywhere.
struct Scene {
  RgbdFrame frame;
  std::vector<std::uint8_t> truth;
};

Scene floorAndWall(int width, int height, double wall_x, double cam_height) {
  Scene s;
  RgbdFrame& f = s.frame;
  f.width = width;
  f.height = height;
  const double focal = 525.0 * width / 640.0;
  f.intrinsics = {focal, focal, (width - 1) / 2.0, (height - 1) / 2.0};
  f.source = "synthetic floor+wall " + std::to_string(width);
  const double pitch = 30.0 * M_PI / 180.0;
  f.extrinsics = CameraExtrinsics{cam_height, pitch, 0.0};
  const std::size_t n = static_cast<std::size_t>(width) * height;
  f.depth_mm.assign(n, 0);
  f.rgb.assign(n, Rgb8{});
  s.truth.assign(n, kVoidLabel);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const double xc = (u - f.intrinsics.cx) / f.intrinsics.fx;
      const double yc = (v - f.intrinsics.cy) / f.intrinsics.fy;
      const double fwd = std::cos(pitch) - std::sin(pitch) * yc;
      const double up = -std::sin(pitch) - std::cos(pitch) * yc;
      const double t_floor = up < 0 ? cam_height / -up : INFINITY;
      const double t_wall = fwd > 0 ? wall_x / fwd : INFINITY;
      const double t = std::min(t_floor, t_wall);
      if (!std::isfinite(t) || t > 8.0) continue;
      const std::size_t i = static_cast<std::size_t>(v) * width + u;
      f.depth_mm[i] = static_cast<std::uint16_t>(std::lround(t * 1000.0));
      const double x = t * fwd, y = -t * xc, z = cam_height + t * up;
      const bool floor = t_floor < t_wall;
      s.truth[i] = static_cast<std::uint8_t>(floor ? Label::Floor : Label::Wall);
      if (floor) {
        const bool dark = (static_cast<int>(std::floor(x / 0.3)) + static_cast<int>(std::floor(y / 0.3))) % 2;
        f.rgb[i] = dark ? Rgb8{90, 70, 50} : Rgb8{150, 130, 110};
      } else {
        const bool dark = static_cast<int>(std::floor(z / 0.4)) % 2;
        f.rgb[i] = dark ? Rgb8{140, 160, 200} : Rgb8{190, 210, 240};
      }
    }
  }
  return s;
}

// No depth at all: no ground plane, so most stages are skipped.
RgbdFrame emptyFrame() {
  RgbdFrame f;
  f.width = 320;
  f.height = 240;
  f.intrinsics = {262.5, 262.5, 159.5, 119.5};
  f.depth_mm.assign(320 * 240, 0);
  f.rgb.assign(320 * 240, Rgb8{10, 20, 30});
  f.source = "empty";
  return f;
}

SegmenterConfig config() {
  SegmenterConfig c;
  c.oversegmentation.kind = OversegmenterKind::Organized;
  return c;
}

std::shared_ptr<const RandomForest> trainOn(const Scene& scene) {
  return test::trainSmallForest(Segmenter(config(), nullptr), scene.frame, scene.truth);
}

// Bitwise equality of float arrays (NaN == NaN here: invalid points must stay
// exactly where they were).
template <class T>
bool sameBytes(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

void expectSameSegmentation(const Oversegmentation& a, const Oversegmentation& b) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  EXPECT_EQ(a.pixel_segment, b.pixel_segment);
  EXPECT_EQ(a.segments, b.segments);
  EXPECT_EQ(a.edges, b.edges);
}

void expectSameFrame(const LabelledFrame& got, const LabelledFrame& want) {
  const PreparedFrame& g = got.segmented.prepared;
  const PreparedFrame& w = want.segmented.prepared;
  EXPECT_TRUE(sameBytes(g.cloud_camera.points, w.cloud_camera.points));
  EXPECT_TRUE(sameBytes(g.cloud_camera.colors, w.cloud_camera.colors));
  EXPECT_TRUE(sameBytes(g.normals_camera.normals, w.normals_camera.normals));
  EXPECT_TRUE(sameBytes(g.cloud_ground.points, w.cloud_ground.points));
  EXPECT_TRUE(sameBytes(g.cloud_ground.colors, w.cloud_ground.colors));
  EXPECT_TRUE(sameBytes(g.normals_ground.normals, w.normals_ground.normals));
  EXPECT_EQ(g.cloud_ground.width, w.cloud_ground.width);
  EXPECT_EQ(g.ground.has_value(), w.ground.has_value());
  expectSameSegmentation(got.segmented.segmentation, want.segmented.segmentation);
  // The classify stage's outputs, which also come from recycled frames.
  EXPECT_TRUE(sameBytes(got.features.features, want.features.features));
  EXPECT_TRUE(sameBytes(got.features.centroids, want.features.centroids));
  EXPECT_TRUE(sameBytes(got.features.regions, want.features.regions));
  EXPECT_TRUE(sameBytes(got.features.scene, want.features.scene));
  EXPECT_TRUE(sameBytes(got.features.objects, want.features.objects));
  EXPECT_TRUE(sameBytes(got.forest_probabilities, want.forest_probabilities));
  EXPECT_TRUE(sameBytes(got.first_round_probabilities, want.first_round_probabilities));
  EXPECT_EQ(got.mrf.labels, want.mrf.labels);
  EXPECT_TRUE(sameBytes(got.mrf.confidence, want.mrf.confidence));
  EXPECT_EQ(got.mrf.iterations, want.mrf.iterations);
  EXPECT_EQ(got.labels.width, want.labels.width);
  EXPECT_EQ(got.labels.labels, want.labels.labels);
  EXPECT_TRUE(sameBytes(got.labels.confidence, want.labels.confidence));
  EXPECT_EQ(got.forest_labels, want.forest_labels);
  EXPECT_EQ(got.tables.size(), want.tables.size());
}

// Every optional stage on (region, scene and object features, the
// auto-context round), with a model trained for them on `scene`.
SegmenterConfig allStagesConfig() {
  SegmenterConfig c = config();
  c.regions.enabled = true;
  c.scene.enabled = true;
  c.objects.enabled = true;
  c.mrf.object_consistency = 0.5f;
  c.context.enabled = true;
  c.context.cross_fit_folds = 0;  // one frame: nothing to cross-fit over
  c.forest.num_trees = 4;
  c.forest.max_depth = 6;
  return c;
}

std::shared_ptr<const RandomForest> trainAllStagesOn(const Scene& scene) {
  const SegmenterConfig c = allStagesConfig();
  const LabeledFrames frames{"scene", 1, [&](std::size_t) {
                               return LabeledFrame{"scene", scene.frame, scene.truth, {}};
                             }};
  ExtractionReport report;
  const auto samples = extractSamples(frames, Segmenter(c, nullptr), report);
  EXPECT_EQ(samples.size(), 1u);
  RandomForest forest = trainModel({&samples[0]}, c);
  forest.setExtractionSettings(extractionSettings(c));
  return std::make_shared<const RandomForest>(std::move(forest));
}

// A, B, no ground, A, B, A again through `reusing`, each frame through the
// buffers of the frames before: each must equal its fresh result.
void expectRecycledStreamGivesFreshResults(const Segmenter& reusing, const Scene& a,
                                           const Scene& b, const LabelledFrame& want_a,
                                           const LabelledFrame& want_b,
                                           const LabelledFrame& want_empty) {
  const std::vector<std::pair<const RgbdFrame*, const LabelledFrame*>> stream = {
      {&a.frame, &want_a}, {&b.frame, &want_b}, {nullptr, &want_empty},
      {&a.frame, &want_a}, {&b.frame, &want_b}, {&a.frame, &want_a}};
  for (std::size_t k = 0; k < stream.size(); ++k) {
    SCOPED_TRACE("frame " + std::to_string(k) + " of the stream");
    LabelledFrame got = reusing.process(stream[k].first ? *stream[k].first : emptyFrame());
    expectSameFrame(got, *stream[k].second);
    reusing.recycle(std::move(got));
  }
}

TEST(BufferReuse, CloudFunctionsWriteIntoUsedBuffersAsIntoFreshOnes) {
  const Scene small = floorAndWall(320, 240, 3.0, 1.2);
  const Scene big = floorAndWall(640, 480, 2.2, 1.0);
  NormalConfig normals_config;
  // Buffers left over from the other size and scene.
  OrganizedCloud cloud = frameToCloud(big.frame);
  NormalImage normals = computeNormals(cloud, normals_config);
  OrganizedCloud moved = cloud;
  NormalImage rotated = normals;
  const Eigen::Isometry3f transform(Eigen::AngleAxisf(0.3f, Eigen::Vector3f::UnitX()));

  frameToCloud(small.frame, 10.0f, cloud);
  const OrganizedCloud fresh_cloud = frameToCloud(small.frame, 10.0f);
  EXPECT_EQ(cloud.width, 320);
  EXPECT_TRUE(sameBytes(cloud.points, fresh_cloud.points));
  EXPECT_TRUE(sameBytes(cloud.colors, fresh_cloud.colors));

  computeNormals(cloud, normals_config, normals);
  const NormalImage fresh_normals = computeNormals(fresh_cloud, normals_config);
  EXPECT_EQ(normals.width, 320);
  EXPECT_TRUE(sameBytes(normals.normals, fresh_normals.normals));

  transformCloud(cloud, transform, moved);
  EXPECT_TRUE(sameBytes(moved.points, transformCloud(fresh_cloud, transform).points));
  rotateNormals(normals, transform.linear(), rotated);
  EXPECT_TRUE(sameBytes(rotated.normals, rotateNormals(fresh_normals, transform.linear()).normals));
}

TEST(BufferReuse, SegmentIntoAUsedSegmentationEqualsAFreshOne) {
  const Scene a = floorAndWall(320, 240, 3.0, 1.2);
  const Scene b = floorAndWall(640, 480, 2.2, 1.0);
  const auto oversegmenter = makeOversegmenter(config().oversegmentation);
  const OrganizedCloud cloud_a = frameToCloud(a.frame), cloud_b = frameToCloud(b.frame);
  const NormalImage normals_a = computeNormals(cloud_a, NormalConfig{});
  const NormalImage normals_b = computeNormals(cloud_b, NormalConfig{});
  const Oversegmentation fresh_a = oversegmenter->segment(cloud_a, normals_a);
  const Oversegmentation fresh_b = oversegmenter->segment(cloud_b, normals_b);
  ASSERT_GT(fresh_a.segments.size(), 50u);
  ASSERT_NE(fresh_a.segments.size(), fresh_b.segments.size());

  Oversegmentation reused;
  for (int round = 0; round < 2; ++round) {  // a -> b -> a -> b: grows, shrinks, grows
    oversegmenter->segmentInto(cloud_a, normals_a, reused);
    expectSameSegmentation(reused, fresh_a);
    oversegmenter->segmentInto(cloud_b, normals_b, reused);
    expectSameSegmentation(reused, fresh_b);
  }
}

TEST(BufferReuse, FinalizeIgnoresWhatAUsedSegmentationHeld) {
  // 4x2 grid: ids 7 and 3, one pixel without a segment.
  Oversegmentation fresh;
  fresh.width = 4;
  fresh.height = 2;
  fresh.pixel_segment = {7, 7, 3, 3, 7, -1, 3, 3};
  Oversegmentation used = fresh;
  used.segments = {{0, 1, 2}, {5}, {6, 7}, {1}, {2, 3, 4, 5, 6}};  // stale lists
  used.edges = {{0, 4}, {1, 2}, {2, 3}};                              // stale edges
  finalizeOversegmentation(fresh, 1);
  finalizeOversegmentation(used, 1);
  expectSameSegmentation(used, fresh);
  EXPECT_EQ(used.segments, (std::vector<std::vector<int>>{{2, 3, 6, 7}, {0, 1, 4}}));
  EXPECT_EQ(used.edges, (std::vector<std::pair<int, int>>{{0, 1}}));
}

TEST(BufferReuse, RecycledFramesGiveTheResultsOfFreshOnes) {
  const Scene a = floorAndWall(320, 240, 3.0, 1.2);
  const Scene b = floorAndWall(640, 480, 2.2, 1.0);
  const auto forest = trainOn(a);
  const Segmenter fresh(config(), forest);
  const LabelledFrame want_a = fresh.process(a.frame);
  const LabelledFrame want_b = fresh.process(b.frame);
  const LabelledFrame want_empty = fresh.process(emptyFrame());
  ASSERT_TRUE(want_a.segmented.prepared.ground);
  ASSERT_FALSE(want_empty.segmented.prepared.ground);

  const Segmenter reusing(config(), forest);
  expectRecycledStreamGivesFreshResults(reusing, a, b, want_a, want_b, want_empty);
}

TEST(BufferReuse, RecycledFramesGiveTheResultsOfFreshOnesWithEveryStage) {
  const Scene a = floorAndWall(320, 240, 3.0, 1.2);
  const Scene b = floorAndWall(640, 480, 2.2, 1.0);
  const auto forest = trainAllStagesOn(a);
  ASSERT_NE(forest->contextRound(), nullptr);
  const Segmenter fresh(allStagesConfig(), forest);
  const LabelledFrame want_a = fresh.process(a.frame);
  const LabelledFrame want_b = fresh.process(b.frame);
  const LabelledFrame want_empty = fresh.process(emptyFrame());
  ASSERT_FALSE(want_a.features.scene.empty());
  ASSERT_FALSE(want_a.features.objects.empty());
  ASSERT_FALSE(want_a.first_round_probabilities.empty());

  const Segmenter reusing(allStagesConfig(), forest);
  expectRecycledStreamGivesFreshResults(reusing, a, b, want_a, want_b, want_empty);
}

// A recycled frame's tables lend their buffers to the next frame's table
// stage: they must never come out as that frame's tables, also when the
// frame has no ground plane (the table stage does not run) or no table.
TEST(BufferReuse, ARecycledFramesTablesAreNotTheNextFramesTables) {
  const Scene a = floorAndWall(320, 240, 3.0, 1.2);
  const auto forest = trainOn(a);
  const Segmenter reusing(config(), forest);
  for (const bool with_ground : {false, true}) {
    SCOPED_TRACE(with_ground ? "a frame without tables" : "a frame without a ground plane");
    LabelledFrame done = reusing.process(a.frame);
    ASSERT_TRUE(done.tables.empty());
    TableCluster stale;
    stale.point_count = 1234;
    stale.pixels.assign(1234, 7);
    stale.hull = {{0.0f, 0.0f}, {1.0f, 0.0f}, {0.0f, 1.0f}};
    done.tables.push_back(stale);
    done.table_diagnostics = {"stale"};
    reusing.recycle(std::move(done));
    const LabelledFrame next = reusing.process(with_ground ? a.frame : emptyFrame());
    EXPECT_EQ(next.segmented.prepared.ground.has_value(), with_ground);
    EXPECT_TRUE(next.tables.empty());
    for (const std::string& line : next.table_diagnostics) EXPECT_NE(line, "stale");
  }
}

// Allocations of prepare() + oversegment() for one frame.
std::uint64_t allocationsOfPrepareAndOversegment(const Segmenter& segmenter, const RgbdFrame& frame,
                                                 SegmentedFrame& out) {
  RgbdFrame copy = frame;  // the caller's frame, not counted
  const std::uint64_t before = bench::g_news.load();
  out = segmenter.oversegment(segmenter.prepare(std::move(copy)));
  return bench::g_news.load() - before;
}

TEST(BufferReuse, AWarmRecyclingStreamAllocatesNextToNothingBeforeClassification) {
  const Scene a = floorAndWall(640, 480, 3.0, 1.2);
  const auto forest = trainOn(a);

  // Without recycle: one pixel list per segment, at least, for every frame.
  const Segmenter plain(config(), forest);
  SegmentedFrame segmented;
  std::uint64_t plain_news = 0;
  for (int k = 0; k < 4; ++k) plain_news = allocationsOfPrepareAndOversegment(plain, a.frame, segmented);
  const std::size_t segments = segmented.segmentation.segments.size();
  ASSERT_GT(segments, 100u);
  EXPECT_GE(plain_news, segments);

  // With recycle, once warm: one allocation per working buffer of the
  // oversegmenter (about 30, whatever the segment count) and finalize's two.
  const Segmenter reusing(config(), forest);
  std::uint64_t reusing_news = 0;
  for (int k = 0; k < 4; ++k) {
    reusing_news = allocationsOfPrepareAndOversegment(reusing, a.frame, segmented);
    LabelledFrame done = reusing.classify(std::move(segmented));
    reusing.recycle(std::move(done));
  }
  EXPECT_LE(reusing_news, 4u) << "segments: " << segments << ", without recycle: " << plain_news;
}

// The whole per-frame path, every optional stage on. What may still
// allocate is the table stage's text (why no table was found, one message)
// and the tables themselves (none in this scene).
TEST(BufferReuse, AWarmRecyclingStreamAllocatesNextToNothing) {
  const Scene a = floorAndWall(640, 480, 3.0, 1.2);
  const auto forest = trainAllStagesOn(a);
  const Segmenter plain(allStagesConfig(), forest);
  const Segmenter reusing(allStagesConfig(), forest);
  std::uint64_t plain_news = 0, reusing_news = 0;
  for (int k = 0; k < 4; ++k) {
    RgbdFrame copy = a.frame;  // the caller's frame, not counted
    std::uint64_t before = bench::g_news.load();
    const LabelledFrame fresh = plain.process(std::move(copy));
    plain_news = bench::g_news.load() - before;

    copy = a.frame;
    before = bench::g_news.load();
    LabelledFrame done = reusing.process(std::move(copy));
    reusing_news = bench::g_news.load() - before;
    ASSERT_TRUE(done.segmented.prepared.ground);
    EXPECT_TRUE(done.tables.empty());
    reusing.recycle(std::move(done));
  }
  EXPECT_GE(plain_news, 100u);
  EXPECT_LE(reusing_news, 6u) << "without recycle: " << plain_news;
}

// Frames without a ground plane between others (a third of the NYU frames
// estimate none): the frame after one must still find the recycled
// buffers, and allocate next to nothing.
TEST(BufferReuse, FramesWithoutAGroundPlaneKeepTheRecycledBuffers) {
  const Scene a = floorAndWall(640, 480, 3.0, 1.2);
  const auto forest = trainAllStagesOn(a);
  const Segmenter reusing(allStagesConfig(), forest);
  std::uint64_t after_empty_news = 0;
  for (int k = 0; k < 8; ++k) {
    const bool empty = k % 2 == 1;
    RgbdFrame copy = empty ? emptyFrame() : a.frame;  // the caller's frame, not counted
    const std::uint64_t before = bench::g_news.load();
    LabelledFrame done = reusing.process(std::move(copy));
    if (!empty && k > 0) after_empty_news = bench::g_news.load() - before;
    ASSERT_EQ(done.segmented.prepared.ground.has_value(), !empty);
    reusing.recycle(std::move(done));
  }
  EXPECT_LE(after_empty_news, 6u);
}

}  // namespace
}  // namespace findmug
