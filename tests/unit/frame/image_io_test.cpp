// Tests for findmug/frame/image_io.hpp: round trips, on-disk byte order, format
// checks with useful messages, corrupt input, and the real NYU PNGs.
#include "findmug/frame/image_io.hpp"

#include <gtest/gtest.h>
#include <png.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "findmug/common/error.hpp"
#include "expect_error.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

using test::errorOf;
using test::TempDir;

std::vector<std::uint8_t> readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeBytes(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

// Reads a PNG with plain libpng and no transforms: the bytes as stored.
struct RawPng {
  png_uint_32 width = 0, height = 0;
  int bit_depth = 0, colour_type = 0;
  std::vector<std::vector<std::uint8_t>> rows;
};
RawPng readRaw(const std::string& path) {
  RawPng raw;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  EXPECT_NE(f, nullptr);
  if (!f) return raw;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  png_init_io(png, f);
  png_read_info(png, info);
  png_get_IHDR(png, info, &raw.width, &raw.height, &raw.bit_depth, &raw.colour_type, nullptr,
               nullptr, nullptr);
  const auto row_bytes = png_get_rowbytes(png, info);
  raw.rows.assign(raw.height, std::vector<std::uint8_t>(row_bytes));
  for (auto& row : raw.rows) png_read_row(png, row.data(), nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  std::fclose(f);
  return raw;
}

// Writes an arbitrary-format PNG with plain libpng (to make "wrong" inputs).
void writeRaw(const std::string& path, int width, int height, int bit_depth, int colour_type,
              const std::vector<std::uint8_t>& data) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  png_init_io(png, f);
  png_set_IHDR(png, info, width, height, bit_depth, colour_type, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (colour_type == PNG_COLOR_TYPE_PALETTE) {
    png_color palette[2] = {{0, 0, 0}, {255, 255, 255}};
    png_set_PLTE(png, info, palette, 2);
  }
  png_write_info(png, info);
  const std::size_t row_bytes = data.size() / static_cast<std::size_t>(height);
  for (int y = 0; y < height; ++y) {
    png_write_row(png, const_cast<png_bytep>(data.data() + y * row_bytes));
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  std::fclose(f);
}

Image<std::uint16_t> ramp16(int w, int h) {
  Image<std::uint16_t> image{w, h, {}};
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      image.pixels.push_back(static_cast<std::uint16_t>(x * 977 + y * 13331));
    }
  }
  return image;
}

Image<Rgb8> pattern(int w, int h) {
  Image<Rgb8> image{w, h, {}};
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      image.pixels.push_back({static_cast<std::uint8_t>(x * 7), static_cast<std::uint8_t>(y * 11),
                              static_cast<std::uint8_t>(x ^ y)});
    }
  }
  return image;
}

TEST(ImageIo, Png16RoundTripKeepsEveryValueAndRowOrder) {
  TempDir dir;
  auto image = ramp16(37, 23);  // odd sizes catch stride mistakes
  image.pixels[0] = 0;
  image.pixels[1] = 65535;
  image.pixels[2] = 0x1234;
  writePng16(dir.str("d.png"), image);
  const auto back = readPng16(dir.str("d.png"));
  EXPECT_EQ(back.width, 37);
  EXPECT_EQ(back.height, 23);
  EXPECT_EQ(back.pixels, image.pixels);
}

TEST(ImageIo, Png16IsBigEndianOnDisk) {
  TempDir dir;
  Image<std::uint16_t> image{2, 1, {0x1234, 0xABCD}};
  writePng16(dir.str("d.png"), image);
  const auto raw = readRaw(dir.str("d.png"));
  ASSERT_EQ(raw.bit_depth, 16);
  ASSERT_EQ(raw.colour_type, PNG_COLOR_TYPE_GRAY);
  ASSERT_EQ(raw.rows.size(), 1u);
  const std::vector<std::uint8_t> expected = {0x12, 0x34, 0xAB, 0xCD};
  EXPECT_EQ(raw.rows[0], expected);

  // And a big-endian file written by someone else reads as the right number.
  writeRaw(dir.str("be.png"), 1, 1, 16, PNG_COLOR_TYPE_GRAY, {0x03, 0xE8});  // 1000
  EXPECT_EQ(readPng16(dir.str("be.png")).pixels.at(0), 1000);
}

