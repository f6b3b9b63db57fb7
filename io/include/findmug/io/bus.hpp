// findmug/io/bus.hpp — the message bus findmug publishes on and listens to.
//
//   Bus          publish(channel, bytes) / subscribe(channel, handler) /
//                handle(timeout). Handlers run on the thread that calls
//                handle(): the bus's *owner thread*. publish() may be called
//                from any thread.
//   LcmBus       the LCM implementation: the only place in findmug that owns
//                an lcm::LCM. A file:// URL replays a log: handle() returns
//                HandleResult::EndOfLog when the log has been read.
//   MemoryBus    an in-process implementation for tests, with LCM's delivery
//                semantics: a published message is queued and handed, on the
//                thread that calls handle(), to the handlers subscribed to its
//                channel at that moment (none: it is discarded). end() makes
//                handle() report EndOfLog once the queue is drained, as a
//                replayed log does.
//   FaultyBus    a decorator whose publish() fails on command (fault tests).
//   SuffixedBus  a decorator that applies the channel suffix (daemon.channel_suffix,
//                --channel-suffix): a program publishes and subscribes by base
//                name (channels.hpp), the bus sends and listens on BASE_SUFFIX.
//                withChannelSuffix() / openBus(url, what, suffix) give one.
//   ReceiveThread  the receive loop every listener needs: a thread that owns a
//                bus and calls handle(100 ms) until stop(), end of log or failure.
//
// Channel names are matched exactly (LcmBus hands them to LCM, which reads them
// as regular expressions; findmug's channel names contain none of its
// metacharacters). Messages are plain bytes: encodeMessage / the decoders in
// lcm_codec.hpp turn them into types; Subscriber<T> (subscriber.hpp) does the
// decoding, counting and receive thread for one typed channel.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace findmug::io {

enum class HandleResult {
  Handled,   // at least one message was dispatched
  Timeout,   // nothing arrived within the timeout
  EndOfLog,  // a replayed log (file://, MemoryBus::end()) has been read to its end
  Failed,    // the transport failed; no more messages will arrive
};

class Bus {
 public:
  using Handler =
      std::function<void(const std::string& channel, const std::uint8_t* data, std::size_t size)>;
  // The same, also given when the message was received (host clock, µs; for a
  // replayed LCM log, when it was recorded).
  using TimedHandler = std::function<void(const std::string& channel, const std::uint8_t* data,
                                          std::size_t size, std::int64_t recv_utime)>;

  virtual ~Bus() = default;

  // Sends `size` bytes on `channel`. Thread-safe. False when the transport
  // refused the message (the caller counts and reports it).
  virtual bool publish(const std::string& channel, const void* data, std::size_t size) = 0;
  // Calls `handler` for each message on `channel`, on the owner thread (the
  // one calling handle()). Subscribe before the owner thread starts handling.
  virtual void subscribeTimed(const std::string& channel, TimedHandler handler) = 0;
  void subscribe(const std::string& channel, Handler handler) {
    subscribeTimed(channel, [h = std::move(handler)](const std::string& c, const std::uint8_t* d,
                                                     std::size_t n, std::int64_t) { h(c, d, n); });
  }
  // Waits at most `timeout` for messages and dispatches them. Owner thread only.
  virtual HandleResult handle(std::chrono::milliseconds timeout) = 0;
  // What the bus is connected to, for messages ("memory", the LCM URL).
  virtual std::string describe() const = 0;
  // True when the bus replays a recorded log (which ends) rather than a live stream.
  virtual bool replaysLog() const = 0;
};

// Encodes an lcm-gen message type and publishes it. False when encoding or
// the transport failed.
template <class Msg>
bool publishMessage(Bus& bus, const std::string& channel, const Msg& message) {
  const int size = message.getEncodedSize();
  if (size < 0) return false;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(size));
  if (message.encode(bytes.data(), 0, size) != size) return false;
  return bus.publish(channel, bytes.data(), bytes.size());
}

// ---- LcmBus -------------------------------------------------------------------

class LcmBus final : public Bus {
 public:
  // Opens `url` ("" = LCM's default, LCM_DEFAULT_URL). Throws findmug::Error
  // naming `what` (the config key or flag the URL came from) when it cannot.
  explicit LcmBus(std::string url, const std::string& what = "LCM URL");
  ~LcmBus() override;
  LcmBus(const LcmBus&) = delete;
  LcmBus& operator=(const LcmBus&) = delete;

  bool publish(const std::string& channel, const void* data, std::size_t size) override;
  void subscribeTimed(const std::string& channel, TimedHandler handler) override;
  HandleResult handle(std::chrono::milliseconds timeout) override;
  std::string describe() const override;
  bool replaysLog() const override { return replaying_log_; }

 private:
  struct Impl;
  std::string url_;
  bool replaying_log_ = false;
  std::unique_ptr<Impl> impl_;
};

// ---- MemoryBus ----------------------------------------------------------------

