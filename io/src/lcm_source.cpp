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
  // Only the bytes are kept here: decoding (JPEG, zlib) waits until next()
  // takes the message, so a frame dropped because the consumer is busy costs
  // a copy, not a decode. Buffers are recycled: no allocation per message in
  // the steady state.
  last_frame_ = Clock::now();
  const auto* bytes = static_cast<const std::uint8_t*>(buffer->data);
  const std::size_t size = buffer->data_size;
  std::unique_lock lock(queue_mutex_);
  if (replaying_log_) {
    queue_changed_.wait(lock, [&] {
      return stopping_ || queue_.size() < static_cast<std::size_t>(options_.lcm_queue_size);
    });
    if (stopping_) return;
  } else {
    std::uint64_t dropped = 0;
    while (queue_.size() >= static_cast<std::size_t>(options_.lcm_queue_size)) {
      spare_.push_back(std::move(queue_.front()));
      queue_.pop_front();
      ++dropped;
    }
    if (dropped > 0) recordDropped(dropped);
  }
  RawMessage message;
  if (!spare_.empty()) {
    message = std::move(spare_.back());
    spare_.pop_back();
  }
  message.bytes.assign(bytes, bytes + size);
  message.channel = channel;
  queue_.push_back(std::move(message));
  queue_changed_.notify_all();
}

std::optional<RgbdFrame> LcmFrameSource::next() {
  for (;;) {
    std::unique_lock lock(queue_mutex_);
    queue_changed_.wait(lock, [&] { return stopping_ || !queue_.empty() || finished_; });
    if (stopping_) return std::nullopt;
    if (queue_.empty()) {  // finished_
      lock.unlock();
      if (state() != SourceState::Failed) setState(SourceState::EndOfStream);
      return std::nullopt;
    }
    RawMessage message = std::move(queue_.front());
    queue_.pop_front();
    queue_changed_.notify_all();  // room for a waiting log reader
    lock.unlock();
    RgbdFrame frame;
    bool good = true;
    try {
      frame = decodeRgbdFrame(message.bytes.data(), message.bytes.size(), message.channel);
      finishFrame(frame, options_);
    } catch (const Error& e) {
      recordRejected(e.what());
      good = false;
    }
    lock.lock();
    if (spare_.size() < static_cast<std::size_t>(options_.lcm_queue_size) + 1) {
      spare_.push_back(std::move(message));
    }
    lock.unlock();
    if (!good) continue;  // bad input: skipped, the next message is tried
    recordDelivered();
    return frame;
  }
}

namespace detail {

std::unique_ptr<FrameSource> makeLcmSource(const SourceSpec& spec) {
  const std::string channel = spec.target.empty() ? std::string(kRgbdChannel) : spec.target;
  return std::make_unique<LcmFrameSource>(channel, spec.options.lcm_url, spec.options);
}

}  // namespace detail
}  // namespace findmug::io
