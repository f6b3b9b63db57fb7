// findmug/io/lcm_source.hpp — frames from rgbd_frame_t messages on an LCM channel.
//
// The source owns its bus (an LcmBus on the URL, or one handed in: tests use an
// io::MemoryBus) and a ReceiveThread (bus.hpp), the bus's owner thread, that
// handles it every 100 ms; next() takes frames from a small queue that thread
// fills. (Not a Subscriber<T>: frames are decoded by next(), not on arrival.)
//   * live URLs (udpm://, memq://): when the queue is full the oldest frame is
//     dropped (stats().frames_dropped): the consumer always sees fresh data;
//   * file:// URLs (replaying a log): the thread waits for room instead, so no
//     frame is lost, and the end of the log ends the stream (EndOfStream).
// The queue holds the messages' bytes: next() decodes the message it takes,
// so a frame dropped from the queue costs no decoding (dropped at the door).
// Bad messages (truncated, corrupt, wrong type) are logged, counted in
// stats().frames_rejected and skipped when next() reaches them. Holes in the
// publisher's seq are counted as stats().frames_lost_in_transit (transit_loss.hpp). State: Starting until the first
// frame, Running while frames come, Reconnecting when a live channel has been silent for
// kSilenceTimeout (the publisher or its camera is gone), EndOfStream at the end of a log.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "findmug/io/bus.hpp"
#include "findmug/io/frame_source.hpp"
#include "findmug/io/transit_loss.hpp"

namespace findmug::io {

class LcmFrameSource : public FrameSourceBase {
 public:
  static constexpr std::chrono::milliseconds kSilenceTimeout{2000};

  // Throws findmug::Error when the URL cannot be opened.
  LcmFrameSource(std::string channel, std::string url, SourceOptions options);
  // Listens on `bus` (its replaysLog() chooses the log behaviour above).
  LcmFrameSource(std::string channel, std::shared_ptr<Bus> bus, SourceOptions options);
  ~LcmFrameSource() override;
  LcmFrameSource(const LcmFrameSource&) = delete;
  LcmFrameSource& operator=(const LcmFrameSource&) = delete;

  std::optional<RgbdFrame> next() override;
  std::string describe() const override { return description_; }

  // The bus the source listens on. memq:// delivers only within one LCM
  // handle, so in-process publishers (tests, an embedded grabber) publish here.
  // Bus::publish is thread-safe.
  Bus& bus() { return *bus_; }

 private:
  void onStop() override;
  void onMessage(const std::string& channel, const std::uint8_t* bytes, std::size_t size);
  void afterWait();
  void onEnd(HandleResult how);

  std::string channel_;
  SourceOptions options_;
  bool replaying_log_ = false;
  std::string description_;
  std::shared_ptr<Bus> bus_;

  std::mutex queue_mutex_;
  std::condition_variable queue_changed_;
  struct RawMessage {
    std::vector<std::uint8_t> bytes;
    std::string channel;
  };
  std::deque<RawMessage> queue_;
  std::vector<RawMessage> spare_;                            // recycled buffers
  std::atomic<Clock::time_point> last_frame_{Clock::now()};  // last good frame received
  bool finished_ = false;  // thread ended (end of log / fatal LCM error)
  TransitLossCounter transit_;  // seq holes, in arrival order (receive thread only)
  bool stopping_ = false;
  ReceiveThread receiver_;  // last member: stopped before the rest goes
};

}  // namespace findmug::io
