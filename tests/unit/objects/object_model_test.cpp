// Taught object models (object_model.hpp): the file round trip to the bit,
// every corruption refused with the file and the field named, the ESF shape
// descriptor deterministic and leaving the C library's rand() alone, the
// roundness cue on cylinders and boxes, version 1 files, and a view made from
// a rendered candidate.
#include "findmug/objects/object_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <thread>

#include "expect_error.hpp"
#include "findmug/objects/object_matcher.hpp"
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
std::size_t roundnessAt(const ObjectModel& m) {
  return viewAt(m) + 4 * (3 + kObjectColourBins + kObjectShapeBins);
}
std::size_t pointCountAt(const ObjectModel& m) { return roundnessAt(m) + 4; }

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
    EXPECT_EQ(std::memcmp(&a.roundness, &b.roundness, sizeof(float)), 0);
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
  EXPECT_CONTAINS(decodeError({bytes.begin(), bytes.begin() + roundnessAt(m) - 1}),
                  "reading views[0].shape");
  EXPECT_CONTAINS(decodeError({bytes.begin(), bytes.begin() + pointCountAt(m) - 1}),
                  "reading views[0].roundness");
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
  poke<std::uint32_t>(bytes, kVersionAt, 3);
  EXPECT_CONTAINS(decodeError(bytes),
                  "mug.fmo: version = 3: unknown format version (this program reads 1 to 2)");
  poke<std::uint32_t>(bytes, kVersionAt, 0);
  EXPECT_CONTAINS(decodeError(bytes), "mug.fmo: version = 0: unknown format version");
}

// Version 1: the same without each view's roundness, and its ESF descriptor
// of all the view's points.
std::vector<std::uint8_t> version1BytesOf(const ObjectModel& m) {
  auto bytes = bytesOf(m);
  EXPECT_EQ(m.views.size(), 1u);
  poke<std::uint32_t>(bytes, kVersionAt, 1);
  const auto at = bytes.begin() + static_cast<std::ptrdiff_t>(roundnessAt(m));
  bytes.erase(at, at + 4);
  return bytes;
}

TEST(ObjectModelFile, Version1LoadsWithRoundnessAndShapeFromItsPoints) {
  ObjectModel m = test::sampleObjectModel("mug", 1, 1000);
  m.views[0].roundness = 0.5f;                     // what the file cannot say: it must be computed
  m.views[0].shape.fill(1.0f / kObjectShapeBins);  // no ESF gives this: it must be replaced
  const auto v1 = version1BytesOf(m);
  const ObjectModel back = decodeObjectModel(v1.data(), v1.size(), "old.fmo");
  ASSERT_EQ(back.views.size(), 1u);
  const auto& points = m.views[0].points;
  EXPECT_EQ(back.views[0].roundness, objectRoundnessResidual(points));
  EXPECT_LT(back.views[0].roundness, 0.02f);  // the points are on a cylinder
  const ObjectShapeDescriptor now = objectShapeDescriptor(points);
  EXPECT_EQ(std::memcmp(back.views[0].shape.data(), now.data(), sizeof(now)), 0);
  // Written again it is a version 2 file holding the computed values.
  const auto v2 = bytesOf(back);
  EXPECT_EQ(v2.size(), v1.size() + 4);
  EXPECT_EQ(v2[kVersionAt], 2);
  const ObjectModel again = decodeObjectModel(v2.data(), v2.size(), "new.fmo");
  EXPECT_EQ(again.views[0].roundness, back.views[0].roundness);
}

TEST(ObjectModelFile, Version1WithoutAShapeIsRefusedNamingIt) {
  ObjectModel m = test::sampleObjectModel("mug", 1, 100);
  for (int i = 0; i < 100; ++i) m.views[0].points[i] = Eigen::Vector3f(0.001f * i, 0.0f, 0.0f);
  const auto v1 = version1BytesOf(m);
  EXPECT_CONTAINS(decodeError(v1), "views[0].points = 100 points: version 1 view without a shape");
}

