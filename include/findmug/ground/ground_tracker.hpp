// findmug/ground/ground_tracker.hpp — the floor of a stream of frames from one mount, kept
// from frame to frame (ground.reestimate_every_frames > 1).
//
// The tracker belongs to whoever runs the stream (findmugd's prepare step, frame_cpu,
// findmug-sequential, the walks and benchmarks), not to the model: a model swapped in keeps
// the floor found so far. Plain data in and out, no lock: one stream is prepared on one
// thread at a time, and its owner says which.
#pragma once

#include <optional>

#include "findmug/cloud/cloud.hpp"
#include "findmug/ground/ground.hpp"

namespace findmug {

class GroundTracker {
 public:
  // estimateGround, or, with config.reestimate_every_frames > 1, the plane estimated in an
  // earlier frame while confirmGround accepts it and fewer than reestimate_every_frames
  // frames have passed since that estimate. With 1 every frame is its own estimate and the
  // tracker keeps nothing.
  std::optional<GroundPlane> groundOf(const OrganizedCloud& cloud_camera,
                                      const NormalImage& normals_camera,
                                      const GroundConfig& config);

  // The plane as last estimated (its support is the reference confirmGround compares
  // with); nullopt before the first estimate or after one that found none.
  const std::optional<GroundPlane>& plane() const { return plane_; }
  // Frames that kept the plane since it was estimated.
  int framesSinceEstimate() const { return frames_since_estimate_; }

 private:
  std::optional<GroundPlane> plane_;
  int frames_since_estimate_ = 0;
};

}  // namespace findmug
