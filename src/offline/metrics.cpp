#include "findmug/offline/metrics.hpp"

#include <cmath>
#include <limits>
#include <numeric>

#include "findmug/common/error.hpp"

namespace findmug {

void ConfusionMatrix::add(std::uint8_t ground_truth, std::uint8_t predicted, std::uint64_t count) {
  if (ground_truth >= kNumLabels) return;  // void ground truth: not evaluated
  const int column = predicted < kNumLabels ? predicted : kNumLabels;
  counts_[ground_truth][column] += count;
}

void ConfusionMatrix::add(const std::vector<std::uint8_t>& ground_truth,
                          const std::vector<std::uint8_t>& predicted) {
  if (ground_truth.size() != predicted.size()) {
    throw Error("ConfusionMatrix::add: ground truth has " + std::to_string(ground_truth.size()) +
                " pixels, prediction " + std::to_string(predicted.size()));
  }
  for (std::size_t i = 0; i < ground_truth.size(); ++i) add(ground_truth[i], predicted[i]);
}

void ConfusionMatrix::merge(const ConfusionMatrix& other) {
  for (int t = 0; t < kNumLabels; ++t) {
    for (int p = 0; p <= kNumLabels; ++p) counts_[t][p] += other.counts_[t][p];
  }
}

std::uint64_t ConfusionMatrix::rowTotal(int truth) const {
  return std::accumulate(counts_[truth].begin(), counts_[truth].end(), std::uint64_t{0});
}

std::uint64_t ConfusionMatrix::total() const {
  std::uint64_t sum = 0;
  for (int t = 0; t < kNumLabels; ++t) sum += rowTotal(t);
  return sum;
}

std::array<double, kNumLabels> ConfusionMatrix::perClassAccuracy() const {
  std::array<double, kNumLabels> out;
  for (int t = 0; t < kNumLabels; ++t) {
    const auto row = rowTotal(t);
    out[t] = row == 0 ? std::numeric_limits<double>::quiet_NaN()
                      : static_cast<double>(counts_[t][t]) / static_cast<double>(row);
  }
  return out;
}

double ConfusionMatrix::classAverageAccuracy() const {
  double sum = 0;
  int present = 0;
  for (double a : perClassAccuracy()) {
    if (!std::isnan(a)) {
      sum += a;
      ++present;
    }
  }
  return present == 0 ? std::numeric_limits<double>::quiet_NaN() : sum / present;
}

double ConfusionMatrix::globalAccuracy() const {
  std::uint64_t correct = 0;
  for (int t = 0; t < kNumLabels; ++t) correct += counts_[t][t];
  const auto all = total();
  return all == 0 ? std::numeric_limits<double>::quiet_NaN()
                  : static_cast<double>(correct) / static_cast<double>(all);
}

}  // namespace findmug