TEST(ImageIo, Png8AndRgbRoundTrip) {
  TempDir dir;
  Image<std::uint8_t> grey{5, 3, {0, 1, 2, 3, 4, 250, 251, 252, 253, 254, 255, 7, 8, 9, 10}};
  writePng8(dir.str("g.png"), grey);
  const auto g = readPng8(dir.str("g.png"));
  EXPECT_EQ(g.width, 5);
  EXPECT_EQ(g.height, 3);
  EXPECT_EQ(g.pixels, grey.pixels);

  const auto colour = pattern(31, 17);
  writePngRgb(dir.str("c.png"), colour);
  const auto c = readPngRgb(dir.str("c.png"));
  EXPECT_EQ(c.width, 31);
  EXPECT_EQ(c.height, 17);
  EXPECT_EQ(c.pixels, colour.pixels);
}

TEST(ImageIo, RgbaIsReadWithAlphaDropped) {
  TempDir dir;
  writeRaw(dir.str("a.png"), 2, 1, 8, PNG_COLOR_TYPE_RGB_ALPHA, {10, 20, 30, 0, 40, 50, 60, 255});
  const auto c = readPngRgb(dir.str("a.png"));
  ASSERT_EQ(c.pixels.size(), 2u);
  EXPECT_EQ(c.pixels[0], (Rgb8{10, 20, 30}));
  EXPECT_EQ(c.pixels[1], (Rgb8{40, 50, 60}));
}

TEST(ImageIo, WrongFormatNamesFileAndWhatWasFound) {
  TempDir dir;
  writePng8(dir.str("depth8.png"), Image<std::uint8_t>{2, 2, {1, 2, 3, 4}});
  auto msg = errorOf([&] { readPng16(dir.str("depth8.png")); });
  EXPECT_NE(msg.find(dir.str("depth8.png")), std::string::npos) << msg;
  EXPECT_NE(msg.find("expected 16-bit single-channel PNG, found 8-bit grey"), std::string::npos)
      << msg;

  writePngRgb(dir.str("rgb.png"), pattern(2, 2));
  msg = errorOf([&] { readPng16(dir.str("rgb.png")); });
  EXPECT_NE(msg.find("found 8-bit RGB"), std::string::npos) << msg;
  msg = errorOf([&] { readPng8(dir.str("rgb.png")); });
  EXPECT_NE(msg.find("expected 8-bit single-channel PNG, found 8-bit RGB"), std::string::npos)
      << msg;

  writePng16(dir.str("d16.png"), ramp16(2, 2));
  msg = errorOf([&] { readPng8(dir.str("d16.png")); });
  EXPECT_NE(msg.find("found 16-bit grey"), std::string::npos) << msg;
  msg = errorOf([&] { readPngRgb(dir.str("d16.png")); });
  EXPECT_NE(msg.find("expected 8-bit RGB or RGBA PNG, found 16-bit grey"), std::string::npos)
      << msg;

  writeRaw(dir.str("pal.png"), 2, 1, 8, PNG_COLOR_TYPE_PALETTE, {0, 1});
  msg = errorOf([&] { readPng8(dir.str("pal.png")); });
  EXPECT_NE(msg.find("found 8-bit palette"), std::string::npos) << msg;

  writeRaw(dir.str("ga.png"), 1, 1, 8, PNG_COLOR_TYPE_GRAY_ALPHA, {5, 255});
  msg = errorOf([&] { readPng8(dir.str("ga.png")); });
  EXPECT_NE(msg.find("found 8-bit grey+alpha"), std::string::npos) << msg;

  writeRaw(dir.str("rgb16.png"), 1, 1, 16, PNG_COLOR_TYPE_RGB, {0, 1, 0, 2, 0, 3});
  msg = errorOf([&] { readPngRgb(dir.str("rgb16.png")); });
  EXPECT_NE(msg.find("found 16-bit RGB"), std::string::npos) << msg;
}

