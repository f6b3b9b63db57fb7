// findmug/features/texture_features.hpp — the 2-D image texture of a patch.
//
// The 14 paper features and the region, scene and object features describe a
// patch's shape, height and the mean and spread of its CIELAB colour, but
// nothing about how that colour is laid out in the image. Classes the forest
// confuses often differ there: a cabinet front and a wall are both vertical
// and plain-coloured on average, but the cabinet has door edges, handles and
// wood grain; a chair has bars and a seat edge where a table top or the floor
// is a plain plane. Four columns from the gradient of CIELAB L* (3x3 Sobel,
// divided by 8: L* units per pixel) at the patch's pixels:
//   texture_gradient_mean   mean gradient magnitude |∇L*| (L*/px): 0 on a
//                           flat colour, large on grain, print or clutter
//   texture_coherence       (λ1 - λ2) / (λ1 + λ2) of the patch's structure
//                           tensor J = Σ ∇L* ∇L*ᵀ (λ1 >= λ2 its eigenvalues):
//                           1 where the gradients share one direction
//                           (stripes, grain, a door edge), 0 where they point
//                           every way (noise, clutter) or there are none
//   texture_orientation     angle between the dominant gradient direction
//                           (J's first eigenvector) and the image vertical,
//                           folded to 0..π/2 (rad): π/2 for vertical edges
//                           (door and cabinet sides, chair legs), 0 for
//                           horizontal ones (shelf and drawer edges); 0 where
//                           the patch has no gradient
//   texture_edge_density    share of the patch's pixels whose |∇L*| exceeds
//                           features.texture_edge_threshold (L*/px)
// The gradient at a pixel reads its 8 neighbours' colours whatever their
// depth or segment, so a patch's boundary edges count too. Pixels on the
// image border have no gradient and are left out.
// Cost: one pass over the frame's pixels (L* by table lookups) and one 3x3
// Sobel per segmented pixel.
#pragma once

#include <array>
#include <string_view>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/supervoxels/oversegmentation.hpp"

namespace findmug {

struct TextureConfig {
  bool enabled = false;         // features.texture
  float edge_threshold = 8.0f;  // features.texture_edge_threshold: |∇L*| of an edge pixel (L*/px)
};

inline constexpr int kTextureFeatureDim = 4;
inline constexpr std::array<std::string_view, kTextureFeatureDim> kTextureFeatureNames = {
    "texture_gradient_mean", "texture_coherence", "texture_orientation", "texture_edge_density"};

// `cloud` (its colours; camera or ground frame alike) shares the
// oversegmentation's grid. Returns kTextureFeatureDim values per segment,
// row-major; a segment with no pixel off the image border gets zeros. Throws
// findmug::Error when the grids disagree or the threshold is not positive.
std::vector<float> computeTextureFeatures(const OrganizedCloud& cloud,
                                          const Oversegmentation& segmentation,
                                          const TextureConfig& config);
// The same into `out`, reusing the memory it holds.
void computeTextureFeaturesInto(const OrganizedCloud& cloud, const Oversegmentation& segmentation,
                                const TextureConfig& config, std::vector<float>& out);

}  // namespace findmug
