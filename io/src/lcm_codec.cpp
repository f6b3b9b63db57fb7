#include "findmug/io/lcm_codec.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <string>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "compression.hpp"
#include "search_position_codec.hpp"
#include "findmug/common/error.hpp"
#include "findmug/frame/image_io.hpp"
#include "findmug/objects/object_model.hpp"

namespace findmug::io {

namespace {

// Same limit as validateFrame(): a Kinect is 640x480; anything beyond 4096 a
// side can only come from a corrupt message, and must be refused before
// width*height sizes an allocation.
constexpr std::int32_t kMaxSide = 4096;

std::string field(std::string_view channel, std::string_view type, std::string_view name) {
  return std::string(channel) + ": " + std::string(type) + "." + std::string(name);
}

void checkDimensions(std::int32_t width, std::int32_t height, std::string_view channel,
                     std::string_view type) {
  if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide) {
    throw Error(field(channel, type, "width/height") + ": absurd image size " +
                std::to_string(width) + "x" + std::to_string(height) + " (expected 1.." +
                std::to_string(kMaxSide) + " per side)");
  }
}

void checkArraySize(std::int32_t declared, std::size_t actual, std::string_view channel,
                    std::string_view type, std::string_view name) {
  if (declared < 0 || static_cast<std::size_t>(declared) != actual) {
    throw Error(field(channel, type, name) + ": size field says " + std::to_string(declared) +
                " but the array holds " + std::to_string(actual));
  }
}

bool finite(double v) { return std::isfinite(v); }

}  // namespace

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
        inflated = detail::zlibDecompress(msg.depth_data.data(), msg.depth_data.size(),
                                          pixels * 2, depth_field);
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

// ---- label images -------------------------------------------------------------------------

findmug_lcm::label_image_t encodeLabelImage(const LabelImageMessage& in, bool with_confidence) {
  findmug_lcm::label_image_t msg =
      encodeLabelImage(in.image, in.utime, in.seq, in.latency_us, with_confidence);
  if (in.camera) setCameraView(msg, in.camera->intrinsics, in.camera->camera_to_base);
  if (!in.color_jpeg.empty()) {
    msg.color_format = findmug_lcm::label_image_t::COLOR_JPEG;
    msg.color_data = in.color_jpeg;
    msg.color_size = static_cast<std::int32_t>(msg.color_data.size());
  }
  return msg;
}