class MemoryBus final : public Bus {
 public:
  // `capacity`: messages queued and not yet handled; when full, the oldest is
  // discarded (counted in discarded()), like a socket buffer nobody reads.
  explicit MemoryBus(std::size_t capacity = 4096);

  bool publish(const std::string& channel, const void* data, std::size_t size) override;
  void subscribeTimed(const std::string& channel, TimedHandler handler) override;
  HandleResult handle(std::chrono::milliseconds timeout) override;
  std::string describe() const override { return "memory"; }
  bool replaysLog() const override { return ended_.load(); }

  // No more messages: handle() returns EndOfLog once the queue is empty.
  void end();
  std::size_t queued() const;
  std::uint64_t published() const { return published_.load(); }
  std::uint64_t discarded() const { return discarded_.load(); }

 private:
  struct Message {
    std::string channel;
    std::vector<std::uint8_t> bytes;
    std::int64_t utime = 0;  // when published
  };
  std::size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable arrived_;
  std::deque<Message> queue_;
  std::multimap<std::string, TimedHandler> handlers_;  // guarded by mutex_; called without it
  std::atomic<bool> ended_{false};
  std::atomic<std::uint64_t> published_{0}, discarded_{0};
};

// ---- FaultyBus ----------------------------------------------------------------

// Forwards to `inner`; while failing(channel) is set, publish() on that
// channel returns false without sending (counted in refused()).
class FaultyBus final : public Bus {
 public:
  explicit FaultyBus(std::shared_ptr<Bus> inner) : inner_(std::move(inner)) {}

  void failPublish(const std::string& channel, bool fail);
  std::uint64_t refused() const { return refused_.load(); }

  bool publish(const std::string& channel, const void* data, std::size_t size) override;
  void subscribeTimed(const std::string& channel, TimedHandler handler) override {
    inner_->subscribeTimed(channel, std::move(handler));
  }
  HandleResult handle(std::chrono::milliseconds timeout) override {
    return inner_->handle(timeout);
  }
  std::string describe() const override { return "faulty " + inner_->describe(); }
  bool replaysLog() const override { return inner_->replaysLog(); }

 private:
  std::shared_ptr<Bus> inner_;
  mutable std::mutex mutex_;
  std::vector<std::string> failing_;
  std::atomic<std::uint64_t> refused_{0};
};

// ---- SuffixedBus -----------------------------------------------------------------

// Forwards to `inner` with every channel name turned into channelName(channel, suffix)
// (channels.hpp): the one place a program's channel suffix is applied. Handlers are
// given the name on the wire (the suffixed one). The suffix is checked at construction
// (findmug::Error naming it).
class SuffixedBus final : public Bus {
 public:
  SuffixedBus(std::shared_ptr<Bus> inner, std::string suffix);

  bool publish(const std::string& channel, const void* data, std::size_t size) override {
    return inner_->publish(wireName(channel), data, size);
  }
  void subscribeTimed(const std::string& channel, TimedHandler handler) override {
    inner_->subscribeTimed(wireName(channel), std::move(handler));
  }
  HandleResult handle(std::chrono::milliseconds timeout) override {
    return inner_->handle(timeout);
  }
  std::string describe() const override {
    return inner_->describe() + " (channels suffixed _" + suffix_ + ")";
  }
  bool replaysLog() const override { return inner_->replaysLog(); }
  // The name `channel` has on the wire.
  std::string wireName(const std::string& channel) const { return channel + "_" + suffix_; }

 private:
  std::shared_ptr<Bus> inner_;
  std::string suffix_;
};

// `bus` itself when `suffix` is empty, else a SuffixedBus over it.
std::shared_ptr<Bus> withChannelSuffix(std::shared_ptr<Bus> bus, const std::string& suffix);

// ---- ReceiveThread --------------------------------------------------------------

// Owns the receive side of one bus: a thread calling handle(kHandleTimeout)
// until stop(), the end of a replayed log or a transport failure. After every
// wait it calls `after_wait` (e.g. to notice a silent publisher); when the
// loop ends by itself it calls `on_end` with EndOfLog or Failed. Both run on
// the receive thread, the bus's owner thread.
class ReceiveThread {
 public:
  static constexpr std::chrono::milliseconds kHandleTimeout{100};

  ReceiveThread() = default;
  ~ReceiveThread() { stop(); }
  ReceiveThread(const ReceiveThread&) = delete;
  ReceiveThread& operator=(const ReceiveThread&) = delete;

  void start(Bus& bus, std::function<void(HandleResult)> on_end,
             std::function<void()> after_wait = {});
  // Asks the loop to end and joins it (within one handle timeout). Idempotent.
  void stop();
  // The loop has ended (stop(), end of log, failure).
  bool finished() const { return finished_.load(); }

 private:
  std::atomic<bool> stop_requested_{false}, finished_{false};
  std::thread thread_;
};

}  // namespace findmug::io
