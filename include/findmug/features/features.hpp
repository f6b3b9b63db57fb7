// findmug/features/features.hpp — the paper's 14-D feature vector per patch.
//
// Computed in the ground-aligned frame (see ground.hpp). Layout:
//   0 pointness    λ0            eigenvalues λ0 <= λ1 <= λ2 of the patch's
//   1 surfaceness  λ1 - λ0       scatter matrix, normalised by their sum so
//   2 linearness   λ2 - λ1       the three are scale-free
//   3 centroid height above ground (m)
//   4 min point height (m)
//   5 max point height (m)
//   6 angle between the mean normal and the ground normal +z (rad, 0..π):
//     0 = up-facing horizontal surface (floor, table top), π/2 = vertical
//     (wall), π = down-facing (ceiling); normals face the camera
//   7 circular standard deviation sqrt(-2 ln R) of the per-point normal
//     angles (rad), R = length of the mean unit phasor e^{iθ}
//   8..10  CIELAB mean L*, a*, b*
//   11..13 CIELAB standard deviation L*, a*, b*
#pragma once

#include <Eigen/Core>
#include <array>
#include <string_view>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/oversegmentation/oversegmentation.hpp"

namespace findmug {

inline constexpr int kFeatureDim = 14;
using FeatureVector = std::array<float, kFeatureDim>;

inline constexpr std::array<std::string_view, kFeatureDim> kFeatureNames = {
    "pointness", "surfaceness", "linearness", "centroid_height", "min_height", "max_height",
    "normal_angle", "normal_angle_circular_std", "lab_l_mean", "lab_a_mean", "lab_b_mean",
    "lab_l_std", "lab_a_std", "lab_b_std"};

// The sums a segment's features were computed from, kept so that a later
// step needing more of the same points (region features merge whole
// segments) does not make another pass over the pixels.
struct SegmentMoments {
  double count = 0;                                     // valid points
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();       // ground frame, metres
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();    // sum of (p - mean)(p - mean)^T
  Eigen::Vector3d normal_sum = Eigen::Vector3d::Zero();  // sum of the unit normals
  float max_z = 0.0f;                                   // highest point (m)
};

struct SegmentFeatures {
  std::vector<FeatureVector> features;     // one per segment
  std::vector<Eigen::Vector3f> centroids;  // ground frame, metres (used by the MRF)
  std::vector<SegmentMoments> moments;     // one per segment (computeFeatures fills them)
  // Region features (region_features.hpp), row-major, kRegionFeatureDim per
  // segment; empty unless features.regions is on.
  std::vector<float> regions;
  // Scene features (scene_features.hpp), row-major, kSceneFeatureDim per
  // segment; empty unless features.scene is on. They follow the region
  // features in a model's rows.
  std::vector<float> scene;
  // Object features (object_features.hpp), row-major, as many per segment
  // as features.objects_columns selects; empty unless features.objects is on. They follow the scene
  // features in a model's rows.
  std::vector<float> objects;
  // Per segment, the object candidate it belongs to (an index into
  // ObjectFeatures::groups, object_features.hpp), -1 for a floor, wall or
  // ceiling plane; empty unless features.objects is on. The MRF's unaries
  // use it (mrf.object_consistency, object_consistency.hpp).
  std::vector<int> object_group;
};

// sRGB (0..255) to CIELAB (D65).
Eigen::Vector3f rgbToLab(const Rgb8& rgb);

// Features of one patch given its points/normals/colours in the ground frame.
FeatureVector computePatchFeatures(const std::vector<Eigen::Vector3f>& points_ground,
                                   const std::vector<Eigen::Vector3f>& normals_ground,
                                   const std::vector<Rgb8>& colors);

// Features of every segment. `cloud_ground` and `normals_ground` share the
// oversegmentation's grid.
SegmentFeatures computeFeatures(const OrganizedCloud& cloud_ground,
                                const NormalImage& normals_ground,
                                const Oversegmentation& segmentation);
// The same into `out` (features, centroids and moments; regions, scene and
// objects are emptied), reusing the memory it holds: a stream of frames then allocates
// nothing here (Segmenter::recycle).
void computeFeaturesInto(const OrganizedCloud& cloud_ground, const NormalImage& normals_ground,
                         const Oversegmentation& segmentation, SegmentFeatures& out);

}  // namespace findmug
