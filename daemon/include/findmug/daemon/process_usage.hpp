// findmug/daemon/process_usage.hpp — what the daemon process uses: CPU cores since the last
// sample (status_t.cpu_used_cores against daemon.max_cpu_cores) and the heap in use.
#pragma once

#include <chrono>
#include <cstdint>
#include <mutex>

namespace findmug::daemon {

class ProcessUsage {
 public:
  using Clock = std::chrono::steady_clock;

  ProcessUsage();
  // CPU time the whole process used since the previous sample (or construction) per wall
  // second: 1.0 = one core busy. Thread-safe.
  double sampleCores();
  // The last value sampleCores() returned (0 before the first).
  double lastCores() const;

  // Bytes the allocator has handed out and not got back (the heap's own view): a leak grows
  // this; memory freed but kept for reuse (daemon.heap_keep_mb, glibc arenas) shows in RSS
  // only. -1 where the C library cannot say.
  static std::int64_t heapInUseBytes();

 private:
  mutable std::mutex mutex_;
  Clock::time_point sample_time_;
  double sample_cpu_s_ = 0.0;
  double cores_ = 0.0;
};

}  // namespace findmug::daemon
