// The Label page's tools in findmug-web; see label_tools.hpp.
#include "label_tools.hpp"

#include <fcntl.h>
#include <httplib.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>

#include "findmug/common/error.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/labels/labels.hpp"
#include "findmug/oversegmentation/oversegmentation.hpp"
#include "web_http.hpp"
#include "web_server.hpp"

namespace findmug::web {

namespace fs = std::filesystem;

namespace {

constexpr const char* kDraftFormat = "findmug-label-draft";
constexpr int kDraftVersion = 1;
constexpr std::size_t kCachedFrames = 4;

// The frame as findmug-train reads it. A folder with label8/ lists only labelled frames:
// a frame not labelled yet is read from a view of the folder without labels.
LabeledFrame loadFrame(const fs::path& dir, std::size_t root_index, const std::string& frame,
                       const std::optional<std::string>& nyu_rotations) {
  DatasetOptions options;
  options.require_labels = false;
  options.nyu_rotations_file = nyu_rotations;
  LabeledFrame loaded;
  auto loadFrom = [&](const fs::path& folder_dir) {
    const DatasetFolder folder(folder_dir.string(), options);
    const auto& names = folder.names();
    const auto it = std::find(names.begin(), names.end(), frame);
    if (it == names.end()) return false;
    loaded = folder.load(static_cast<std::size_t>(it - names.begin()));
    return true;
  };
  if (fs::exists(dir / "label8") && loadFrom(dir)) return loaded;
  const fs::path view = fs::temp_directory_path() /
                        ("findmug-web-" + std::to_string(::getpid()) + "-" +
                         std::to_string(root_index));
  fs::remove_all(view);
  fs::create_directories(view);
  for (const char* part : {"rgb", "depth", "intrinsics.yaml", "extrinsics.csv", "gravity.csv"}) {
    if (fs::exists(dir / part)) fs::create_symlink(dir / part, view / part);
  }
  bool found = false;
  try {
    found = loadFrom(view);
  } catch (...) {
    fs::remove_all(view);
    throw;
  }
  fs::remove_all(view);
  if (!found) throw Error("frame " + frame + " is not in " + dir.string());
  return loaded;
}

// Per-patch mean colour and normal, for the region tool.
void describePatches(const Oversegmentation& segmentation, const PreparedFrame& prepared,
                     LabelFrame& out) {
  const std::size_t n = segmentation.segments.size();
  out.mean_rgb.assign(n, {0, 0, 0});
  out.mean_normal.assign(n, {0, 0, 0});
  const auto& rgb = prepared.frame.rgb;
  const auto& normals = prepared.normals_camera.normals;
  for (std::size_t s = 0; s < n; ++s) {
    double c[3] = {0, 0, 0}, v[3] = {0, 0, 0};
    for (int i : segmentation.segments[s]) {
      const auto k = static_cast<std::size_t>(i);
      if (k < rgb.size()) {
        c[0] += rgb[k].r;
        c[1] += rgb[k].g;
        c[2] += rgb[k].b;
      }
      if (k < normals.size() && normals[k].allFinite()) {
        for (int a = 0; a < 3; ++a) v[a] += normals[k][a];
      }
    }
    const double count = std::max<double>(1.0, static_cast<double>(segmentation.segments[s].size()));
    const double length = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int a = 0; a < 3; ++a) {
      out.mean_rgb[s][a] = static_cast<float>(c[a] / count);
      out.mean_normal[s][a] = length > 0 ? static_cast<float>(v[a] / length) : 0.0f;
    }
  }
}

}  // namespace

LabelFrames::LabelFrames(SegmenterConfig config, std::shared_ptr<const RandomForest> model,
                         std::string model_name, std::optional<std::string> nyu_rotations)
    : segmenter_(std::move(config), std::move(model)),
      model_name_(std::move(model_name)),
      nyu_rotations_(std::move(nyu_rotations)) {}

std::shared_ptr<const LabelFrame> LabelFrames::of(const fs::path& root, std::size_t root_index,
                                                  const std::string& frame) {
  const std::string key = std::to_string(root_index) + "/" + frame;
  // One frame at a time: a second request for it waits and takes the cached result.
  std::lock_guard lock(mutex_);
  for (const auto& f : cache_) {
    if (f->key == key) return f;
  }
  auto made = make(root, root_index, frame);
  cache_.push_back(made);
  if (cache_.size() > kCachedFrames) cache_.erase(cache_.begin());
  return made;
}

