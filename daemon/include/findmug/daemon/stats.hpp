// findmug/daemon/stats.hpp — sliding-window latency percentiles and rates for status_t.
//
// Both look only at a recent window, so the status message describes the
// recent past (a slow start-up frame does not haunt p95 forever) and memory
// stays bounded. Not thread-safe: owners lock around them.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <deque>
#include <utility>
#include <vector>

namespace findmug::daemon {

struct LatencySummary {
  double p50_ms = 0, p95_ms = 0, max_ms = 0;
  std::size_t samples = 0;
};

// Latency samples of the last `window` of time (at most `max_samples`).
class LatencyWindow {
 public:
  using Clock = std::chrono::steady_clock;

  explicit LatencyWindow(Clock::duration window = std::chrono::seconds(10),
                         std::size_t max_samples = 4096)
      : window_(window), max_samples_(std::max<std::size_t>(max_samples, 1)) {}

  void add(double ms, Clock::time_point now = Clock::now()) {
    samples_.emplace_back(now, ms);
    if (samples_.size() > max_samples_) samples_.pop_front();
  }

  // Nearest-rank percentiles over the samples not older than the window;
  // all zero when there are none.
  LatencySummary summary(Clock::time_point now = Clock::now()) const {
    std::vector<double> sorted;
    for (const auto& [t, ms] : samples_) {
      if (now - t <= window_) sorted.push_back(ms);
    }
    LatencySummary s;
    s.samples = sorted.size();
    if (sorted.empty()) return s;
    std::sort(sorted.begin(), sorted.end());
    auto rank = [&](double q) {
      const auto idx = static_cast<std::size_t>(std::ceil(q * static_cast<double>(sorted.size())));
      return sorted[std::clamp<std::size_t>(idx, 1, sorted.size()) - 1];
    };
    s.p50_ms = rank(0.50);
    s.p95_ms = rank(0.95);
    s.max_ms = sorted.back();
    return s;
  }

 private:
  Clock::duration window_;
  std::size_t max_samples_;
  std::deque<std::pair<Clock::time_point, double>> samples_;
};

// Events per second over the last `window` events (and not older than
// `horizon`, so a stalled stream decays to 0 instead of freezing its last rate).
class RateMeter {
 public:
  using Clock = std::chrono::steady_clock;

  explicit RateMeter(std::size_t window = 30, Clock::duration horizon = std::chrono::seconds(10))
      : window_(std::max<std::size_t>(window, 2)), horizon_(horizon) {}

  void tick(Clock::time_point now = Clock::now()) {
    stamps_.push_back(now);
    if (stamps_.size() > window_) stamps_.pop_front();
  }

  // (n - 1) events per (now - oldest kept stamp): for a steady stream of
  // period T this is 1/T; when the stream stops the span keeps growing, so
  // the rate decays towards 0 instead of freezing.
  double rate(Clock::time_point now = Clock::now()) const {
    std::size_t first = 0;
    while (first < stamps_.size() && now - stamps_[first] > horizon_) ++first;
    const std::size_t n = stamps_.size() - first;
    if (n < 2) return 0.0;
    const double span = std::chrono::duration<double>(now - stamps_[first]).count();
    return span > 0 ? static_cast<double>(n - 1) / span : 0.0;
  }

 private:
  std::size_t window_;
  Clock::duration horizon_;
  std::deque<Clock::time_point> stamps_;
};

}  // namespace findmug::daemon
