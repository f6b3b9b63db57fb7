#include "findmug/io/lcm_source.hpp"

#include <spdlog/spdlog.h>

#include <lcm/lcm-cpp.hpp>

#include "findmug/error.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "sources_internal.hpp"

namespace findmug::io {

LcmFrameSource::LcmFrameSource(std::string channel, std::string url, SourceOptions options)
    : channel_(std::move(channel)), url_(std::move(url)), options_(std::move(options)) {
  if (channel_.empty()) throw Error("lcm source: empty channel name");
  if (options_.lcm_queue_size < 1) {
    throw Error("lcm source: queue size " + std::to_string(options_.lcm_queue_size) + " < 1");
  }
  replaying_log_ = url_.rfind("file://", 0) == 0;
  description_ =
      "lcm:" + channel_ + " (" + (url_.empty() ? std::string("default URL") : url_) + ")";
  lcm_ = std::make_unique<lcm::LCM>(url_);
  if (!lcm_->good()) {
    throw Error("lcm source: cannot open LCM URL '" + url_ + "'" +
                (url_.empty() ? " (the default, from LCM_DEFAULT_URL)" : ""));
  }
  lcm_->subscribe(channel_, &LcmFrameSource::onMessage, this);
  thread_ = std::thread([this] { run(); });
}

LcmFrameSource::~LcmFrameSource() {
  stop();
  if (thread_.joinable()) thread_.join();
}

void LcmFrameSource::onStop() {
  std::lock_guard lock(queue_mutex_);
  stopping_ = true;
  // Frames still waiting here will never be processed: count them as
  // dropped so that frames in = published + dropped holds after a stop too.
  if (!queue_.empty()) {
    recordDropped(queue_.size());
    queue_.clear();
  }
  queue_changed_.notify_all();
}

void LcmFrameSource::run() {
  for (;;) {
    {
      std::lock_guard lock(queue_mutex_);
      if (stopping_) break;
    }
    // Short timeout: the loop must notice stop() promptly.
    const int rc = lcm_->handleTimeout(100);
    // A live publisher that falls silent looks like a lost camera: say so in
    // state() (back to Running with the next frame).
    if (!replaying_log_ && state() == SourceState::Running &&
        Clock::now() - last_frame_.load() > kSilenceTimeout) {
      spdlog::warn("{}: no frame for {} ms; waiting for the publisher", description_,
                   std::chrono::duration_cast<std::chrono::milliseconds>(kSilenceTimeout).count());
      setState(SourceState::Reconnecting);
    }
    if (rc < 0) {
      if (replaying_log_) {
        spdlog::info("{}: end of log", description_);
      } else {
        recordError("LCM handle failed; no more messages can be received");
        setState(SourceState::Failed);
      }
      break;
    }
  }
  std::lock_guard lock(queue_mutex_);
  finished_ = true;
  queue_changed_.notify_all();
}

void LcmFrameSource::onMessage(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
  RgbdFrame frame;
  try {
    frame = decodeRgbdFrame(buffer->data, static_cast<std::size_t>(buffer->data_size), channel);
    finishFrame(frame, options_);
  } catch (const Error& e) {
    recordRejected(e.what());
    return;
  }
  last_frame_ = Clock::now();
  std::unique_lock lock(queue_mutex_);
  if (replaying_log_) {
    queue_changed_.wait(lock, [&] {
      return stopping_ || queue_.size() < static_cast<std::size_t>(options_.lcm_queue_size);
    });
    if (stopping_) return;
  } else {
    std::uint64_t dropped = 0;
    while (queue_.size() >= static_cast<std::size_t>(options_.lcm_queue_size)) {
      queue_.pop_front();
      ++dropped;
    }
    if (dropped > 0) recordDropped(dropped);
  }
  queue_.push_back(std::move(frame));
  queue_changed_.notify_all();
}

std::optional<RgbdFrame> LcmFrameSource::next() {
  std::unique_lock lock(queue_mutex_);
  queue_changed_.wait(lock, [&] { return stopping_ || !queue_.empty() || finished_; });
  if (stopping_) return std::nullopt;
  if (queue_.empty()) {  // finished_
    lock.unlock();
    if (state() != SourceState::Failed) setState(SourceState::EndOfStream);
    return std::nullopt;
  }
  RgbdFrame frame = std::move(queue_.front());
  queue_.pop_front();
  queue_changed_.notify_all();  // room for a waiting log reader
  lock.unlock();
  recordDelivered();
  return frame;
}

namespace detail {

std::unique_ptr<FrameSource> makeLcmSource(const SourceSpec& spec) {
  const std::string channel = spec.target.empty() ? std::string(kRgbdChannel) : spec.target;
  return std::make_unique<LcmFrameSource>(channel, spec.options.lcm_url, spec.options);
}

}  // namespace detail
}  // namespace findmug::io