std::shared_ptr<const LabelFrame> LabelFrames::make(const fs::path& root, std::size_t root_index,
                                                    const std::string& frame) const {
  LabeledFrame loaded = loadFrame(root, root_index, frame, nyu_rotations_);
  // The cloud, normals and patches as the Segmenter makes them; the oversegmenter also
  // runs when no floor was found (the daemon would skip such a frame, a person can still
  // label it, without a prediction).
  PreparedFrame prepared = segmenter_.prepare(std::move(loaded.frame));
  auto out = std::make_shared<LabelFrame>();
  out->key = std::to_string(root_index) + "/" + frame;
  Oversegmentation segmentation;
  if (prepared.ground) {
    SegmentedFrame segmented = segmenter_.oversegment(std::move(prepared));
    if (segmenter_.forest()) {
      LabelledFrame labelled = segmenter_.classify(std::move(segmented));
      out->prediction =
          labelled.mrf.labels.empty() ? labelled.forest_labels : labelled.mrf.labels;
      segmented = std::move(labelled.segmented);
    } else {
      out->prediction_error = "findmug-web runs without a model (--model or web.model_path)";
    }
    segmentation = std::move(segmented.segmentation);
    prepared = std::move(segmented.prepared);
  } else {
    segmentation = makeOversegmenter(segmenter_.config().oversegmentation)
                       ->segment(prepared.cloud_camera, prepared.normals_camera);
    out->prediction_error = "no ground plane found in frame " + frame +
                            " (ground.* settings): the model cannot label it";
  }
  out->width = segmentation.width;
  out->height = segmentation.height;
  out->segments = static_cast<int>(segmentation.segments.size());
  if (out->segments >= 0xFFFF) throw Error(out->key + ": too many patches for the page");
  out->patch.resize(segmentation.pixel_segment.size());
  for (std::size_t i = 0; i < out->patch.size(); ++i) {
    const int s = segmentation.pixel_segment[i];
    out->patch[i] = s < 0 ? 0xFFFF : static_cast<std::uint16_t>(s);
  }
  out->edges = segmentation.edges;
  describePatches(segmentation, prepared, *out);
  if (out->prediction && out->prediction->size() != segmentation.segments.size()) {
    out->prediction.reset();
    out->prediction_error = "the model answered for another number of patches";
  }
  return out;
}

std::vector<std::uint8_t> labelsFromRuns(const nlohmann::json& runs, std::size_t pixels) {
  if (!runs.is_array()) throw Error("runs must be an array of [label id, count]");
  std::vector<std::uint8_t> labels;
  labels.reserve(pixels);
  for (const auto& run : runs) {
    if (!run.is_array() || run.size() != 2 || !run[0].is_number_unsigned() ||
        !run[1].is_number_unsigned()) {
      throw Error("each run must be [label id, count]");
    }
    const std::uint64_t id = run[0].get<std::uint64_t>();
    const std::uint64_t count = run[1].get<std::uint64_t>();
    if (id >= static_cast<std::uint64_t>(kNumLabels) && id != kVoidLabel) {
      throw Error("label id " + std::to_string(id) + " is not 0.." +
                  std::to_string(kNumLabels - 1) + " or 255");
    }
    if (count > pixels - labels.size()) throw Error("runs cover more than width x height pixels");
    labels.insert(labels.end(), count, static_cast<std::uint8_t>(id));
  }
  if (labels.size() != pixels) {
    throw Error("runs cover " + std::to_string(labels.size()) + " of " + std::to_string(pixels) +
                " pixels");
  }
  return labels;
}

nlohmann::json runsOf(const std::vector<std::uint8_t>& labels) {
  nlohmann::json out = nlohmann::json::array();
  for (std::size_t i = 0; i < labels.size();) {
    std::size_t j = i;
    while (j < labels.size() && labels[j] == labels[i]) ++j;
    out.push_back({labels[i], j - i});
    i = j;
  }
  return out;
}

fs::path draftPath(const fs::path& root, const std::string& frame) {
  return root / "drafts" / (frame + ".json");
}

nlohmann::json draftJson(const LabelDraft& draft) {
  return {{"format", kDraftFormat},       {"version", kDraftVersion},
          {"frame", draft.frame},         {"width", draft.width},
          {"height", draft.height},       {"strokes", draft.strokes},
          {"author", draft.author},       {"base_mtime_ns", draft.base_mtime_ns},
          {"updated_utc", draft.updated_utc}, {"runs", runsOf(draft.labels)}};
}

