#include "tool_common.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <map>

#include "findmug/common/error.hpp"
#include "findmug/common/numbers.hpp"
#include "findmug/offline/pseudo_labels.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "findmug_cli.hpp"

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

std::vector<std::string> LabeledInput::names() const {
  if (folder_) return folder_->names();
  std::vector<std::string> out;
  for (std::size_t i = 0; i < frames_.count; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "%04zu", i + 1);
    out.push_back(name);
  }
  return out;
}

void addDatasetFlags(CLI::App& app, DatasetFlags& f) {
  app.add_option("--data", f.data, "labelled dataset folder (repeatable: the folders' frames "
                                   "together; frame names must be unique across them)")
      ->type_name("DIR")
      ->allow_extra_args(false);
  app.add_option("--mat", f.mats, "the NYU Depth V2 labelled .mat file (repeatable)")
      ->type_name("FILE")
      ->allow_extra_args(false);
  app.add_option("--nyu894-csv", f.nyu894_csv,
                 "NYU 894-to-40 class map (CSV) for --mat (default: the installed one)")
      ->type_name("FILE")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  app.add_flag("--no-nyu-border", f.no_nyu_border,
               "keep the white border of NYU frames (masked as void by default)");
  app.add_option("--nyu-rotations", f.nyu_rotations,
                 "NYU's camera_rotations_NYU.txt: every NYU frame's gravity (frames of every "
                 "--data folder named by NYU index, and --mat frames)")
      ->type_name("FILE")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
}

DatasetOptions datasetOptions(const DatasetFlags& f, const Config& whole) {
  const SegmenterConfig& config = whole.segmenter;
  const TrainingOptions& training = whole.offline.training;
  DatasetOptions options;
  options.mask_nyu_border = !f.no_nyu_border;
  // Split labels and internal classes need each patch's finer class (label40/ or
  // label13/ beside label8/).
  options.fine_labels_folder = fineLabelsFolder(config, training);
  options.fine_labels_asked_by =
      config.learner.classes != ClassScheme::Labels
          ? std::string("learner.classes = ") + classSchemeName(config.learner.classes)
          : std::string("training.split_labels");
  // Internal classes infer the finer class of frames labelled with the 8 labels
  // only (inferMissingFineLabels); split labels need them everywhere.
  options.fine_labels_optional = config.learner.classes != ClassScheme::Labels;
  if (config.learner.classes == ClassScheme::Nyu13 && !f.mats.empty())
    throw Error("learner.classes = nyu13: --mat gives NYU-40 classes only (use nyu40, or a "
                "dataset folder with label13/)");
  if (training.split_labels == SplitLabels::Nyu13 && !f.mats.empty())
    throw Error("training.split_labels = nyu13: --mat gives NYU-40 classes only (use nyu40, or a "
                "dataset folder with label13/)");
  if (!f.nyu_rotations.empty()) options.nyu_rotations_file = f.nyu_rotations;
  return options;
}

std::unique_ptr<LabeledInputs> LabeledInputs::open(const DatasetFlags& f,
                                                   const DatasetOptions& options) {
  auto all = std::unique_ptr<LabeledInputs>(new LabeledInputs);
  for (const auto& dir : f.data) {
    all->inputs_.push_back(LabeledInput::folder(dir, options));
    all->sources_.push_back(dir);
    all->from_mat_.push_back(false);
  }
  for (const auto& mat : f.mats) {
    all->inputs_.push_back(LabeledInput::mat(mat, f.nyu894_csv, options.nyu_rotations_file));
    all->sources_.push_back(mat);
    all->from_mat_.push_back(true);
  }
  std::map<std::string, std::size_t> input_of_name;
  std::vector<std::string> collisions;
  std::string description;
  for (std::size_t k = 0; k < all->inputs_.size(); ++k) {
    const std::vector<std::string> names = all->inputs_[k]->names();
    for (std::size_t i = 0; i < names.size(); ++i) {
      const auto [it, added] = input_of_name.emplace(names[i], k);
      if (!added) {
        collisions.push_back(names[i] + " (" + all->sources_[it->second] + " and " +
                             all->sources_[k] + ")");
      }
      all->input_of_.push_back(k);
      all->index_in_input_.push_back(i);
      all->names_.push_back(names[i]);
    }
    description += (k ? " + " : "") + all->inputs_[k]->frames().description;
  }
  if (!collisions.empty()) {
    std::string list;
    for (std::size_t i = 0; i < collisions.size() && i < 10; ++i) list += (i ? ", " : "") + collisions[i];
    if (collisions.size() > 10) list += ", ...";
    throw Error(std::to_string(collisions.size()) +
                " frame name(s) in more than one input (frames must be unique): " + list);
  }
  all->frames_.description = description;
  all->frames_.count = all->names_.size();
  all->frames_.load = [raw = all.get()](std::size_t i) {
    if (i >= raw->names_.size()) {
      throw Error(raw->frames_.description + ": frame " + std::to_string(i) + " of " +
                  std::to_string(raw->names_.size()));
    }
    return raw->inputs_[raw->input_of_[i]]->frames().load(raw->index_in_input_[i]);
  };
  return all;
}

