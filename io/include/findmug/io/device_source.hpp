// findmug/io/device_source.hpp — a frame source over a device that can be lost and come back.
//
// A camera on a robot gets unplugged, browns out, or its driver stops
// delivering. FrameSource's contract (frame_source.hpp) says such a source
// closes the device, retries with exponential back-off, shows Reconnecting
// meanwhile and counts each successful re-open in stats().reconnects.
// DeviceSource implements that loop once, over a small Device interface
// (open / read with a time limit / close). The OpenNI2 source is a Device
// inside a DeviceSource; so is any other device, and so is a test's device
// that disappears on command — the loss-and-return path under test is the
// one a camera goes through.
//
// The loop in next():
//   * device closed: wait the next back-off delay (reconnect_initial, then
//     doubling, at most reconnect_max), then Device::open(). A failure is
//     recorded ("...; retrying in N ms") and the state stays Reconnecting; a
//     success counts a reconnect and starts the back-off from the beginning
//     for the next loss. Running again with the first frame delivered.
//   * device open: Device::read(poll). A frame is finished (option
//     overrides, validateFrame; invalid = rejected), numbered (seq) and
//     returned; Pending / Rejected show the device is alive; Idle means
//     nothing came within `poll`. A device that shows no life for
//     frame_timeout, or reports Lost, is closed: Reconnecting (or Failed
//     when reconnect is off, e.g. file playback, which cannot come back).
//     Ended is the end of a finite stream (EndOfStream).
// Every wait is interruptible by stop(): sleeps wake at once, a read returns
// within `poll`.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "findmug/frame/frame.hpp"
#include "findmug/io/frame_source.hpp"

namespace findmug::io {

// Exponential back-off: initial, 2x, 4x, ... capped at max. Not thread-safe.
class Backoff {
 public:
  // Throws findmug::Error when initial <= 0 or max < initial.
  Backoff(std::chrono::milliseconds initial, std::chrono::milliseconds max);
  // The wait before the coming attempt; the one after is twice as long (capped).
  std::chrono::milliseconds next();
  // What next() will return, without advancing.
  std::chrono::milliseconds peek() const { return current_; }
  // Back to the initial delay (after a success).
  void reset() { current_ = initial_; }

 private:
  std::chrono::milliseconds initial_, max_, current_;
};

// What one Device::read() produced.
struct DeviceRead {
  enum class Kind {
    Frame,     // `frame` holds a whole frame (seq/validation are done by DeviceSource)
    Pending,   // data arrived but no whole frame yet (one of two streams, say)
    Idle,      // nothing within the time limit
    Rejected,  // bad data skipped (`error` says what); the device is alive
    Lost,      // the device is gone or broken (`error` says why)
    Ended,     // a finite recording is exhausted
  };
  Kind kind = Kind::Idle;
  std::optional<RgbdFrame> frame;
  std::string error;
  // Images the device discarded during this read (e.g. unpaired).
  std::uint64_t dropped = 0;

  static DeviceRead of(RgbdFrame f) { return {Kind::Frame, std::move(f), {}, 0}; }
  static DeviceRead with(Kind kind, std::string error = {}) {
    return {kind, std::nullopt, std::move(error), 0};
  }
};

// A camera (or anything that can vanish). Called from one thread — the
// one calling DeviceSource::next() — except describe(), which must be
// thread-safe.
class Device {
 public:
  virtual ~Device() = default;
  // "openni2:<first device> (PrimeSense Carmine 1.09, uri ...)": for logs and status.
  virtual std::string describe() const = 0;
  // Opens (or re-opens after close()); returns an error message, empty on success.
  virtual std::string open() = 0;
  // Releases the device; no-op when closed. The next open() starts afresh.
  virtual void close() = 0;
  // Waits at most about `limit` for the next frame.
  virtual DeviceRead read(std::chrono::milliseconds limit) = 0;
};

struct DeviceSourceSettings {
  // Back-off between re-open attempts (SourceOptions::reconnect_initial / _max).
  std::chrono::milliseconds reconnect_initial{500};
  std::chrono::milliseconds reconnect_max{5000};
  // A device without any data for this long is considered lost.
  std::chrono::milliseconds frame_timeout{2000};
  // Time limit of one read(): how promptly stop() and the timeout are noticed.
  std::chrono::milliseconds poll{100};
  // false: a device that cannot be opened at start-up is a configuration
  // error (thrown), and a loss ends the source as Failed (file playback).
  bool reconnect = true;
  // Frames per second to pace delivery at, 0 = as they come (playback speed).
  double rate_hz = 0.0;
};

// One re-open attempt, for diagnostics and tests (kept: the latest 64).
struct ReconnectAttempt {
  std::chrono::steady_clock::time_point at;  // when open() was called
  std::chrono::milliseconds waited;          // the back-off delay before it
  bool succeeded = false;
  std::string error;  // open()'s message when it failed
};

class DeviceSource : public FrameSourceBase {
 public:
  // Opens the device. When that fails, the source starts in Reconnecting
  // and next() keeps trying; without settings.reconnect it throws
  // findmug::Error naming the device instead. `options` supplies the frame
  // overrides (intrinsics, extrinsics) applied to every frame.
  DeviceSource(std::unique_ptr<Device> device, DeviceSourceSettings settings,
               SourceOptions options = {});
  ~DeviceSource() override;

  std::optional<RgbdFrame> next() override;
  std::string describe() const override { return device_->describe(); }

  // Re-open attempts so far, oldest first (thread-safe).
  std::vector<ReconnectAttempt> reconnectAttempts() const;

 private:
  // Waits out the back-off and tries open() until it works (true) or stop().
  bool reopen();
  void lose(const std::string& why);

  std::unique_ptr<Device> device_;
  DeviceSourceSettings settings_;
  SourceOptions options_;
  Backoff backoff_;
  bool open_ = false;
  std::int64_t seq_ = 0;
  Clock::time_point last_activity_ = Clock::now();
  mutable std::mutex attempts_mutex_;
  std::deque<ReconnectAttempt> attempts_;
};

}  // namespace findmug::io
