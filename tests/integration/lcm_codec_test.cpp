// LCM codecs: round trips for every compression, and every class of corrupt
// message (truncated at many lengths, flipped bytes, wrong size fields, absurd
// dimensions, unknown compression ids, corrupt zlib / JPEG / PNG, wrong type)
// must end in findmug::Error — never a crash, a huge allocation, or another
// exception type.
#include "findmug/io/lcm_codec.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <cstring>
#include <functional>
#include <random>

#include <zlib.h>

#include "findmug/common/error.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/frame/image_io.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/frame_source.hpp"
#include "findmug/io/lcm_codec_objects.hpp"
#include "lcm_samples.hpp"
#include "test_data.hpp"

namespace findmug::io {
namespace {

using Bytes = std::vector<std::uint8_t>;

// A frame with structure (a slanted plane, a box, holes) and a smooth colour
// gradient, so that compression behaves as on real data.
RgbdFrame makeFrame(int width = 64, int height = 48) {
  RgbdFrame f;
  f.width = width;
  f.height = height;
  f.intrinsics = {520.5, 519.25, 31.5, 23.75};
  f.extrinsics = CameraExtrinsics{1.1, 0.35, -0.02};
  f.utime = 1700000000123456ULL;
  f.seq = 42;
  f.source = "synthetic";
  std::mt19937 rng(7);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      std::uint16_t d = static_cast<std::uint16_t>(1500 + 20 * v + 3 * u);
      if (u > width / 3 && u < width / 2 && v > height / 3) d = 900;
      if ((u * 7 + v * 13) % 29 == 0) d = 0;  // holes
      if (v == height - 1) d = 65535;         // extreme value survives
      f.depth_mm.push_back(d);
      f.rgb.push_back(Rgb8{static_cast<std::uint8_t>(u * 255 / width),
                           static_cast<std::uint8_t>(v * 255 / height),
                           static_cast<std::uint8_t>(128 + (rng() % 8))});
    }
  }
  return f;
}

double meanAbsColourError(const std::vector<Rgb8>& a, const std::vector<Rgb8>& b) {
  EXPECT_EQ(a.size(), b.size());
  double sum = 0;
  for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) {
    sum += std::abs(a[i].r - b[i].r) + std::abs(a[i].g - b[i].g) + std::abs(a[i].b - b[i].b);
  }
  return sum / (3.0 * a.size());
}

// Runs `decode` and reports how it ended: "ok", "error: <message>" for
// findmug::Error, "OTHER: ..." for any other exception (a test failure).
template <typename F>
std::string outcome(F&& decode) {
  try {
    decode();
    return "ok";
  } catch (const Error& e) {
    return std::string("error: ") + e.what();
  } catch (const std::exception& e) {
    return std::string("OTHER: ") + e.what();
  }
}

template <typename F>
void expectError(F&& decode, const std::string& must_contain) {
  const std::string result = outcome(decode);
  ASSERT_EQ(result.rfind("error: ", 0), 0u) << result;
  EXPECT_NE(result.find(must_contain), std::string::npos)
      << "message '" << result << "' lacks '" << must_contain << "'";
}

void putBe32(Bytes& b, std::size_t offset, std::int32_t value) {
  const auto v = static_cast<std::uint32_t>(value);
  b[offset] = static_cast<std::uint8_t>(v >> 24);
  b[offset + 1] = static_cast<std::uint8_t>(v >> 16);
  b[offset + 2] = static_cast<std::uint8_t>(v >> 8);
  b[offset + 3] = static_cast<std::uint8_t>(v);
}

// Byte offsets in an encoded rgbd_frame_t (layout of rgbd_frame_t.lcm).
struct RgbdOffsets {
  std::size_t source_len, width, height, fx, depth_compression, depth_size, depth_data,
      color_compression, color_size, color_data;
};
RgbdOffsets rgbdOffsets(const findmug_lcm::rgbd_frame_t& m) {
  RgbdOffsets o{};
  o.source_len = 8 + 8 + 8;
  o.width = o.source_len + 4 + m.source.size() + 1;
  o.height = o.width + 4;
  o.fx = o.height + 4;
  o.depth_compression = o.fx + 32 + 1 + 24;
  o.depth_size = o.depth_compression + 1;
  o.depth_data = o.depth_size + 4;
  o.color_compression = o.depth_data + static_cast<std::size_t>(m.depth_size);
  o.color_size = o.color_compression + 1;
  o.color_data = o.color_size + 4;
  return o;
}

// ---- channels ---------------------------------------------------------------------

TEST(Channels, SuffixIsAppendedWithUnderscore) {
  EXPECT_EQ(channelName(kRgbdChannel, ""), "FINDMUG_RGBD");
  EXPECT_EQ(channelName(kLabelsChannel, "KITCHEN"), "FINDMUG_LABELS_KITCHEN");
  EXPECT_EQ(channelName(kStatusChannel, "robot2"), "FINDMUG_STATUS_robot2");
}

TEST(Channels, BadSuffixIsRejected) {
  expectError([] { channelName(kTablesChannel, "A B"); }, "A B");
  expectError([] { channelName(kTablesChannel, "_X"); }, "_X");
  expectError([] { channelName(kTablesChannel, "X/Y"); }, "X/Y");
}

// ---- RGB-D round trips -----------------------------------------------------------------

struct Combo {
  DepthCompression depth;
  ColorCompression color;
};

std::string comboName(const ::testing::TestParamInfo<Combo>& info) {
  static const char* const kDepth[] = {"DepthNone", "DepthZlib"};
  static const char* const kColor[] = {"ColorNone", "ColorJpeg", "ColorPng"};
  return std::string(kDepth[static_cast<int>(info.param.depth)]) +
         kColor[static_cast<int>(info.param.color)];
}

class RgbdRoundTrip : public ::testing::TestWithParam<Combo> {};

TEST_P(RgbdRoundTrip, BytesInFrameOut) {
  const RgbdFrame in = makeFrame();
  RgbdEncodeOptions opt;
  opt.depth = GetParam().depth;
  opt.color = GetParam().color;
  const findmug_lcm::rgbd_frame_t msg = encodeRgbdFrame(in, opt);
  EXPECT_EQ(msg.depth_compression, static_cast<std::int8_t>(opt.depth));
  EXPECT_EQ(msg.color_compression, static_cast<std::int8_t>(opt.color));
  const Bytes bytes = encodeMessage(msg);
  const RgbdFrame out = decodeRgbdFrame(bytes.data(), bytes.size(), "FINDMUG_RGBD");

  EXPECT_EQ(out.width, in.width);
  EXPECT_EQ(out.height, in.height);
  EXPECT_EQ(out.utime, in.utime);
  EXPECT_EQ(out.seq, in.seq);
  EXPECT_EQ(out.source, "FINDMUG_RGBD: synthetic");
  EXPECT_EQ(out.intrinsics.fx, in.intrinsics.fx);
  EXPECT_EQ(out.intrinsics.fy, in.intrinsics.fy);
  EXPECT_EQ(out.intrinsics.cx, in.intrinsics.cx);
  EXPECT_EQ(out.intrinsics.cy, in.intrinsics.cy);
  ASSERT_TRUE(out.extrinsics.has_value());
  EXPECT_EQ(out.extrinsics->height_m, 1.1);
  EXPECT_EQ(out.extrinsics->pitch_rad, 0.35);
  EXPECT_EQ(out.extrinsics->roll_rad, -0.02);
  EXPECT_EQ(out.depth_mm, in.depth_mm);  // depth is always lossless
  if (opt.color == ColorCompression::Jpeg) {
    EXPECT_LT(meanAbsColourError(out.rgb, in.rgb), 3.0);
    EXPECT_NE(out.rgb, in.rgb);  // it really went through JPEG
  } else {
    EXPECT_EQ(out.rgb, in.rgb);
  }
  if (opt.depth == DepthCompression::Zlib) {
    EXPECT_LT(msg.depth_data.size(), in.depth_mm.size() * 2);
  } else {
    EXPECT_EQ(msg.depth_data.size(), in.depth_mm.size() * 2);
  }
}

INSTANTIATE_TEST_SUITE_P(AllCompressions, RgbdRoundTrip,
                         ::testing::Values(Combo{DepthCompression::None, ColorCompression::None},
                                           Combo{DepthCompression::None, ColorCompression::Jpeg},
                                           Combo{DepthCompression::None, ColorCompression::Png},
                                           Combo{DepthCompression::Zlib, ColorCompression::None},
                                           Combo{DepthCompression::Zlib, ColorCompression::Jpeg},
                                           Combo{DepthCompression::Zlib, ColorCompression::Png}),
                         comboName);

// ---- RGB-D corrupt messages ----------------------------------------------------------------

Bytes encodedFrame(DepthCompression depth, ColorCompression color, int w = 16, int h = 12) {
  RgbdEncodeOptions opt;
  opt.depth = depth;
  opt.color = color;
  return encodeMessage(encodeRgbdFrame(makeFrame(w, h), opt));
}

