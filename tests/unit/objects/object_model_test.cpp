// Taught object models (object_model.hpp): the file round trip to the bit,
// every corruption refused with the file and the field named, the ESF shape
// descriptor deterministic and leaving the C library's rand() alone, and a
// view made from a rendered candidate.
#include "findmug/objects/object_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <thread>

#include "expect_error.hpp"
#include "object_scenes.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

using test::errorOf;

std::vector<std::uint8_t> bytesOf(const ObjectModel& m) { return encodeObjectModel(m); }

std::string decodeError(const std::vector<std::uint8_t>& bytes) {
  return errorOf([&] { decodeObjectModel(bytes.data(), bytes.size(), "mug.fmo"); });
}

// Offsets in the file of one view of 200 points (object_model.hpp's layout).
constexpr std::size_t kVersionAt = 8;
constexpr std::size_t kNameLengthAt = 12;
std::size_t viewCountAt(const ObjectModel& m) { return 16 + m.name.size(); }
std::size_t viewAt(const ObjectModel& m) { return viewCountAt(m) + 4; }
std::size_t pointCountAt(const ObjectModel& m) {
  return viewAt(m) + 4 * (3 + kObjectColourBins + kObjectShapeBins);
}

template <typename T>
void poke(std::vector<std::uint8_t>& bytes, std::size_t at, T value) {
  std::memcpy(bytes.data() + at, &value, sizeof(T));
}

TEST(ObjectModelFile, RoundTripIsBitExact) {
  const ObjectModel m = test::sampleObjectModel("red_mug-2", 3);
  test::TempDir dir;
  const std::string path = dir.str("red_mug.fmo");
  saveObjectModel(path, m);
  const ObjectModel back = loadObjectModel(path);
  ASSERT_EQ(back.name, m.name);
  ASSERT_EQ(back.views.size(), m.views.size());
  for (std::size_t v = 0; v < m.views.size(); ++v) {
    const auto& a = m.views[v];
    const auto& b = back.views[v];
    EXPECT_EQ(std::memcmp(&a.height_above_top, &b.height_above_top, sizeof(float)), 0);
    EXPECT_EQ(std::memcmp(a.extents.data(), b.extents.data(), 2 * sizeof(float)), 0);
    EXPECT_EQ(std::memcmp(a.colour_histogram.data(), b.colour_histogram.data(),
                          sizeof(a.colour_histogram)),
              0);
    EXPECT_EQ(std::memcmp(a.shape.data(), b.shape.data(), sizeof(a.shape)), 0);
    ASSERT_EQ(a.points.size(), b.points.size());
    for (std::size_t i = 0; i < a.points.size(); ++i) {
      EXPECT_EQ(std::memcmp(a.points[i].data(), b.points[i].data(), 3 * sizeof(float)), 0);
      EXPECT_EQ(a.colors[i], b.colors[i]);
    }
  }
  EXPECT_EQ(bytesOf(back), bytesOf(m));
  // The temporary file of the atomic save is gone.
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 1);
}

TEST(ObjectModelFile, TruncationAtEveryOffsetIsRefusedNamingTheField) {
  const ObjectModel m = test::sampleObjectModel("mug", 1, 20);
  const auto bytes = bytesOf(m);
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    const std::vector<std::uint8_t> cut(bytes.begin(), bytes.begin() + n);
    const std::string e = decodeError(cut);
    ASSERT_NE(e.find("mug.fmo: truncated at byte " + std::to_string(n) + " reading "),
              std::string::npos)
        << "at " << n << ": " << e;
  }
  EXPECT_CONTAINS(decodeError({bytes.begin(), bytes.begin() + 4}), "reading magic");
  EXPECT_CONTAINS(decodeError({bytes.begin(), bytes.begin() + kVersionAt + 2}), "reading version");
  EXPECT_CONTAINS(decodeError({bytes.begin(), bytes.begin() + pointCountAt(m) - 1}),
                  "reading views[0].shape");
  EXPECT_CONTAINS(decodeError({bytes.begin(), bytes.end() - 1}), "reading views[0].points");
}

TEST(ObjectModelFile, TrailingBytesAreRefused) {
  auto bytes = bytesOf(test::sampleObjectModel("mug", 1));
  bytes.push_back(0);
  EXPECT_CONTAINS(decodeError(bytes), "mug.fmo: trailing bytes = 1");
}

TEST(ObjectModelFile, BadMagicAndUnknownVersionAreRefused) {
  const auto good = bytesOf(test::sampleObjectModel("mug", 1));
  auto bytes = good;
  bytes[0] ^= 0x20;
  EXPECT_CONTAINS(decodeError(bytes), "mug.fmo: magic = \"fMOBJECT\"");
  bytes = good;
  poke<std::uint32_t>(bytes, kVersionAt, 2);
  EXPECT_CONTAINS(decodeError(bytes), "mug.fmo: version = 2: unknown format version");
}

