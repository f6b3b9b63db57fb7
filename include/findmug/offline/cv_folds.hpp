// findmug/offline/cv_folds.hpp — how frames are split for cross-validation and for
// learning curves: scenes of frames, folds that never split a scene, training
// subsets of N frames, and the a + b*ln(N) trend fitted to a learning curve.
//
// A frame's scene comes from the `scene` column of its folder's frames.csv
// when there is one. Otherwise, for NYU Depth V2 frames, from their NYU index
// (the `nyu_index` column, or the .mat file's order). NYU's labelled set is
// stored scene after scene, and its official train/test split is by scene:
// - with the split (the test indices, nyuv2_meta/split_test_indices.txt), a
//   scene is a run of consecutive NYU indices on one side of the split; this
//   never splits a scene, whichever frames are present (it may join
//   neighbouring scenes of one side);
// - without it, sorted by index, a frame whose index is more than `gap` above
//   the previous frame's starts a new scene; on the 46 shared test frames
//   together every gap above 2 has a train index in it and gap 2 keeps each
//   room of the images together, but with frames missing (one folder alone)
//   a room can be split (docs/measurements/eval-protocol.md lists the check).
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace findmug {

// One row of a dataset folder's frames.csv (header with at least `frame`;
// `nyu_index` and `scene` are optional columns).
struct FrameListing {
  std::optional<long> nyu_index;
  std::string scene;  // "" when the file has no scene column
};

// Reads DIR/frames.csv; an absent file gives an empty map. Errors name the
// file and line (a row with the wrong number of fields, a bad nyu_index, a
// frame listed twice).
std::map<std::string, FrameListing> loadFrameListing(const std::string& dir);
std::map<std::string, FrameListing> parseFrameListing(const std::string& csv_text,
                                                      const std::string& source);

// Scene keys for NYU indices by the index-run rule above (one key per input,
// in input order): "nyu<first index of the run>". Throws for gap < 0.
std::vector<std::string> nyuIndexRunScenes(const std::vector<long>& nyu_indices, int gap);

// The official test indices from a file of whitespace-separated NYU indices
// (split_test_indices.txt); errors name the file and the bad entry.
std::vector<long> loadNyuTestIndices(const std::string& path);
std::vector<long> parseNyuTestIndices(const std::string& text, const std::string& source);

// Scene keys for NYU indices by runs of the official split (see above): one
// key per input, "nyu<first index of the run>". Throws for an index < 1.
std::vector<std::string> nyuSplitRunScenes(const std::vector<long>& nyu_indices,
                                           const std::vector<long>& test_indices);

// Fold (0..folds-1) of each frame, contiguous blocks in the given order:
// frame i goes to fold i * folds / n.
std::vector<int> blockFolds(std::size_t frames, int folds);

// Fold of each frame with every scene whole in one fold. Scenes are placed
// largest first (ties: the scene whose first frame comes first) into the
// fold holding the fewest frames so far (ties: the lowest fold). Deterministic;
// a fold may stay empty when there are fewer scenes than folds. Throws for
// folds < 1.
std::vector<int> sceneFolds(const std::vector<std::string>& scene_of_frame, int folds);

// `n` of the `candidates` (frame indices), chosen reproducibly by `seed`:
// the candidates' scenes in a seeded random order, each taken whole while it
// fits; then, if fewer than n were taken, frames of the remaining scenes in
// that order. Sorted; all candidates when n >= their number. Throws for n < 1.
std::vector<std::size_t> chooseTrainingSubset(const std::vector<std::size_t>& candidates,
                                              const std::vector<std::string>& scene_of_frame,
                                              int n, std::uint64_t seed);

// Least-squares fit of y = a + b ln(x) (x > 0; NaN values of y are skipped).
// Throws unless at least two distinct x remain.
struct LogTrend {
  double a = 0.0, b = 0.0;
  double r2 = 0.0;  // coefficient of determination (NaN when y is constant)
  int points = 0;
  double at(double x) const;
};
LogTrend fitLogTrend(const std::vector<double>& x, const std::vector<double>& y);

}  // namespace findmug