LabelDraft readDraft(const fs::path& file, const std::string& frame, int width, int height) {
  const auto bad = [&](const std::string& why) {
    return Error(file.string() + ": not a label draft of frame " + frame + ": " + why);
  };
  std::ifstream in(file, std::ios::binary);
  if (!in) throw bad("cannot read it");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const std::exception& e) {
    throw bad(std::string("not JSON (") + e.what() + ")");
  }
  if (!j.is_object() || j.value("format", "") != kDraftFormat) {
    throw bad(std::string("no \"format\": \"") + kDraftFormat + "\"");
  }
  if (!j.contains("version") || !j["version"].is_number_integer() ||
      j["version"].get<int>() != kDraftVersion) {
    throw bad("version is not " + std::to_string(kDraftVersion));
  }
  for (const char* key : {"frame", "author", "base_mtime_ns", "updated_utc"}) {
    if (!j.contains(key) || !j[key].is_string()) throw bad(std::string("field '") + key + "' must be text");
  }
  for (const char* key : {"width", "height", "strokes"}) {
    if (!j.contains(key) || !j[key].is_number_unsigned()) {
      throw bad(std::string("field '") + key + "' must be an unsigned number");
    }
  }
  LabelDraft d;
  d.frame = j["frame"].get<std::string>();
  if (d.frame != frame) throw bad("it is the draft of frame '" + d.frame + "'");
  d.width = static_cast<int>(std::min<std::uint64_t>(j["width"].get<std::uint64_t>(), 1u << 20));
  d.height = static_cast<int>(std::min<std::uint64_t>(j["height"].get<std::uint64_t>(), 1u << 20));
  if (d.width != width || d.height != height) {
    throw bad("it is " + std::to_string(d.width) + "x" + std::to_string(d.height) +
              ", the frame " + std::to_string(width) + "x" + std::to_string(height));
  }
  d.strokes = static_cast<int>(std::min<std::uint64_t>(j["strokes"].get<std::uint64_t>(), 1u << 30));
  d.author = j["author"].get<std::string>();
  d.base_mtime_ns = j["base_mtime_ns"].get<std::string>();
  d.updated_utc = j["updated_utc"].get<std::string>();
  try {
    d.labels = labelsFromRuns(j.contains("runs") ? j["runs"] : nlohmann::json(),
                              static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  } catch (const Error& e) {
    throw bad(e.what());
  }
  return d;
}

void writeDraft(const fs::path& file, const LabelDraft& draft) {
  const fs::path tmp = file.parent_path() / ("." + file.filename().string() + ".tmp");
  const std::string text = draftJson(draft).dump() + "\n";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw Error(tmp.string() + ": cannot write");
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n <= 0) {
      ::close(fd);
      throw Error(tmp.string() + ": cannot write");
    }
    done += static_cast<std::size_t>(n);
  }
  // On disk before the rename: a crash right after leaves the new draft or the old one.
  const bool synced = ::fsync(fd) == 0;
  ::close(fd);
  if (!synced) throw Error(tmp.string() + ": cannot flush to disk");
  fs::rename(tmp, file);
}