findmug_lcm::label_image_t encodeLabelImage(const LabelImage& image, std::uint64_t utime,
                                            std::int64_t seq, std::int64_t latency_us,
                                            bool with_confidence) {
  checkDimensions(image.width, image.height, "encode", "label_image_t");
  const std::size_t pixels = static_cast<std::size_t>(image.width) * image.height;
  if (image.labels.size() != pixels) {
    throw Error("label image encode: " + std::to_string(image.labels.size()) + " labels for " +
                std::to_string(image.width) + "x" + std::to_string(image.height));
  }
  // Validated in a branch-free pass the compiler vectorises (a compare and
  // a throw per pixel cost about half a millisecond a VGA frame); the first
  // bad pixel is looked for only when there is one.
  const auto badLabel = [](std::uint8_t label) {
    return label >= kNumLabels && label != kVoidLabel;
  };
  const std::uint8_t* labels = image.labels.data();
  unsigned any_bad = 0;
  for (std::size_t i = 0; i < pixels; ++i) any_bad |= badLabel(labels[i]) ? 1u : 0u;
  if (any_bad) {
    const std::size_t i =
        static_cast<std::size_t>(std::find_if(labels, labels + pixels, badLabel) - labels);
    throw Error("label image encode: pixel " + std::to_string(i) + " has label id " +
                std::to_string(image.labels[i]));
  }
  findmug_lcm::label_image_t msg;
  // The generated struct leaves its scalars uninitialised: no camera, no colour.
  msg.has_camera = false;
  msg.fx = msg.fy = msg.cx = msg.cy = 0.0;
  for (auto& row : msg.camera_to_base) std::fill(std::begin(row), std::end(row), 0.0);
  msg.color_format = findmug_lcm::label_image_t::COLOR_ABSENT;
  msg.color_size = 0;
  msg.utime = static_cast<std::int64_t>(utime);
  msg.seq = seq;
  msg.width = image.width;
  msg.height = image.height;
  msg.num_labels = kNumLabels;
  for (auto name : kLabelNames) msg.label_names.emplace_back(name);
  msg.compression = findmug_lcm::label_image_t::COMPRESSION_ZLIB;
  msg.labels_data = detail::zlibCompressRuns(image.labels.data(), pixels);
  msg.labels_size = static_cast<std::int32_t>(msg.labels_data.size());
  msg.has_confidence = with_confidence && !image.confidence.empty();
  if (msg.has_confidence) {
    if (image.confidence.size() != pixels) {
      throw Error("label image encode: " + std::to_string(image.confidence.size()) +
                  " confidences for " + std::to_string(pixels) + " pixels");
    }
    // Kept per thread: a stream of frames of one size then allocates (and
    // clears) nothing here; every byte is written below.
    thread_local std::vector<std::uint8_t> quantised_buffer;
    std::vector<std::uint8_t>& quantised = quantised_buffer;
    quantised.resize(pixels);
    const float* confidence = image.confidence.data();
    // Every value is checked and quantised in one branch-free pass, an
    // out-of-range one (or NaN) as 0; the first bad value is looked for only
    // when there is one. Quantising: std::lround(x) without the libm call
    // (one per pixel, ~1 ms a VGA frame): x = c * 255 is in [0, 255], so
    // truncation is floor and x - floor(x) is exact; halves round up, as
    // lround's ties away from zero do. SSE2 (every x86-64) takes sixteen
    // values a step: GCC does not vectorise the plain loop, as it may not
    // reorder floating-point compares that could raise exceptions.
    unsigned any_bad = 0;
    std::size_t i = 0;
#if defined(__SSE2__)
    {
      const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
      const __m128 scale = _mm_set1_ps(255.0f), half = _mm_set1_ps(0.5f);
      __m128 bad = _mm_setzero_ps();
      for (; i + 16 <= pixels; i += 16) {
        __m128i q[4];
        for (int k = 0; k < 4; ++k) {
          const __m128 c = _mm_loadu_ps(confidence + i + 4 * k);
          const __m128 ok = _mm_and_ps(_mm_cmpge_ps(c, zero), _mm_cmple_ps(c, one));
          bad = _mm_or_ps(bad, _mm_andnot_ps(ok, _mm_castsi128_ps(_mm_set1_epi32(-1))));
          const __m128 x = _mm_and_ps(_mm_mul_ps(c, scale), ok);
          const __m128i down = _mm_cvttps_epi32(x);
          const __m128 up = _mm_cmpge_ps(_mm_sub_ps(x, _mm_cvtepi32_ps(down)), half);
          q[k] = _mm_sub_epi32(down, _mm_castps_si128(up));  // up is -1 where rounding up
        }
        _mm_storeu_si128(reinterpret_cast<__m128i*>(quantised.data() + i),
                         _mm_packus_epi16(_mm_packs_epi32(q[0], q[1]), _mm_packs_epi32(q[2], q[3])));
      }
      any_bad = _mm_movemask_ps(bad) != 0 ? 1u : 0u;
    }
#endif
    for (; i < pixels; ++i) {
      const float c = confidence[i];
      const bool ok = c >= 0.0f && c <= 1.0f;
      any_bad |= ok ? 0u : 1u;
      const float x = ok ? c * 255.0f : 0.0f;
      const int down = static_cast<int>(x);
      quantised[i] =
          static_cast<std::uint8_t>(down + (x - static_cast<float>(down) >= 0.5f ? 1 : 0));
    }
    if (any_bad) {
      const std::size_t i = static_cast<std::size_t>(
          std::find_if(confidence, confidence + pixels,
                       [](float c) { return !(c >= 0.0f && c <= 1.0f); }) -
          confidence);
      throw Error("label image encode: pixel " + std::to_string(i) + " confidence " +
                  std::to_string(image.confidence[i]) + " outside [0, 1]");
    }
    msg.confidence_data = detail::zlibCompressRuns(quantised.data(), pixels);
  }
  msg.confidence_size = static_cast<std::int32_t>(msg.confidence_data.size());
  msg.latency_us = latency_us;
  return msg;
}

