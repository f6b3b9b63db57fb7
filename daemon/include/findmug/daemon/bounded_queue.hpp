// findmug/daemon/bounded_queue.hpp — a small thread-safe FIFO with an explicit
// policy for what happens when it is full.
//
// The daemon's stages are joined by these queues. Frames are perishable: when
// a consumer falls behind, the right answer for a robot is to forget the
// oldest waiting frame and keep the newest, so latency stays bounded
// (DropPolicy::DropOldest, every drop counted). There is no blocking policy: push() never waits, so a
// stage's worker handing its result on can never be stalled by a slow stage
// after it (which would stall every worker of the stage behind it).
//
// Every pop hands out a ticket: 0, 1, 2, ... in pop order. Because pops are
// FIFO, ticket order is arrival order among the items that survived the drop
// policy, which is exactly what a reorder buffer downstream of parallel
// workers needs (see reorder_buffer.hpp). Drops therefore never leave holes
// in the ticket sequence.
//
// close() ends the queue: pushes are refused, blocked callers wake, and pop
// returns what is left before reporting the end (or nothing, after clear()).
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <utility>

namespace findmug::daemon {

enum class DropPolicy {
  DropOldest,  // full: evict the oldest waiting item, count it, accept the new one
};

enum class PushResult {
  Accepted,
  AcceptedDroppedOldest,  // accepted; the oldest waiting item was evicted
  Closed,                 // refused: the queue is closed (the item is discarded)
};

template <typename T>
class BoundedQueue {
 public:
  struct Popped {
    T value;
    std::uint64_t ticket;  // 0, 1, 2, ... in pop order
  };

  BoundedQueue(std::size_t capacity, DropPolicy policy) : capacity_(capacity), policy_(policy) {
    if (capacity_ == 0) throw std::invalid_argument("BoundedQueue capacity must be at least 1");
  }
  BoundedQueue(const BoundedQueue&) = delete;
  BoundedQueue& operator=(const BoundedQueue&) = delete;

  // Adds `value` under the queue's drop policy; never blocks. `evicted`, when
  // given, receives the dropped item (so a caller can log which frame was lost).
  PushResult push(T value, std::optional<T>* evicted = nullptr) {
    std::unique_lock lock(mutex_);
    if (closed_) return PushResult::Closed;
    PushResult result = PushResult::Accepted;
    if (items_.size() >= capacity_) {
      if (evicted) *evicted = std::move(items_.front());
      items_.pop_front();
      ++dropped_;
      ++evicted_;
      result = PushResult::AcceptedDroppedOldest;
    }
    items_.push_back(std::move(value));
    ++pushed_;
    lock.unlock();
    not_empty_.notify_one();
    return result;
  }

  // Waits for an item. Returns nullopt once the queue is closed and empty.
  std::optional<Popped> pop() {
    std::unique_lock lock(mutex_);
    not_empty_.wait(lock, [&] { return closed_ || !items_.empty(); });
    return takeFrontLocked(lock);
  }

  // As pop(), but gives up after `timeout` (nullopt; check closed()).
  template <typename Rep, typename Period>
  std::optional<Popped> popFor(std::chrono::duration<Rep, Period> timeout) {
    std::unique_lock lock(mutex_);
    not_empty_.wait_for(lock, timeout, [&] { return closed_ || !items_.empty(); });
    return takeFrontLocked(lock);
  }

  // Waits at most `timeout` until the queue has room (or is closed). True
  // when a push now would neither block nor evict (nothing else pushing).
  // Lets a producer take its next item only when it can be accepted, so
  // that items are dropped before any work is spent on them.
  template <typename Rep, typename Period>
  bool waitForRoom(std::chrono::duration<Rep, Period> timeout) {
    std::unique_lock lock(mutex_);
    return not_full_.wait_for(lock, timeout, [&] { return closed_ || items_.size() < capacity_; }) &&
           !closed_;
  }

  // Waits at most `timeout` until no item waits (or the queue is closed); true when empty
  // and open. A producer that pushes only then never has an item wait behind another.
  template <typename Rep, typename Period>
  bool waitUntilEmpty(std::chrono::duration<Rep, Period> timeout) {
    std::unique_lock lock(mutex_);
    return not_full_.wait_for(lock, timeout, [&] { return closed_ || items_.empty(); }) &&
           !closed_;
  }

  // Refuses further pushes and wakes every waiter (pop, waitForRoom). Items already queued can
  // still be popped (drain) unless clear() discards them.
  void close() {
    {
      std::lock_guard lock(mutex_);
      closed_ = true;
    }
    not_empty_.notify_all();
    not_full_.notify_all();
  }

  // Discards every waiting item, counting them as dropped; returns how many.
  std::size_t clear() {
    std::size_t n;
    {
      std::lock_guard lock(mutex_);
      n = items_.size();
      dropped_ += n;
      items_.clear();
    }
    not_full_.notify_all();
    return n;
  }

  std::size_t size() const {
    std::lock_guard lock(mutex_);
    return items_.size();
  }
  bool closed() const {
    std::lock_guard lock(mutex_);
    return closed_;
  }
  std::size_t capacity() const { return capacity_; }
  DropPolicy policy() const { return policy_; }
  std::uint64_t droppedCount() const {
    std::lock_guard lock(mutex_);
    return dropped_;
  }
  // Of those, the ones evicted by the policy (the rest were discarded by clear()).
  std::uint64_t evictedCount() const {
    std::lock_guard lock(mutex_);
    return evicted_;
  }
  // Items handed out by pop so far (= the next ticket).
  std::uint64_t poppedCount() const {
    std::lock_guard lock(mutex_);
    return next_ticket_;
  }
  std::uint64_t pushedCount() const {
    std::lock_guard lock(mutex_);
    return pushed_;
  }

 private:
  std::optional<Popped> takeFrontLocked(std::unique_lock<std::mutex>& lock) {
    if (items_.empty()) return std::nullopt;
    Popped popped{std::move(items_.front()), next_ticket_++};
    items_.pop_front();
    lock.unlock();
    not_full_.notify_all();  // waitForRoom and waitUntilEmpty callers
    return popped;
  }

  const std::size_t capacity_;
  const DropPolicy policy_;
  mutable std::mutex mutex_;
  std::condition_variable not_empty_, not_full_;
  std::deque<T> items_;
  bool closed_ = false;
  std::uint64_t next_ticket_ = 0;
  std::uint64_t dropped_ = 0;
  std::uint64_t evicted_ = 0;
  std::uint64_t pushed_ = 0;
};

}  // namespace findmug::daemon
