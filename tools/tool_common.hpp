// Shared plumbing of the findmug tools: number flags, labelled inputs, progress.
// (Flags themselves are parsed by the CLI11 layer in cli/findmug_cli.hpp.)
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "findmug/config.hpp"
#include "findmug/dataset.hpp"
#include "findmug/training.hpp"

namespace findmug::tools {

// A flag's value as a number; throws findmug::Error "FLAG: 'TEXT' is not a
// number" unless the whole text is one. Shared by every findmug program.
double parseNumber(const std::string& flag, const std::string& text);

// A labelled data set opened from a folder (--data DIR) or from the official
// NYU file (--mat nyu_depth_v2_labeled.mat); owns what `frames` refers to.
class LabeledInput {
 public:
  static std::unique_ptr<LabeledInput> folder(const std::string& dir,
                                              const DatasetOptions& options);
  // `nyu_rotations`: NYU's camera_rotations_NYU.txt, giving every frame its gravity.
  static std::unique_ptr<LabeledInput> mat(const std::string& path, const std::string& nyu894_csv,
                                           const std::optional<std::string>& nyu_rotations = {});
  const LabeledFrames& frames() const { return frames_; }

 private:
  std::unique_ptr<DatasetFolder> folder_;
  std::unique_ptr<NyuMatFile> mat_;
  std::shared_ptr<const NyuRotations> rotations_;
  LabeledFrames frames_;
};

// A one-line progress bar on stderr when it is a terminal; silent otherwise.
class ProgressBar {
 public:
  explicit ProgressBar(std::string label);
  void update(int done, int total);
  void finish();

 private:
  std::string label_;
  bool tty_;
  bool drawn_ = false;
};

}  // namespace findmug::tools