namespace {

// label_image_t.has_camera and its fields: finite positive intrinsics, a rotation
// (orthonormal, determinant +1) and a finite translation; nullopt without a camera.
std::optional<CameraView> decodeCameraView(const findmug_lcm::label_image_t& msg,
                                           std::string_view channel) {
  constexpr std::string_view type = "label_image_t";
  if (!msg.has_camera) return std::nullopt;
  for (double v : {msg.fx, msg.fy}) {
    if (!(std::isfinite(v) && v > 0.0)) {
      throw Error(field(channel, type, "fx/fy") + ": focal length " + std::to_string(v) +
                  " is not a positive finite number");
    }
  }
  if (!std::isfinite(msg.cx) || !std::isfinite(msg.cy)) {
    throw Error(field(channel, type, "cx/cy") + ": principal point is not finite");
  }
  CameraView view;
  view.intrinsics = {msg.fx, msg.fy, msg.cx, msg.cy};
  Eigen::Matrix3d r;
  Eigen::Vector3d t;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 4; ++j) {
      const double v = msg.camera_to_base[i][j];
      if (!std::isfinite(v)) {
        throw Error(field(channel, type, "camera_to_base") + ": element [" + std::to_string(i) +
                    "][" + std::to_string(j) + "] is not finite");
      }
      if (j < 3) {
        r(i, j) = v;
      } else {
        t(i) = v;
      }
    }
  }
  const double off = (r * r.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (off > 1e-3 || r.determinant() < 0.0) {
    throw Error(field(channel, type, "camera_to_base") +
                ": the 3x3 part is not a rotation (R R^T differs from I by " +
                std::to_string(off) + ")");
  }
  view.camera_to_base.linear() = r;
  view.camera_to_base.translation() = t;
  return view;
}

// label_image_t.color_format and color_data: the JPEG's bytes, checked for the
// markers that open and close one (the full decode is decodeLabelImageColor's).
std::vector<std::uint8_t> checkedColorJpeg(const findmug_lcm::label_image_t& msg,
                                           std::string_view channel) {
  constexpr std::string_view type = "label_image_t";
  checkArraySize(msg.color_size, msg.color_data.size(), channel, type, "color_size");
  switch (msg.color_format) {
    case findmug_lcm::label_image_t::COLOR_ABSENT:
      if (msg.color_size != 0) {
        throw Error(field(channel, type, "color_size") + ": " + std::to_string(msg.color_size) +
                    " bytes but color_format is COLOR_ABSENT");
      }
      return {};
    case findmug_lcm::label_image_t::COLOR_JPEG: {
      const auto& d = msg.color_data;
      if (d.size() < 4 || d[0] != 0xFF || d[1] != 0xD8 || d[d.size() - 2] != 0xFF ||
          d[d.size() - 1] != 0xD9) {
        throw Error(field(channel, type, "color_data") +
                    ": not a JPEG (no start and end of image markers)");
      }
      return d;
    }
    default:
      throw Error(field(channel, type, "color_format") + ": unknown colour format id " +
                  std::to_string(msg.color_format) + " (expected 0 absent or 1 jpeg)");
  }
}

}  // namespace

void setCameraView(findmug_lcm::label_image_t& message, const CameraIntrinsics& intrinsics,
                   const Eigen::Isometry3d& camera_to_base) {
  message.has_camera = true;
  message.fx = intrinsics.fx;
  message.fy = intrinsics.fy;
  message.cx = intrinsics.cx;
  message.cy = intrinsics.cy;
  const Eigen::Matrix<double, 3, 4> m = camera_to_base.matrix().topRows<3>();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 4; ++j) message.camera_to_base[i][j] = m(i, j);
  }
}

void setColorJpeg(findmug_lcm::label_image_t& message, const std::vector<Rgb8>& rgb, int quality) {
  const std::size_t pixels = static_cast<std::size_t>(message.width) * message.height;
  if (rgb.size() != pixels) {
    throw Error("label image encode: " + std::to_string(rgb.size()) + " colour pixels for " +
                std::to_string(message.width) + "x" + std::to_string(message.height));
  }
  if (quality < 1 || quality > 100) {
    throw Error("label image encode: JPEG quality " + std::to_string(quality) +
                " outside 1..100");
  }
  message.color_data = detail::jpegCompressRgb(rgb, message.width, message.height, quality);
  message.color_size = static_cast<std::int32_t>(message.color_data.size());
  message.color_format = findmug_lcm::label_image_t::COLOR_JPEG;
}

