// Texture features on a hand-made image whose answers are known: vertical,
// horizontal and diagonal stripes and a flat patch, each patch far enough
// from the others that its Sobel windows see only its own pattern.
#include "findmug/features/texture_features.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/features/features.hpp"

namespace findmug {
namespace {

using ::testing::HasSubstr;

enum Patch { kVertical, kHorizontal, kDiagonal, kFlat, kEmpty, kBorderOnly };
enum Column { kGradientMean, kCoherence, kOrientation, kEdgeDensity };

constexpr std::uint8_t kDark = 90, kBright = 160;
constexpr float kHalfPi = std::numbers::pi_v<float> / 2;

// Stripes two pixels wide: the pattern dark, dark, bright, bright along `t`.
Rgb8 stripe(int t) {
  const std::uint8_t v = (t / 2) % 2 == 0 ? kDark : kBright;
  return Rgb8{v, v, v};
}

// An 80 x 12 image in four 20-column regions: stripes varying along x
// (vertical stripes), along y (horizontal), along x + y (diagonal), flat
// grey. Each patch covers its region's columns but the two at either side,
// and every row (rows 0 and 11 are the image border: no gradient there).
// kEmpty has no pixels, kBorderOnly only pixels of the top row.
struct Image {
  static constexpr int kWidth = 80, kHeight = 12;
  OrganizedCloud cloud;
  Oversegmentation seg;