TEST(RgbdCorrupt, TruncatedAtEveryLengthIsAnError) {
  for (auto [depth, color] : {std::pair{DepthCompression::None, ColorCompression::None},
                              std::pair{DepthCompression::Zlib, ColorCompression::Jpeg},
                              std::pair{DepthCompression::Zlib, ColorCompression::Png}}) {
    const Bytes full = encodedFrame(depth, color);
    ASSERT_EQ(outcome([&] { decodeRgbdFrame(full.data(), full.size(), "C"); }), "ok");
    for (std::size_t len = 0; len < full.size(); ++len) {
      const std::string result =
          outcome([&] { decodeRgbdFrame(full.data(), len, "FINDMUG_RGBD"); });
      ASSERT_EQ(result.rfind("error: FINDMUG_RGBD", 0), 0u) << "length " << len << ": " << result;
    }
  }
}

TEST(RgbdCorrupt, TrailingBytesAreAnError) {
  Bytes b = encodedFrame(DepthCompression::Zlib, ColorCompression::Jpeg);
  b.push_back(0);
  expectError([&] { decodeRgbdFrame(b.data(), b.size(), "C"); }, "unexpected bytes");
}

TEST(RgbdCorrupt, FlippedBytesNeverCrash) {
  // Flips anywhere: the result is a valid frame (a flip inside raw pixel data
  // is undetectable) or a findmug::Error — nothing else.
  std::mt19937 rng(1234);
  int errors = 0;
  for (auto [depth, color] : {std::pair{DepthCompression::None, ColorCompression::None},
                              std::pair{DepthCompression::Zlib, ColorCompression::Jpeg},
                              std::pair{DepthCompression::Zlib, ColorCompression::Png}}) {
    const Bytes full = encodedFrame(depth, color);
    for (int trial = 0; trial < 1500; ++trial) {
      Bytes b = full;
      const int flips = 1 + static_cast<int>(rng() % 3);
      for (int k = 0; k < flips; ++k)
        b[rng() % b.size()] ^= static_cast<std::uint8_t>(1 + rng() % 255);
      const std::string result = outcome([&] { decodeRgbdFrame(b.data(), b.size(), "C"); });
      ASSERT_TRUE(result == "ok" || result.rfind("error: ", 0) == 0) << result;
      errors += result != "ok";
    }
  }
  EXPECT_GT(errors, 1500);  // most flips land in checked structure or compressed data
}

TEST(RgbdCorrupt, SizeFieldBeyondTheMessageIsRejectedBeforeAllocating) {
  const Bytes full = encodedFrame(DepthCompression::Zlib, ColorCompression::Jpeg);
  findmug_lcm::rgbd_frame_t msg =
      decodeMessage<findmug_lcm::rgbd_frame_t>(full.data(), full.size(), "C");
  const RgbdOffsets o = rgbdOffsets(msg);
  for (std::int32_t bad : {0x7fffffff, 2000000000, static_cast<std::int32_t>(full.size())}) {
    Bytes b = full;
    putBe32(b, o.depth_size, bad);
    expectError([&] { decodeRgbdFrame(b.data(), b.size(), "FINDMUG_RGBD"); },
                "FINDMUG_RGBD: rgbd_frame_t.depth_size");
    b = full;
    putBe32(b, o.color_size, bad);
    expectError([&] { decodeRgbdFrame(b.data(), b.size(), "FINDMUG_RGBD"); }, "color_size");
  }
  Bytes b = full;
  putBe32(b, o.depth_size, -5);
  expectError([&] { decodeRgbdFrame(b.data(), b.size(), "C"); }, "negative count -5");
  b = full;
  putBe32(b, o.source_len, 0);
  expectError([&] { decodeRgbdFrame(b.data(), b.size(), "C"); }, "rgbd_frame_t.source");
  b = full;
  putBe32(b, o.source_len, -1);
  expectError([&] { decodeRgbdFrame(b.data(), b.size(), "C"); }, "rgbd_frame_t.source");
  b = full;
  putBe32(b, o.source_len, 1 << 30);
  expectError([&] { decodeRgbdFrame(b.data(), b.size(), "C"); }, "rgbd_frame_t.source");
}

TEST(RgbdCorrupt, AbsurdOrMismatchedDimensions) {
  const Bytes full = encodedFrame(DepthCompression::None, ColorCompression::None);
  const RgbdOffsets o =
      rgbdOffsets(decodeMessage<findmug_lcm::rgbd_frame_t>(full.data(), full.size(), "C"));
  for (std::int32_t w : {0, -16, 100000, 1 << 30}) {
    Bytes b = full;
    putBe32(b, o.width, w);
    expectError([&] { decodeRgbdFrame(b.data(), b.size(), "FINDMUG_RGBD"); }, "absurd image size");
  }
  // Plausible but wrong: the raw depth no longer matches width*height.
  Bytes b = full;
  putBe32(b, o.width, 15);
  expectError([&] { decodeRgbdFrame(b.data(), b.size(), "FINDMUG_RGBD"); },
              "rgbd_frame_t.depth_data");
  // Same with zlib and JPEG: inflated size and JPEG size disagree.
  const Bytes zj = encodedFrame(DepthCompression::Zlib, ColorCompression::Jpeg);
  const RgbdOffsets oz =
      rgbdOffsets(decodeMessage<findmug_lcm::rgbd_frame_t>(zj.data(), zj.size(), "C"));
  b = zj;
  putBe32(b, oz.height, 11);
  expectError([&] { decodeRgbdFrame(b.data(), b.size(), "C"); }, "inflates to more than");
  b = zj;
  putBe32(b, oz.height, 13);
  expectError([&] { decodeRgbdFrame(b.data(), b.size(), "C"); }, "zlib stream inflates to 384");
}

TEST(RgbdCorrupt, UnknownCompressionIds) {
  const Bytes full = encodedFrame(DepthCompression::Zlib, ColorCompression::Jpeg);
  const RgbdOffsets o =
      rgbdOffsets(decodeMessage<findmug_lcm::rgbd_frame_t>(full.data(), full.size(), "C"));
  Bytes b = full;
  b[o.depth_compression] = 7;
  expectError([&] { decodeRgbdFrame(b.data(), b.size(), "C"); },
              "depth_compression: unknown compression id 7");
  b = full;
  b[o.color_compression] = 0xff;
  expectError([&] { decodeRgbdFrame(b.data(), b.size(), "C"); },
              "color_compression: unknown compression id -1");
}

TEST(RgbdCorrupt, BadZlibStreams) {
  RgbdFrame f = makeFrame(16, 12);
  findmug_lcm::rgbd_frame_t msg =
      encodeRgbdFrame(f, {DepthCompression::Zlib, ColorCompression::None});
  // Garbage instead of a zlib stream.
  findmug_lcm::rgbd_frame_t bad = msg;
  bad.depth_data.assign(40, 0x5a);
  bad.depth_size = 40;
  expectError([&] { decodeRgbdFrame(bad, "C"); }, "corrupt zlib stream");
  // A damaged body (adler32 catches what inflate does not).
  bad = msg;
  bad.depth_data[bad.depth_data.size() / 2] ^= 0x10;
  expectError([&] { decodeRgbdFrame(bad, "C"); }, "depth_data");
  // A stream cut short.
  bad = msg;
  bad.depth_data.resize(bad.depth_data.size() - 6);
  bad.depth_size = static_cast<std::int32_t>(bad.depth_data.size());
  expectError([&] { decodeRgbdFrame(bad, "C"); }, "zlib");
  // Bytes after the end of a complete stream.
  bad = msg;
  bad.depth_data.push_back(0);
  bad.depth_size += 1;
  expectError([&] { decodeRgbdFrame(bad, "C"); }, "after the end of the zlib stream");
  // Size field and array disagree in an in-memory message.
  bad = msg;
  bad.depth_size += 3;
  expectError([&] { decodeRgbdFrame(bad, "C"); }, "depth_size: size field says");
}

TEST(RgbdCorrupt, BadJpegAndPng) {
  const RgbdFrame f = makeFrame(32, 24);
  const findmug_lcm::rgbd_frame_t jpeg =
      encodeRgbdFrame(f, {DepthCompression::None, ColorCompression::Jpeg});
  findmug_lcm::rgbd_frame_t bad = jpeg;
  bad.color_data.resize(bad.color_data.size() / 2);  // truncated: libjpeg would grey-fill
  bad.color_size = static_cast<std::int32_t>(bad.color_data.size());
  expectError([&] { decodeRgbdFrame(bad, "FINDMUG_RGBD"); }, "rgbd_frame_t.color_data: bad JPEG");
  bad = jpeg;
  bad.color_data.assign(100, 0x11);
  bad.color_size = 100;
  expectError([&] { decodeRgbdFrame(bad, "C"); }, "bad JPEG");
  bad = jpeg;
  bad.color_data.clear();
  bad.color_size = 0;
  expectError([&] { decodeRgbdFrame(bad, "C"); }, "empty JPEG");
  // A valid JPEG of another size.
  bad = jpeg;
  bad.color_data =
      encodeRgbdFrame(makeFrame(16, 24), {DepthCompression::None, ColorCompression::Jpeg})
          .color_data;
  bad.color_size = static_cast<std::int32_t>(bad.color_data.size());
  expectError([&] { decodeRgbdFrame(bad, "C"); }, "JPEG is 16x24, message says 32x24");

  const findmug_lcm::rgbd_frame_t png =
      encodeRgbdFrame(f, {DepthCompression::None, ColorCompression::Png});
  bad = png;
  bad.color_data.resize(bad.color_data.size() - 20);
  bad.color_size = static_cast<std::int32_t>(bad.color_data.size());
  EXPECT_THROW(decodeRgbdFrame(bad, "C"), Error);
  bad = png;
  bad.color_data =
      encodeRgbdFrame(makeFrame(32, 12), {DepthCompression::None, ColorCompression::Png})
          .color_data;
  bad.color_size = static_cast<std::int32_t>(bad.color_data.size());
  expectError([&] { decodeRgbdFrame(bad, "C"); }, "PNG is 32x12");
}

