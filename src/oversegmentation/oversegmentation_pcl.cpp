// The reference oversegmenter: PCL's SupervoxelClustering (VCCS, Papon et
// al. 2013), as used by the paper. PCL types stay inside this file.
//
// The organized cloud goes in as an organized pcl::PointCloud so that PCL
// bins voxels in its "single camera" space (x/z, y/z, ln z: voxels grow with
// depth like the Kinect's point spacing). Our normals are handed over, so
// PCL does not recompute them. Every valid input pixel gets the label of the
// voxel it fell into; the adjacency is PCL's voxel adjacency between
// supervoxels, renumbered with the segments.
//
// Cost: 150-360 ms per 640x480 frame on this machine; the organized
// oversegmenter (oversegmentation_organized.cpp) is the fast alternative.
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/segmentation/supervoxel_clustering.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <string>

#include "findmug/common/error.hpp"
#include "findmug/oversegmentation/oversegmentation.hpp"
#include "oversegmentation/oversegmentation_internal.hpp"

namespace findmug {
namespace {

class PclSupervoxelOversegmenter final : public Oversegmenter {
 public:
  explicit PclSupervoxelOversegmenter(const OversegmentationConfig& config) : config_(config) {}

  std::string name() const override { return "pcl_supervoxels"; }

  Oversegmentation segment(const OrganizedCloud& cloud, const NormalImage& normals) const override {
    detail::checkOversegmentationInput(cloud, normals, "PCL supervoxels");
    const int w = cloud.width;
    const int h = cloud.height;
    const std::size_t n = cloud.size();

    Oversegmentation seg;
    seg.width = w;
    seg.height = h;
    seg.pixel_segment.assign(n, -1);

    const float nan = std::numeric_limits<float>::quiet_NaN();
    auto pcl_cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZRGBA>>(
        static_cast<std::uint32_t>(w), static_cast<std::uint32_t>(h));
    auto pcl_normals = std::make_shared<pcl::PointCloud<pcl::Normal>>(
        static_cast<std::uint32_t>(w), static_cast<std::uint32_t>(h));
    pcl_cloud->is_dense = false;
    std::size_t valid_count = 0;
    for (std::size_t i = 0; i < n; ++i) {
      pcl::PointXYZRGBA& p = (*pcl_cloud)[i];
      pcl::Normal& nm = (*pcl_normals)[i];
      if (!cloud.valid(i)) {
        p.x = p.y = p.z = nan;
        nm.normal_x = nm.normal_y = nm.normal_z = 0.0f;
        nm.curvature = 0.0f;
        continue;
      }
      const Eigen::Vector3f& q = cloud.points[i];
      // Points with z <= 0 have no single-camera transform (ln z); they cannot
      // come from a camera, so they are treated as invalid.
      if (!(q.z() > 0.0f)) {
        p.x = p.y = p.z = nan;
        nm.normal_x = nm.normal_y = nm.normal_z = 0.0f;
        nm.curvature = 0.0f;
        continue;
      }
      ++valid_count;
      p.x = q.x();
      p.y = q.y();
      p.z = q.z();
      p.r = cloud.colors[i].r;
      p.g = cloud.colors[i].g;
      p.b = cloud.colors[i].b;
      p.a = 255;
      // A valid point without a normal adds a zero vector to its voxel's
      // normal sum (PCL sums then normalises), so it does not poison it.
      const Eigen::Vector3f& nv = normals.normals[i];
      if (nv.allFinite()) {
        nm.normal_x = nv.x();
        nm.normal_y = nv.y();
        nm.normal_z = nv.z();
      } else {
        nm.normal_x = nm.normal_y = nm.normal_z = 0.0f;
      }
      nm.curvature = 0.0f;
    }
    if (valid_count == 0) {
      finalizeOversegmentation(seg, config_.min_segment_points);
      return seg;
    }

    pcl::SupervoxelClustering<pcl::PointXYZRGBA> clustering(config_.voxel_resolution_m,
                                                            config_.seed_resolution_m);
    clustering.setUseSingleCameraTransform(true);
    clustering.setColorImportance(config_.color_importance);
    clustering.setSpatialImportance(config_.spatial_importance);
    clustering.setNormalImportance(config_.normal_importance);
    clustering.setInputCloud(pcl_cloud);
    clustering.setNormalCloud(pcl_normals);
    std::map<std::uint32_t, pcl::Supervoxel<pcl::PointXYZRGBA>::Ptr> supervoxels;
    clustering.extract(supervoxels);

    // Labels start at 1, 0 = in no supervoxel. They are bounded by the seed
    // count, hence by the pixel count, which finalizeOversegmentation needs.
    const pcl::PointCloud<pcl::PointXYZL>::Ptr labeled = clustering.getLabeledCloud();
    if (labeled->size() != n) {
      throw Error("PCL supervoxels: labelled cloud has " + std::to_string(labeled->size()) +
                  " points, input has " + std::to_string(n));
    }
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t label = (*labeled)[i].label;
      if (label > 0 && label < n) seg.pixel_segment[i] = static_cast<int>(label);
    }

    std::multimap<std::uint32_t, std::uint32_t> adjacency;
    clustering.getSupervoxelAdjacency(adjacency);
    seg.edges.reserve(adjacency.size());
    for (const auto& [a, b] : adjacency) {
      if (a == b || a == 0 || b == 0 || a >= n || b >= n) continue;
      seg.edges.emplace_back(static_cast<int>(std::min(a, b)), static_cast<int>(std::max(a, b)));
    }
    finalizeOversegmentation(seg, config_.min_segment_points, EdgeSource::Keep);
    return seg;
  }

 private:
  OversegmentationConfig config_;
};

}  // namespace

namespace detail {
std::unique_ptr<Oversegmenter> makePclSupervoxelOversegmenter(
    const OversegmentationConfig& config) {
  return std::make_unique<PclSupervoxelOversegmenter>(config);
}
}  // namespace detail

}  // namespace findmug
