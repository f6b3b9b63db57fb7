// label_image_t <-> LabelImage / LabelImageMessage, with the camera view and colour JPEG
// (findmug/io/lcm_codec.hpp).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "findmug/io/lcm_codec.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "compression.hpp"
#include "findmug/common/error.hpp"
#include "findmug/frame/image_io.hpp"
#include "lcm_codec_checks.hpp"

namespace findmug::io {

using detail::checkArraySize;
using detail::checkDimensions;
using detail::checkFinite;
using detail::field;
using detail::finite;

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
        _mm_storeu_si128(
            reinterpret_cast<__m128i*>(quantised.data() + i),
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
      const std::size_t i =
          static_cast<std::size_t>(std::find_if(confidence, confidence + pixels,
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
                ": the 3x3 part is not a rotation (R R^T differs from I by " + std::to_string(off) +
                ")");
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
    throw Error("label image encode: JPEG quality " + std::to_string(quality) + " outside 1..100");
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

}  // namespace findmug::io