TEST(RgbdCorrupt, BadValuesAreRejected) {
  findmug_lcm::rgbd_frame_t msg = encodeRgbdFrame(makeFrame(16, 12));
  findmug_lcm::rgbd_frame_t bad = msg;
  bad.fx = std::nan("");
  expectError([&] { decodeRgbdFrame(bad, "FINDMUG_RGBD"); }, "intrinsics");
  bad = msg;
  bad.fy = -3;
  expectError([&] { decodeRgbdFrame(bad, "FINDMUG_RGBD"); }, "intrinsics");
  bad = msg;
  bad.height_m = 40.0;
  expectError([&] { decodeRgbdFrame(bad, "FINDMUG_RGBD"); }, "extrinsics");
  bad = msg;
  bad.utime = -1;
  expectError([&] { decodeRgbdFrame(bad, "FINDMUG_RGBD"); }, "utime");
}

TEST(RgbdCorrupt, OtherMessageTypeIsRejectedByHash) {
  LabelImageMessage labels;
  labels.image.width = 4;
  labels.image.height = 2;
  labels.image.labels.assign(8, 1);
  const Bytes b = encodeMessage(encodeLabelImage(labels));
  expectError([&] { decodeRgbdFrame(b.data(), b.size(), "FINDMUG_RGBD"); },
              "FINDMUG_RGBD: not a findmug_lcm.rgbd_frame_t");
}

// ---- label images ------------------------------------------------------------------------------

LabelImageMessage makeLabels(int w = 20, int h = 10, bool confidence = true) {
  LabelImageMessage m;
  m.utime = 123456789;
  m.seq = 77;
  m.latency_us = 81234;
  m.image.width = w;
  m.image.height = h;
  for (int i = 0; i < w * h; ++i) {
    m.image.labels.push_back(i % 11 == 0 ? kVoidLabel : static_cast<std::uint8_t>(i % kNumLabels));
    if (confidence) m.image.confidence.push_back(i % 11 == 0 ? 0.0f : (i % 101) / 100.0f);
  }
  return m;
}

TEST(LabelCodec, RoundTripWithConfidence) {
  const LabelImageMessage in = makeLabels();
  const findmug_lcm::label_image_t msg = encodeLabelImage(in);
  EXPECT_TRUE(msg.has_confidence);
  EXPECT_EQ(msg.compression, findmug_lcm::label_image_t::COMPRESSION_ZLIB);
  ASSERT_EQ(msg.label_names.size(), static_cast<std::size_t>(kNumLabels));
  EXPECT_EQ(msg.label_names[4], "table");
  const Bytes b = encodeMessage(msg);
  const LabelImageMessage out = decodeLabelImage(b.data(), b.size(), "FINDMUG_LABELS");
  EXPECT_EQ(out.utime, in.utime);
  EXPECT_EQ(out.seq, in.seq);
  EXPECT_EQ(out.latency_us, in.latency_us);
  EXPECT_EQ(out.image.width, 20);
  EXPECT_EQ(out.image.labels, in.image.labels);
  ASSERT_EQ(out.image.confidence.size(), in.image.confidence.size());
  for (std::size_t i = 0; i < in.image.confidence.size(); ++i) {
    EXPECT_NEAR(out.image.confidence[i], in.image.confidence[i], 0.5 / 255 + 1e-6) << i;
  }
}

TEST(LabelCodec, ConfidenceIsQuantisedAsLroundDoes) {
  // Every float c in [0, 1] whose c * 255 lies at or next to a half step
  // (where rounding can go either way), plus a regular sweep: the byte sent
  // is std::lround(c * 255) for each.
  std::vector<float> values;
  for (int k = 0; k <= 255; ++k) {
    for (const float step : {k - 0.5f, static_cast<float>(k), k + 0.5f}) {
      float c = step / 255.0f;
      for (int n = 0; n < 3; ++n) c = std::nextafter(c, 0.0f);
      for (int n = 0; n < 7; ++n, c = std::nextafter(c, 2.0f)) {
        if (c >= 0.0f && c <= 1.0f) values.push_back(c);
      }
    }
  }
  for (int i = 0; i <= 10000; ++i) values.push_back(static_cast<float>(i) / 10000.0f);
  while (values.size() % 64 != 0) values.push_back(1.0f);  // a 64-pixel-wide image
  LabelImageMessage in;
  in.image.width = 64;
  in.image.height = static_cast<int>(values.size() / 64);
  in.image.labels.assign(values.size(), 0);
  in.image.confidence = values;
  const LabelImageMessage out = decodeLabelImage(encodeLabelImage(in), "C");
  ASSERT_EQ(out.image.confidence.size(), values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    // The decoder gives byte / 255.
    ASSERT_EQ(out.image.confidence[i], static_cast<float>(std::lround(values[i] * 255.0f)) / 255.0f)
        << "c = " << values[i];
  }
}

TEST(LabelCodec, RoundTripWithoutConfidence) {
  LabelImageMessage in = makeLabels();
  const findmug_lcm::label_image_t msg = encodeLabelImage(in, /*with_confidence=*/false);
  EXPECT_FALSE(msg.has_confidence);
  EXPECT_EQ(msg.confidence_size, 0);
  const LabelImageMessage out = decodeLabelImage(msg, "C");
  EXPECT_TRUE(out.image.confidence.empty());
  EXPECT_EQ(out.image.labels, in.image.labels);
  // Uncompressed labels are accepted too.
  findmug_lcm::label_image_t raw = msg;
  raw.compression = findmug_lcm::label_image_t::COMPRESSION_NONE;
  raw.labels_data = in.image.labels;
  raw.labels_size = static_cast<std::int32_t>(raw.labels_data.size());
  EXPECT_EQ(decodeLabelImage(raw, "C").image.labels, in.image.labels);
}

// zlib's own inflate (not the libdeflate decoder the codec uses) of a
// compressed label or confidence array: what any client library would see.
Bytes inflateWithZlib(const std::vector<std::uint8_t>& stream, std::size_t size) {
  Bytes out(size + 1);  // one spare byte: a stream that inflates to more fails the size check
  uLongf out_size = static_cast<uLongf>(out.size());
  const int rc = uncompress(out.data(), &out_size, stream.data(), static_cast<uLong>(stream.size()));
  EXPECT_EQ(rc, Z_OK);
  out.resize(out_size);
  return out;
}

// The encoder's own deflate (fixed codes, runs as distance-1 matches, stored
// blocks for data without runs) must give streams that zlib itself inflates
// to the same bytes, for every byte value (the 8- and 9-bit literal codes,
// through the confidence), every run length up to past two maximal matches
// (how a run is split into matches), and data without runs.
TEST(LabelCodec, StreamsInflateWithZlibItself) {
  const auto check = [](const LabelImageMessage& in, const std::string& what) {
    const findmug_lcm::label_image_t msg = encodeLabelImage(in);
    const std::size_t pixels = in.image.labels.size();
    EXPECT_EQ(inflateWithZlib(msg.labels_data, pixels), in.image.labels) << what;
    Bytes quantised;
    for (const float c : in.image.confidence) {
      quantised.push_back(static_cast<std::uint8_t>(std::lround(c * 255.0f)));
    }
    EXPECT_EQ(inflateWithZlib(msg.confidence_data, pixels), quantised) << what;
    return msg;
  };
  // Runs of every length 1..600 (labels) and of every confidence byte value.
  LabelImageMessage runs;
  for (int length = 1; length <= 600; ++length) {
    for (int k = 0; k < length; ++k) {
      runs.image.labels.push_back(length % 3 == 0 ? kVoidLabel : static_cast<std::uint8_t>(length % 8));
      runs.image.confidence.push_back(static_cast<float>((length * 7) % 256) / 255.0f);
    }
  }
  while (runs.image.labels.size() % 600 != 0) {
    runs.image.labels.push_back(1);
    runs.image.confidence.push_back(1.0f);
  }
  runs.image.width = 600;
  runs.image.height = static_cast<int>(runs.image.labels.size() / 600);
  const auto runs_msg = check(runs, "runs of 1..600");
  // 180,300 bytes in 600 runs: a few bytes per run, far below the data.
  EXPECT_LT(runs_msg.labels_data.size(), 8000u);

  // No runs at all: random confidence bytes go into stored blocks (several
  // of them: 640 x 480 is more than one 64 KiB block), never much larger.
  LabelImageMessage noise;
  noise.image.width = 640;
  noise.image.height = 480;
  std::mt19937 rng(11);
  for (int i = 0; i < 640 * 480; ++i) {
    noise.image.labels.push_back(static_cast<std::uint8_t>(rng() % kNumLabels));
    noise.image.confidence.push_back(static_cast<float>(rng() % 256) / 255.0f);
  }
  const auto noise_msg = check(noise, "noise");
  EXPECT_LE(noise_msg.confidence_data.size(), 640u * 480u + 5u * 5u + 6u);

  // Byte counts that follow the Fibonacci numbers (1, 1, 2, 3, 5, ... for 24
  // values, shuffled): their Huffman code is 23 bits deep, beyond deflate's
  // 15, so the encoder must limit the code lengths.
  LabelImageMessage skewed;
  {
    std::vector<std::uint8_t> bytes;
    std::uint32_t a = 1, b = 1;
    for (int value = 0; value < 24; ++value) {
      bytes.insert(bytes.end(), a, static_cast<std::uint8_t>(value * 10));
      const std::uint32_t next = a + b;
      a = b;
      b = next;
    }
    std::shuffle(bytes.begin(), bytes.end(), rng);
    while (bytes.size() % 640 != 0) bytes.push_back(0);
    skewed.image.width = 640;
    skewed.image.height = static_cast<int>(bytes.size() / 640);
    skewed.image.labels.assign(bytes.size(), 3);
    for (const std::uint8_t q : bytes) skewed.image.confidence.push_back(q / 255.0f);
  }
  const auto skewed_msg = check(skewed, "Fibonacci counts");
  EXPECT_LT(skewed_msg.confidence_data.size(), skewed.image.labels.size() / 2);

  // One value everywhere, and a single pixel.
  LabelImageMessage flat;
  flat.image.width = 640;
  flat.image.height = 480;
  flat.image.labels.assign(640 * 480, 4);
  flat.image.confidence.assign(640 * 480, 0.5f);
  EXPECT_LT(check(flat, "flat").labels_data.size(), 1000u);
  check(makeLabels(1, 1), "one pixel");
}

