// findmug/oversegmentation.hpp — supervoxel patches and their adjacency graph.
//
// Segments are sets of pixels of the organized cloud. Two oversegmenters sit
// behind one interface: PCL's SupervoxelClustering (the paper's, the
// reference) and a fast one that works on the image grid.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "findmug/cloud.hpp"

namespace findmug {

struct Oversegmentation {
  int width = 0;
  int height = 0;
  // pixel -> segment index, -1 for pixels in no segment (invalid depth or
  // dropped small patches).
  std::vector<int> pixel_segment;
  // segment -> its pixels (indices into the organized grid)
  std::vector<std::vector<int>> segments;
  // undirected adjacency, each edge once with first < second
  std::vector<std::pair<int, int>> edges;
};

enum class OversegmenterKind { PclSupervoxels, Organized };

struct OversegmentationConfig {
  OversegmenterKind kind = OversegmenterKind::PclSupervoxels;
  float voxel_resolution_m = 0.01f;  // paper / Papon defaults
  float seed_resolution_m = 0.1f;
  float color_importance = 0.2f;
  float spatial_importance = 0.4f;
  float normal_importance = 1.0f;
  int min_segment_points = 20;  // smaller patches are dropped (unreliable features)
  int max_iterations = 5;       // organized oversegmenter: assignment/update rounds
  int search_window_factor = 2; // organized: search window = factor * grid step
};

class Oversegmenter {
 public:
  virtual ~Oversegmenter() = default;
  // `cloud_camera` and `normals_camera` in the camera optical frame.
  virtual Oversegmentation segment(const OrganizedCloud& cloud_camera,
                                   const NormalImage& normals_camera) const = 0;
  virtual std::string name() const = 0;
};

std::unique_ptr<Oversegmenter> makeOversegmenter(const OversegmentationConfig& config);

// Re-derives `edges`, drops segments below `min_points` and renumbers
// segments densely. Shared by both oversegmenters.
void finalizeOversegmentation(Oversegmentation& seg, int min_points);

// Quality against a ground-truth label image (same grid, 255 = void):
struct OversegmentationQuality {
  double boundary_recall = 0.0;          // GT boundary pixels within `tolerance_px` of a segment boundary
  double undersegmentation_error = 0.0;  // leakage across GT regions, as in Achanta et al. (SLIC)
  int segment_count = 0;
};
OversegmentationQuality evaluateOversegmentation(const Oversegmentation& seg,
                                                 const std::vector<std::uint8_t>& gt_labels,
                                                 int tolerance_px = 2);

}  // namespace findmug
