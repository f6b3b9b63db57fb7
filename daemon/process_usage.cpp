// CPU and heap of the daemon process; see process_usage.hpp.
#include "findmug/daemon/process_usage.hpp"

#include <ctime>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace findmug::daemon {

namespace {

double processCpuSeconds() {
  timespec ts{};
  if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts) != 0) return 0.0;
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

}  // namespace

ProcessUsage::ProcessUsage() : sample_time_(Clock::now()), sample_cpu_s_(processCpuSeconds()) {}

double ProcessUsage::sampleCores() {
  const double cpu_s = processCpuSeconds();
  const auto now = Clock::now();
  std::lock_guard lock(mutex_);
  const double wall_s = std::chrono::duration<double>(now - sample_time_).count();
  if (wall_s > 0.0) cores_ = (cpu_s - sample_cpu_s_) / wall_s;
  sample_cpu_s_ = cpu_s;
  sample_time_ = now;
  return cores_;
}

double ProcessUsage::lastCores() const {
  std::lock_guard lock(mutex_);
  return cores_;
}

std::int64_t ProcessUsage::heapInUseBytes() {
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 33))
  const struct mallinfo2 m = mallinfo2();
  return static_cast<std::int64_t>(m.uordblks + m.hblkhd);
#else
  return -1;
#endif
}

}  // namespace findmug::daemon
