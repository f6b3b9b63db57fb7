// findmug/daemon/stage.hpp — one pipeline stage: a function run on a queue's items.
//
// A stage owns its input queue (bounded, with a drop policy), runs `work` on
// each item and hands the results to `emit` IN INPUT ORDER, one call at a
// time. It runs in one of two modes, selected at construction:
//
//   Threaded    `workers` threads pop from the queue. With several workers
//               items are processed in parallel; a reorder buffer keyed by
//               the queue's pop tickets restores input order before emit.
//               This is how the bottleneck stage (segmentation) uses every
//               core while publishing in frame order.
//   Sequential  push() runs work and emit inline on the caller's thread. The
//               same pipeline then runs deterministically, frame by frame,
//               which is what tests and offline tools want.
//
// A single-worker stage may also have a periodic `tick`, run by its worker
// thread between items (or inline by tick() in sequential mode). The
// publisher stage uses it for the status message so that one thread alone
// owns the output LCM handle.
//
// A threaded stage may have a `gate`, run by a worker before it takes the
// next item: the prepare stage waits there until the segment queue has
// room, so that under overload frames wait (and are dropped, keeping the
// newest) in its input queue, before any work is spent on them.
//
// `work` returns nullopt when an item yields nothing (e.g. a rejected frame);
// an exception escaping `work` is reported through `on_error` and treated
// the same way. Either way the item's place in the order is released, so
// one bad frame never stalls the frames behind it.
#pragma once

#include <pthread.h>

#include <atomic>
#include <chrono>
#include <exception>
#include <functional>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "findmug/daemon/bounded_queue.hpp"
#include "findmug/daemon/reorder_buffer.hpp"
#include "findmug/daemon/stats.hpp"

namespace findmug::daemon {

enum class ExecutionMode { Threaded, Sequential };

// What stop() does with items still waiting in the input queue.
enum class StopMode {
  Drain,    // process everything already queued, then stop
  Discard,  // drop what is queued (counted as drops); only in-flight items finish
};

struct StageOptions {
  std::string name;
  ExecutionMode mode = ExecutionMode::Threaded;
  int workers = 1;
  std::size_t queue_capacity = 2;
  DropPolicy policy = DropPolicy::DropOldest;
  std::chrono::steady_clock::duration latency_window = std::chrono::seconds(10);
  // Periodic tick (single worker only); zero = none.
  std::chrono::steady_clock::duration tick_period{0};
  // Threaded: the workers' thread name (top -H; the benchmarks read a named thread's CPU
  // time from /proc), at most 15 characters; "" = unnamed.
  std::string thread_name{};
};

struct StageStats {
  std::string name;
  std::size_t queue_depth = 0;
  std::size_t queue_capacity = 0;
  std::uint64_t accepted = 0;   // items that entered the queue
  std::uint64_t dropped = 0;    // evicted by the drop policy or discarded at stop
  std::uint64_t evicted = 0;    // of those, evicted by the drop policy (queue full)
  std::uint64_t completed = 0;  // work returned a value
  std::uint64_t failed = 0;     // work returned nullopt or threw
  std::size_t in_flight = 0;    // taken from the queue, not yet emitted (incl. held for reorder)
  LatencySummary latency;       // wall time of `work`
};

// What a stage calls, by name (designated initialisers at the call site: `{.work = ...,
// .emit = ..., .on_error = ...}`). `work` and `emit` are required, the rest optional (the
// `{}` initialisers let a call site leave them out without a missing-initialiser warning).
template <typename In, typename Out>
struct StageCallbacks {
  std::function<std::optional<Out>(In&)> work{};     // an item -> its result, or nothing
  std::function<void(Out&&)> emit{};                 // each result, in input order, one at a time
  // An item the drop policy evicted; the callback may move from it (e.g. hand its buffers
  // back for reuse), nothing reads it afterwards.
  std::function<void(In& dropped)> on_drop{};
  std::function<void(const std::string& what)> on_error{};  // an exception escaped `work`
  std::function<void()> tick{};  // every StageOptions::tick_period (single worker only)
  std::function<void()> gate{};  // run by a worker before it takes the next item
};

template <typename In, typename Out>
class Stage {
 public:
  Stage(StageOptions options, StageCallbacks<In, Out> callbacks)
      : options_(std::move(options)),
        work_(std::move(callbacks.work)),
        emit_(std::move(callbacks.emit)),
        on_drop_(std::move(callbacks.on_drop)),
        on_error_(std::move(callbacks.on_error)),
        tick_(std::move(callbacks.tick)),
        gate_(std::move(callbacks.gate)),
        queue_(options_.queue_capacity, options_.policy),
        latency_(options_.latency_window) {
    if (!work_ || !emit_) {
      throw std::invalid_argument(options_.name + ": work and emit are required");
    }
    if (options_.workers < 1) throw std::invalid_argument(options_.name + ": workers must be >= 1");
    if (tick_ && options_.workers != 1) {
      throw std::invalid_argument(options_.name + ": a ticking stage must have one worker");
    }
  }
  Stage(const Stage&) = delete;
  Stage& operator=(const Stage&) = delete;
  ~Stage() { stop(StopMode::Discard); }

  void start() {
    if (options_.mode == ExecutionMode::Sequential || !threads_.empty()) return;
    for (int i = 0; i < options_.workers; ++i) threads_.emplace_back([this] { workerLoop(); });
  }