  Image() {
    cloud.width = seg.width = kWidth;
    cloud.height = seg.height = kHeight;
    cloud.points.assign(kWidth * kHeight, Eigen::Vector3f(1.0f, 0.0f, 0.0f));
    cloud.colors.resize(kWidth * kHeight);
    seg.pixel_segment.assign(kWidth * kHeight, -1);
    seg.segments.resize(6);
    for (int r = 0; r < kHeight; ++r) {
      for (int c = 0; c < kWidth; ++c) {
        const int i = r * kWidth + c;
        const int region = c / 20;
        const Rgb8 grey{128, 128, 128};
        cloud.colors[i] = region == 0   ? stripe(c)
                          : region == 1 ? stripe(r)
                          : region == 2 ? stripe(c + r)
                                        : grey;
        const int x = c % 20;
        if (x >= 2 && x < 18) {
          const int s = region == 3 && r == 0 ? kBorderOnly : region;
          seg.pixel_segment[i] = s;
          seg.segments[s].push_back(i);
        }
      }
    }
  }
};

float lightness(std::uint8_t v) { return rgbToLab(Rgb8{v, v, v}).x(); }

TEST(TextureFeatures, StripesGiveTheirOrientationAndFullCoherence) {
  const Image image;
  const std::vector<float> v = computeTextureFeatures(image.cloud, image.seg, TextureConfig{});
  ASSERT_EQ(v.size(), 6u * kTextureFeatureDim);
  auto at = [&](Patch s, Column k) { return v[s * kTextureFeatureDim + k]; };
  // With the pattern dark, dark, bright, bright, the pixels either side of
  // every pixel differ by one step: the Sobel (divided by 8) is half the step.
  const float step = lightness(kBright) - lightness(kDark);
  // So that every stripe pixel is above the default threshold of 8.
  ASSERT_GT(step / (2 * std::sqrt(2.0f)), 8.5f);
  EXPECT_NEAR(at(kVertical, kGradientMean), step / 2, 0.05f);
  EXPECT_NEAR(at(kHorizontal, kGradientMean), step / 2, 0.05f);
  // Along x + y both Sobel components are a quarter step: |∇| = step / (2√2).
  EXPECT_NEAR(at(kDiagonal, kGradientMean), step / (2 * std::sqrt(2.0f)), 0.05f);
  for (Patch s : {kVertical, kHorizontal, kDiagonal}) {
    EXPECT_NEAR(at(s, kCoherence), 1.0f, 1e-4f) << s;
    EXPECT_FLOAT_EQ(at(s, kEdgeDensity), 1.0f) << s;
  }
  // Vertical stripes: the gradient is horizontal, at π/2 from the vertical.
  EXPECT_NEAR(at(kVertical, kOrientation), kHalfPi, 1e-4f);
  EXPECT_NEAR(at(kHorizontal, kOrientation), 0.0f, 1e-4f);
  EXPECT_NEAR(at(kDiagonal, kOrientation), kHalfPi / 2, 1e-4f);
}

TEST(TextureFeatures, FlatEmptyAndBorderPatchesAreZero) {
  const Image image;
  const std::vector<float> v = computeTextureFeatures(image.cloud, image.seg, TextureConfig{});
  for (Patch s : {kFlat, kEmpty, kBorderOnly}) {
    for (int k = 0; k < kTextureFeatureDim; ++k)
      EXPECT_EQ(v[s * kTextureFeatureDim + k], 0.0f) << "patch " << s << " column " << k;
  }
}

TEST(TextureFeatures, EdgeDensityFollowsTheThreshold) {
  const Image image;
  const float step = lightness(kBright) - lightness(kDark);
  TextureConfig config;
  // Between the diagonal stripes' |∇| (step / (2√2)) and the others' (step / 2).
  config.edge_threshold = 0.43f * step;
  const std::vector<float> v = computeTextureFeatures(image.cloud, image.seg, config);
  EXPECT_FLOAT_EQ(v[kVertical * kTextureFeatureDim + kEdgeDensity], 1.0f);
  EXPECT_FLOAT_EQ(v[kHorizontal * kTextureFeatureDim + kEdgeDensity], 1.0f);
  EXPECT_EQ(v[kDiagonal * kTextureFeatureDim + kEdgeDensity], 0.0f);
  // The other columns do not depend on it.
  const std::vector<float> plain = computeTextureFeatures(image.cloud, image.seg, TextureConfig{});
  for (int s = 0; s < 6; ++s) {
    for (int k : {kGradientMean, kCoherence, kOrientation})
      EXPECT_EQ(v[s * kTextureFeatureDim + k], plain[s * kTextureFeatureDim + k]);
  }
}

// A patch half on stripes and half on flat grey (its pixels need not touch:
// the gradient reads the image, not the segments): half its pixels are
// edges, its mean gradient is halved, and the flat half adds no direction.
TEST(TextureFeatures, ColumnsAreSharesOverThePatchsPixels) {
  Image image;
  for (int i : image.seg.segments[kFlat]) {
    image.seg.pixel_segment[i] = kVertical;
    image.seg.segments[kVertical].push_back(i);
  }
  image.seg.segments[kFlat].clear();
  const std::vector<float> v = computeTextureFeatures(image.cloud, image.seg, TextureConfig{});
  const float step = lightness(kBright) - lightness(kDark);
  EXPECT_FLOAT_EQ(v[kVertical * kTextureFeatureDim + kEdgeDensity], 0.5f);
  EXPECT_NEAR(v[kVertical * kTextureFeatureDim + kGradientMean], step / 4, 0.05f);
  EXPECT_NEAR(v[kVertical * kTextureFeatureDim + kCoherence], 1.0f, 1e-4f);
  EXPECT_NEAR(v[kVertical * kTextureFeatureDim + kOrientation], kHalfPi, 1e-4f);
  for (int k = 0; k < kTextureFeatureDim; ++k) EXPECT_EQ(v[kFlat * kTextureFeatureDim + k], 0.0f);
}

TEST(TextureFeatures, RefusesMismatchedGridsAndThresholds) {
  Image image;
  TextureConfig bad;
  bad.edge_threshold = 0.0f;
  try {
    computeTextureFeatures(image.cloud, image.seg, bad);
    FAIL() << "expected a threshold of 0 to be refused";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("features.texture_edge_threshold"));
  }
  image.cloud.colors.pop_back();
  try {
    computeTextureFeatures(image.cloud, image.seg, TextureConfig{});
    FAIL() << "expected mismatched grids to be refused";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("grids disagree"));
  }
}

// The buffer-reusing variant gives the same values, also after a larger frame.
TEST(TextureFeatures, IntoReusesItsOutput) {
  const Image image;
  const std::vector<float> want = computeTextureFeatures(image.cloud, image.seg, TextureConfig{});
  std::vector<float> out(1000, 7.0f);
  computeTextureFeaturesInto(image.cloud, image.seg, TextureConfig{}, out);
  EXPECT_EQ(out, want);
}

}  // namespace
}  // namespace findmug
