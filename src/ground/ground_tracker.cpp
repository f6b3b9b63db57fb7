#include "findmug/ground/ground_tracker.hpp"

namespace findmug {

std::optional<GroundPlane> GroundTracker::groundOf(const OrganizedCloud& cloud_camera,
                                                   const NormalImage& normals_camera,
                                                   const GroundConfig& config) {
  if (config.reestimate_every_frames <= 1) return estimateGround(cloud_camera, normals_camera, config);
  if (plane_ && frames_since_estimate_ + 1 < config.reestimate_every_frames) {
    if (auto kept = confirmGround(cloud_camera, normals_camera, *plane_, config)) {
      ++frames_since_estimate_;
      return kept;
    }
  }
  plane_ = estimateGround(cloud_camera, normals_camera, config);
  frames_since_estimate_ = 0;
  return plane_;
}

}  // namespace findmug
