// findmug/tables/table_regions.hpp — one label per horizontal surface at table height.
//
// The MRF decides patch by patch, so a table top is often split between
// table, object, cabinet and chair (perf-log §1f: the commonest reason a
// true table is not matched). The region vote takes the regions of
// region_features.hpp (neighbouring patches merged while their normals and
// planes agree) and gives every patch of a region that is
//   - horizontal: region normal within tables.region_max_tilt_deg of +z,
//   - at table height: region centroid height within
//     [tables.min_table_height_m, tables.max_table_height_m],
//   - large enough: region area >= tables.region_min_area_m2,
// the label with the highest area-weighted mean of the model's p(y|x) over
// the region (patch weight = its pixel count), and that mean as its
// confidence. Other regions keep their (MRF) labels. It runs after the MRF,
// in Segmenter::classify and findmug-eval alike, when the model has region
// features (features.regions) and tables.region_vote is on.
#pragma once

#include <cstdint>
#include <vector>

#include "findmug/features/region_features.hpp"
#include "findmug/labels/labels.hpp"
#include "findmug/tables/tables.hpp"

namespace findmug {

struct RegionVoteResult {
  std::vector<std::uint8_t> labels;  // per segment
  std::vector<float> confidence;     // per segment (voted: the region's mean p of its label)
  int regions_voted = 0;             // regions that passed the tests
  int segments_changed = 0;          // segments whose label the vote changed
};

// `labels` and `confidence`: per segment, the MRF's (or forest's) answer;
// `probabilities`: the model's p(y|x) per segment; `weights`: pixel count
// per segment; `regions`: computeRegionFeatures of the same segmentation.
// Throws findmug::Error when the sizes disagree.
RegionVoteResult voteTableRegions(const std::vector<std::uint8_t>& labels,
                                  const std::vector<float>& confidence,
                                  const std::vector<ClassProbabilities>& probabilities,
                                  const std::vector<float>& weights, const RegionFeatures& regions,
                                  const TableConfig& config);

// The decision's bias towards tables (tables.table_weight): p(table) of
// every distribution multiplied by `weight`, then renormalised. Applied to
// the MRF's unaries (and so to the region vote): with weight > 1 a patch the
// forest finds about as likely table as object becomes table. 1 = unchanged.
void weightTableProbabilityInPlace(std::vector<ClassProbabilities>& p, float weight);
std::vector<ClassProbabilities> weightTableProbability(std::vector<ClassProbabilities> p,
                                                       float weight);

}  // namespace findmug
