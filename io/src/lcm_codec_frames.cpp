// rgbd_frame_t <-> RgbdFrame and the compression names (findmug/io/lcm_codec.hpp).
#include <cstring>
#include <string>

#include "compression.hpp"
#include "findmug/common/error.hpp"
#include "findmug/frame/image_io.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "lcm_codec_checks.hpp"

namespace findmug::io {

using detail::checkArraySize;
using detail::checkDimensions;
using detail::checkFinite;
using detail::field;
using detail::finite;

// ---- compression names ------------------------------------------------------------

DepthCompression parseDepthCompression(std::string_view name) {
  if (name == "none") return DepthCompression::None;
  if (name == "zlib") return DepthCompression::Zlib;
  throw Error("depth compression '" + std::string(name) + "': expected none or zlib");
}

ColorCompression parseColorCompression(std::string_view name) {
  if (name == "none") return ColorCompression::None;
  if (name == "jpeg" || name == "jpg") return ColorCompression::Jpeg;
  if (name == "png") return ColorCompression::Png;
  throw Error("colour compression '" + std::string(name) + "': expected none, jpeg or png");
}

// ---- RGB-D frames ---------------------------------------------------------------------

findmug_lcm::rgbd_frame_t encodeRgbdFrame(const RgbdFrame& frame,
                                          const RgbdEncodeOptions& options) {
  validateFrame(frame);
  findmug_lcm::rgbd_frame_t msg;
  msg.utime = static_cast<std::int64_t>(frame.utime);
  msg.seq = frame.seq;
  msg.source = frame.source;
  msg.width = frame.width;
  msg.height = frame.height;
  msg.fx = frame.intrinsics.fx;
  msg.fy = frame.intrinsics.fy;
  msg.cx = frame.intrinsics.cx;
  msg.cy = frame.intrinsics.cy;
  msg.has_extrinsics = frame.extrinsics.has_value();
  msg.height_m = frame.extrinsics ? frame.extrinsics->height_m : 0.0;
  msg.pitch_rad = frame.extrinsics ? frame.extrinsics->pitch_rad : 0.0;
  msg.roll_rad = frame.extrinsics ? frame.extrinsics->roll_rad : 0.0;

  // Depth on the wire is little-endian whatever the host.
  std::vector<std::uint8_t> depth(frame.depth_mm.size() * 2);
  for (std::size_t i = 0; i < frame.depth_mm.size(); ++i) {
    depth[2 * i] = static_cast<std::uint8_t>(frame.depth_mm[i] & 0xff);
    depth[2 * i + 1] = static_cast<std::uint8_t>(frame.depth_mm[i] >> 8);
  }
  switch (options.depth) {
    case DepthCompression::None:
      msg.depth_data = std::move(depth);
      break;
    case DepthCompression::Zlib:
      msg.depth_data = detail::zlibCompress(depth.data(), depth.size(), options.zlib_level);
      break;
  }
  msg.depth_compression = static_cast<std::int8_t>(options.depth);
  msg.depth_size = static_cast<std::int32_t>(msg.depth_data.size());

  switch (options.color) {
    case ColorCompression::None:
      msg.color_data.resize(frame.rgb.size() * 3);
      std::memcpy(msg.color_data.data(), frame.rgb.data(), msg.color_data.size());
      break;
    case ColorCompression::Jpeg:
      msg.color_data =
          detail::jpegCompressRgb(frame.rgb, frame.width, frame.height, options.jpeg_quality);
      break;
    case ColorCompression::Png:
      msg.color_data = encodePngRgb(Image<Rgb8>{frame.width, frame.height, frame.rgb});
      break;
  }
  msg.color_compression = static_cast<std::int8_t>(options.color);
  msg.color_size = static_cast<std::int32_t>(msg.color_data.size());
  return msg;
}

RgbdFrame decodeRgbdFrame(const findmug_lcm::rgbd_frame_t& msg, std::string_view channel) {
  constexpr std::string_view type = "rgbd_frame_t";
  checkDimensions(msg.width, msg.height, channel, type);
  checkArraySize(msg.depth_size, msg.depth_data.size(), channel, type, "depth_size");
  checkArraySize(msg.color_size, msg.color_data.size(), channel, type, "color_size");
  if (msg.utime < 0) {
    throw Error(field(channel, type, "utime") + ": negative time " + std::to_string(msg.utime));
  }
  const std::size_t pixels = static_cast<std::size_t>(msg.width) * msg.height;

  RgbdFrame frame;
  frame.width = msg.width;
  frame.height = msg.height;
  frame.utime = static_cast<std::uint64_t>(msg.utime);
  frame.seq = msg.seq;
  frame.source = std::string(channel) + (msg.source.empty() ? "" : ": " + msg.source);
  frame.intrinsics = {msg.fx, msg.fy, msg.cx, msg.cy};
  if (msg.has_extrinsics)
    frame.extrinsics = CameraExtrinsics{msg.height_m, msg.pitch_rad, msg.roll_rad};

  const std::string depth_field = field(channel, type, "depth_data");
  // Depth is little-endian on the wire: on a little-endian host the bytes go
  // straight into depth_mm (inflated there, or copied), with no second pass.
  constexpr bool kLittleEndian = std::endian::native == std::endian::little;
  std::vector<std::uint8_t> inflated;
  const std::vector<std::uint8_t>* depth_bytes = &msg.depth_data;
  frame.depth_mm.resize(pixels);
  switch (msg.depth_compression) {
    case findmug_lcm::rgbd_frame_t::DEPTH_NONE:
      if (msg.depth_data.size() != pixels * 2) {
        throw Error(depth_field + ": " + std::to_string(msg.depth_data.size()) +
                    " bytes of raw depth, expected " + std::to_string(pixels * 2) + " for " +
                    std::to_string(msg.width) + "x" + std::to_string(msg.height));
      }
      if (kLittleEndian) {
        std::memcpy(frame.depth_mm.data(), msg.depth_data.data(), pixels * 2);
        depth_bytes = nullptr;
      }
      break;
    case findmug_lcm::rgbd_frame_t::DEPTH_ZLIB:
      if (kLittleEndian) {
        detail::zlibDecompressInto(msg.depth_data.data(), msg.depth_data.size(),
                                   reinterpret_cast<std::uint8_t*>(frame.depth_mm.data()),
                                   pixels * 2, depth_field);
        depth_bytes = nullptr;
      } else {
        inflated = detail::zlibDecompress(msg.depth_data.data(), msg.depth_data.size(), pixels * 2,
                                          depth_field);
        depth_bytes = &inflated;
      }
      break;
    default:
      throw Error(field(channel, type, "depth_compression") + ": unknown compression id " +
                  std::to_string(msg.depth_compression) + " (expected 0 none or 1 zlib)");
  }
  if (depth_bytes) {
    for (std::size_t i = 0; i < pixels; ++i) {
      frame.depth_mm[i] =
          static_cast<std::uint16_t>((*depth_bytes)[2 * i] | ((*depth_bytes)[2 * i + 1] << 8));
    }
  }

  const std::string color_field = field(channel, type, "color_data");
  switch (msg.color_compression) {
    case findmug_lcm::rgbd_frame_t::COLOR_NONE:
      if (msg.color_data.size() != pixels * 3) {
        throw Error(color_field + ": " + std::to_string(msg.color_data.size()) +
                    " bytes of raw RGB, expected " + std::to_string(pixels * 3));
      }
      frame.rgb.resize(pixels);
      std::memcpy(frame.rgb.data(), msg.color_data.data(), pixels * 3);
      break;
    case findmug_lcm::rgbd_frame_t::COLOR_JPEG:
      frame.rgb = detail::jpegDecompressRgb(msg.color_data.data(), msg.color_data.size(), msg.width,
                                            msg.height, color_field);
      break;
    case findmug_lcm::rgbd_frame_t::COLOR_PNG: {
      if (msg.color_data.empty()) throw Error(color_field + ": empty PNG data");
      Image<Rgb8> image = decodePngRgb(msg.color_data, color_field);
      if (image.width != msg.width || image.height != msg.height) {
        throw Error(color_field + ": PNG is " + std::to_string(image.width) + "x" +
                    std::to_string(image.height) + ", message says " + std::to_string(msg.width) +
                    "x" + std::to_string(msg.height));
      }
      frame.rgb = std::move(image.pixels);
      break;
    }
    default:
      throw Error(field(channel, type, "color_compression") + ": unknown compression id " +
                  std::to_string(msg.color_compression) + " (expected 0 none, 1 jpeg or 2 png)");
  }
  validateFrame(frame);  // intrinsics, extrinsics; names the channel via frame.source
  return frame;
}

std::optional<std::int64_t> peekRgbdFrameSeq(const void* data, std::size_t size) {
  // Wire layout: 8-byte fingerprint, int64 utime, int64 seq, all big-endian.
  if (data == nullptr || size < 24) return std::nullopt;
  const auto* b = static_cast<const std::uint8_t*>(data);
  auto be64 = [b](std::size_t at) {
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < 8; ++i) v = (v << 8) | b[at + i];
    return v;
  };
  if (be64(0) != static_cast<std::uint64_t>(findmug_lcm::rgbd_frame_t::getHash())) {
    return std::nullopt;
  }
  return static_cast<std::int64_t>(be64(16));
}

RgbdFrame decodeRgbdFrame(const void* data, std::size_t size, std::string_view channel) {
  return decodeRgbdFrame(decodeMessage<findmug_lcm::rgbd_frame_t>(data, size, channel), channel);
}

}  // namespace findmug::io
