// findmug/offline/metrics.hpp — segmentation accuracy as the paper reports it.
//
// Pixel-wise confusion over the eight labels, void excluded. Class-average
// accuracy = mean of the diagonal of the row-normalised confusion matrix
// (mean per-class recall over classes that occur in the ground truth);
// global accuracy = correctly labelled pixels / labelled pixels.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "findmug/labels/labels.hpp"

namespace findmug {

class ConfusionMatrix {
 public:
  // Rows: ground truth, columns: prediction. Pixels whose ground truth is
  // void are ignored; a void prediction on a labelled pixel counts as wrong
  // (column kNumLabels, "no prediction").
  void add(const std::vector<std::uint8_t>& ground_truth, const std::vector<std::uint8_t>& predicted);
  void add(std::uint8_t ground_truth, std::uint8_t predicted, std::uint64_t count = 1);
  void merge(const ConfusionMatrix& other);

  std::uint64_t count(int truth, int predicted) const { return counts_[truth][predicted]; }
  std::uint64_t rowTotal(int truth) const;
  std::uint64_t total() const;
  // Per-class recall; NaN for classes absent from the ground truth.
  std::array<double, kNumLabels> perClassAccuracy() const;
  double classAverageAccuracy() const;  // over classes present in the ground truth
  double globalAccuracy() const;

 private:
  // Last column: labelled pixels that got no prediction (void output).
  std::array<std::array<std::uint64_t, kNumLabels + 1>, kNumLabels> counts_{};
};

}  // namespace findmug