TEST(ObjectModelFile, BadNamesAreRefused) {
  const ObjectModel m = test::sampleObjectModel("mug", 1);
  auto bytes = bytesOf(m);
  bytes[16] = 'M';  // the name's first letter
  EXPECT_CONTAINS(decodeError(bytes), "name = \"Mug\"");
  bytes = bytesOf(m);
  poke<std::uint32_t>(bytes, kNameLengthAt, 0);
  EXPECT_CONTAINS(decodeError(bytes), "name_length = 0");
  poke<std::uint32_t>(bytes, kNameLengthAt, 33);
  EXPECT_CONTAINS(decodeError(bytes), "name_length = 33");
  for (const char* bad : {"", "my mug", "mug/..", "mug!", "abcdefghijabcdefghijabcdefghijabc"}) {
    ObjectModel named = m;
    named.name = bad;
    EXPECT_CONTAINS(errorOf([&] { encodeObjectModel(named); }), "name = \"" + named.name + "\"");
  }
}

TEST(ObjectModelFile, ViewCountOutOfRangeIsRefused) {
  const ObjectModel m = test::sampleObjectModel("mug", 1);
  auto bytes = bytesOf(m);
  poke<std::uint32_t>(bytes, viewCountAt(m), 0);
  EXPECT_CONTAINS(decodeError(bytes), "mug.fmo: view_count = 0: must be in [1, 10]");
  poke<std::uint32_t>(bytes, viewCountAt(m), 11);
  EXPECT_CONTAINS(decodeError(bytes), "view_count = 11");
  ObjectModel none = m;
  none.views.clear();
  EXPECT_CONTAINS(errorOf([&] { encodeObjectModel(none); }), "view_count = 0");
  const ObjectModel eleven = test::sampleObjectModel("mug", 11, 20);
  EXPECT_CONTAINS(errorOf([&] { encodeObjectModel(eleven); }), "view_count = 11");
  EXPECT_NO_THROW(encodeObjectModel(test::sampleObjectModel("mug", 10, 20)));
}

TEST(ObjectModelFile, PointCountOutOfRangeIsRefusedBeforeAllocating) {
  const ObjectModel m = test::sampleObjectModel("mug", 1);
  auto bytes = bytesOf(m);
  poke<std::uint32_t>(bytes, pointCountAt(m), 5);
  EXPECT_CONTAINS(decodeError(bytes), "views[0].point_count = 5: must be in [20, 2000]");
  poke<std::uint32_t>(bytes, pointCountAt(m), 0xFFFFFFFFu);
  EXPECT_CONTAINS(decodeError(bytes), "views[0].point_count = 4294967295");
  poke<std::uint32_t>(bytes, pointCountAt(m), 2000);  // allowed, but the bytes are not there
  EXPECT_CONTAINS(decodeError(bytes), "truncated");
}

TEST(ObjectModelFile, NonFiniteAndOutOfRangeValuesAreRefused) {
  const ObjectModel m = test::sampleObjectModel("mug", 2);
  const auto good = bytesOf(m);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  auto bytes = good;
  poke(bytes, viewAt(m), nan);
  EXPECT_CONTAINS(decodeError(bytes), "views[0].height_above_top = nan");
  bytes = good;
  poke(bytes, viewAt(m), -0.1f);
  EXPECT_CONTAINS(decodeError(bytes), "views[0].height_above_top = -0.1");
  bytes = good;
  poke(bytes, viewAt(m) + 8, 0.5f);  // second half-length above the first
  EXPECT_CONTAINS(decodeError(bytes), "views[0].extents[1] = 0.5");
  bytes = good;
  poke(bytes, viewAt(m) + 12 + 4 * 3, nan);  // colour bin 3
  EXPECT_CONTAINS(decodeError(bytes), "views[0].colour_histogram[3] = nan");
  bytes = good;
  poke(bytes, pointCountAt(m) + 4 + 15 * 3 + 4, nan);  // point 3's y
  EXPECT_CONTAINS(decodeError(bytes), "views[0].points[3].y = nan");
}

TEST(ObjectModelFile, HistogramsMustSumToOne) {
  ObjectModel m = test::sampleObjectModel("mug", 2);
  auto bytes = bytesOf(m);
  poke(bytes, viewAt(m) + 12 + 4 * 1, 0.5f);  // the one full colour bin halved
  EXPECT_CONTAINS(decodeError(bytes), "views[0].colour_histogram = sum 0.5: must sum to 1");
  m.views[1].shape[7] += 0.01f;
  EXPECT_CONTAINS(errorOf([&] { encodeObjectModel(m); }), "views[1].shape = sum 1.01");
}

