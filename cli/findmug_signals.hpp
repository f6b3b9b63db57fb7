// findmug_signals.hpp — the one way findmug programs stop on SIGINT / SIGTERM.
//
// StopSignals blocks SIGINT and SIGTERM in the thread that makes it (threads it
// starts later inherit the mask) and waits for them on a thread of its own
// (sigwait). So no program code runs inside a signal handler, and no worker
// thread sees a system call fail with EINTR because of a Ctrl-C; the signal
// becomes a flag (requested()) and, if asked, calls made on that thread
// (onStop(): Daemon::requestStop, FrameSource::stop, ...).
//
// Make it early in main(), before anything that may start a thread (LCM
// providers, frame sources). Should a thread started earlier take the signal
// anyway, a handler passes it on to the waiting thread, so it still counts.
// One StopSignals at a time per process.
//
// A daemon may also take SIGHUP (StopSignals(true)): it is blocked and taken by
// the same thread, stops nothing, and runs the onHangup() action each time
// (findmugd: reload the model; systemd's ExecReload sends it).
#pragma once

#include <signal.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <thread>

namespace findmug::cli {

class StopSignals {
 public:
  // `take_hangup`: also take SIGHUP (see above); otherwise SIGHUP keeps its default.
  explicit StopSignals(bool take_hangup = false);
  // Stops the waiting thread; restores the signal mask of the thread that made it
  // and the signals' previous handlers.
  ~StopSignals();
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

  // True once SIGINT or SIGTERM has arrived.
  bool requested() const noexcept { return requested_.load(); }
  // The signal that asked to stop (SIGINT or SIGTERM), 0 before one has.
  int signalNumber() const noexcept { return signal_number_.load(); }

  // An action registered by onStop(); destroying it unregisters the action (and
  // waits for it if it is running), so it cannot outlive what it touches.
  class Registration {
   public:
    Registration() = default;
    Registration(Registration&& other) noexcept;
    Registration& operator=(Registration&& other) noexcept;
    ~Registration();

   private:
    friend class StopSignals;
    Registration(StopSignals* owner, std::uint64_t id) : owner_(owner), id_(id) {}
    StopSignals* owner_ = nullptr;
    std::uint64_t id_ = 0;
  };

  // Runs `action` once when the first stop signal arrives, on the waiting thread
  // (so it must be thread-safe); at once on the calling thread if one already has.
  [[nodiscard]] Registration onStop(std::function<void()> action);

  // The action each SIGHUP runs on the waiting thread (needs take_hangup); replaces
  // the previous one, and an empty one clears it (waiting for a running one), so
  // clear it before what it touches goes away.
  void onHangup(std::function<void()> action);
  // SIGHUPs taken so far.
  std::uint64_t hangups() const noexcept { return hangups_.load(); }

  // Waits until a stop signal arrives or `timeout` has passed; returns requested().
  bool waitFor(std::chrono::milliseconds timeout);

 private:
  void waitLoop();
  void remove(std::uint64_t id);

  sigset_t signals_{};
  sigset_t old_mask_{};
  struct sigaction old_int_ {
  }, old_term_{}, old_hup_{};
  bool take_hangup_ = false;
  std::atomic<std::uint64_t> hangups_{0};
  std::function<void()> hangup_action_;  // guarded by mutex_; run holding running_
  std::atomic<bool> requested_{false};
  std::atomic<int> signal_number_{0};
  std::mutex mutex_;    // requested_ transitions, closing_, actions_
  std::mutex running_;  // held while actions run, so remove() waits for them
  std::condition_variable changed_;
  bool closing_ = false;
  std::uint64_t next_id_ = 1;
  std::map<std::uint64_t, std::function<void()>> actions_;
  std::thread waiter_;
};

}  // namespace findmug::cli
