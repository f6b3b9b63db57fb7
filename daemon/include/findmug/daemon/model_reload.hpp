// findmug/daemon/model_reload.hpp — the model the pipeline classifies with, and
// loading it again while frames flow.
//
//   ModelSlot      the Segmenter in use, made for one model (the config is the
//                  daemon's, fixed). The prepare step takes it once per frame
//                  (segmenter()) and the frame's later steps keep that one
//                  (PreparedJob::segmenter), so a swap lands between frames: a
//                  frame is prepared and classified wholly by the old model and
//                  its settings or wholly by the new one, and none waits for a load.
//   ModelReloader  its own thread, never a frame thread: on request() it reads
//                  the model file again and checks it exactly as start-up does
//                  (loadModel: readable, not corrupt, has trees; the Segmenter's
//                  constructor: configForModel, the new model's recorded
//                  settings taken for every key the config does not give, a
//                  given one that differs refused naming both values; then
//                  checkModelMatchesConfig), then swaps it into the slot. A refused model
//                  is logged (which file, why) and counted; the running one
//                  stays. Requests made while a load runs are folded into one
//                  more load after it. status() is what status_t reports.
//
// Requests come from SIGHUP (findmugd's main, systemd's ExecReload) and from
// reload_model commands (command_input.hpp), both through Pipeline::requestModelReload.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "findmug/settings/config.hpp"
#include "findmug/daemon/status_snapshot.hpp"
#include "findmug/learner/forest.hpp"
#include "findmug/segmenter/segmenter.hpp"

namespace findmug::daemon {

class ModelSlot {
 public:
  // Throws findmug::Error (from the Segmenter) when `forest` does not match `config`.
  ModelSlot(SegmenterConfig config, std::shared_ptr<const RandomForest> forest,
            std::string model_id);

  // The Segmenter to run one frame's step with (thread-safe; keep it for the step).
  std::shared_ptr<const Segmenter> segmenter() const;
  std::string modelId() const;
  const SegmenterConfig& config() const { return config_; }

  // Makes a Segmenter for `forest` (throws findmug::Error naming every setting
  // that differs from the config, as at start-up) and swaps it in; frames
  // already holding the old one finish with it.
  void install(std::shared_ptr<const RandomForest> forest, std::string model_id);

 private:
  SegmenterConfig config_;
  mutable std::mutex mutex_;  // guards the two below
  std::shared_ptr<const Segmenter> segmenter_;
  std::string model_id_;
};

class ModelReloader {
 public:
  // `on_refused` (on the reloader's thread) receives the refusal line, for the
  // pipeline's last_error; logging is done here.
  ModelReloader(std::string model_path, ModelSlot& slot,
                std::function<void(const std::string&)> on_refused = {});
  ~ModelReloader();
  ModelReloader(const ModelReloader&) = delete;
  ModelReloader& operator=(const ModelReloader&) = delete;

  // Asks for a load of the model file (never blocks on it). `request_id` is the
  // command's (-1 for SIGHUP); `origin` says who asked, for the log.
  void request(std::int64_t request_id, const std::string& origin);
  ReloadStatus status() const;
  // Ends the thread after the load in progress, if any. Idempotent.
  void stop();

 private:
  void loop();
  void loadOnce(std::int64_t request_id, const std::string& origin);

  std::string model_path_;
  ModelSlot& slot_;
  std::function<void(const std::string&)> on_refused_;
  mutable std::mutex mutex_;  // guards everything below
  std::condition_variable wake_;
  bool stopping_ = false;
  std::optional<std::pair<std::int64_t, std::string>> pending_;  // the latest request
  ReloadStatus status_;
  std::thread thread_;
};

}  // namespace findmug::daemon
