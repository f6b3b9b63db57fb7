#include "findmug/io/device_source.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>

#include "findmug/common/error.hpp"

namespace findmug::io {

namespace {
constexpr std::size_t kAttemptHistory = 64;
}

Backoff::Backoff(std::chrono::milliseconds initial, std::chrono::milliseconds max)
    : initial_(initial), max_(max), current_(initial) {
  if (initial.count() <= 0 || max < initial) {
    throw Error("reconnect back-off: initial " + std::to_string(initial.count()) +
                " ms must be > 0 and at most the maximum " + std::to_string(max.count()) + " ms");
  }
}

std::chrono::milliseconds Backoff::next() {
  const auto now = current_;
  // Doubling saturates at max_ (no overflow however long the device is gone).
  current_ = current_ > max_ / 2 ? max_ : current_ * 2;
  return now;
}

DeviceSource::DeviceSource(std::unique_ptr<Device> device, DeviceSourceSettings settings,
                           SourceOptions options)
    : device_(std::move(device)),
      settings_(settings),
      options_(std::move(options)),
      backoff_(settings.reconnect_initial, settings.reconnect_max) {
  if (settings_.poll.count() <= 0 || settings_.frame_timeout < settings_.poll) {
    throw Error(device_->describe() + ": frame timeout " +
                std::to_string(settings_.frame_timeout.count()) + " ms must be at least the poll " +
                std::to_string(settings_.poll.count()) + " ms (> 0)");
  }
  if (const std::string error = device_->open(); !error.empty()) {
    // A file that cannot be opened is a configuration error: say so now.
    if (!settings_.reconnect) throw Error(device_->describe() + ": " + error);
    setState(SourceState::Reconnecting);
    recordError(error + "; retrying");
  } else {
    open_ = true;
    last_activity_ = Clock::now();
  }
}

DeviceSource::~DeviceSource() {
  if (open_) device_->close();
}

std::vector<ReconnectAttempt> DeviceSource::reconnectAttempts() const {
  std::lock_guard lock(attempts_mutex_);
  return {attempts_.begin(), attempts_.end()};
}

bool DeviceSource::reopen() {
  while (!stopRequested()) {
    const auto wait = backoff_.next();
    if (!sleepUntil(Clock::now() + wait)) return false;
    ReconnectAttempt attempt{Clock::now(), wait, false, device_->open()};
    attempt.succeeded = attempt.error.empty();
    {
      std::lock_guard lock(attempts_mutex_);
      attempts_.push_back(attempt);
      if (attempts_.size() > kAttemptHistory) attempts_.pop_front();
    }
    if (attempt.succeeded) {
      open_ = true;
      last_activity_ = Clock::now();
      backoff_.reset();
      recordReconnect();
      spdlog::info("{}: device open again", describe());
      return true;
    }
    setState(SourceState::Reconnecting);
    recordError(attempt.error + "; retrying in " + std::to_string(backoff_.peek().count()) + " ms");
  }
  return false;
}

void DeviceSource::lose(const std::string& why) {
  recordError(why + (settings_.reconnect ? "; device lost, reconnecting" : ""));
  device_->close();
  open_ = false;
  setState(settings_.reconnect ? SourceState::Reconnecting : SourceState::Failed);
}

std::optional<RgbdFrame> DeviceSource::next() {
  while (!stopRequested()) {
    if (!open_) {
      if (!settings_.reconnect) {  // cannot come back (playback); lose() said why
        setState(SourceState::Failed);
        return std::nullopt;
      }
      if (!reopen()) break;
    }
    DeviceRead got = device_->read(settings_.poll);
    if (got.dropped > 0) recordDropped(got.dropped);
    switch (got.kind) {
      case DeviceRead::Kind::Frame: {
        last_activity_ = Clock::now();
        if (!got.frame) {
          recordRejected(describe() + ": the device reported a frame but gave none");
          continue;
        }
        RgbdFrame frame = std::move(*got.frame);
        try {
          finishFrame(frame, options_);
        } catch (const Error& e) {
          recordRejected(e.what());
          continue;
        }
        if (!pace(settings_.rate_hz)) break;
        frame.seq = seq_++;
        recordDelivered();
        return frame;
      }
      case DeviceRead::Kind::Pending:
        last_activity_ = Clock::now();
        continue;
      case DeviceRead::Kind::Rejected:
        last_activity_ = Clock::now();
        recordRejected(got.error);
        continue;
      case DeviceRead::Kind::Idle:
        if (Clock::now() - last_activity_ > settings_.frame_timeout) {
          lose("no frame for " + std::to_string(settings_.frame_timeout.count()) + " ms");
        }
        continue;
      case DeviceRead::Kind::Lost:
        lose(got.error);
        continue;
      case DeviceRead::Kind::Ended:
        setState(SourceState::EndOfStream);
        return std::nullopt;
    }
    break;  // stopped while pacing
  }
  setState(SourceState::Stopped);
  return std::nullopt;
}

}  // namespace findmug::io