TEST(ImageIo, MissingNonPngAndTruncatedFilesAreErrors) {
  TempDir dir;
  auto msg = errorOf([&] { readPng8(dir.str("nope.png")); });
  EXPECT_NE(msg.find(dir.str("nope.png")), std::string::npos) << msg;
  EXPECT_NE(msg.find("cannot open"), std::string::npos) << msg;

  writeBytes(dir.str("text.png"), {'h', 'e', 'l', 'l', 'o', ' ', 'w', 'o', 'r', 'l', 'd'});
  msg = errorOf([&] { readPngRgb(dir.str("text.png")); });
  EXPECT_NE(msg.find(dir.str("text.png")), std::string::npos) << msg;
  EXPECT_NE(msg.find("not a PNG"), std::string::npos) << msg;

  writeBytes(dir.str("empty.png"), {});
  EXPECT_THROW(readPng16(dir.str("empty.png")), Error);

  writePngRgb(dir.str("full.png"), pattern(64, 64));
  auto bytes = readBytes(dir.str("full.png"));
  for (std::size_t keep : {std::size_t{12}, std::size_t{40}, bytes.size() / 2, bytes.size() - 20}) {
    std::vector<std::uint8_t> cut(bytes.begin(), bytes.begin() + static_cast<long>(keep));
    writeBytes(dir.str("cut.png"), cut);
    msg = errorOf([&] { readPngRgb(dir.str("cut.png")); });
    EXPECT_NE(msg.find(dir.str("cut.png")), std::string::npos) << "kept " << keep << ": " << msg;
  }

  // A flipped byte in the compressed data fails the CRC / inflate check.
  auto corrupt = bytes;
  corrupt[corrupt.size() / 2] ^= 0xFF;
  writeBytes(dir.str("bad.png"), corrupt);
  EXPECT_THROW(readPngRgb(dir.str("bad.png")), Error);
}

TEST(ImageIo, WritersRejectInconsistentImagesAndBadPaths) {
  TempDir dir;
  auto msg = errorOf([&] { writePng8(dir.str("x.png"), Image<std::uint8_t>{3, 3, {1, 2}}); });
  EXPECT_NE(msg.find("2 pixels, expected 9"), std::string::npos) << msg;
  EXPECT_THROW(writePng16(dir.str("x.png"), Image<std::uint16_t>{0, 5, {}}), Error);
  msg = errorOf([&] { writePngRgb(dir.str("no/such/dir/x.png"), pattern(2, 2)); });
  EXPECT_NE(msg.find("no/such/dir/x.png"), std::string::npos) << msg;
}

TEST(ImageIo, InMemoryRgbRoundTripAndBadBytes) {
  const auto colour = pattern(40, 30);
  const auto bytes = encodePngRgb(colour);
  ASSERT_GT(bytes.size(), 8u);
  EXPECT_EQ(png_sig_cmp(bytes.data(), 0, 8), 0);
  const auto back = decodePngRgb(bytes, "lcm colour");
  EXPECT_EQ(back.width, 40);
  EXPECT_EQ(back.height, 30);
  EXPECT_EQ(back.pixels, colour.pixels);

  auto msg = errorOf([&] { decodePngRgb({1, 2, 3}, "msg 42 colour"); });
  EXPECT_NE(msg.find("msg 42 colour"), std::string::npos) << msg;
  std::vector<std::uint8_t> cut(bytes.begin(), bytes.begin() + static_cast<long>(bytes.size() / 2));
  msg = errorOf([&] { decodePngRgb(cut, "msg 43 colour"); });
  EXPECT_NE(msg.find("msg 43 colour"), std::string::npos) << msg;
  EXPECT_THROW(encodePngRgb(Image<Rgb8>{4, 4, {}}), Error);
}

TEST(ImageIo, ReadsRealNyuFrames) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  const auto rgb = readPngRgb((nyu / "rgb" / "0001.png").string());
  const auto depth = readPng16((nyu / "depth" / "0001.png").string());
  const auto label = readPng8((nyu / "label40" / "0001.png").string());
  for (auto [w, h] : {std::pair{rgb.width, rgb.height}, std::pair{depth.width, depth.height},
                      std::pair{label.width, label.height}}) {
    EXPECT_EQ(w, 640);
    EXPECT_EQ(h, 480);
  }
  // Millimetres of an indoor scene: a byte-swapped read would give medians
  // in the tens of thousands or near zero.
  auto sorted = depth.pixels;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const auto median = sorted[sorted.size() / 2];
  EXPECT_GT(median, 500);
  EXPECT_LT(median, 6000);
  EXPECT_LE(*std::max_element(label.pixels.begin(), label.pixels.end()), 40);
  // Reading the depth as colour must fail loudly.
  EXPECT_THROW(readPngRgb((nyu / "depth" / "0001.png").string()), Error);
}

}  // namespace
}  // namespace findmug
