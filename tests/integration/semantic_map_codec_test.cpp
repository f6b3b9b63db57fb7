// semantic_map_t (FINDMUG_SEMANTIC_MAP): a map's voxels round trip through the message, and
// the hardened decoder refuses every kind of corrupt message with an error naming the field.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/semantic_map_codec.hpp"
#include "findmug/map/semantic_map.hpp"

namespace findmug::io {
namespace {

// A map of a floor patch and a table top seen twice from straight above.
SemanticMap smallMap() {
  SemanticMap map;
  OrganizedCloud cloud;
  LabelImage labels;
  cloud.width = labels.width = 40;
  cloud.height = labels.height = 40;
  for (int y = 0; y < 40; ++y) {
    for (int x = 0; x < 40; ++x) {
      const bool top = x >= 10 && x < 30 && y >= 10 && y < 30;
      cloud.points.emplace_back(0.025f * static_cast<float>(x - 20),
                                0.025f * static_cast<float>(y - 20), top ? 0.75f : 1.5f);
      cloud.colors.push_back(Rgb8{});
      labels.labels.push_back(static_cast<std::uint8_t>(top ? Label::Table : Label::Floor));
      labels.confidence.push_back(top ? 0.9f : 0.6f);
    }
  }
  Eigen::Isometry3d camera = Eigen::Isometry3d::Identity();
  camera.linear() << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  camera.translation() = Eigen::Vector3d(-3.0, 2.0, 1.5);
  map.integrate(cloud, labels, camera, 1000);
  map.integrate(cloud, labels, camera, 2000);
  return map;
}

std::vector<std::uint8_t> wire(const findmug_lcm::semantic_map_t& msg) {
  return encodeMessage(msg);
}

std::string errorOf(const std::vector<std::uint8_t>& bytes) {
  try {
    decodeSemanticMap(bytes.data(), bytes.size(), "FINDMUG_SEMANTIC_MAP");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(SemanticMapCodec, RoundTripKeepsEveryVoxelWithLabelAndConfidence) {
  const SemanticMap map = smallMap();
  const SemanticMapMessage message = semanticMapMessage(map, 2000, 7);
  ASSERT_EQ(message.voxels.size(), 400u);  // every 2nd pixel (pixel_stride) in its own voxel
  EXPECT_EQ(message.frames, 2);
  int tables = 0;
  for (const SemanticMapVoxel& v : message.voxels) {
    const Eigen::Vector3d centre(v.i * 0.05, v.j * 0.05, v.k * 0.05);
    const SemanticMap::Voxel* voxel = map.find(centre);
    ASSERT_NE(voxel, nullptr);
    float confidence = 0.0f;
    EXPECT_EQ(v.label, SemanticMap::labelOf(*voxel, &confidence));
    EXPECT_NEAR(v.confidence / 255.0f, confidence, 0.5f / 255.0f);
    tables += v.label == static_cast<std::uint8_t>(Label::Table);
  }
  EXPECT_EQ(tables, 100);
  for (const bool compress : {true, false}) {
    const auto bytes = wire(encodeSemanticMap(message, compress));
    const SemanticMapMessage back = decodeSemanticMap(bytes.data(), bytes.size(), "test");
    EXPECT_EQ(back.voxels, message.voxels);
    EXPECT_EQ(back.utime, 2000u);
    EXPECT_EQ(back.seq, 7);
    EXPECT_EQ(back.frames, 2);
    EXPECT_FLOAT_EQ(back.voxel_size_m, 0.05f);
  }
  // zlib pays: a map of surfaces compresses.
  EXPECT_LT(encodeSemanticMap(message, true).data.size(), message.voxels.size() * 8 / 2);
}

TEST(SemanticMapCodec, CorruptMessagesAreRefusedNamingTheField) {
  const SemanticMapMessage message = semanticMapMessage(smallMap(), 2000, 7);
  const findmug_lcm::semantic_map_t good = encodeSemanticMap(message, true);
  auto expectError = [](const std::vector<std::uint8_t>& bytes, const std::string& what) {
    const std::string e = errorOf(bytes);
    EXPECT_NE(e.find("FINDMUG_SEMANTIC_MAP"), std::string::npos) << e;
    EXPECT_NE(e.find(what), std::string::npos) << "expected '" << what << "' in: " << e;
  };
  EXPECT_EQ(errorOf(wire(good)), "");

  std::vector<std::uint8_t> bytes = wire(good);
  expectError(std::vector<std::uint8_t>(bytes.begin(), bytes.begin() + bytes.size() - 3),
              "data_size");
  bytes[0] ^= 1;
  expectError(bytes, "type hash mismatch");
  expectError(std::vector<std::uint8_t>(bytes.begin(), bytes.begin() + 5), "<hash>");

  findmug_lcm::semantic_map_t m = good;
  m.num_voxels += 1;  // the records inflate to fewer bytes than announced
  expectError(wire(m), "semantic_map_t.data");
  m = good;
  m.num_voxels = -1;
  expectError(wire(m), "num_voxels");
  m.num_voxels = kMaxSemanticMapVoxels + 1;
  expectError(wire(m), "num_voxels");
  m = good;
  m.compression = 7;
  expectError(wire(m), "compression");
  m = good;
  m.voxel_size_m = std::nanf("");
  expectError(wire(m), "voxel_size_m");
  m = good;
  m.utime = -5;
  expectError(wire(m), "utime");
  m = good;
  m.data[m.data.size() / 2] ^= 0x55;  // a corrupt zlib stream
  expectError(wire(m), "semantic_map_t.data");

  // Raw records: a label out of range, and voxels out of order.
  SemanticMapMessage bad = message;
  bad.voxels[3].label = 9;
  expectError(wire(encodeSemanticMap(bad, false)), "label id 9");
  bad = message;
  std::swap(bad.voxels[1], bad.voxels[2]);
  expectError(wire(encodeSemanticMap(bad, false)), "out of order");
  bad = message;
  bad.voxels[2] = bad.voxels[1];
  expectError(wire(encodeSemanticMap(bad, false)), "out of order or repeated");
}

}  // namespace
}  // namespace findmug::io
