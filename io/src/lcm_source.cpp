#include "findmug/io/lcm_source.hpp"

#include <spdlog/spdlog.h>

#include "findmug/common/error.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/udpm.hpp"
#include "sources_internal.hpp"

namespace findmug::io {

LcmFrameSource::LcmFrameSource(std::string channel, std::string url, SourceOptions options)
    : LcmFrameSource(std::move(channel), std::shared_ptr<Bus>(openBus(url, "lcm source (" + url + ")")),
                     std::move(options)) {}

LcmFrameSource::LcmFrameSource(std::string channel, std::shared_ptr<Bus> bus, SourceOptions options)
    : channel_(std::move(channel)), options_(std::move(options)), bus_(std::move(bus)) {
  if (channel_.empty()) throw Error("lcm source: empty channel name");
  if (options_.lcm_queue_size < 1) {
    throw Error("lcm source: queue size " + std::to_string(options_.lcm_queue_size) + " < 1");
  }
  replaying_log_ = bus_->replaysLog();
  description_ = "lcm:" + channel_ + " (" + bus_->describe() + ")";
  bus_->subscribe(channel_, [this](const std::string& ch, const std::uint8_t* bytes,
                                   std::size_t size) { onMessage(ch, bytes, size); });
  receiver_.start(
      *bus_, [this](HandleResult how) { onEnd(how); }, [this] { afterWait(); });
}

LcmFrameSource::~LcmFrameSource() {
  stop();
  receiver_.stop();
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

void LcmFrameSource::afterWait() {
  // A live publisher that falls silent looks like a lost camera: say so in
  // state() (back to Running with the next frame).
  if (!replaying_log_ && state() == SourceState::Running &&
      Clock::now() - last_frame_.load() > kSilenceTimeout) {
    spdlog::warn("{}: no frame for {} ms; waiting for the publisher", description_,
                 std::chrono::duration_cast<std::chrono::milliseconds>(kSilenceTimeout).count());
    setState(SourceState::Reconnecting);
  }
}

void LcmFrameSource::onEnd(HandleResult how) {
  if (how == HandleResult::EndOfLog) {
    spdlog::info("{}: end of log", description_);
  } else {
    recordError("LCM handle failed; no more messages can be received");
    setState(SourceState::Failed);
  }
  std::lock_guard lock(queue_mutex_);
  finished_ = true;
  queue_changed_.notify_all();
}

void LcmFrameSource::onMessage(const std::string& channel, const std::uint8_t* bytes,
                               std::size_t size) {
  // Only the bytes are kept here: decoding (JPEG, zlib) waits until next()
  // takes the message, so a frame dropped because the consumer is busy costs
  // a copy, not a decode. Buffers are recycled: no allocation per message in
  // the steady state.
  last_frame_ = Clock::now();
  // Holes in seq are frames the network lost (udpm drops a whole frame when one
  // of its datagrams is lost): counted on arrival, before any queueing.
  if (const auto seq = peekRgbdFrameSeq(bytes, size)) {
    const std::uint64_t before = transit_.lost();
    transit_.observe(*seq);
    if (transit_.lost() != before) recordLostInTransit(transit_.lost());
  }
  std::unique_lock lock(queue_mutex_);
  if (stopping_) return;  // stopped: next() takes nothing more (the queue was counted)
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