std::vector<Rgb8> decodeLabelImageColor(const LabelImageMessage& message,
                                        std::string_view channel) {
  if (message.color_jpeg.empty()) return {};
  return detail::jpegDecompressRgb(message.color_jpeg.data(), message.color_jpeg.size(),
                                   message.image.width, message.image.height,
                                   std::string(channel) + " label_image_t.color_data");
}

LabelImageMessage decodeLabelImage(const findmug_lcm::label_image_t& msg,
                                   std::string_view channel) {
  constexpr std::string_view type = "label_image_t";
  checkDimensions(msg.width, msg.height, channel, type);
  checkArraySize(msg.num_labels, msg.label_names.size(), channel, type, "num_labels");
  checkArraySize(msg.labels_size, msg.labels_data.size(), channel, type, "labels_size");
  checkArraySize(msg.confidence_size, msg.confidence_data.size(), channel, type, "confidence_size");
  // The ids are part of the contract (labels.hpp); a publisher with other
  // names would make every client mis-colour silently.
  if (msg.num_labels != kNumLabels) {
    throw Error(field(channel, type, "num_labels") + ": " + std::to_string(msg.num_labels) +
                " labels, expected " + std::to_string(kNumLabels));
  }
  for (int i = 0; i < kNumLabels; ++i) {
    if (msg.label_names[static_cast<std::size_t>(i)] != kLabelNames[static_cast<std::size_t>(i)]) {
      throw Error(field(channel, type, "label_names") + ": id " + std::to_string(i) + " is '" +
                  msg.label_names[static_cast<std::size_t>(i)] + "', expected '" +
                  std::string(kLabelNames[static_cast<std::size_t>(i)]) + "'");
    }
  }
  if (msg.utime < 0) {
    throw Error(field(channel, type, "utime") + ": negative time " + std::to_string(msg.utime));
  }
  if (msg.latency_us < 0) {
    throw Error(field(channel, type, "latency_us") + ": negative latency " +
                std::to_string(msg.latency_us));
  }
  const std::size_t pixels = static_cast<std::size_t>(msg.width) * msg.height;
  auto unpack = [&](const std::vector<std::uint8_t>& data, std::string_view name) {
    const std::string where = field(channel, type, name);
    switch (msg.compression) {
      case findmug_lcm::label_image_t::COMPRESSION_NONE:
        if (data.size() != pixels) {
          throw Error(where + ": " + std::to_string(data.size()) + " bytes, expected " +
                      std::to_string(pixels));
        }
        return data;
      case findmug_lcm::label_image_t::COMPRESSION_ZLIB:
        return detail::zlibDecompress(data.data(), data.size(), pixels, where);
      default:
        throw Error(field(channel, type, "compression") + ": unknown compression id " +
                    std::to_string(msg.compression) + " (expected 0 none or 1 zlib)");
    }
  };

  LabelImageMessage out;
  out.utime = static_cast<std::uint64_t>(msg.utime);
  out.seq = msg.seq;
  out.latency_us = msg.latency_us;
  out.image.width = msg.width;
  out.image.height = msg.height;
  out.image.labels = unpack(msg.labels_data, "labels_data");
  for (std::size_t i = 0; i < pixels; ++i) {
    const std::uint8_t id = out.image.labels[i];
    if (id >= kNumLabels && id != kVoidLabel) {
      throw Error(field(channel, type, "labels_data") + ": pixel " + std::to_string(i) +
                  " has label id " + std::to_string(id) + " (expected 0.." +
                  std::to_string(kNumLabels - 1) + " or 255)");
    }
  }
  if (msg.has_confidence) {
    const std::vector<std::uint8_t> q = unpack(msg.confidence_data, "confidence_data");
    out.image.confidence.resize(pixels);
    for (std::size_t i = 0; i < pixels; ++i) out.image.confidence[i] = q[i] / 255.0f;
  } else if (msg.confidence_size != 0) {
    throw Error(field(channel, type, "confidence_size") + ": " +
                std::to_string(msg.confidence_size) + " bytes but has_confidence is false");
  }
  out.camera = decodeCameraView(msg, channel);
  out.color_jpeg = checkedColorJpeg(msg, channel);
  return out;
}

LabelImageMessage decodeLabelImage(const void* data, std::size_t size, std::string_view channel) {
  return decodeLabelImage(decodeMessage<findmug_lcm::label_image_t>(data, size, channel), channel);
}

// ---- tables ------------------------------------------------------------------------------------