// A real label image (NYU frame 0's ground truth, void included) comes out
// no larger than zlib's own run-length deflate made it (level 1, Z_RLE: the
// encoder before its own deflate), give or take a few per cent.
TEST(LabelCodec, RealLabelImageIsAsSmallAsZlibRle) {
  FINDMUG_REQUIRE_DATA(dir, "nyuv2_labeled");
  LabelImageMessage in;
  const auto frame = DatasetFolder(dir.string()).load(0);
  in.image.width = 640;
  in.image.height = 480;
  in.image.labels = frame.labels;
  ASSERT_EQ(in.image.labels.size(), 640u * 480u);
  const findmug_lcm::label_image_t msg = encodeLabelImage(in, /*with_confidence=*/false);
  EXPECT_EQ(inflateWithZlib(msg.labels_data, in.image.labels.size()), in.image.labels);
  z_stream zs{};
  ASSERT_EQ(deflateInit2(&zs, 1, Z_DEFLATED, 15, 8, Z_RLE), Z_OK);
  Bytes rle(deflateBound(&zs, 640 * 480));
  zs.next_in = in.image.labels.data();
  zs.avail_in = 640 * 480;
  zs.next_out = rle.data();
  zs.avail_out = static_cast<uInt>(rle.size());
  ASSERT_EQ(deflate(&zs, Z_FINISH), Z_STREAM_END);
  const std::size_t rle_size = zs.total_out;
  deflateEnd(&zs);
  EXPECT_LE(msg.labels_data.size(), rle_size * 105 / 100) << "zlib Z_RLE: " << rle_size;
  std::printf("label image of NYU frame 0: %zu bytes (zlib level 1 Z_RLE: %zu)\n",
              msg.labels_data.size(), rle_size);
}

TEST(LabelCodec, EncoderRefusesBadInput) {
  LabelImageMessage m = makeLabels();
  m.image.labels[3] = 9;
  expectError([&] { encodeLabelImage(m); }, "label id 9");
  m = makeLabels();
  m.image.confidence[5] = 1.5f;
  expectError([&] { encodeLabelImage(m); }, "confidence");
  // The message names the first bad pixel, in the sixteen-wide part of the
  // check and in its tail (200 pixels: 192 + 8), NaN included.
  m = makeLabels();
  m.image.labels[150] = 200;
  m.image.labels[170] = 9;
  expectError([&] { encodeLabelImage(m); }, "pixel 150 has label id 200");
  m = makeLabels();
  m.image.confidence[37] = -0.25f;
  m.image.confidence[90] = std::numeric_limits<float>::quiet_NaN();
  expectError([&] { encodeLabelImage(m); }, "pixel 37 confidence");
  m = makeLabels();
  m.image.confidence[197] = std::numeric_limits<float>::quiet_NaN();
  expectError([&] { encodeLabelImage(m); }, "pixel 197 confidence");
  m = makeLabels();
  m.image.labels.pop_back();
  EXPECT_THROW(encodeLabelImage(m), Error);
}

TEST(LabelCorrupt, EveryClass) {
  const LabelImageMessage in = makeLabels();
  const findmug_lcm::label_image_t good = encodeLabelImage(in);
  const Bytes full = encodeMessage(good);
  for (std::size_t len = 0; len < full.size(); ++len) {
    const std::string r = outcome([&] { decodeLabelImage(full.data(), len, "FINDMUG_LABELS"); });
    ASSERT_EQ(r.rfind("error: FINDMUG_LABELS", 0), 0u) << len << ": " << r;
  }
  std::mt19937 rng(99);
  for (int trial = 0; trial < 2000; ++trial) {
    Bytes b = full;
    b[rng() % b.size()] ^= static_cast<std::uint8_t>(1 + rng() % 255);
    const std::string r = outcome([&] { decodeLabelImage(b.data(), b.size(), "C"); });
    ASSERT_TRUE(r == "ok" || r.rfind("error: ", 0) == 0) << r;
  }
  findmug_lcm::label_image_t bad = good;
  bad.label_names[4] = "desk";
  expectError([&] { decodeLabelImage(bad, "C"); }, "id 4 is 'desk', expected 'table'");
  bad = good;
  bad.num_labels = 7;
  bad.label_names.pop_back();
  expectError([&] { decodeLabelImage(bad, "C"); }, "num_labels");
  bad = good;
  bad.width = 5000;
  expectError([&] { decodeLabelImage(bad, "C"); }, "absurd image size");
  bad = good;
  bad.width = 19;
  expectError([&] { decodeLabelImage(bad, "C"); }, "labels_data");
  bad = good;
  bad.compression = 3;
  expectError([&] { decodeLabelImage(bad, "C"); }, "unknown compression id 3");
  bad = good;
  bad.has_confidence = false;
  expectError([&] { decodeLabelImage(bad, "C"); }, "has_confidence is false");
  bad = good;
  bad.confidence_data.assign(30, 0x78);
  bad.confidence_size = 30;
  expectError([&] { decodeLabelImage(bad, "C"); }, "confidence_data");
  bad = good;
  bad.latency_us = -4;
  expectError([&] { decodeLabelImage(bad, "C"); }, "latency_us");
  // An id outside the label set inside a valid zlib stream.
  bad = good;
  std::vector<std::uint8_t> labels = in.image.labels;
  labels[17] = 42;
  bad.compression = findmug_lcm::label_image_t::COMPRESSION_NONE;
  bad.labels_data = labels;
  bad.labels_size = static_cast<std::int32_t>(labels.size());
  bad.has_confidence = false;
  bad.confidence_data.clear();
  bad.confidence_size = 0;
  expectError([&] { decodeLabelImage(bad, "C"); }, "pixel 17 has label id 42");
}

