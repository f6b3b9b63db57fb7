// findmug/io/lcm_source.hpp — frames from rgbd_frame_t messages on an LCM channel.
//
// The source owns its LCM handle and a thread that runs handleTimeout() on
// it; next() takes frames from a small queue the thread fills.
//   * live URLs (udpm://, memq://): when the queue is full the oldest frame is
//     dropped (stats().frames_dropped): the consumer always sees fresh data;
//   * file:// URLs (replaying a log): the thread waits for room instead, so no
//     frame is lost, and the end of the log ends the stream (EndOfStream).
// The queue holds the messages' bytes: next() decodes the message it takes,
// so a frame dropped from the queue costs no decoding (dropped at the door).
// Bad messages (truncated, corrupt, wrong type) are logged, counted in
// stats().frames_rejected and skipped when next() reaches them. State: Starting until the first
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

#include "findmug/io/frame_source.hpp"

namespace lcm {
class LCM;
class ReceiveBuffer;
}  // namespace lcm

namespace findmug::io {

class LcmFrameSource : public FrameSourceBase {
 public:
  static constexpr std::chrono::milliseconds kSilenceTimeout{2000};

  // Throws findmug::Error when the URL cannot be opened.
  LcmFrameSource(std::string channel, std::string url, SourceOptions options);
  ~LcmFrameSource() override;
  LcmFrameSource(const LcmFrameSource&) = delete;
  LcmFrameSource& operator=(const LcmFrameSource&) = delete;

  std::optional<RgbdFrame> next() override;
  std::string describe() const override { return description_; }

  // The handle the source listens on. memq:// delivers only within one
  // handle, so in-process publishers (tests, an embedded grabber) publish here.
  // lcm::LCM::publish is thread-safe.
  lcm::LCM& lcm() { return *lcm_; }

  // Message handler, called on the source's thread (public for LCM's subscribe).
  void onMessage(const lcm::ReceiveBuffer* buffer, const std::string& channel);

 private:
  void onStop() override;
  void run();

  std::string channel_;
  std::string url_;
  SourceOptions options_;
  bool replaying_log_ = false;
  std::string description_;
  std::unique_ptr<lcm::LCM> lcm_;

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
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace findmug::io