namespace {

findmug_lcm::search_position_t toLcmMap(const SearchPosition& p, const RobotPose& pose) {
  findmug_lcm::search_position_t out = detail::searchPositionToLcm(p);
  const Eigen::Vector2d m = transformPointD(pose.pose, p.xy.cast<double>());
  out.x = m.x();
  out.y = m.y();
  out.yaw = wrapAngle(p.yaw + pose.pose.yaw);
  return out;
}

void checkFinite(std::initializer_list<double> values, const std::string& where) {
  for (double v : values) {
    if (!finite(v)) throw Error(where + ": non-finite value");
  }
}

}  // namespace

findmug_lcm::tables_t encodeTables(const TablesMessage& in) {
  return encodeTables(in.utime, in.seq, in.content, in.tables, in.map_pose, in.map_info);
}

findmug_lcm::tables_t encodeTables(std::uint64_t utime, std::int64_t seq, TablesContent content,
                                   std::span<const TableCluster> tables,
                                   const std::optional<RobotPose>& map_pose,
                                   std::span<const TableMapInfo> map_info) {
  if (!map_info.empty() && map_info.size() != tables.size()) {
    throw Error("encodeTables: " + std::to_string(map_info.size()) + " map entries for " +
                std::to_string(tables.size()) + " tables");
  }
  if (content == TablesContent::Map) {
    if (!map_pose) throw Error("encodeTables: a table map message needs the robot's map pose");
    for (std::size_t k = 0; k < tables.size(); ++k) {
      if (map_info.empty() || map_info[k].map_id <= 0 || map_info[k].map_id != tables[k].id) {
        throw Error("encodeTables: table map entry " + std::to_string(k) +
                    " needs id == map_id > 0");
      }
    }
  }
  findmug_lcm::tables_t msg;
  msg.utime = static_cast<std::int64_t>(utime);
  msg.seq = seq;
  msg.content = static_cast<std::int8_t>(content);
  msg.has_map_pose = map_pose.has_value();
  if (map_pose)
    msg.map_pose = encodeRobotPose(*map_pose);
  else
    msg.map_pose = encodeRobotPose(RobotPose{});
  msg.num_tables = static_cast<std::int32_t>(tables.size());
  for (std::size_t k = 0; k < tables.size(); ++k) {
    const TableCluster& t = tables[k];
    findmug_lcm::table_t out;
    out.id = t.id;
    const TableMapInfo info = map_info.empty() ? TableMapInfo{} : map_info[k];
    out.map_id = info.map_id;
    out.confirmed = info.confirmed;
    out.sightings = info.sightings;
    out.viewpoints = info.viewpoints;
    out.center[0] = t.center.x();
    out.center[1] = t.center.y();
    for (int i = 0; i < 3; ++i) out.centroid[i] = t.centroid[i];
    out.top_height = t.top_height;
    for (int i = 0; i < 2; ++i) {
      out.major_axis[i] = t.major_axis[i];
      out.minor_axis[i] = t.minor_axis[i];
      out.extents[i] = t.extents[i];
    }
    out.hull_size = static_cast<std::int32_t>(t.hull.size());
    for (const auto& p : t.hull) out.hull.push_back({p.x(), p.y()});
    out.point_count = t.point_count;
    out.mean_confidence = t.mean_confidence;
    out.num_search_positions = static_cast<std::int32_t>(t.search_positions.size());
    for (const auto& p : t.search_positions) out.search_positions.push_back(detail::searchPositionToLcm(p));
    if (map_pose) {
      const Eigen::Vector2d c =
          transformPointD(map_pose->pose, t.centroid.head<2>().cast<double>());
      out.map_centroid[0] = c.x();
      out.map_centroid[1] = c.y();
      out.map_centroid[2] = t.centroid.z();
      const Eigen::Vector2d center = transformPointD(map_pose->pose, t.center.cast<double>());
      out.map_center[0] = center.x();
      out.map_center[1] = center.y();
      for (const auto& p : t.hull) {
        const Eigen::Vector2d m = transformPointD(map_pose->pose, p.cast<double>());
        out.map_hull.push_back({m.x(), m.y()});
      }
      for (const auto& p : t.search_positions) {
        out.map_search_positions.push_back(toLcmMap(p, *map_pose));
      }
    } else {
      // The arrays share their length fields with the base-frame ones.
      for (int i = 0; i < 3; ++i) out.map_centroid[i] = 0.0;
      out.map_center[0] = out.map_center[1] = 0.0;
      out.map_hull.assign(t.hull.size(), std::vector<double>(2, 0.0));
      out.map_search_positions.assign(t.search_positions.size(), detail::searchPositionToLcm(SearchPosition{}));
    }
    msg.tables.push_back(std::move(out));
  }
  return msg;
}

