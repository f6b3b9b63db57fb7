// findmug/frame/depth_holes.hpp — depth for the short gaps a live depth camera leaves.
//
// The NYU frames the forest learns from hold hole-filled depth; a live Kinect
// or Xtion gives raw depth with gaps: the projector's shadow beside near
// objects, ragged depth edges, dark or shiny surfaces (a varnished table top
// most of all). Patches then break up, table tops lose area and the
// features stop looking like the training frames' (raw-like copies lose 14
// points of table pixels: docs/measurements/depth-holes.md).
// fillDepthHoles() gives the short gaps depth before the cloud is made:
//   1. along each column, then along each row, a run of pixels without depth
//      between two pixels with depth, at most `max_run_px` long, is filled;
//   2. when its two ends lie on one smooth surface (depths within
//      `smooth_tolerance` of the farther one) the run is interpolated
//      linearly between them (a specular spot on a table top);
//   3. otherwise it takes the farther end's depth (a step: a Kinect's shadow
//      lies on the surface behind the near object, as NYU's own fill assumes);
//   4. runs that touch the image border or are longer stay without depth (a
//      window, a mirror, what lies beyond the camera's range).
// The filled pixels are points like the others for every later stage. One
// pass over the image per direction, in memory order, in place; one int per
// column of per-thread scratch.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace findmug {

struct DepthHoleFillConfig {
  int max_run_px = 0;            // cloud.fill_depth_max_run_px (0 = off, up to 10000)
  float smooth_tolerance = 0.03f;  // cloud.fill_depth_smooth_tolerance (0..1)
};

// Throws findmug::Error naming the setting when a value is out of range.
void validateDepthHoleFillConfig(const DepthHoleFillConfig& config);

// Fills `depth_mm` (width x height, row-major, 0 = no depth) in place as
// above. Returns how many pixels it filled. Throws findmug::Error when the
// size is not width x height or `config` is out of range.
std::size_t fillDepthHoles(std::vector<std::uint16_t>& depth_mm, int width, int height,
                           const DepthHoleFillConfig& config);

}  // namespace findmug
