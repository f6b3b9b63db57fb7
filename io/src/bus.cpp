// The bus implementations; see bus.hpp.
#include "findmug/io/bus.hpp"

#include <algorithm>
#include <cerrno>
#include <climits>
#include <lcm/lcm-cpp.hpp>

#include "findmug/common/error.hpp"
#include "findmug/io/channels.hpp"

namespace findmug::io {

// ---- LcmBus -------------------------------------------------------------------

struct LcmBus::Impl {
  explicit Impl(const std::string& url) : lcm(url) {}
  lcm::LCM lcm;
  // Handlers stay at fixed addresses: LCM keeps a pointer to each.
  std::vector<std::unique_ptr<TimedHandler>> handlers;
};

LcmBus::LcmBus(std::string url, const std::string& what)
    : url_(std::move(url)), replaying_log_(url_.rfind("file://", 0) == 0) {
  impl_ = std::make_unique<Impl>(url_);
  if (!impl_->lcm.good()) {
    throw Error(what + ": cannot open LCM provider '" +
                (url_.empty() ? std::string("<default>") : url_) + "'" +
                (url_.empty() ? " (the default, from LCM_DEFAULT_URL)" : ""));
  }
}

// Destroying the handle flushes a file:// log and leaves a udpm group.
LcmBus::~LcmBus() = default;

bool LcmBus::publish(const std::string& channel, const void* data, std::size_t size) {
  if (size > static_cast<std::size_t>(UINT_MAX)) return false;
  // lcm::LCM::publish is thread-safe.
  return impl_->lcm.publish(channel, data, static_cast<unsigned int>(size)) == 0;
}

void LcmBus::subscribeTimed(const std::string& channel, TimedHandler handler) {
  impl_->handlers.push_back(std::make_unique<TimedHandler>(std::move(handler)));
  TimedHandler* h = impl_->handlers.back().get();
  impl_->lcm.subscribeFunction(
      channel,
      +[](const lcm::ReceiveBuffer* buffer, const std::string& ch, TimedHandler* target) {
        (*target)(ch, static_cast<const std::uint8_t*>(buffer->data),
                  static_cast<std::size_t>(buffer->data_size), buffer->recv_utime);
      },
      h);
}

HandleResult LcmBus::handle(std::chrono::milliseconds timeout) {
  const int rc = impl_->lcm.handleTimeout(static_cast<int>(timeout.count()));
  if (rc > 0) return HandleResult::Handled;
  if (rc == 0) return HandleResult::Timeout;
  // A signal interrupted the wait (the clients' and tools' stop signals): not a failure.
  if (!replaying_log_ && errno == EINTR) return HandleResult::Timeout;
  // LCM reports the end of a replayed log as an error: say which it is.
  return replaying_log_ ? HandleResult::EndOfLog : HandleResult::Failed;
}

std::string LcmBus::describe() const { return url_.empty() ? std::string("default URL") : url_; }

// ---- MemoryBus ----------------------------------------------------------------

MemoryBus::MemoryBus(std::size_t capacity) : capacity_(std::max<std::size_t>(capacity, 1)) {}

bool MemoryBus::publish(const std::string& channel, const void* data, std::size_t size) {
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  {
    std::lock_guard lock(mutex_);
    if (ended_.load()) return false;  // nothing is delivered after end()
    while (queue_.size() >= capacity_) {
      queue_.pop_front();
      discarded_.fetch_add(1);
    }
    const auto utime = std::chrono::duration_cast<std::chrono::microseconds>(
                           std::chrono::system_clock::now().time_since_epoch())
                           .count();
    queue_.push_back(Message{channel, std::vector<std::uint8_t>(bytes, bytes + size),
                             static_cast<std::int64_t>(utime)});
  }
  published_.fetch_add(1);
  arrived_.notify_all();
  return true;
}

void MemoryBus::subscribeTimed(const std::string& channel, TimedHandler handler) {
  std::lock_guard lock(mutex_);
  handlers_.emplace(channel, std::move(handler));
}

HandleResult MemoryBus::handle(std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  if (!arrived_.wait_for(lock, timeout, [&] { return !queue_.empty() || ended_.load(); })) {
    return HandleResult::Timeout;
  }
  if (queue_.empty()) return HandleResult::EndOfLog;
  // One message per call, as LCM does; handlers run without the lock so that
  // they may publish (on this or another channel).
  Message message = std::move(queue_.front());
  queue_.pop_front();
  std::vector<TimedHandler*> targets;
  const auto [first, last] = handlers_.equal_range(message.channel);
  for (auto it = first; it != last; ++it) targets.push_back(&it->second);
  lock.unlock();
  for (TimedHandler* h : targets) {
    (*h)(message.channel, message.bytes.data(), message.bytes.size(), message.utime);
  }
  return HandleResult::Handled;
}

void MemoryBus::end() {
  {
    std::lock_guard lock(mutex_);
    ended_.store(true);
  }
  arrived_.notify_all();
}

std::size_t MemoryBus::queued() const {
  std::lock_guard lock(mutex_);
  return queue_.size();
}

// ---- FaultyBus ----------------------------------------------------------------

SuffixedBus::SuffixedBus(std::shared_ptr<Bus> inner, std::string suffix)
    : inner_(std::move(inner)), suffix_(std::move(suffix)) {
  if (suffix_.empty()) throw Error("SuffixedBus: empty channel suffix");
  checkChannelSuffix(suffix_);  // a malformed one: an Error naming it
}

std::shared_ptr<Bus> withChannelSuffix(std::shared_ptr<Bus> bus, const std::string& suffix) {
  if (suffix.empty()) return bus;
  return std::make_shared<SuffixedBus>(std::move(bus), suffix);
}

void FaultyBus::failPublish(const std::string& channel, bool fail) {
  std::lock_guard lock(mutex_);
  const auto it = std::find(failing_.begin(), failing_.end(), channel);
  if (fail && it == failing_.end()) failing_.push_back(channel);
  if (!fail && it != failing_.end()) failing_.erase(it);
}

bool FaultyBus::publish(const std::string& channel, const void* data, std::size_t size) {
  {
    std::lock_guard lock(mutex_);
    if (std::find(failing_.begin(), failing_.end(), channel) != failing_.end()) {
      refused_.fetch_add(1);
      return false;
    }
  }
  return inner_->publish(channel, data, size);
}

// ---- ReceiveThread --------------------------------------------------------------

void ReceiveThread::start(Bus& bus, std::function<void(HandleResult)> on_end,
                          std::function<void()> after_wait) {
  stop();
  stop_requested_.store(false);
  finished_.store(false);
  thread_ =
      std::thread([this, &bus, on_end = std::move(on_end), after_wait = std::move(after_wait)] {
        while (!stop_requested_.load()) {
          // Short timeout: the loop must notice stop() promptly.
          const HandleResult result = bus.handle(kHandleTimeout);
          if (after_wait) after_wait();
          if (result == HandleResult::EndOfLog || result == HandleResult::Failed) {
            if (on_end) on_end(result);
            break;
          }
        }
        finished_.store(true);
      });
}

void ReceiveThread::stop() {
  stop_requested_.store(true);
  if (thread_.joinable()) thread_.join();
}

}  // namespace findmug::io
