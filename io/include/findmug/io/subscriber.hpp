// findmug/io/subscriber.hpp — one typed channel on a bus: decode, count, keep the latest.
//
// Subscriber<T> subscribes to one channel of a Bus (bus.hpp) and decodes each
// message with a hardened decoder of lcm_codec.hpp (decodeRobotPose,
// decodeTables, ...). A message the decoder refuses is counted as rejected
// and reported through `on_error` (one line naming the channel and what was
// wrong: the decoder's message); nothing is thrown out of the thread that
// handles the bus. A good one
// is counted, kept as latest() and handed to `on_message`.
//
// Who handles the bus:
//   * startReceiving(on_end): the subscriber's own ReceiveThread owns the bus
//     (handle() every 100 ms) until stop(), the end of a replayed log or a
//     transport failure (ended() says which; on_end is called with it);
//   * otherwise the caller's thread owns it and calls bus.handle() itself
//     (the single-threaded clients, with several subscribers on one bus).
// Callbacks run on the bus's owner thread; the counters and latest() may be
// read from any thread.
#pragma once

#include <atomic>
#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>

#include "findmug/io/bus.hpp"

namespace findmug::io {

template <class T>
class Subscriber {
 public:
  using Decode =
      std::function<T(const std::uint8_t* data, std::size_t size, const std::string& channel)>;
  using OnMessage = std::function<void(const T& message, const std::string& channel)>;
  using OnError = std::function<void(const std::string& what)>;

  // Subscribes at once (before any thread handles `bus`); `bus` must outlive
  // the subscriber.
  Subscriber(Bus& bus, std::string channel, Decode decode, OnMessage on_message = {},
             OnError on_error = {})
      : bus_(bus),
        channel_(std::move(channel)),
        decode_(std::move(decode)),
        on_message_(std::move(on_message)),
        on_error_(std::move(on_error)) {
    bus_.subscribe(channel_, [this](const std::string& ch, const std::uint8_t* data,
                                    std::size_t size) { receive(ch, data, size); });
  }
  ~Subscriber() { stop(); }
  Subscriber(const Subscriber&) = delete;
  Subscriber& operator=(const Subscriber&) = delete;

  // Starts the receive thread (the subscriber owns the bus from now on).
  // `on_end` (on that thread) learns whether the loop ended at the end of a
  // replayed log (EndOfLog) or because the transport failed (Failed).
  void startReceiving(std::function<void(HandleResult)> on_end = {}) {
    receiver_.start(bus_, [this, on_end = std::move(on_end)](HandleResult how) {
      ended_.store(how);
      if (on_end) on_end(how);
    });
  }
  // Stops the receive thread, if any. Idempotent; counters and latest() stay readable.
  void stop() { receiver_.stop(); }

  // Messages that arrived (accepted + rejected).
  std::uint64_t received() const { return accepted_.load() + rejected_.load(); }
  std::uint64_t accepted() const { return accepted_.load(); }  // after their handler ran
  std::uint64_t rejected() const { return rejected_.load(); }
  std::optional<T> latest() const {
    std::lock_guard lock(latest_mutex_);
    return latest_;
  }
  // The receive thread has ended (stop(), end of a replayed log, failure).
  bool finished() const { return receiver_.finished(); }
  // How it ended by itself: EndOfLog or Failed; Handled while it runs or after stop().
  HandleResult ended() const { return ended_.load(); }
  const std::string& channel() const { return channel_; }
  Bus& bus() { return bus_; }

 private:
  void receive(const std::string& channel, const std::uint8_t* data, std::size_t size) {
    std::optional<T> message;
    try {
      message.emplace(decode_(data, size, channel));
    } catch (const std::exception& e) {
      rejected_.fetch_add(1);
      report(e.what());
      return;
    }
    {
      std::lock_guard lock(latest_mutex_);
      latest_ = *message;
    }
    if (on_message_) {
      try {
        on_message_(*message, channel);
      } catch (const std::exception& e) {  // the receive thread must survive its user
        report(channel + ": " + e.what());
      }
    }
    // Counted once its handler is done, so that a caller who sees the count go up may rely
    // on what the handler did (counted before, the pose input reported a pose received
    // before its history held it, and a frame submitted then could miss it).
    accepted_.fetch_add(1);
  }
  void report(const std::string& what) {
    if (on_error_) on_error_(what);
  }

  Bus& bus_;
  std::string channel_;
  Decode decode_;
  OnMessage on_message_;
  OnError on_error_;
  mutable std::mutex latest_mutex_;
  std::optional<T> latest_;
  std::atomic<std::uint64_t> accepted_{0}, rejected_{0};
  std::atomic<HandleResult> ended_{HandleResult::Handled};
  ReceiveThread receiver_;
};

}  // namespace findmug::io
