// findmug/oversegmentation/oversegmentation.hpp — the frame split into patches (made as
// supervoxels) and their adjacency graph.
//
// Segments are sets of pixels of the organized cloud. Two oversegmenters sit
// behind one interface: PCL's SupervoxelClustering (the paper's, the
// reference) and a fast one that works on the image grid.
//
// The organized oversegmenter (issue 7) is SLIC/VCCS on the image grid:
// seeds on an adaptive grid whose pixel spacing follows depth so that seeds
// are about `seed_resolution_m` apart on the 3-D surface, iterative local
// assignment with PCL's distance (colour + 3-D position + normal, same
// importances), then connectivity enforcement. Its segment count is tuned to
// PCL's with `organized_seed_density`.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "findmug/cloud/cloud.hpp"

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
  // Organized by default: as accurate as PCL's on NYU and 9x faster at the same
  // segment count (BENCHMARKS.md); PclSupervoxels is the paper's, the reference.
  OversegmenterKind kind = OversegmenterKind::Organized;
  float voxel_resolution_m = 0.01f;  // paper / Papon defaults
  float seed_resolution_m = 0.1f;
  float color_importance = 0.2f;
  float spatial_importance = 0.4f;
  float normal_importance = 1.0f;
  int min_segment_points = 20;   // smaller patches are dropped (unreliable features)
  int max_iterations = 5;        // organized oversegmenter: assignment/update rounds
  int search_window_factor = 2;  // organized: search window = factor * grid step
  // Organized: seeds per seed_resolution_m^2 of surface; the segment count
  // is proportional to it. PCL's octree seeding gives about 1.5 (a surface
  // crosses more seed cubes than its area says): at 1.5 the count matches
  // PCL's on the 31 NYU frames at the same seed resolution (organized/PCL
  // mean 0.99, median 0.95, 19 of 31 frames within 15 %, range 0.66-1.50).
  float organized_seed_density = 1.5f;
};

// Throws findmug::Error naming the field when a value is out of range
// (non-positive resolutions, seed <= voxel resolution, negative or all-zero
// importances, iterations outside 1..100, window factor outside 1..10, ...).
void validateOversegmentationConfig(const OversegmentationConfig& config);

class Oversegmenter {
 public:
  virtual ~Oversegmenter() = default;
  // `cloud_camera` and `normals_camera` in the camera optical frame.
  // Throws findmug::Error when their sizes disagree.
  virtual Oversegmentation segment(const OrganizedCloud& cloud_camera,
                                   const NormalImage& normals_camera) const = 0;
  // The same result written into `out`, reusing the memory it holds (e.g.
  // the segmentation of an earlier frame: the per-segment pixel lists keep
  // their capacity, so a warm frame allocates next to nothing). What `out`
  // held before does not matter. The default just assigns segment().
  virtual void segmentInto(const OrganizedCloud& cloud_camera, const NormalImage& normals_camera,
                           Oversegmentation& out) const {
    out = segment(cloud_camera, normals_camera);
  }
  virtual std::string name() const = 0;
};

// Validates the config, then builds the oversegmenter of `config.kind`.
std::unique_ptr<Oversegmenter> makeOversegmenter(const OversegmentationConfig& config);

// Where finalizeOversegmentation takes the adjacency from.
enum class EdgeSource {
  ImageGrid,  // derive it: segments with 4-neighbouring pixels are adjacent
  Keep,       // keep `seg.edges` as given (ids as in the input pixel_segment), remapped
};

// Re-derives `edges`, drops segments below `min_points` and renumbers
// segments densely. Shared by both oversegmenters.
//
// Input: `pixel_segment` (width*height ids, -1 = none; ids need not be
// dense but must be < width*height). `segments` is ignored and rebuilt (its
// inner vectors keep their capacity, for callers that recycle `seg`).
// Kept ids are renumbered in increasing order, so the result is
// deterministic. With EdgeSource::Keep, edges touching a dropped segment are
// removed, self-loops and duplicates too. Throws findmug::Error on sizes or
// ids out of range.
void finalizeOversegmentation(Oversegmentation& seg, int min_points,
                              EdgeSource edge_source = EdgeSource::ImageGrid);

// Quality against a ground-truth label image (same grid, 255 = void).
//
// Boundary recall: a GT boundary pixel is a non-void pixel with a 4-neighbour
// of a different non-void label (boundaries to void are unknown, so they are
// ignored). It is recalled when a segment boundary pixel (a pixel whose
// segment id, -1 included, differs from a 4-neighbour's) lies within a
// (2*tolerance_px+1)^2 square around it.
//
// Undersegmentation error (Achanta et al., "SLIC superpixels", TPAMI 2012):
// over pixels P that are non-void and in a segment, N = |P|, GT regions g =
// 4-connected components of equal label, |s| = pixels of segment s in P:
//   UE = ( sum_g sum_{s : |s ∩ g| > 0.05 |s|} |s|  -  N ) / N
// i.e. the share of pixels by which segments leak out of the GT regions they
// overlap (0 when every segment lies inside one region). The 5 % overlap
// threshold is the paper's, against GT boundary imprecision.
//
// Both are NaN when undefined (no GT boundary pixel / N = 0).
struct OversegmentationQuality {
  double boundary_recall = 0.0;  // GT boundary pixels within `tolerance_px` of a segment boundary
  double undersegmentation_error = 0.0;  // leakage across GT regions, as in Achanta et al. (SLIC)
  int segment_count = 0;
};
OversegmentationQuality evaluateOversegmentation(const Oversegmentation& seg,
                                                 const std::vector<std::uint8_t>& gt_labels,
                                                 int tolerance_px = 2);

}  // namespace findmug