// The camera the daemon used and its colour image (label_image_t's camera and colour
// fields, added for findmug-web): round trip, absent by default, every bad value refused.
TEST(LabelCodec, CameraAndColourRoundTrip) {
  LabelImageMessage in = makeLabels();
  {
    const Bytes plain = encodeMessage(encodeLabelImage(in));
    const LabelImageMessage out = decodeLabelImage(plain.data(), plain.size(), "FINDMUG_LABELS");
    EXPECT_FALSE(out.camera.has_value());
    EXPECT_TRUE(out.color_jpeg.empty());
    EXPECT_TRUE(decodeLabelImageColor(out, "FINDMUG_LABELS").empty());
  }
  CameraView camera;
  camera.intrinsics = CameraIntrinsics{518.9, 519.5, 325.6, 253.7};
  camera.camera_to_base.linear() =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, -0.5, 0.8).normalized()).toRotationMatrix();
  camera.camera_to_base.translation() = Eigen::Vector3d(0.05, -0.02, 1.31);
  findmug_lcm::label_image_t msg = encodeLabelImage(in);
  setCameraView(msg, camera.intrinsics, camera.camera_to_base);
  std::vector<Rgb8> rgb(static_cast<std::size_t>(in.image.width) * in.image.height);
  const auto width = static_cast<std::size_t>(in.image.width);
  for (std::size_t i = 0; i < rgb.size(); ++i) {  // a smooth gradient, as camera images are
    rgb[i] = Rgb8{static_cast<std::uint8_t>(40 + 8 * (i % width)),
                  static_cast<std::uint8_t>(60 + 10 * (i / width)), 128};
  }
  setColorJpeg(msg, rgb, 95);
  EXPECT_EQ(msg.color_format, findmug_lcm::label_image_t::COLOR_JPEG);
  const Bytes b = encodeMessage(msg);
  const LabelImageMessage out = decodeLabelImage(b.data(), b.size(), "FINDMUG_LABELS");
  ASSERT_TRUE(out.camera.has_value());
  EXPECT_EQ(out.camera->intrinsics.fy, 519.5);
  EXPECT_TRUE(out.camera->camera_to_base.isApprox(camera.camera_to_base, 1e-15));
  EXPECT_EQ(out.image.labels, in.image.labels);
  const std::vector<Rgb8> decoded = decodeLabelImageColor(out, "FINDMUG_LABELS");
  ASSERT_EQ(decoded.size(), rgb.size());
  int worst = 0;
  for (std::size_t i = 0; i < rgb.size(); ++i) {
    worst = std::max({worst, std::abs(decoded[i].r - rgb[i].r), std::abs(decoded[i].g - rgb[i].g),
                      std::abs(decoded[i].b - rgb[i].b)});
  }
  EXPECT_LT(worst, 24);  // JPEG at quality 95 on a small gradient
  // Re-encoding the decoded message keeps both.
  const Bytes again = encodeMessage(encodeLabelImage(out));
  EXPECT_EQ(again, b);

  findmug_lcm::label_image_t bad = msg;
  bad.fx = 0;
  expectError([&] { decodeLabelImage(bad, "C"); }, "fx/fy");
  bad = msg;
  bad.cy = std::numeric_limits<double>::quiet_NaN();
  expectError([&] { decodeLabelImage(bad, "C"); }, "cx/cy");
  bad = msg;
  bad.camera_to_base[1][3] = std::numeric_limits<double>::infinity();
  expectError([&] { decodeLabelImage(bad, "C"); }, "element [1][3] is not finite");
  bad = msg;
  bad.camera_to_base[0][0] *= 2;
  expectError([&] { decodeLabelImage(bad, "C"); }, "not a rotation");
  bad = msg;
  for (int i = 0; i < 3; ++i) bad.camera_to_base[i][0] = -bad.camera_to_base[i][0];  // a mirror
  expectError([&] { decodeLabelImage(bad, "C"); }, "not a rotation");
  bad = msg;
  bad.color_format = 7;
  expectError([&] { decodeLabelImage(bad, "C"); }, "unknown colour format id 7");
  bad = msg;
  bad.color_format = findmug_lcm::label_image_t::COLOR_ABSENT;
  expectError([&] { decodeLabelImage(bad, "C"); }, "color_format is COLOR_ABSENT");
  bad = msg;
  bad.color_data[0] = 0;
  expectError([&] { decodeLabelImage(bad, "C"); }, "not a JPEG");
  bad = msg;
  bad.color_size += 1;
  expectError([&] { decodeLabelImage(bad, "C"); }, "color_size");
  // Markers right, content broken: the message decodes, the full decode refuses it.
  bad = msg;
  std::fill(bad.color_data.begin() + 2, bad.color_data.end() - 2, 0x11);
  const LabelImageMessage broken = decodeLabelImage(bad, "C");
  expectError([&] { (void)decodeLabelImageColor(broken, "FINDMUG_LABELS"); },
              "FINDMUG_LABELS label_image_t.color_data");
  EXPECT_THROW(setColorJpeg(msg, std::vector<Rgb8>(3), 80), Error);
  EXPECT_THROW(setColorJpeg(msg, rgb, 0), Error);
}

// ---- tables
// --------------------------------------------------------------------------------------

TablesMessage makeTables() {
  TablesMessage m;
  m.utime = 5550001;
  m.seq = 9;
  TableCluster t;
  t.id = 0;
  t.centroid = {1.5f, 0.25f, 0.74f};
  t.top_height = 0.75f;
  t.major_axis = Eigen::Vector2f(0.6f, 0.8f);
  t.minor_axis = Eigen::Vector2f(-0.8f, 0.6f);
  t.extents = {0.6f, 0.4f};
  t.hull = {{1.0f, 0.0f}, {2.0f, 0.0f}, {2.0f, 0.5f}, {1.0f, 0.5f}};
  t.point_count = 4321;
  t.mean_confidence = 0.8125f;
  SearchPosition a;
  a.xy = {0.5f, 0.25f};
  a.yaw = 0.0f;
  SearchPosition b;
  b.xy = {2.5f, 0.25f};
  b.yaw = static_cast<float>(M_PI);
  b.reachable = false;
  b.reason = "obstacle within robot radius";
  t.search_positions = {a, b};
  m.tables.push_back(t);
  TableCluster t2 = t;
  t2.id = 1;
  t2.hull.clear();
  t2.search_positions.clear();
  m.tables.push_back(t2);
  return m;
}

TEST(TablesCodec, RoundTripInBaseFrame) {
  const TablesMessage in = makeTables();
  const Bytes b = encodeMessage(encodeTables(in));
  const TablesMessage out = decodeTables(b.data(), b.size(), "FINDMUG_TABLES");
  EXPECT_EQ(out.utime, in.utime);
  EXPECT_EQ(out.seq, in.seq);
  EXPECT_FALSE(out.map_pose.has_value());
  EXPECT_TRUE(out.map_tables.empty());
  ASSERT_EQ(out.tables.size(), 2u);
  const TableCluster& t = out.tables[0];
  EXPECT_EQ(t.centroid, in.tables[0].centroid);
  EXPECT_EQ(t.top_height, 0.75f);
  EXPECT_EQ(t.major_axis, in.tables[0].major_axis);
  EXPECT_EQ(t.minor_axis, in.tables[0].minor_axis);
  EXPECT_EQ(t.extents, in.tables[0].extents);
  EXPECT_EQ(t.hull, in.tables[0].hull);
  EXPECT_EQ(t.point_count, 4321);
  EXPECT_EQ(t.mean_confidence, 0.8125f);
  ASSERT_EQ(t.search_positions.size(), 2u);
  EXPECT_EQ(t.search_positions[1].xy, in.tables[0].search_positions[1].xy);
  EXPECT_FALSE(t.search_positions[1].reachable);
  EXPECT_EQ(t.search_positions[1].reason, "obstacle within robot radius");
  EXPECT_EQ(out.tables[1].id, 1);
  EXPECT_TRUE(out.tables[1].hull.empty());
}

TEST(TablesCodec, MapFrameCopiesFollowThePose) {
  TablesMessage in = makeTables();
  in.map_pose = RobotPose{777, {10.0, -2.0, M_PI / 2}};  // robot at (10,-2) facing map +y
  const Bytes b = encodeMessage(encodeTables(in));
  const TablesMessage out = decodeTables(b.data(), b.size(), "C");
  ASSERT_TRUE(out.map_pose.has_value());
  EXPECT_EQ(out.map_pose->utime, 777u);
  ASSERT_EQ(out.map_tables.size(), 2u);
  const MapFrameTable& m = out.map_tables[0];
  // Base (x forward, y left) rotated by +90 deg: (x, y) -> (-y, x), then shifted.
  EXPECT_NEAR(m.centroid.x(), 10.0 - 0.25, 1e-6);
  EXPECT_NEAR(m.centroid.y(), -2.0 + 1.5, 1e-6);
  EXPECT_NEAR(m.centroid.z(), 0.74, 1e-6);
  ASSERT_EQ(m.hull.size(), 4u);
  EXPECT_NEAR(m.hull[1].x(), 10.0, 1e-6);
  EXPECT_NEAR(m.hull[1].y(), 0.0, 1e-6);
  ASSERT_EQ(m.search_positions.size(), 2u);
  EXPECT_NEAR(m.search_positions[0].yaw, M_PI / 2, 1e-6);
  // pi + pi/2 wraps to -pi/2.
  EXPECT_NEAR(m.search_positions[1].yaw, -M_PI / 2, 1e-6);
  EXPECT_FALSE(m.search_positions[1].reachable);
  // Base-frame fields are untouched by the pose.
  EXPECT_EQ(out.tables[0].centroid, in.tables[0].centroid);
}