std::vector<std::string> LabeledInputs::scenes(int gap,
                                               const std::vector<long>* nyu_test_indices) const {
  // Read only here: training needs no frames.csv.
  std::vector<std::map<std::string, FrameListing>> listings;
  for (std::size_t k = 0; k < inputs_.size(); ++k) {
    listings.push_back(from_mat_[k] ? std::map<std::string, FrameListing>{}
                                    : loadFrameListing(sources_[k]));
  }
  std::vector<std::string> out(names_.size());
  std::vector<std::size_t> nyu_frames;
  std::vector<long> nyu_indices;
  for (std::size_t i = 0; i < names_.size(); ++i) {
    const auto& listing = listings[input_of_[i]];
    const auto listed = listing.find(names_[i]);
    const FrameListing frame = listed != listing.end() ? listed->second : FrameListing{};
    if (!frame.scene.empty()) {
      out[i] = "scene:" + frame.scene;
    } else if (frame.nyu_index || from_mat_[input_of_[i]]) {
      nyu_frames.push_back(i);
      nyu_indices.push_back(frame.nyu_index ? *frame.nyu_index
                                            : static_cast<long>(index_in_input_[i]) + 1);
    }
  }
  const std::vector<std::string> runs = nyu_test_indices
                                            ? nyuSplitRunScenes(nyu_indices, *nyu_test_indices)
                                            : nyuIndexRunScenes(nyu_indices, gap);
  for (std::size_t k = 0; k < nyu_frames.size(); ++k) out[nyu_frames[k]] = runs[k];
  return out;
}

void addUnlabelledFlag(CLI::App& app, std::vector<std::string>& dirs) {
  app.add_option("--unlabelled", dirs,
                 "folder of unlabelled frames (rgb/, depth/) for the semi-supervised rounds "
                 "(training.pseudo_rounds; repeatable)")
      ->type_name("DIR")
      ->allow_extra_args(false);
}

namespace {

// Whether every frame of `dir` is listed with an NYU index in its frames.csv.
bool allFramesNyuIndexed(const std::string& dir, const std::vector<std::string>& names) {
  const auto listing = loadFrameListing(dir);
  for (const auto& name : names) {
    const auto it = listing.find(name);
    if (it == listing.end() || !it->second.nyu_index) return false;
  }
  return !names.empty();
}

}  // namespace

std::vector<FrameSample> extractUnlabelled(const std::vector<std::string>& dirs,
                                           const DatasetFlags& flags,
                                           const SegmenterConfig& config,
                                           const LabeledInputs& labelled,
                                           ExtractionReport& report) {
  report = {};
  std::vector<FrameSample> out;
  if (dirs.empty()) return out;
  std::map<std::string, std::string> source_of;
  for (std::size_t i = 0; i < labelled.frames().count; ++i)
    source_of.emplace(labelled.nameOf(i), labelled.sourceOf(i));
  const Segmenter segmenter(unlabelledExtractionConfig(config), nullptr);
  for (const auto& dir : dirs) {
    DatasetOptions options;
    options.mask_nyu_border = !flags.no_nyu_border;
    options.require_labels = false;
    const DatasetFolder listing(dir, options);
    for (const auto& name : listing.names()) {
      const auto [it, added] = source_of.emplace(name, dir);
      if (!added)
        throw Error("--unlabelled " + dir + ": frame " + name + " is also in " + it->second +
                    " (a frame is either labelled or unlabelled, and evaluated frames are never "
                    "pseudo-labelled)");
    }
    if (config.ground.source == GroundSource::Gravity && !flags.nyu_rotations.empty() &&
        allFramesNyuIndexed(dir, listing.names()))
      options.nyu_rotations_file = flags.nyu_rotations;
    const auto folder = LabeledInput::folder(dir, options);
    // Labels, if the folder has any, are not used: the frames stand for frames nobody labelled.
    LabeledFrames frames = folder->frames();
    const auto load = frames.load;
    frames.load = [load](std::size_t i) {
      LabeledFrame frame = load(i);
      std::fill(frame.labels.begin(), frame.labels.end(), kVoidLabel);
      frame.fine_labels.clear();
      return frame;
    };
    ExtractionReport part;
    ProgressBar bar("features " + dir);
    auto samples = extractSamples(frames, segmenter, part,
                                  [&](int done, int total) { bar.update(done, total); });
    bar.finish();
    report.frames_total += part.frames_total;
    report.frames_used += part.frames_used;
    for (auto& d : part.dropped) report.dropped.push_back(dir + ": " + d);
    for (auto& g : part.ground_methods) report.ground_methods.push_back(g);
    for (auto& s : samples) out.push_back(std::move(s));
  }
  return out;
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

RandomForest loadModelWithItsSettings(const std::string& path, Config& config) {
  RandomForest model = RandomForest::load(path);
  config.segmenter = configForModel(config.segmenter, model);
  checkModelMatchesConfig(model, config.segmenter);
  return model;
}

}  // namespace findmug::tools
