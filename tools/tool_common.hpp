// Shared plumbing of the findmug tools: number flags, labelled inputs (the
// dataset flags --data/--mat/--nyu-rotations/... of findmug-train and
// findmug-eval, several inputs as one), progress.
// (Flags themselves are parsed by the CLI11 layer in cli/findmug_cli.hpp.)
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "findmug/frame/dataset.hpp"
#include "findmug/offline/cv_folds.hpp"
#include "findmug/offline/nyu_mat.hpp"
#include "findmug/offline/training.hpp"
#include "findmug/settings/config.hpp"

namespace CLI {
class App;
}

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
  // Frame names in index order ("0001".. for the .mat file).
  std::vector<std::string> names() const;

 private:
  std::unique_ptr<DatasetFolder> folder_;
  std::unique_ptr<NyuMatFile> mat_;
  std::shared_ptr<const NyuRotations> rotations_;
  LabeledFrames frames_;
};

// The flags naming labelled frames, the same in every tool that reads them.
struct DatasetFlags {
  std::vector<std::string> data;  // --data DIR (repeatable)
  std::vector<std::string> mats;  // --mat FILE (repeatable)
  std::string nyu894_csv, nyu_rotations;
  bool no_nyu_border = false;
};
void addDatasetFlags(CLI::App& app, DatasetFlags& flags);
// The folder-reading options those flags and the config ask for; throws
// findmug::Error for a combination that cannot work (split labels nyu13 with --mat).
DatasetOptions datasetOptions(const DatasetFlags& flags, const Config& config);

// Every --data folder, then every --mat file, as one indexed collection of
// frames (frames() numbers them in that order). Frame names must be unique
// across the inputs: a name in two of them is refused with an error naming
// the name and both inputs.
class LabeledInputs {
 public:
  static std::unique_ptr<LabeledInputs> open(const DatasetFlags& flags,
                                             const DatasetOptions& options);
  const LabeledFrames& frames() const { return frames_; }
  const std::string& nameOf(std::size_t frame) const { return names_[frame]; }
  // The --data folder or --mat file frame i comes from.
  const std::string& sourceOf(std::size_t frame) const { return sources_[input_of_[frame]]; }
  // Each frame's scene (cv_folds.hpp): the `scene` column of its folder's
  // frames.csv; else, for NYU frames (a frames.csv with `nyu_index`, or a
  // --mat file), runs of NYU's split when `nyu_test_indices` is given, else
  // NYU index runs with `gap`; "" when neither is known.
  std::vector<std::string> scenes(int gap, const std::vector<long>* nyu_test_indices) const;

 private:
  std::vector<std::unique_ptr<LabeledInput>> inputs_;
  std::vector<std::string> sources_;
  std::vector<std::size_t> input_of_, index_in_input_;
  std::vector<std::string> names_;
  std::vector<bool> from_mat_;
  LabeledFrames frames_;
};

// Unlabelled frames for the semi-supervised rounds (--unlabelled DIR,
// repeatable; pseudo_labels.hpp): rgb/ and depth/ (any label folder is
// ignored). A frame gets NYU's gravity from --nyu-rotations when the folder's
// frames.csv gives every frame an nyu_index and ground.source = gravity;
// otherwise its ground is fitted in the frame (report.ground_methods says
// which). A frame name also among the labelled inputs, or in two unlabelled
// folders, is refused with an error naming it, so that no evaluated frame is
// ever pseudo-labelled; so is a frame that cannot be read (the file is named).
void addUnlabelledFlag(CLI::App& app, std::vector<std::string>& dirs);
std::vector<FrameSample> extractUnlabelled(const std::vector<std::string>& dirs,
                                           const DatasetFlags& flags,
                                           const SegmenterConfig& config,
                                           const LabeledInputs& labelled,
                                           ExtractionReport& report);

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

// The model file at `path`, with `config` taking the settings it records (configForModel:
// a value the config gives otherwise is refused naming both) and checked against it
// (checkModelMatchesConfig), so that the features are extracted as the model's were.
RandomForest loadModelWithItsSettings(const std::string& path, Config& config);

}  // namespace findmug::tools
