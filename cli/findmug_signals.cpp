#include "findmug_signals.hpp"

#include <pthread.h>

#include <cstring>
#include <string>
#include <vector>

#include "findmug/common/error.hpp"

namespace findmug::cli {

namespace {

// The waiting thread of the live StopSignals, for the forwarding handler.
std::atomic<pthread_t*> g_waiter{nullptr};
pthread_t g_waiter_id;

// Runs only in a thread that did not block the signals (one started before the
// StopSignals): hands the signal to the waiting thread. pthread_kill is
// async-signal-safe (POSIX.1-2008 TC1).
void forwardSignal(int signal_number) {
  if (pthread_t* waiter = g_waiter.load()) pthread_kill(*waiter, signal_number);
}

}  // namespace

StopSignals::StopSignals(bool take_hangup) : take_hangup_(take_hangup) {
  sigemptyset(&signals_);
  sigaddset(&signals_, SIGINT);
  sigaddset(&signals_, SIGTERM);
  if (take_hangup_) sigaddset(&signals_, SIGHUP);
  if (const int rc = pthread_sigmask(SIG_BLOCK, &signals_, &old_mask_); rc != 0) {
    throw Error(std::string("cannot block SIGINT/SIGTERM: ") + std::strerror(rc));
  }
  waiter_ = std::thread([this] { waitLoop(); });
  g_waiter_id = waiter_.native_handle();
  g_waiter = &g_waiter_id;
  struct sigaction action {};
  action.sa_handler = forwardSignal;
  action.sa_flags = SA_RESTART;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, &old_int_);
  sigaction(SIGTERM, &action, &old_term_);
  if (take_hangup_) sigaction(SIGHUP, &action, &old_hup_);
}

StopSignals::~StopSignals() {
  sigaction(SIGINT, &old_int_, nullptr);
  sigaction(SIGTERM, &old_term_, nullptr);
  if (take_hangup_) sigaction(SIGHUP, &old_hup_, nullptr);
  g_waiter = nullptr;
  {
    std::lock_guard lock(mutex_);
    closing_ = true;
  }
  // Wakes sigwait(): SIGTERM is blocked in the waiting thread, so it stays
  // pending for that thread until sigwait takes it; closing_ says it is ours.
  pthread_kill(waiter_.native_handle(), SIGTERM);
  waiter_.join();
  pthread_sigmask(SIG_SETMASK, &old_mask_, nullptr);
}

void StopSignals::waitLoop() {
  for (;;) {
    int signal_number = 0;
    if (sigwait(&signals_, &signal_number) != 0) continue;
    std::unique_lock running(running_);
    if (signal_number == SIGHUP) {
      std::function<void()> action;
      {
        std::lock_guard lock(mutex_);
        if (closing_) return;
        action = hangup_action_;
      }
      hangups_.fetch_add(1);
      if (action) action();
      continue;
    }
    std::vector<std::function<void()>> actions;
    {
      std::lock_guard lock(mutex_);
      if (closing_) return;
      if (requested_) continue;  // the first signal decides; later ones change nothing
      signal_number_ = signal_number;
      requested_ = true;
      for (auto& [id, action] : actions_) actions.push_back(std::move(action));
      actions_.clear();
    }
    changed_.notify_all();
    for (auto& action : actions) action();
  }
}

StopSignals::Registration StopSignals::onStop(std::function<void()> action) {
  {
    std::lock_guard lock(mutex_);
    if (!requested_) {
      const std::uint64_t id = next_id_++;
      actions_.emplace(id, std::move(action));
      return Registration(this, id);
    }
  }
  action();
  return Registration();
}

void StopSignals::onHangup(std::function<void()> action) {
  std::lock_guard running(running_);
  std::lock_guard lock(mutex_);
  hangup_action_ = std::move(action);
}

void StopSignals::remove(std::uint64_t id) {
  std::lock_guard running(running_);
  std::lock_guard lock(mutex_);
  actions_.erase(id);
}

bool StopSignals::waitFor(std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  changed_.wait_for(lock, timeout, [this] { return requested_.load(); });
  return requested_;
}

StopSignals::Registration::Registration(Registration&& other) noexcept
    : owner_(other.owner_), id_(other.id_) {
  other.owner_ = nullptr;
}

StopSignals::Registration& StopSignals::Registration::operator=(Registration&& other) noexcept {
  if (this != &other) {
    if (owner_) owner_->remove(id_);
    owner_ = other.owner_;
    id_ = other.id_;
    other.owner_ = nullptr;
  }
  return *this;
}

StopSignals::Registration::~Registration() {
  if (owner_) owner_->remove(id_);
}

}  // namespace findmug::cli
