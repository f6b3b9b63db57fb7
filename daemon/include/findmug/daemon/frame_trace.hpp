// findmug/daemon/frame_trace.hpp — when one frame entered and left each queue and step of the
// pipeline, and the optional CSV file (daemon.frame_trace_file) that records it per frame.
//
// The status message reports each stage's time; what it cannot show is where a slow frame
// waited (behind another frame at the door, in the segment queue, in the reorder buffer
// behind a slower frame, in the publish queue). The trace answers that for every published
// frame: tests/bench/daemon_bench.sh turns it into the "where the latency goes" table.
#pragma once

#include <chrono>
#include <cstdint>
#include <fstream>
#include <mutex>
#include <string>

namespace findmug::daemon {

// Instants of one frame's way through the pipeline (steady clock; default = not reached).
struct FrameTrace {
  using Clock = std::chrono::steady_clock;
  Clock::time_point prepare_start{}, prepare_end{};  // the prepare step
  Clock::time_point segment_start{}, segment_end{};  // a segment worker
  Clock::time_point released{};       // left the reorder buffer, handed to the publish queue
  Clock::time_point publish_start{};  // taken by the publish thread
  std::uint64_t submit_utime = 0;     // host clock at submit (against the frame's own utime)
};

// Appends one CSV row per published frame to a file. Thread-safe; rows are buffered and
// flushed by close() (and when the buffer fills).
class FrameTraceWriter {
 public:
  // Creates (truncates) `path`; throws findmug::Error naming daemon.frame_trace_file and the
  // path when it cannot be written.
  explicit FrameTraceWriter(const std::string& path);

  // seq, the frame's utime, then microseconds: source (frame utime to submit, host clock:
  // transit and the source's queue), door (submit to the prepare step), prepare, segment_wait,
  // segment, reorder, publish_wait, publish, total (submit to published).
  void write(std::int64_t seq, std::int64_t frame_utime, FrameTrace::Clock::time_point arrival,
             const FrameTrace& trace, FrameTrace::Clock::time_point published);
  void close();

 private:
  std::mutex mutex_;
  std::ofstream out_;
};

}  // namespace findmug::daemon