TablesMessage decodeTables(const findmug_lcm::tables_t& msg, std::string_view channel) {
  constexpr std::string_view type = "tables_t";
  checkArraySize(msg.num_tables, msg.tables.size(), channel, type, "num_tables");
  if (msg.utime < 0) {
    throw Error(field(channel, type, "utime") + ": negative time " + std::to_string(msg.utime));
  }
  if (msg.content != findmug_lcm::tables_t::CONTENT_FRAME &&
      msg.content != findmug_lcm::tables_t::CONTENT_MAP) {
    throw Error(field(channel, type, "content") + ": unknown content id " +
                std::to_string(static_cast<int>(msg.content)) + " (expected " +
                std::to_string(static_cast<int>(findmug_lcm::tables_t::CONTENT_FRAME)) + " or " +
                std::to_string(static_cast<int>(findmug_lcm::tables_t::CONTENT_MAP)) + ")");
  }
  const bool map_content = msg.content == findmug_lcm::tables_t::CONTENT_MAP;
  if (map_content && !msg.has_map_pose) {
    throw Error(field(channel, type, "has_map_pose") +
                ": a table map message (CONTENT_MAP) must carry the robot's map pose");
  }
  TablesMessage out;
  out.utime = static_cast<std::uint64_t>(msg.utime);
  out.seq = msg.seq;
  out.content = map_content ? TablesContent::Map : TablesContent::Frame;
  if (msg.has_map_pose) {
    const auto& p = msg.map_pose;
    checkFinite({p.x, p.y, p.yaw}, field(channel, type, "map_pose"));
    if (p.utime < 0) {
      throw Error(field(channel, type, "map_pose.utime") + ": negative time " +
                  std::to_string(p.utime));
    }
    out.map_pose = RobotPose{static_cast<std::uint64_t>(p.utime), {p.x, p.y, p.yaw}};
  }
  for (std::size_t k = 0; k < msg.tables.size(); ++k) {
    const findmug_lcm::table_t& t = msg.tables[k];
    const std::string where = field(channel, type, "tables[" + std::to_string(k) + "]");
    checkArraySize(t.hull_size, t.hull.size(), channel, type,
                   "tables[" + std::to_string(k) + "].hull_size");
    checkArraySize(t.hull_size, t.map_hull.size(), channel, type,
                   "tables[" + std::to_string(k) + "].map_hull");
    checkArraySize(t.num_search_positions, t.search_positions.size(), channel, type,
                   "tables[" + std::to_string(k) + "].num_search_positions");
    checkArraySize(t.num_search_positions, t.map_search_positions.size(), channel, type,
                   "tables[" + std::to_string(k) + "].map_search_positions");
    checkFinite({t.centroid[0], t.centroid[1], t.centroid[2], t.top_height, t.major_axis[0],
                 t.major_axis[1], t.minor_axis[0], t.minor_axis[1], t.extents[0], t.extents[1]},
                where + ".centroid/top_height/axes/extents");
    const double major_norm = std::hypot(t.major_axis[0], t.major_axis[1]);
    const double minor_norm = std::hypot(t.minor_axis[0], t.minor_axis[1]);
    if (std::abs(major_norm - 1.0) > 1e-3 || std::abs(minor_norm - 1.0) > 1e-3) {
      throw Error(where + ": principal axes are not unit vectors (|major| " +
                  std::to_string(major_norm) + ", |minor| " + std::to_string(minor_norm) + ")");
    }
    if (t.extents[0] < 0 || t.extents[1] < 0) throw Error(where + ".extents: negative extent");
    if (t.point_count < 0) {
      throw Error(where + ".point_count: negative (" + std::to_string(t.point_count) + ")");
    }
    if (!(t.mean_confidence >= 0.0f && t.mean_confidence <= 1.0f)) {
      throw Error(where + ".mean_confidence: " + std::to_string(t.mean_confidence) +
                  " outside [0, 1]");
    }
    checkFinite({t.center[0], t.center[1]}, where + ".center");
    if (t.map_id < 0 || t.sightings < 0) {
      throw Error(where + ".map_id/sightings: negative (" + std::to_string(t.map_id) + ", " +
                  std::to_string(t.sightings) + ")");
    }
    if (t.viewpoints < 0 || t.viewpoints > t.sightings) {
      throw Error(where + ".viewpoints: " + std::to_string(t.viewpoints) + " outside [0, sightings " +
                  std::to_string(t.sightings) + "]");
    }
    if (t.confirmed && t.map_id == 0) {
      throw Error(where + ".confirmed: set for a table that is not in the map (map_id 0)");
    }
    if (map_content && (t.map_id == 0 || t.id != t.map_id)) {
      throw Error(where + ".map_id: a table map entry needs id == map_id > 0 (id " +
                  std::to_string(t.id) + ", map_id " + std::to_string(t.map_id) + ")");
    }
    out.map_info.push_back({t.map_id, t.confirmed != 0, t.sightings, t.viewpoints});
    TableCluster c;
    c.id = t.id;
    c.center = Eigen::Vector2f(static_cast<float>(t.center[0]), static_cast<float>(t.center[1]));
    c.centroid =
        Eigen::Vector3f(static_cast<float>(t.centroid[0]), static_cast<float>(t.centroid[1]),
                        static_cast<float>(t.centroid[2]));
    c.top_height = static_cast<float>(t.top_height);
    c.major_axis =
        Eigen::Vector2f(static_cast<float>(t.major_axis[0]), static_cast<float>(t.major_axis[1]));
    c.minor_axis =
        Eigen::Vector2f(static_cast<float>(t.minor_axis[0]), static_cast<float>(t.minor_axis[1]));
    c.extents = Eigen::Vector2f(static_cast<float>(t.extents[0]), static_cast<float>(t.extents[1]));
    for (const auto& p : t.hull) {
      checkFinite({p[0], p[1]}, where + ".hull");
      c.hull.emplace_back(static_cast<float>(p[0]), static_cast<float>(p[1]));
    }
    c.point_count = t.point_count;
    c.mean_confidence = t.mean_confidence;
    for (const auto& p : t.search_positions) {
      c.search_positions.push_back(detail::searchPositionFromLcm(p, where + ".search_positions"));
    }
    if (msg.has_map_pose) {
      MapFrameTable m;
      checkFinite({t.map_centroid[0], t.map_centroid[1], t.map_centroid[2]},
                  where + ".map_centroid");
      m.centroid = Eigen::Vector3d(t.map_centroid[0], t.map_centroid[1], t.map_centroid[2]);
      checkFinite({t.map_center[0], t.map_center[1]}, where + ".map_center");
      m.center = Eigen::Vector2d(t.map_center[0], t.map_center[1]);
      for (const auto& p : t.map_hull) {
        checkFinite({p[0], p[1]}, where + ".map_hull");
        m.hull.emplace_back(p[0], p[1]);
      }
      for (const auto& p : t.map_search_positions) {
        m.search_positions.push_back(detail::searchPositionFromLcm(p, where + ".map_search_positions"));
      }
      out.map_tables.push_back(std::move(m));
    }
    out.tables.push_back(std::move(c));
  }
  return out;
}