TEST(ObjectModelFile, LoadErrorsNameTheFile) {
  test::TempDir dir;
  const std::string path = dir.str("broken.fmo");
  std::ofstream(path, std::ios::binary) << "FMOBJECT";
  EXPECT_CONTAINS(errorOf([&] { loadObjectModel(path); }), path + ": truncated");
  EXPECT_CONTAINS(errorOf([&] { loadObjectModel(dir.str("missing.fmo")); }),
                  dir.str("missing.fmo") + ": cannot open");
}

TEST(ObjectShape, IsDeterministicOnAnyThreadAndLeavesRandAlone) {
  const ObjectModel m = test::sampleObjectModel("mug", 1, 400);
  const auto& points = m.views[0].points;
  std::srand(1234);
  const int expected = std::rand();
  std::srand(1234);
  const ObjectShapeDescriptor a = objectShapeDescriptor(points);
  EXPECT_EQ(std::rand(), expected) << "ESF reseeded the C library's rand()";
  ObjectShapeDescriptor b{};
  std::thread([&] { b = objectShapeDescriptor(points); }).join();
  EXPECT_EQ(std::memcmp(a.data(), b.data(), sizeof(a)), 0);
  double sum = 0.0;
  for (float v : a) sum += v;
  EXPECT_NEAR(sum, 1.0, 1e-4);
  EXPECT_EQ(shapeDescriptorDistance(a, b), 0.0f);
}

TEST(ObjectShape, SeparatesACylinderFromAPlane) {
  const auto cylinder = test::sampleObjectModel("mug", 1, 400).views[0].points;
  std::vector<Eigen::Vector3f> plane;
  for (int i = 0; i < 400; ++i) plane.emplace_back(0.004f * (i % 20), 0.005f * (i / 20), 0.0f);
  const float d =
      shapeDescriptorDistance(objectShapeDescriptor(cylinder), objectShapeDescriptor(plane));
  EXPECT_GT(d, 0.3f);
}

TEST(ObjectShape, RefusesTooFewOrCollinearPoints) {
  std::vector<Eigen::Vector3f> line;
  for (int i = 0; i < 100; ++i) line.emplace_back(0.001f * i, 0.0f, 0.0f);
  EXPECT_CONTAINS(errorOf([&] { objectShapeDescriptor(line); }), "do not span a surface");
  std::vector<Eigen::Vector3f> few(line.begin(), line.begin() + 19);
  EXPECT_CONTAINS(errorOf([&] { objectShapeDescriptor(few); }),
                  "19 distinct finite points, need 20");
  // Copies of a point count once (ESF would draw triples of one place for ever).
  std::vector<Eigen::Vector3f> copies(1990, Eigen::Vector3f(0.01f, 0.02f, 0.03f));
  copies.insert(copies.end(), few.begin(), few.end() - 1);
  EXPECT_CONTAINS(errorOf([&] { objectShapeDescriptor(copies); }),
                  "19 distinct finite points, need 20");
}

TEST(ObjectView, MadeFromARenderedCandidate) {
  auto scene = test::makeTableScene();
  const Rgb8 red{200, 40, 40};
  const int mug = test::addMug(scene, scene.table_center, 0.04, 0.10, 0.5, red);
  const auto r = test::renderTable(scene, test::cameraAround(scene, 0.3, 1.1), 7);
  const TableObject c = test::candidateOf(r, mug, static_cast<float>(scene.top_z));
  ASSERT_GT(c.point_count, 200);
  const ObjectView view = makeObjectView(r.cloud_ground, c);
  EXPECT_NEAR(view.height_above_top, 0.10f, 0.015f);
  EXPECT_GE(view.extents.x(), view.extents.y());
  EXPECT_EQ(view.points.size(), std::min<std::size_t>(c.point_count, kMaxObjectViewPoints));
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : view.points) mean += p.cast<double>();
  EXPECT_LT((mean / view.points.size()).norm(), 1e-4);
  EXPECT_EQ(view.colour_histogram, c.colour_histogram);
  // Red: most pixels in the hue sectors either side of 0 degrees (0 and 11).
  const auto& h = view.colour_histogram;
  EXPECT_GT(h[0] + h[1] + h[22] + h[23], 0.8f);
  ObjectModel m{"mug", {view}};
  EXPECT_NO_THROW(validateObjectModel(m, "test"));
  TableObject outside = c;
  outside.pixels.push_back(640 * 480);
  EXPECT_CONTAINS(errorOf([&] { makeObjectView(r.cloud_ground, outside); }),
                  "pixel 307200 outside the 640x480 cloud");
}

}  // namespace
}  // namespace findmug
