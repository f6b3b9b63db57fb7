// The model slot and its reloader; see model_reload.hpp.
#include "findmug/daemon/model_reload.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <exception>

#include "findmug/daemon/daemon.hpp"
#include "findmug/common/error.hpp"

namespace findmug::daemon {

namespace {
std::uint64_t utimeNow() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                        std::chrono::system_clock::now().time_since_epoch())
                                        .count());
}
}  // namespace

ModelSlot::ModelSlot(SegmenterConfig config, std::shared_ptr<const RandomForest> forest,
                     std::string model_id)
    : config_(std::move(config)),
      segmenter_(std::make_shared<const Segmenter>(config_, std::move(forest))),
      model_id_(std::move(model_id)) {}

std::shared_ptr<const Segmenter> ModelSlot::segmenter() const {
  std::lock_guard lock(mutex_);
  return segmenter_;
}

std::string ModelSlot::modelId() const {
  std::lock_guard lock(mutex_);
  return model_id_;
}

void ModelSlot::install(std::shared_ptr<const RandomForest> forest, std::string model_id) {
  if (!forest || forest->empty()) throw Error(model_id + ": the model has no trees");
  // Built outside the lock: frames keep taking the old one meanwhile.
  auto next = std::make_shared<const Segmenter>(config_, std::move(forest));
  std::shared_ptr<const Segmenter> previous;
  {
    std::lock_guard lock(mutex_);
    previous = std::move(segmenter_);
    segmenter_ = std::move(next);
    model_id_ = std::move(model_id);
  }
  // `previous` is freed here unless a frame still holds it (then by that frame).
}

ModelReloader::ModelReloader(std::string model_path, ModelSlot& slot,
                             std::function<void(const std::string&)> on_refused)
    : model_path_(std::move(model_path)), slot_(slot), on_refused_(std::move(on_refused)) {
  thread_ = std::thread([this] { loop(); });
}

ModelReloader::~ModelReloader() { stop(); }

void ModelReloader::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void ModelReloader::request(std::int64_t request_id, const std::string& origin) {
  {
    std::lock_guard lock(mutex_);
    if (pending_) {
      spdlog::info("model reload ({}) folded into the one already asked for ({})", origin,
                   pending_->second);
    }
    pending_ = std::make_pair(request_id, origin);
  }
  wake_.notify_all();
}

ReloadStatus ModelReloader::status() const {
  std::lock_guard lock(mutex_);
  return status_;
}

void ModelReloader::loop() {
  std::unique_lock lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return stopping_ || pending_.has_value(); });
    if (stopping_) return;
    const auto [request_id, origin] = *pending_;
    pending_.reset();
    lock.unlock();
    loadOnce(request_id, origin);
    lock.lock();
  }
}

void ModelReloader::loadOnce(std::int64_t request_id, const std::string& origin) {
  spdlog::info("model reload ({}): loading {}", origin, model_path_);
  const std::string running = slot_.modelId();
  bool ok = false;
  std::string result;
  try {
    std::string model_id;
    std::shared_ptr<const RandomForest> forest = loadModel(model_path_, &model_id);
    slot_.install(forest, model_id);
    ok = true;
    result = "loaded " + model_id + " (was " + running + ")";
    spdlog::info("model reload ({}): {} from {} ({})", origin, result, model_path_,
                 forest->summary());
  } catch (const std::exception& e) {
    result = "refused " + model_path_ + ": " + e.what() + "; still running " + running;
    spdlog::error("model reload ({}): {}", origin, result);
    if (on_refused_) on_refused_("model reload: " + result);
  }
  std::lock_guard lock(mutex_);
  (ok ? status_.reloads : status_.refused) += 1;
  status_.last_ok = ok;
  status_.last_result = result;
  status_.last_utime = utimeNow();
  status_.last_request_id = request_id;
}

}  // namespace findmug::daemon