void addLabelToolRoutes(httplib::Server& s, LabelFrames& frames,
                        const std::vector<fs::path>& roots, FrameOfRequest frame_of) {
  s.Get("/api/label/graph", [&frames, &roots, frame_of](const httplib::Request& req,
                                                        httplib::Response& res) {
    std::size_t root = 0;
    const auto frame = frame_of(req, res, root);
    if (!frame) return;
    const auto f = frames.of(roots[root], root, *frame);
    nlohmann::json rgb = nlohmann::json::array(), normal = nlohmann::json::array(),
                   edges = nlohmann::json::array();
    for (int s = 0; s < f->segments; ++s) {
      for (int a = 0; a < 3; ++a) {
        rgb.push_back(std::round(f->mean_rgb[s][a] * 10.0f) / 10.0f);
        normal.push_back(std::round(f->mean_normal[s][a] * 1e4f) / 1e4f);
      }
    }
    for (const auto& [a, b] : f->edges) {
      edges.push_back(a);
      edges.push_back(b);
    }
    sendJson(res, {{"patches", f->segments}, {"rgb", rgb}, {"normal", normal}, {"edges", edges}});
  });
  s.Get("/api/label/prediction", [&frames, &roots, frame_of](const httplib::Request& req,
                                                             httplib::Response& res) {
    std::size_t root = 0;
    const auto frame = frame_of(req, res, root);
    if (!frame) return;
    if (!frames.hasModel()) {
      return fail(res, 404, "findmug-web runs without a model (--model or web.model_path)");
    }
    const auto f = frames.of(roots[root], root, *frame);
    if (!f->prediction) return fail(res, 422, f->prediction_error);
    sendJson(res, {{"model", frames.modelName()}, {"labels", *f->prediction}});
  });
  s.Get("/api/label/draft", [&frames, &roots, frame_of](const httplib::Request& req,
                                                        httplib::Response& res) {
    std::size_t root = 0;
    const auto frame = frame_of(req, res, root);
    if (!frame) return;
    const fs::path file = draftPath(roots[root], *frame);
    if (!fs::exists(file)) return sendJson(res, {{"draft", nullptr}});
    const auto f = frames.of(roots[root], root, *frame);
    try {
      const LabelDraft draft = readDraft(file, *frame, f->width, f->height);
      sendJson(res, {{"draft", draftJson(draft)}});
    } catch (const Error& e) {
      fail(res, 422, e.what());
    }
  });
  s.Post("/api/label/draft", [&frames, &roots, frame_of](const httplib::Request& req,
                                                         httplib::Response& res) {
    std::size_t root = 0;
    const auto frame = frame_of(req, res, root);
    if (!frame) return;
    auto parsed = jsonObjectBody(req.body, res);
    if (!parsed) return;
    nlohmann::json body = std::move(*parsed);
    for (const char* key : {"width", "height", "runs", "strokes", "author"}) {
      if (!body.contains(key)) return fail(res, 400, std::string("missing field '") + key + "'");
    }
    if (!body["width"].is_number_unsigned() || !body["height"].is_number_unsigned() ||
        !body["strokes"].is_number_unsigned() || !body["author"].is_string()) {
      return fail(res, 400, "width, height, strokes must be unsigned numbers, author text");
    }
    const auto f = frames.of(roots[root], root, *frame);
    if (body["width"].get<std::uint64_t>() != static_cast<std::uint64_t>(f->width) ||
        body["height"].get<std::uint64_t>() != static_cast<std::uint64_t>(f->height)) {
      return fail(res, 400, "the draft's size is not the frame's " + std::to_string(f->width) +
                                "x" + std::to_string(f->height));
    }
    LabelDraft draft;
    draft.frame = *frame;
    draft.width = f->width;
    draft.height = f->height;
    draft.strokes = static_cast<int>(std::min<std::uint64_t>(body["strokes"].get<std::uint64_t>(), 1u << 30));
    draft.author = body["author"].get<std::string>();
    if (draft.author.size() > 200) return fail(res, 400, "author longer than 200 characters");
    if (body.contains("base_mtime_ns") && body["base_mtime_ns"].is_string()) {
      draft.base_mtime_ns = body["base_mtime_ns"].get<std::string>();
    }
    draft.updated_utc = utcNow();
    try {
      draft.labels = labelsFromRuns(
          body["runs"], static_cast<std::size_t>(f->width) * static_cast<std::size_t>(f->height));
    } catch (const Error& e) {
      return fail(res, 400, e.what());
    }
    const fs::path& dir = roots[root];
    if (!fs::exists(fs::symlink_status(dir / "drafts"))) fs::create_directory(dir / "drafts");
    const ResolvedPath out = resolveInside(dir, "drafts/" + *frame + ".json", true);
    if (out.status != 200) return fail(res, out.status, out.error);
    writeDraft(out.path, draft);
    sendJson(res, {{"draft", "drafts/" + *frame + ".json"}, {"strokes", draft.strokes}});
  });
  s.Delete("/api/label/draft", [&roots, frame_of](const httplib::Request& req,
                                                  httplib::Response& res) {
    std::size_t root = 0;
    const auto frame = frame_of(req, res, root);
    if (!frame) return;
    const ResolvedPath file = resolveInside(roots[root], "drafts/" + *frame + ".json");
    if (file.status != 200) return fail(res, file.status, file.error);
    fs::remove(file.path);
    sendJson(res, {{"discarded", "drafts/" + *frame + ".json"}});
  });
}

}  // namespace findmug::web