TablesMessage decodeTables(const void* data, std::size_t size, std::string_view channel) {
  return decodeTables(decodeMessage<findmug_lcm::tables_t>(data, size, channel), channel);
}

findmug_lcm::robot_pose_t encodeRobotPose(const RobotPose& pose) {
  findmug_lcm::robot_pose_t msg;
  msg.utime = static_cast<std::int64_t>(pose.utime);
  msg.x = pose.pose.x;
  msg.y = pose.pose.y;
  msg.yaw = pose.pose.yaw;
  return msg;
}

RobotPose decodeRobotPose(const void* data, std::size_t size, std::string_view channel) {
  const findmug_lcm::robot_pose_t msg =
      decodeMessage<findmug_lcm::robot_pose_t>(data, size, channel);
  checkFinite({msg.x, msg.y, msg.yaw}, field(channel, "robot_pose_t", "x/y/yaw"));
  if (msg.utime < 0) {
    throw Error(field(channel, "robot_pose_t", "utime") + ": negative time " +
                std::to_string(msg.utime));
  }
  return RobotPose{static_cast<std::uint64_t>(msg.utime), {msg.x, msg.y, msg.yaw}};
}

namespace {

void checkCommand(const CommandMessage& c, std::string_view channel) {
  const auto where = [&](std::string_view name) { return field(channel, "command_t", name); };
  if (c.request_id < 0) {
    throw Error(where("request_id") + ": negative id " + std::to_string(c.request_id));
  }
  if (c.command.empty() || c.command.size() > kMaxCommandName) {
    throw Error(where("command") + ": " + std::to_string(c.command.size()) +
                " characters, expected 1.." + std::to_string(kMaxCommandName));
  }
  for (const char ch : c.command) {
    if (!((ch >= 'a' && ch <= 'z') || ch == '_')) {
      throw Error(where("command") + ": character " +
                  std::to_string(static_cast<unsigned char>(ch)) + " is not one of [a-z_]");
    }
  }
  if (c.argument.size() > kMaxCommandArgument) {
    throw Error(where("argument") + ": " + std::to_string(c.argument.size()) +
                " characters, at most " + std::to_string(kMaxCommandArgument));
  }
  for (const char ch : c.argument) {
    const auto u = static_cast<unsigned char>(ch);
    if (u < 0x20 || u == 0x7f) {
      throw Error(where("argument") + ": control character " + std::to_string(u));
    }
  }
  if (c.command == "teach") (void)parseTeachArgument(c.argument, where("argument"));
}

// A decimal number of at most `max_digits` digits, no sign, no leading zero but "0".
std::optional<std::int64_t> plainNumber(std::string_view text, std::size_t max_digits) {
  if (text.empty() || text.size() > max_digits) return std::nullopt;
  if (text.size() > 1 && text[0] == '0') return std::nullopt;
  std::int64_t v = 0;
  for (const char ch : text) {
    if (ch < '0' || ch > '9') return std::nullopt;
    v = v * 10 + (ch - '0');
  }
  return v;
}

}  // namespace

