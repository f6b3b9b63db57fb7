// Texture features: the frame's L* image by table lookups, a 3x3 Sobel at
// every segmented pixel off the image border, and per segment the sums of
// the gradient magnitude, the structure tensor and the edge pixels.
#include "findmug/features/texture_features.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "findmug/common/error.hpp"
#include "common/scratch.hpp"

namespace findmug {

namespace {

// sRGB (8 bit) -> CIELAB L* (D65): Y as the sum of three per-channel tables
// (the linearised channel times its weight in Y), then L* = 116 f(Y) - 16
// from a linearly interpolated table of f on [0, 1]. The interpolation error
// is below 0.01 L*, far below what one step of 8-bit input changes.
class LightnessTable {
 public:
  LightnessTable() {
    constexpr double kYWeight[3] = {0.2126729, 0.7151522, 0.0721750};  // sRGB -> Y (D65)
    for (int c = 0; c < 256; ++c) {
      const double v = c / 255.0;
      const double linear = v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
      for (int k = 0; k < 3; ++k) weighted_[k][c] = static_cast<float>(kYWeight[k] * linear);
    }
    constexpr double kEpsilon = 216.0 / 24389.0;  // (6/29)^3
    constexpr double kKappa = 24389.0 / 27.0;     // (29/3)^3
    for (int k = 0; k <= kSteps; ++k) {
      const double y = static_cast<double>(k) / kSteps;
      const double f = y > kEpsilon ? std::cbrt(y) : (kKappa * y + 16.0) / 116.0;
      lightness_[k] = static_cast<float>(116.0 * f - 16.0);
    }
    lightness_[kSteps + 1] = lightness_[kSteps];  // the interpolation may read one past Y = 1
  }

  float operator()(const Rgb8& rgb) const {
    const float y = std::clamp(weighted_[0][rgb.r] + weighted_[1][rgb.g] + weighted_[2][rgb.b],
                               0.0f, 1.0f);
    const float at = y * kSteps;
    const int k = static_cast<int>(at);
    const float t = at - static_cast<float>(k);
    return lightness_[k] + t * (lightness_[k + 1] - lightness_[k]);
  }

 private:
  static constexpr int kSteps = 4096;
  float weighted_[3][256];
  float lightness_[kSteps + 2];
};

const LightnessTable& lightnessTable() {
  static const LightnessTable table;
  return table;
}

struct TextureSums {
  double count = 0;      // pixels with a gradient
  double magnitude = 0;  // sum of |∇L*|
  double xx = 0, yy = 0, xy = 0;  // structure tensor
  double edges = 0;      // pixels with |∇L*| above the threshold
};

}  // namespace

std::vector<float> computeTextureFeatures(const OrganizedCloud& cloud,
                                          const Oversegmentation& segmentation,
                                          const TextureConfig& config) {
  std::vector<float> out;
  computeTextureFeaturesInto(cloud, segmentation, config, out);
  return out;
}

void computeTextureFeaturesInto(const OrganizedCloud& cloud, const Oversegmentation& segmentation,
                                const TextureConfig& config, std::vector<float>& out) {
  const std::size_t pixels = segmentation.pixel_segment.size();
  const int width = segmentation.width, height = segmentation.height;
  if (cloud.colors.size() != pixels || cloud.width != width || cloud.height != height ||
      static_cast<std::size_t>(width) * static_cast<std::size_t>(height) != pixels) {
    throw Error("computeTextureFeatures: grids disagree: segmentation has " +
                std::to_string(width) + " x " + std::to_string(height) + " (" +
                std::to_string(pixels) + " pixels), cloud " + std::to_string(cloud.width) +
                " x " + std::to_string(cloud.height) + " with " +
                std::to_string(cloud.colors.size()) + " colours");
  }
  if (!(config.edge_threshold > 0.0f))
    throw Error("computeTextureFeatures: features.texture_edge_threshold = " +
                std::to_string(config.edge_threshold) + " must be positive");
  const std::size_t n = segmentation.segments.size();
  out.assign(n * kTextureFeatureDim, 0.0f);
  if (n == 0 || width < 3 || height < 3) return;

  thread_local std::vector<float> lightness_tls;
  thread_local std::vector<TextureSums> sums_tls;
  detail::Borrowed lightness_buffer(lightness_tls);
  detail::Borrowed sums_buffer(sums_tls);
  std::vector<float>& lightness = *lightness_buffer;
  std::vector<TextureSums>& sums = *sums_buffer;
  const LightnessTable& table = lightnessTable();
  lightness.resize(pixels);
  for (std::size_t i = 0; i < pixels; ++i) lightness[i] = table(cloud.colors[i]);
  sums.assign(n, TextureSums{});

  const float threshold = config.edge_threshold;
  const std::size_t w = static_cast<std::size_t>(width);
  for (int r = 1; r + 1 < height; ++r) {
    const std::size_t row = static_cast<std::size_t>(r) * w;
    const int* segment = segmentation.pixel_segment.data() + row;
    const float* up = lightness.data() + row - w;
    const float* mid = lightness.data() + row;
    const float* down = lightness.data() + row + w;
    for (int c = 1; c + 1 < width; ++c) {
      const int s = segment[c];
      if (s < 0) continue;
      // Sobel, divided by 8: L* units per pixel.
      const float gx = ((up[c + 1] + 2.0f * mid[c + 1] + down[c + 1]) -
                        (up[c - 1] + 2.0f * mid[c - 1] + down[c - 1])) * 0.125f;
      const float gy = ((down[c - 1] + 2.0f * down[c] + down[c + 1]) -
                        (up[c - 1] + 2.0f * up[c] + up[c + 1])) * 0.125f;
      const float magnitude = std::sqrt(gx * gx + gy * gy);
      TextureSums& t = sums[static_cast<std::size_t>(s)];
      t.count += 1.0;
      t.magnitude += magnitude;
      t.xx += gx * gx;
      t.yy += gy * gy;
      t.xy += gx * gy;
      if (magnitude > threshold) t.edges += 1.0;
    }
  }

  for (std::size_t s = 0; s < n; ++s) {
    const TextureSums& t = sums[s];
    if (t.count == 0) continue;
    float* row = out.data() + s * kTextureFeatureDim;
    row[0] = static_cast<float>(t.magnitude / t.count);
    const double trace = t.xx + t.yy;
    // Below (1e-3 L*/px)² per pixel the patch is flat: no direction.
    if (trace > 1e-6 * t.count) {
      const double spread = std::hypot(t.xx - t.yy, 2.0 * t.xy);  // λ1 - λ2
      row[1] = static_cast<float>(std::min(1.0, spread / trace));
      // The first eigenvector's angle from the image x axis, in (-π/2, π/2].
      const double theta = 0.5 * std::atan2(2.0 * t.xy, t.xx - t.yy);
      row[2] = static_cast<float>(std::numbers::pi / 2 - std::abs(theta));
    }
    row[3] = static_cast<float>(t.edges / t.count);
  }
}

}  // namespace findmug