// The table map's additions: box centres, map entries (stable id,
// confirmation, sightings, viewpoints) and the content id survive the round trip; the
// map-frame centre follows the pose like the centroid.
TEST(TablesCodec, MapEntriesCentresAndContentRoundTrip) {
  TablesMessage in = makeTables();
  in.tables[0].center = Eigen::Vector2f(1.55f, 0.2f);
  in.map_info = {{7, true, 4, 3}, {0, false, 0, 0}};
  Bytes b = encodeMessage(encodeTables(in));
  TablesMessage out = decodeTables(b.data(), b.size(), "C");
  EXPECT_EQ(out.content, TablesContent::Frame);
  EXPECT_EQ(out.tables[0].center, in.tables[0].center);
  ASSERT_EQ(out.map_info.size(), 2u);
  EXPECT_EQ(out.map_info[0].map_id, 7);
  EXPECT_TRUE(out.map_info[0].confirmed);
  EXPECT_EQ(out.map_info[0].sightings, 4);
  EXPECT_EQ(out.map_info[0].viewpoints, 3);
  EXPECT_EQ(out.map_info[1].map_id, 0);
  EXPECT_FALSE(out.map_info[1].confirmed);

  // No map entries given: every table decodes as "not in the map".
  in.map_info.clear();
  b = encodeMessage(encodeTables(in));
  out = decodeTables(b.data(), b.size(), "C");
  ASSERT_EQ(out.map_info.size(), 2u);
  EXPECT_EQ(out.map_info[0].map_id, 0);
  EXPECT_EQ(out.map_info[0].sightings, 0);

  // A table map message: ids are the stable ids, the pose is mandatory.
  TablesMessage map = makeTables();
  map.content = TablesContent::Map;
  map.map_pose = RobotPose{9, {10.0, -2.0, M_PI / 2}};
  map.tables[0].id = 3;
  map.tables[0].center = Eigen::Vector2f(1.5f, 0.25f);
  map.tables[1].id = 5;
  map.map_info = {{3, true, 3, 0}, {5, true, 12, 0}};
  b = encodeMessage(encodeTables(map));
  out = decodeTables(b.data(), b.size(), "FINDMUG_TABLE_MAP");
  EXPECT_EQ(out.content, TablesContent::Map);
  ASSERT_EQ(out.map_tables.size(), 2u);
  EXPECT_NEAR(out.map_tables[0].center.x(), 10.0 - 0.25, 1e-6);
  EXPECT_NEAR(out.map_tables[0].center.y(), -2.0 + 1.5, 1e-6);
  EXPECT_EQ(out.tables[1].id, 5);
  EXPECT_EQ(out.map_info[1].sightings, 12);

  TablesMessage wrong = map;
  wrong.map_pose.reset();
  EXPECT_THROW(encodeTables(wrong), Error);
  wrong = map;
  wrong.map_info[1].map_id = 6;  // id 5 != map_id 6
  EXPECT_THROW(encodeTables(wrong), Error);
  wrong = makeTables();
  wrong.map_info = {{1, false, 1, 0}};  // one entry for two tables
  EXPECT_THROW(encodeTables(wrong), Error);
}

TEST(TablesCorrupt, BadMapEntriesAndContentAreNamed) {
  TablesMessage in = makeTables();
  in.map_pose = RobotPose{1, {1.0, 2.0, 0.3}};
  in.map_info = {{2, true, 3, 0}, {0, false, 0, 0}};
  const findmug_lcm::tables_t good = encodeTables(in);
  findmug_lcm::tables_t bad = good;
  bad.content = 7;
  expectError([&] { decodeTables(bad, "C"); }, "tables_t.content: unknown content id 7");
  bad = good;
  bad.content =
      findmug_lcm::tables_t::CONTENT_MAP;  // table 1 has map_id 0, table 0 id 0 != map_id 2
  expectError([&] { decodeTables(bad, "C"); }, "tables[0].map_id");
  bad = good;
  bad.content = findmug_lcm::tables_t::CONTENT_MAP;
  bad.has_map_pose = false;
  expectError([&] { decodeTables(bad, "C"); }, "has_map_pose");
  bad = good;
  bad.tables[1].confirmed = true;  // confirmed, but not in the map
  expectError([&] { decodeTables(bad, "C"); }, "tables[1].confirmed");
  bad = good;
  bad.tables[0].sightings = -1;
  expectError([&] { decodeTables(bad, "C"); }, "tables[0].map_id/sightings");
  bad = good;
  bad.tables[0].viewpoints = 4;  // more viewpoints than its 3 sightings
  expectError([&] { decodeTables(bad, "C"); }, "tables[0].viewpoints: 4 outside [0, sightings 3]");
  bad = good;
  bad.tables[0].viewpoints = -1;
  expectError([&] { decodeTables(bad, "C"); }, "tables[0].viewpoints");
  bad = good;
  bad.tables[0].center[0] = INFINITY;
  expectError([&] { decodeTables(bad, "C"); }, "tables[0].center");
  bad = good;
  bad.tables[1].map_center[1] = std::nan("");
  expectError([&] { decodeTables(bad, "C"); }, "tables[1].map_center");
}

TEST(TablesCorrupt, EveryClass) {
  TablesMessage in = makeTables();
  in.map_pose = RobotPose{1, {1.0, 2.0, 0.3}};
  in.map_info = {{2, true, 3, 0}, {0, false, 0, 0}};
  const findmug_lcm::tables_t good = encodeTables(in);
  const Bytes full = encodeMessage(good);
  for (std::size_t len = 0; len < full.size(); ++len) {
    const std::string r = outcome([&] { decodeTables(full.data(), len, "FINDMUG_TABLES"); });
    ASSERT_EQ(r.rfind("error: FINDMUG_TABLES", 0), 0u) << len << ": " << r;
  }
  std::mt19937 rng(5);
  for (int trial = 0; trial < 3000; ++trial) {
    Bytes b = full;
    b[rng() % b.size()] ^= static_cast<std::uint8_t>(1 + rng() % 255);
    const std::string r = outcome([&] { decodeTables(b.data(), b.size(), "C"); });
    ASSERT_TRUE(r == "ok" || r.rfind("error: ", 0) == 0) << r;
  }
  // num_tables huge: refused by the wire check, not by a failed allocation.
  Bytes b = full;
  putBe32(b, 8 + 8 + 8 + 1 + 32, 0x7fffffff);
  expectError([&] { decodeTables(b.data(), b.size(), "C"); }, "num_tables");
  findmug_lcm::tables_t bad = good;
  bad.tables[0].major_axis[0] = 2.0;
  expectError([&] { decodeTables(bad, "C"); }, "not unit vectors");
  bad = good;
  bad.tables[0].centroid[1] = std::nan("");
  expectError([&] { decodeTables(bad, "C"); }, "tables[0]");
  bad = good;
  bad.tables[0].mean_confidence = 1.5f;
  expectError([&] { decodeTables(bad, "C"); }, "mean_confidence");
  bad = good;
  bad.tables[0].hull_size = 3;
  expectError([&] { decodeTables(bad, "C"); }, "tables[0].hull_size");
  bad = good;
  bad.tables[0].search_positions[0].yaw = INFINITY;
  expectError([&] { decodeTables(bad, "C"); }, "search_positions");
  bad = good;
  bad.map_pose.x = std::nan("");
  expectError([&] { decodeTables(bad, "C"); }, "map_pose");
  bad = good;
  bad.num_tables = 3;
  expectError([&] { decodeTables(bad, "C"); }, "num_tables");
}

// ---- table-top objects ---------------------------------------------------------------------

// Two candidates on the second of makeTables()' two tables, the second cut off.
TableObjectDetection makeObjects() {
  TableObjectDetection d;
  TableObject mug;
  mug.id = 0;
  mug.table = 1;
  mug.centroid = {1.4f, 0.1f, 0.82f};
  mug.height_above_top = 0.11f;
  mug.major_axis = Eigen::Vector2f(0.6f, 0.8f);
  mug.extents = {0.045f, 0.04f};
  mug.center = {1.41f, 0.1f};
  mug.point_count = 140;
  mug.mean_rgb = {190.0f, 35.0f, 30.5f};
  mug.colour_histogram[0] = 0.625f;
  mug.colour_histogram[1] = 0.25f;
  mug.colour_histogram[27] = 0.125f;
  mug.pixels = {10, 11, 12};
  TableObject box = mug;
  box.id = 1;
  box.centroid = {1.8f, -0.2f, 0.9f};
  box.point_count = 90;
  box.truncation = kTruncatedBorder | kTruncatedDepthHole;
  d.objects = {mug, box};
  return d;
}

TEST(ObjectsCodec, RoundTripInBaseFrame) {
  const TablesMessage tables = makeTables();
  const TableObjectDetection in = makeObjects();
  const Bytes b =
      encodeMessage(encodeObjects(5550001, 9, in, tables.tables, std::nullopt, {}));
  const ObjectsMessage out = decodeObjects(b.data(), b.size(), "FINDMUG_OBJECTS");
  EXPECT_EQ(out.utime, 5550001u);
  EXPECT_EQ(out.seq, 9);
  EXPECT_EQ(out.content, TablesContent::Frame);
  EXPECT_EQ(out.num_tables, 2);
  EXPECT_FALSE(out.map_pose.has_value());
  ASSERT_EQ(out.objects.size(), 2u);
  ASSERT_EQ(out.map_info.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    const TableObject& o = out.objects[k];
    const TableObject& want = in.objects[k];
    EXPECT_EQ(o.id, want.id);
    EXPECT_EQ(o.table, 1);
    EXPECT_EQ(o.centroid, want.centroid);
    EXPECT_EQ(o.height_above_top, want.height_above_top);
    EXPECT_EQ(o.major_axis, want.major_axis);
    EXPECT_EQ(o.extents, want.extents);
    EXPECT_EQ(o.center, want.center);
    EXPECT_EQ(o.point_count, want.point_count);
    EXPECT_EQ(o.mean_rgb, want.mean_rgb);
    EXPECT_EQ(o.colour_histogram, want.colour_histogram);
    EXPECT_EQ(o.truncation, want.truncation);
    EXPECT_TRUE(o.pixels.empty());
    EXPECT_EQ(out.map_info[k].table_map_id, 0);
    EXPECT_EQ(out.map_info[k].map_id, 0);
  }
}