  // Threaded: enqueue under the drop policy; never blocks.
  // Sequential: run work + emit now. Returns false if the stage is stopped.
  bool push(In item) {
    if (options_.mode == ExecutionMode::Sequential) {
      if (queue_.closed()) return false;
      accepted_.fetch_add(1);
      in_flight_.fetch_add(1);
      auto result = run(item);
      if (result) emit_(std::move(*result));
      in_flight_.fetch_sub(1);
      return true;
    }
    std::optional<In> evicted;
    const PushResult r = queue_.push(std::move(item), &evicted);
    if (r == PushResult::Closed) return false;
    accepted_.fetch_add(1);
    if (r == PushResult::AcceptedDroppedOldest && evicted && on_drop_) on_drop_(*evicted);
    return true;
  }

  // Waits at most `timeout` for room in the input queue; false on timeout or
  // once the stage is closed.
  template <typename Rep, typename Period>
  bool waitForRoom(std::chrono::duration<Rep, Period> timeout) {
    return queue_.waitForRoom(timeout);
  }
  // Waits at most `timeout` until nothing waits in the input queue; false on timeout or
  // once the stage is closed.
  template <typename Rep, typename Period>
  bool waitUntilEmpty(std::chrono::duration<Rep, Period> timeout) {
    return queue_.waitUntilEmpty(timeout);
  }
  bool closed() const { return queue_.closed(); }
  std::size_t queueSize() const { return queue_.size(); }

  // Sequential mode: run the periodic tick now (threaded mode ticks itself).
  void tick() {
    if (tick_) tick_();
  }

  // Closes the input, handles queued items per `mode`, joins the workers.
  // Idempotent. After stop(), push() returns false.
  void stop(StopMode mode) {
    close(mode);
    join();
  }

  // The two halves of stop(), for a caller that must not wait for an item
  // in flight longer than it can afford (see Pipeline::stop).
  void close(StopMode mode) {
    if (mode == StopMode::Discard) queue_.clear();
    queue_.close();
  }
  void join() {
    for (auto& t : threads_) {
      if (t.joinable()) t.join();
    }
    threads_.clear();
  }

  StageStats stats() const {
    StageStats s;
    s.name = options_.name;
    // Read in this order so that an item moving between the queue, a worker
    // and the next stage is counted twice rather than not at all (a caller
    // waiting for the pipeline to go idle must never see it idle too early).
    const std::uint64_t released = released_.load();
    s.queue_depth = queue_.size();
    const std::uint64_t popped = queue_.poppedCount();
    s.queue_capacity = queue_.capacity();
    s.accepted = accepted_.load();
    s.dropped = queue_.droppedCount();
    s.evicted = queue_.evictedCount();
    s.completed = completed_.load();
    s.failed = failed_.load();
    s.in_flight = options_.mode == ExecutionMode::Sequential
                      ? in_flight_.load()
                      : static_cast<std::size_t>(popped - released);
    std::lock_guard lock(latency_mutex_);
    s.latency = latency_.summary();
    return s;
  }

  const StageOptions& options() const { return options_; }

 private:
  std::optional<Out> run(In& item) {
    const auto t0 = std::chrono::steady_clock::now();
    std::optional<Out> result;
    try {
      result = work_(item);
    } catch (const std::exception& e) {
      if (on_error_) on_error_(options_.name + ": " + e.what());
    } catch (...) {
      if (on_error_) on_error_(options_.name + ": unknown exception");
    }
    const auto t1 = std::chrono::steady_clock::now();
    {
      std::lock_guard lock(latency_mutex_);
      latency_.add(std::chrono::duration<double, std::milli>(t1 - t0).count(), t1);
    }
    (result ? completed_ : failed_).fetch_add(1);
    return result;
  }

  void workerLoop() {
    using Clock = std::chrono::steady_clock;
    if (!options_.thread_name.empty()) {
      pthread_setname_np(pthread_self(), options_.thread_name.substr(0, 15).c_str());
    }
    const bool ticking = tick_ && options_.tick_period > Clock::duration::zero();
    auto next_tick = Clock::now() + options_.tick_period;
    for (;;) {
      std::optional<typename BoundedQueue<In>::Popped> popped;
      if (gate_) gate_();
      if (ticking) {
        popped = queue_.popFor(std::max(next_tick - Clock::now(), Clock::duration::zero()));
      } else {
        popped = queue_.pop();
      }
      if (popped) {
        auto result = run(popped->value);
        std::lock_guard lock(release_mutex_);
        reorder_.insert(popped->ticket, std::move(result));
        for (auto& r : reorder_.release()) emit_(std::move(r));
        // Tickets released so far (results and tombstones) have left the
        // stage; set after emit, so a result is never in neither stage.
        released_.store(reorder_.nextTicket());
      }
      if (ticking && Clock::now() >= next_tick) {
        tick_();
        next_tick = Clock::now() + options_.tick_period;
      }
      if (!popped && queue_.closed() && queue_.size() == 0) break;
    }
  }

  StageOptions options_;
  decltype(StageCallbacks<In, Out>::work) work_;
  decltype(StageCallbacks<In, Out>::emit) emit_;
  decltype(StageCallbacks<In, Out>::on_drop) on_drop_;
  decltype(StageCallbacks<In, Out>::on_error) on_error_;
  decltype(StageCallbacks<In, Out>::tick) tick_;
  decltype(StageCallbacks<In, Out>::gate) gate_;
  BoundedQueue<In> queue_;
  std::vector<std::thread> threads_;

  std::mutex release_mutex_;
  ReorderBuffer<Out> reorder_;

  mutable std::mutex latency_mutex_;
  LatencyWindow latency_;
  std::atomic<std::uint64_t> accepted_{0}, completed_{0}, failed_{0};
  std::atomic<std::size_t> in_flight_{0};   // sequential mode
  std::atomic<std::uint64_t> released_{0};  // threaded mode: tickets that left the stage
};

}  // namespace findmug::daemon
