// label_tools.hpp — what findmug-web's Label page needs beyond the saved label file:
// each frame's oversegmentation with its patch graph (neighbours, mean colour and normal
// per patch: the region tool grows over it in the page), the configured model's
// per-patch prediction (the page's starting point), and the autosaved draft of the
// labelling in progress (DATA/drafts/NAME.json, rewritten whole after every stroke, so a
// crash loses at most the stroke in flight).
//
// Endpoints (root, frame as query parameters, checked like the other label endpoints):
//   GET    /api/label/graph       {patches, rgb[3N], normal[3N], edges[2E]}
//   GET    /api/label/prediction  {model, labels[N]}; 404 without a model, 422 when the
//                                 frame cannot be classified (no ground plane)
//   GET    /api/label/draft       {draft: null} or {draft: {...as POST takes it, plus
//                                 updated_utc}}; 422 a draft file that is not one (the
//                                 message names the file and what is wrong)
//   POST   /api/label/draft       {width, height, runs, strokes, author, base_mtime_ns}
//   DELETE /api/label/draft
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "findmug/learner/forest.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "findmug/settings/config.hpp"

namespace httplib {
class Server;
struct Request;
struct Response;
}  // namespace httplib

namespace findmug::web {

// A dataset frame as the Label page shows it.
struct LabelFrame {
  std::string key;  // root/frame
  int width = 0, height = 0, segments = 0;
  std::vector<std::uint16_t> patch;  // per pixel, 0xFFFF = in no patch
  // Per patch: mean colour (0..255) and mean unit normal (camera frame; 0 when none).
  std::vector<std::array<float, 3>> mean_rgb, mean_normal;
  std::vector<std::pair<int, int>> edges;  // neighbouring patches, each pair once
  // The model's label per patch (after the MRF when it runs), or why there is none.
  std::optional<std::vector<std::uint8_t>> prediction;
  std::string prediction_error;
};

// Makes (and keeps the last few) LabelFrames with the segmenter settings the model was
// trained with. Thread-safe: one frame is made at a time.
class LabelFrames {
 public:
  // `model` may be null (no prediction). Throws findmug::Error when the model's settings
  // differ from those `config` gives (configForModel, as findmugd does).
  LabelFrames(SegmenterConfig config, std::shared_ptr<const RandomForest> model,
              std::string model_name, std::optional<std::string> nyu_rotations);
  std::shared_ptr<const LabelFrame> of(const std::filesystem::path& root, std::size_t root_index,
                                       const std::string& frame);
  bool hasModel() const { return segmenter_.forest() != nullptr; }
  const std::string& modelName() const { return model_name_; }

 private:
  std::shared_ptr<const LabelFrame> make(const std::filesystem::path& root,
                                         std::size_t root_index, const std::string& frame) const;
  Segmenter segmenter_;
  std::string model_name_;
  std::optional<std::string> nyu_rotations_;
  std::mutex mutex_;
  std::vector<std::shared_ptr<const LabelFrame>> cache_;
};

// Row-major runs [[label id, count], ...] (ids 0..7 or 255) as `pixels` labels. Throws
// findmug::Error saying what is wrong (a bad run, an id, too few or too many pixels).
std::vector<std::uint8_t> labelsFromRuns(const nlohmann::json& runs, std::size_t pixels);
// The inverse: labels as runs.
nlohmann::json runsOf(const std::vector<std::uint8_t>& labels);

// The labelling in progress of one frame.
struct LabelDraft {
  std::string frame;
  int width = 0, height = 0;
  std::vector<std::uint8_t> labels;  // width*height
  int strokes = 0;                   // strokes since the labelling started
  std::string author;
  std::string base_mtime_ns;  // the label file it started from ("" = none)
  std::string updated_utc;
};
// DATA/drafts/NAME.json.
std::filesystem::path draftPath(const std::filesystem::path& root, const std::string& frame);
nlohmann::json draftJson(const LabelDraft& draft);
// Throws findmug::Error naming `file` and what is wrong when it is not a draft of
// `frame` at width x height.
LabelDraft readDraft(const std::filesystem::path& file, const std::string& frame, int width,
                     int height);
// Written beside its place, flushed to disk and renamed over it.
void writeDraft(const std::filesystem::path& file, const LabelDraft& draft);

// The frame a request names: its data folder's index and name, or nullopt after an
// error answer (the server's own checks).
using FrameOfRequest = std::function<std::optional<std::string>(
    const httplib::Request&, httplib::Response&, std::size_t& root_index)>;
// Adds the endpoints listed at the top.
void addLabelToolRoutes(httplib::Server& server, LabelFrames& frames,
                        const std::vector<std::filesystem::path>& roots, FrameOfRequest frame_of);

}  // namespace findmug::web