// The map-frame centroid goes through the pose exactly as the tables' does, and each
// object names its table's map id.
TEST(ObjectsCodec, MapCentroidFollowsThePoseAsTheTablesDo) {
  TablesMessage tables = makeTables();
  tables.tables[1].centroid = makeObjects().objects[1].centroid;  // the box's place
  tables.map_pose = RobotPose{777, {10.0, -2.0, M_PI / 2}};
  tables.map_info = {{3, true, 4, 0}, {8, false, 1, 0}};
  const Bytes tb = encodeMessage(encodeTables(tables));
  const TablesMessage t = decodeTables(tb.data(), tb.size(), "T");
  const Bytes ob = encodeMessage(encodeObjects(5550001, 9, makeObjects(), tables.tables,
                                               tables.map_pose, tables.map_info));
  const ObjectsMessage o = decodeObjects(ob.data(), ob.size(), "O");
  ASSERT_TRUE(o.map_pose.has_value());
  EXPECT_EQ(o.map_pose->utime, 777u);
  EXPECT_NEAR(o.map_info[0].map_centroid.x(), 10.0 - 0.1, 1e-6);
  EXPECT_NEAR(o.map_info[0].map_centroid.y(), -2.0 + 1.4, 1e-6);
  EXPECT_NEAR(o.map_info[0].map_centroid.z(), 0.82, 1e-6);
  // The box stands where table 1's centroid is: both map to the same point.
  EXPECT_EQ(o.map_info[1].map_centroid, t.map_tables[1].centroid);
  EXPECT_EQ(o.map_info[0].table_map_id, 8);
  EXPECT_EQ(o.objects[0].centroid, makeObjects().objects[0].centroid);  // base frame untouched
}

// "Looked, nothing": a frame with tables and no candidates is a valid, empty message.
TEST(ObjectsCodec, NoCandidatesIsAnEmptyMessage) {
  const Bytes b =
      encodeMessage(encodeObjects(1, 2, TableObjectDetection{}, makeTables().tables, {}, {}));
  const ObjectsMessage out = decodeObjects(b.data(), b.size(), "O");
  EXPECT_EQ(out.num_tables, 2);
  EXPECT_TRUE(out.objects.empty());
}

TEST(ObjectsCodec, EncoderRefusesAnObjectOffTheTables) {
  TableObjectDetection d = makeObjects();
  d.objects[1].table = 2;
  expectError([&] { encodeObjects(1, 2, d, makeTables().tables, {}, {}); }, "table 2 of 2");
  expectError(
      [&] { encodeObjects(1, 2, makeObjects(), makeTables().tables, {}, {{TableMapInfo{}}}); },
      "1 table map entries for 2 tables");
  // What the decoder refuses, the encoder refuses too, naming the field.
  d = makeObjects();
  d.objects[0].colour_histogram[1] = 0.5f;
  expectError([&] { encodeObjects(1, 2, d, makeTables().tables, {}, {}); },
              "encodeObjects: objects_t.objects[0].colour_histogram: sums to 1.25");
  d = makeObjects();
  d.objects[1].point_count = 0;
  expectError([&] { encodeObjects(1, 2, d, makeTables().tables, {}, {}); },
              "objects[1].point_count");
}

TEST(ObjectsCodec, TheSampleMessageDecodes) {
  const findmug_lcm::objects_t sample = test::sampleObjects();
  const Bytes b = encodeMessage(sample);
  const ObjectsMessage out = decodeObjects(b.data(), b.size(), "O");
  ASSERT_EQ(out.objects.size(), 2u);
  EXPECT_EQ(out.objects[1].truncation, kTruncatedBorder | kTruncatedDepthHole);
  EXPECT_EQ(out.map_info[0].table_map_id, 4);
  // The sample's map centroid is the encoder's for its pose.
  const TableObject& o = out.objects[0];
  TableCluster table;
  table.centroid = o.centroid;
  const Bytes tb = encodeMessage(
      encodeTables(1, 2, TablesContent::Frame, std::vector<TableCluster>{table}, out.map_pose, {}));
  const TablesMessage t = decodeTables(tb.data(), tb.size(), "T");
  EXPECT_NEAR((out.map_info[0].map_centroid - t.map_tables[0].centroid).norm(), 0.0, 1e-6);
}

// Every check of decodeObjects, each naming the field.
TEST(ObjectsCorrupt, EveryFieldCheckNamesTheField) {
  const findmug_lcm::objects_t good = test::sampleObjects();
  ASSERT_NO_THROW(decodeObjects(good, "C"));
  struct Case {
    std::function<void(findmug_lcm::objects_t&)> spoil;
    std::string named;
  };
  const std::vector<Case> cases = {
      {[](auto& m) { m.num_objects = 3; }, "objects_t.num_objects: size field says 3"},
      {[](auto& m) { m.utime = -1; }, "objects_t.utime: negative"},
      {[](auto& m) { m.content = 7; }, "objects_t.content: unknown content id 7"},
      {[](auto& m) { m.num_tables = -1; }, "objects_t.num_tables: negative"},
      {[](auto& m) { m.map_pose.yaw = NAN; }, "objects_t.map_pose"},
      {[](auto& m) { m.map_pose.utime = -5; }, "objects_t.map_pose.utime"},
      {[](auto& m) { m.objects[1].id = 0; }, "objects[1].id: 0 appears twice"},
      {[](auto& m) { m.objects[1].id = 2; }, "objects[1].id: 2 outside [0, num_objects 2)"},
      {[](auto& m) { m.objects[1].table_id = 2; },
       "objects[1].table_id: 2 outside [0, num_tables 2)"},
      {[](auto& m) { m.num_tables = 1; }, "objects[1].table_id: 1 outside [0, num_tables 1)"},
      {[](auto& m) { m.objects[0].table_id = -1; }, "objects[0].table_id"},
      {[](auto& m) { m.objects[0].table_map_id = -1; }, "objects[0].table_map_id: negative"},
      {[](auto& m) { m.objects[0].centroid[2] = INFINITY; }, "objects[0].centroid"},
      {[](auto& m) { m.objects[0].map_centroid[0] = NAN; }, "objects[0].map_centroid"},
      {[](auto& m) { m.objects[0].height_above_top = -0.1; }, "objects[0].height_above_top"},
      {[](auto& m) { m.objects[0].height_above_top = NAN; }, "objects[0].height_above_top"},
      {[](auto& m) { m.objects[0].major_axis[0] = 0.7; },
       "objects[0].major_axis: not a unit vector"},
      {[](auto& m) { m.objects[0].major_axis[1] = NAN; }, "objects[0].major_axis"},
      {[](auto& m) { m.objects[0].extents[1] = -0.01; }, "objects[0].extents: negative"},
      {[](auto& m) { m.objects[0].center[0] = NAN; }, "objects[0].center"},
      {[](auto& m) { m.objects[0].point_count = 0; }, "objects[0].point_count"},
      {[](auto& m) { m.objects[0].mean_rgb[2] = 256.0f; }, "objects[0].mean_rgb"},
      {[](auto& m) { m.objects[0].mean_rgb[0] = NAN; }, "objects[0].mean_rgb"},
      {[](auto& m) { m.objects[0].colour_histogram[5] = -0.1f; },
       "objects[0].colour_histogram[5]"},
      {[](auto& m) { m.objects[0].colour_histogram[5] = NAN; }, "objects[0].colour_histogram[5]"},
      {[](auto& m) { m.objects[0].colour_histogram[0] = 0.5f; },
       "objects[0].colour_histogram: sums to 0.875"},
      {[](auto& m) { m.objects[0].truncation = 8; }, "objects[0].truncation: unknown bits"},
      {[](auto& m) { m.objects[0].map_id = 3; }, "must be 0 in a frame message"},
      {[](auto& m) { m.objects[0].sightings = 1; }, "must be 0 in a frame message"},
      {[](auto& m) { m.objects[0].last_seen_utime = 1; }, "must be 0 in a frame message"},
      {[](auto& m) {
         m.content = findmug_lcm::objects_t::CONTENT_MAP;
         m.has_map_pose = false;
       },
       "objects_t.has_map_pose"},
      {[](auto& m) { m.content = findmug_lcm::objects_t::CONTENT_MAP; },
       "objects[0].map_id: an object map entry needs id == map_id > 0"},
  };
  for (const Case& c : cases) {
    findmug_lcm::objects_t bad = good;
    c.spoil(bad);
    expectError([&] { decodeObjects(bad, "C"); }, c.named);
  }
}

// Map content (reserved for an object map): the entries need their stable ids.
TEST(ObjectsCodec, MapContentNeedsMapEntries) {
  findmug_lcm::objects_t m = test::sampleObjects();
  m.content = findmug_lcm::objects_t::CONTENT_MAP;
  for (int k = 0; k < 2; ++k) {
    m.objects[k].id = m.objects[k].map_id = 5 + k;
    m.objects[k].sightings = 3;
    m.objects[k].last_seen_utime = 5550001;
  }
  const Bytes b = encodeMessage(m);
  const ObjectsMessage out = decodeObjects(b.data(), b.size(), "O");
  EXPECT_EQ(out.content, TablesContent::Map);
  EXPECT_EQ(out.map_info[1].map_id, 6);
  EXPECT_EQ(out.map_info[1].sightings, 3);
  EXPECT_EQ(out.map_info[1].last_seen_utime, 5550001u);
  m.objects[1].sightings = 0;
  expectError([&] { decodeObjects(m, "C"); }, "objects[1].sightings/last_seen_utime");
}