TEST(ObjectModelFile, RoundnessOutOfRangeIsRefused) {
  const ObjectModel m = test::sampleObjectModel("mug", 1);
  auto bytes = bytesOf(m);
  poke(bytes, roundnessAt(m), std::numeric_limits<float>::quiet_NaN());
  EXPECT_CONTAINS(decodeError(bytes),
                  "views[0].roundness = nan: must be a finite number in [0, 1]");
  poke(bytes, roundnessAt(m), 1.5f);
  EXPECT_CONTAINS(decodeError(bytes), "views[0].roundness = 1.5");
  poke(bytes, roundnessAt(m), -0.1f);
  EXPECT_CONTAINS(decodeError(bytes), "views[0].roundness = -0.1");
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

// A partial view of a vertical object's side and top as a depth camera at
// `bearing` (rad, from the object towards the camera) sees it: the surface
// points facing the camera, 1 cm apart, with Gaussian noise of `sigma` m
// along the line of sight. Cylinder of radius `r`, or box of half sides `a`,
// `b` turned by `yaw`.
std::vector<Eigen::Vector3f> seenSide(bool cylinder, double r_or_a, double b, double yaw,
                                      double bearing, double sigma, unsigned seed) {
  std::vector<Eigen::Vector3f> points;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  const Eigen::Vector2d view(std::cos(bearing), std::sin(bearing));
  const double h = 0.10, step = 0.004;
  auto add = [&](Eigen::Vector2d xy, double z, const Eigen::Vector2d& normal) {
    if (normal.dot(view) <= 0.05) return;  // faces away or grazing
    xy += noise(rng) * view;
    points.emplace_back(static_cast<float>(xy.x()), static_cast<float>(xy.y()),
                        static_cast<float>(z));
  };
  for (double z = 0.0; z <= h; z += step) {
    if (cylinder) {
      for (double t = 0.0; t < 2 * M_PI; t += step / r_or_a) {
        const Eigen::Vector2d n(std::cos(t), std::sin(t));
        add(r_or_a * n, z, n);
      }
      continue;
    }
    const Eigen::Rotation2Dd rot(yaw);
    const double half[2] = {r_or_a, b};
    for (int axis = 0; axis < 2; ++axis)
      for (int sign : {-1, 1}) {
        const Eigen::Vector2d n =
            rot * (axis == 0 ? Eigen::Vector2d(sign, 0) : Eigen::Vector2d(0, sign));
        const Eigen::Vector2d along =
            rot * (axis == 0 ? Eigen::Vector2d(0, 1) : Eigen::Vector2d(1, 0));
        const double len = half[1 - axis];
        for (double u = -len; u <= len; u += step) add(half[axis] * n + u * along, z, n);
      }
  }
  // The top (which the cue leaves out), seen from above.
  for (double x = -r_or_a; x <= r_or_a; x += step)
    for (double y = -r_or_a; y <= r_or_a; y += step)
      if (!cylinder || x * x + y * y <= r_or_a * r_or_a)
        points.emplace_back(static_cast<float>(x), static_cast<float>(y),
                            static_cast<float>(h + noise(rng)));
  return points;
}

TEST(ObjectRoundness, ACylinderIsRoundABoxIsNot) {
  unsigned seed = 1;
  for (double bearing : {0.0, 0.7, 2.0, 4.0}) {
    for (double sigma : {0.0, 0.003}) {
      const float cyl = objectRoundnessResidual(seenSide(true, 0.04, 0, 0, bearing, sigma, seed++));
      EXPECT_LT(cyl, 0.05f) << "cylinder, bearing " << bearing << ", noise " << sigma;
      EXPECT_LT(cyl, ObjectMatcherConfig{}.max_roundness_residual);
      // A box of the mug's size: one face (yaw 0 facing bearing 0), or an L of two.
      for (double yaw : {0.0, 0.3, M_PI / 4}) {
        const float box = objectRoundnessResidual(
            seenSide(false, 0.04, 0.04, bearing + yaw, bearing, sigma, seed++));
        EXPECT_GT(box, 0.08f) << "box, yaw " << yaw << ", bearing " << bearing << ", noise "
                              << sigma;
      }
    }
  }
}

TEST(ObjectRoundness, TooFewSidePointsOrAFlatFaceAreNotRound) {
  EXPECT_EQ(objectRoundnessResidual({}), kNotRound);
  std::vector<Eigen::Vector3f> face;
  for (int i = 0; i < 400; ++i) face.emplace_back(0.004f * (i % 20), 0.0f, 0.005f * (i / 20));
  EXPECT_EQ(objectRoundnessResidual(face), kNotRound);
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
  EXPECT_EQ(view.roundness, objectRoundnessResidual(view.points));
  EXPECT_LT(view.roundness, ObjectMatcherConfig{}.max_roundness_residual) << "a mug is round";
  ObjectModel m{"mug", {view}};
  EXPECT_NO_THROW(validateObjectModel(m, "test"));
  TableObject outside = c;
  outside.pixels.push_back(640 * 480);
  EXPECT_CONTAINS(errorOf([&] { makeObjectView(r.cloud_ground, outside); }),
                  "pixel 307200 outside the 640x480 cloud");
}

TEST(ObjectView, FromHeldPointsIsTheViewFromTheCloud) {
  // findmugd's teacher keeps a candidate's points past its frame; the view it makes from
  // them must be the one findmug-teach makes from the cloud, bit for bit.
  auto scene = test::makeTableScene();
  const int mug = test::addMug(scene, scene.table_center, 0.04, 0.10, 0.5, Rgb8{40, 60, 200});
  const auto r = test::renderTable(scene, test::cameraAround(scene, 0.3, 1.1), 7);
  const TableObject c = test::candidateOf(r, mug, static_cast<float>(scene.top_z));
  std::vector<Eigen::Vector3f> points;
  std::vector<Rgb8> colors;
  objectPointsOf(r.cloud_ground, c.pixels, kMaxObjectViewPoints, points, colors);
  const ObjectView held = makeObjectView(c, points, colors);
  const ObjectView direct = makeObjectView(r.cloud_ground, c);
  EXPECT_EQ(encodeObjectModel({"mug", {held}}), encodeObjectModel({"mug", {direct}}));
  colors.pop_back();
  EXPECT_CONTAINS(errorOf([&] { makeObjectView(c, points, colors); }), "colours");
  points.resize(5);
  colors.resize(5);
  EXPECT_CONTAINS(errorOf([&] { makeObjectView(c, points, colors); }), "need 20");
}

TEST(ObjectModelFile, AddingViewsMakesAModelThenGrowsItUpToTen) {
  test::TempDir dir;
  const std::string path = dir.str("mug.fmo");
  const ObjectView view = test::sampleObjectModel("mug", 1).views[0];
  for (int n = 1; n <= kMaxObjectViews; ++n) EXPECT_EQ(addObjectViewToFile(path, "mug", view), n);
  const ObjectModel m = loadObjectModel(path);
  EXPECT_EQ(m.name, "mug");
  EXPECT_EQ(m.views.size(), static_cast<std::size_t>(kMaxObjectViews));
  EXPECT_CONTAINS(errorOf([&] { addObjectViewToFile(path, "mug", view); }),
                  "already has 10 views");
  EXPECT_EQ(loadObjectModel(path).views.size(), static_cast<std::size_t>(kMaxObjectViews));
  // Another name in the file, a bad name, a corrupt file: refused, the file kept.
  EXPECT_CONTAINS(errorOf([&] { addObjectViewToFile(path, "cup", view); }), "holds \"mug\"");
  EXPECT_CONTAINS(errorOf([&] { addObjectViewToFile(dir.str("x.fmo"), "X Y", view); }), "X Y");
  { std::ofstream(dir.str("bad.fmo")) << "FMOBJECT junk"; }
  EXPECT_THROW(addObjectViewToFile(dir.str("bad.fmo"), "bad", view), Error);
  // Nothing but the model files is left in the folder (the writes go through a rename).
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path())) {
    ++files;
    EXPECT_EQ(e.path().extension(), ".fmo") << e.path();
  }
  EXPECT_EQ(files, 2);
}

}  // namespace
}  // namespace findmug
