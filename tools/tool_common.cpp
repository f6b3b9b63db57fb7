#include "tool_common.hpp"

#include <unistd.h>

#include <cstdio>

#include "findmug/error.hpp"
#include "findmug/numbers.hpp"

namespace findmug::tools {

double parseNumber(const std::string& flag, const std::string& text) {
  const auto value = findmug::parseNumber(text);
  if (!value) throw Error(flag + ": '" + text + "' is not a number");
  return *value;
}

std::unique_ptr<LabeledInput> LabeledInput::folder(const std::string& dir,
                                                   const DatasetOptions& options) {
  auto input = std::unique_ptr<LabeledInput>(new LabeledInput);
  input->folder_ = std::make_unique<DatasetFolder>(dir, options);
  input->frames_ = framesOf(*input->folder_);
  return input;
}

std::unique_ptr<LabeledInput> LabeledInput::mat(const std::string& path,
                                                const std::string& nyu894_csv,
                                                const std::optional<std::string>& nyu_rotations) {
  auto input = std::unique_ptr<LabeledInput>(new LabeledInput);
  input->mat_ = nyu894_csv.empty() ? std::make_unique<NyuMatFile>(path)
                                   : std::make_unique<NyuMatFile>(path, nyu894_csv);
  input->frames_ = framesOf(*input->mat_, path);
  if (nyu_rotations) {
    // The .mat holds frames in NYU index order: frame i is NYU index i + 1.
    input->rotations_ = std::make_shared<const NyuRotations>(loadNyuRotations(*nyu_rotations));
    auto load = input->frames_.load;
    input->frames_.load = [load, rotations = input->rotations_](std::size_t i) {
      LabeledFrame frame = load(i);
      frame.frame.gravity_up = rotations->upForIndex(static_cast<long>(i) + 1);
      return frame;
    };
  }
  return input;
}

ProgressBar::ProgressBar(std::string label) : label_(std::move(label)), tty_(isatty(2) != 0) {}

void ProgressBar::update(int done, int total) {
  if (!tty_ || total <= 0) return;
  constexpr int kWidth = 30;
  const int filled = kWidth * done / total;
  std::fprintf(stderr, "\r%s [%s%s] %d/%d", label_.c_str(), std::string(filled, '#').c_str(),
               std::string(kWidth - filled, ' ').c_str(), done, total);
  std::fflush(stderr);
  drawn_ = true;
}

void ProgressBar::finish() {
  if (drawn_) std::fprintf(stderr, "\n");
  drawn_ = false;
}

}  // namespace findmug::tools