// The object map as findmugd publishes it on FINDMUG_OBJECT_MAP: names and scores come
// through; a bad name, a score out of range, a name in a frame message and a table index
// below -1 are refused by field.
TEST(ObjectsCodec, ObjectMapCarriesNamesAndRefusesBadOnes) {
  const findmug_lcm::objects_t good = test::sampleObjectMap();
  const Bytes b = encodeMessage(good);
  const ObjectsMessage out = decodeObjects(b.data(), b.size(), "FINDMUG_OBJECT_MAP");
  ASSERT_EQ(out.objects.size(), 2u);
  EXPECT_EQ(out.map_info[0].name, "mug");
  EXPECT_FLOAT_EQ(out.map_info[0].name_score, 0.8f);
  EXPECT_EQ(out.map_info[1].name, "");
  EXPECT_EQ(out.objects[1].table, -1) << "its table is not among the confirmed ones";
  struct Case {
    std::function<void(findmug_lcm::objects_t&)> spoil;
    std::string named;
  };
  const std::vector<Case> cases = {
      {[](auto& m) { m.objects[0].name = "Red Mug"; }, "objects[0].name: "},
      {[](auto& m) { m.objects[0].name_score = 1.5f; }, "objects[0].name_score"},
      {[](auto& m) { m.objects[0].name_score = NAN; }, "objects[0].name_score"},
      {[](auto& m) { m.objects[1].name_score = 0.5f; }, "objects[1].name_score"},
      {[](auto& m) { m.objects[1].table_id = -2; }, "objects[1].table_id: -2 outside [-1"},
      {[](auto& m) {
         m = test::sampleObjects();
         m.objects[0].name = "mug";
       },
       "objects[0].name/name_score: must be"},
      {[](auto& m) {
         m = test::sampleObjects();
         m.objects[0].table_id = -1;
       },
       "objects[0].table_id: -1 outside [0"},
  };
  for (const Case& c : cases) {
    findmug_lcm::objects_t bad = good;
    c.spoil(bad);
    expectError([&] { decodeObjects(bad, "C"); }, c.named);
  }
}

// encodeObjectMap: map-frame fields from the map, the others relative to the robot, the
// table index among the confirmed tables (-1 when not there), what it makes decodes.
TEST(ObjectsCodec, EncodeObjectMapPlacesObjectsRelativeToTheRobot) {
  MappedObject mug;
  mug.id = 4;
  mug.centroid = {3.0f, 1.0f, 0.8f};
  mug.major_axis = {0.0f, 1.0f};
  mug.extents = {0.05f, 0.04f};
  mug.height_above_top = 0.1f;
  mug.mean_rgb = {200, 30, 30};
  mug.colour_histogram[0] = 0.7f;
  mug.colour_histogram[1] = 0.3001f;  // a running mean: sums to 1 only roughly
  mug.point_count = 300;
  mug.table_id = 7;
  mug.name = "mug";
  mug.name_score = 0.9f;
  mug.sightings = 5;
  mug.last_seen_utime = 900;
  MappedObject other = mug;
  other.id = 5;
  other.table_id = 8;  // tentative: not among the confirmed tables
  other.name = "";
  other.name_score = 0.0f;
  TableCluster seven;
  seven.id = 7;
  const std::vector<MappedObject> objects = {mug, other};
  const std::vector<TableCluster> tables = {seven};
  const RobotPose pose{1000, Pose2D{2.0, 1.0, M_PI / 2}};
  const Bytes b = encodeMessage(encodeObjectMap(1000, 33, objects, tables, pose));
  const ObjectsMessage out = decodeObjects(b.data(), b.size(), "FINDMUG_OBJECT_MAP");
  EXPECT_EQ(out.content, TablesContent::Map);
  EXPECT_EQ(out.seq, 33);
  EXPECT_EQ(out.num_tables, 1);
  ASSERT_EQ(out.objects.size(), 2u);
  EXPECT_EQ(out.objects[0].table, 0);
  EXPECT_EQ(out.objects[1].table, -1);
  EXPECT_EQ(out.map_info[0].table_map_id, 7);
  EXPECT_EQ(out.map_info[1].table_map_id, 8);
  EXPECT_EQ(out.map_info[0].map_id, 4);
  EXPECT_EQ(out.map_info[0].name, "mug");
  EXPECT_NEAR(out.map_info[0].map_centroid.x(), 3.0, 1e-6);
  // 1 m to the right of a robot at (2, 1) facing +y (base frame: x ahead, y to the left).
  EXPECT_NEAR(out.objects[0].centroid.x(), 0.0, 1e-5);
  EXPECT_NEAR(out.objects[0].centroid.y(), -1.0, 1e-5);
  EXPECT_NEAR(out.objects[0].major_axis.x(), 1.0, 1e-5) << "map +y is the robot's +x";
}

TEST(ObjectsCorrupt, EveryClass) {
  const Bytes full = encodeMessage(test::sampleObjects());
  for (std::size_t len = 0; len < full.size(); ++len) {
    const std::string r = outcome([&] { decodeObjects(full.data(), len, "FINDMUG_OBJECTS"); });
    ASSERT_EQ(r.rfind("error: FINDMUG_OBJECTS", 0), 0u) << len << ": " << r;
  }
  std::mt19937 rng(6);
  std::size_t refused = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    Bytes b = full;
    b[rng() % b.size()] ^= static_cast<std::uint8_t>(1 + rng() % 255);
    const std::string r = outcome([&] { decodeObjects(b.data(), b.size(), "C"); });
    ASSERT_TRUE(r == "ok" || r.rfind("error: ", 0) == 0) << r;
    refused += r != "ok";
  }
  EXPECT_GT(refused, 100u);  // the checks do refuse flipped bytes
  // num_objects huge: refused by the wire check, not by a failed allocation.
  Bytes b = full;
  putBe32(b, 8 + 8 + 8 + 1 + 4 + 1 + 32, 0x7fffffff);
  expectError([&] { decodeObjects(b.data(), b.size(), "C"); }, "objects_t.num_objects");
  // Another type's bytes: refused by the type hash.
  const Bytes tables = encodeMessage(encodeTables(makeTables()));
  expectError([&] { decodeObjects(tables.data(), tables.size(), "C"); },
              "not a findmug_lcm.objects_t");
}

// ---- status and robot pose -----------------------------------------------------------------

TEST(StatusAndPose, SourceStateValuesMatchStatusConstants) {
  EXPECT_EQ(static_cast<int>(SourceState::Starting), findmug_lcm::status_t::SOURCE_STARTING);
  EXPECT_EQ(static_cast<int>(SourceState::Running), findmug_lcm::status_t::SOURCE_RUNNING);
  EXPECT_EQ(static_cast<int>(SourceState::Reconnecting),
            findmug_lcm::status_t::SOURCE_RECONNECTING);
  EXPECT_EQ(static_cast<int>(SourceState::EndOfStream),
            findmug_lcm::status_t::SOURCE_END_OF_STREAM);
  EXPECT_EQ(static_cast<int>(SourceState::Stopped), findmug_lcm::status_t::SOURCE_STOPPED);
  EXPECT_EQ(static_cast<int>(SourceState::Failed), findmug_lcm::status_t::SOURCE_FAILED);
  EXPECT_EQ(sourceStateName(SourceState::Reconnecting), "reconnecting");
}

TEST(StatusAndPose, RoundTripAndTruncation) {
  const findmug_lcm::status_t s = findmug::test::sampleStatus();
  const Bytes b = encodeMessage(s);
  const findmug_lcm::status_t out =
      decodeMessage<findmug_lcm::status_t>(b.data(), b.size(), "FINDMUG_STATUS");
  EXPECT_EQ(out.stage_names, s.stage_names);
  EXPECT_EQ(out.latency_p95_us, s.latency_p95_us);
  EXPECT_EQ(out.queue_capacities, s.queue_capacities);
  EXPECT_EQ(out.model_id, "forest.fmf");
  EXPECT_EQ(out.source_state, findmug_lcm::status_t::SOURCE_RUNNING);
  for (std::size_t len = 0; len < b.size(); ++len) {
    EXPECT_THROW(decodeMessage<findmug_lcm::status_t>(b.data(), len, "C"), Error) << len;
  }
  Bytes huge = b;
  // num_stages sits after hash, 6 int64, a double and two floats.
  putBe32(huge, 8 + 6 * 8 + 8 + 8, 0x40000000);
  expectError([&] { decodeMessage<findmug_lcm::status_t>(huge.data(), huge.size(), "C"); },
              "num_stages");

  const Bytes p = encodeMessage(encodeRobotPose(RobotPose{5, {1.0, 2.0, -0.5}}));
  const RobotPose pose = decodeRobotPose(p.data(), p.size(), "FINDMUG_ROBOT_POSE");
  EXPECT_EQ(pose.utime, 5u);
  EXPECT_EQ(pose.pose.yaw, -0.5);
  for (std::size_t len = 0; len < p.size(); ++len) {
    EXPECT_THROW(decodeRobotPose(p.data(), len, "C"), Error) << len;
  }
  findmug_lcm::robot_pose_t nan_pose = encodeRobotPose(RobotPose{5, {std::nan(""), 0, 0}});
  const Bytes n = encodeMessage(nan_pose);
  expectError([&] { decodeRobotPose(n.data(), n.size(), "C"); }, "x/y/yaw");
}

}  // namespace
}  // namespace findmug::io