TeachRequest parseTeachArgument(const std::string& argument, std::string_view where) {
  std::string quoted(1, '\'');
  quoted.append(argument, 0, 80);
  quoted.push_back('\'');
  const auto first = argument.find(' ');
  const auto second = first == std::string::npos ? first : argument.find(' ', first + 1);
  if (second == std::string::npos || argument.find(' ', second + 1) != std::string::npos) {
    throw Error(std::string(where) + ": teach takes \"NAME SEQ INDEX\" (three words, one space " +
                "apart), got " + quoted);
  }
  TeachRequest out;
  out.name = argument.substr(0, first);
  try {
    validateObjectModelName(out.name);
  } catch (const Error& e) {
    throw Error(std::string(where) + ": teach NAME: " + e.what());
  }
  const std::string_view text(argument);
  const auto seq = plainNumber(text.substr(first + 1, second - first - 1), 18);
  if (!seq) {
    throw Error(std::string(where) + ": teach SEQ: not a frame number (0..10^18) in " + quoted);
  }
  const auto index = plainNumber(text.substr(second + 1), 4);
  if (!index || *index > kMaxTeachIndex) {
    throw Error(std::string(where) + ": teach INDEX: not a candidate index (0.." +
                std::to_string(kMaxTeachIndex) + ") in " + quoted);
  }
  out.seq = *seq;
  out.index = static_cast<int>(*index);
  return out;
}

std::string teachArgument(const TeachRequest& request) {
  return request.name + " " + std::to_string(request.seq) + " " + std::to_string(request.index);
}

findmug_lcm::command_t encodeCommand(const CommandMessage& command) {
  checkCommand(command, "encodeCommand");
  findmug_lcm::command_t msg;
  msg.utime = static_cast<std::int64_t>(command.utime);
  msg.request_id = command.request_id;
  msg.command = command.command;
  msg.argument = command.argument;
  return msg;
}

CommandMessage decodeCommand(const void* data, std::size_t size, std::string_view channel) {
  const findmug_lcm::command_t msg = decodeMessage<findmug_lcm::command_t>(data, size, channel);
  if (msg.utime < 0) {
    throw Error(field(channel, "command_t", "utime") + ": negative time " +
                std::to_string(msg.utime));
  }
  CommandMessage out{static_cast<std::uint64_t>(msg.utime), msg.request_id, msg.command,
                     msg.argument};
  checkCommand(out, channel);
  return out;
}

}  // namespace findmug::io
