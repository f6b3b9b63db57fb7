// The per-frame trace file; see frame_trace.hpp.
#include "findmug/daemon/frame_trace.hpp"

#include "findmug/common/error.hpp"

namespace findmug::daemon {

namespace {

std::int64_t microseconds(FrameTrace::Clock::time_point from, FrameTrace::Clock::time_point to) {
  // An instant never stamped (left at its default) shows as -1 rather than a huge span.
  if (from == FrameTrace::Clock::time_point{} || to == FrameTrace::Clock::time_point{}) return -1;
  return std::chrono::duration_cast<std::chrono::microseconds>(to - from).count();
}

}  // namespace

FrameTraceWriter::FrameTraceWriter(const std::string& path) : out_(path, std::ios::trunc) {
  if (!out_) throw Error("daemon.frame_trace_file: cannot write '" + path + "'");
  out_ << "seq,frame_utime,source_us,door_us,prepare_us,segment_wait_us,segment_us,reorder_us,"
          "publish_wait_us,publish_us,total_us\n";
}

void FrameTraceWriter::write(std::int64_t seq, std::int64_t frame_utime,
                             FrameTrace::Clock::time_point arrival, const FrameTrace& t,
                             FrameTrace::Clock::time_point published) {
  const std::int64_t source_us = frame_utime > 0 && t.submit_utime > 0
                                     ? static_cast<std::int64_t>(t.submit_utime) - frame_utime
                                     : -1;
  std::lock_guard lock(mutex_);
  if (!out_.is_open()) return;
  out_ << seq << ',' << frame_utime << ',' << source_us << ','
       << microseconds(arrival, t.prepare_start) << ','
       << microseconds(t.prepare_start, t.prepare_end) << ','
       << microseconds(t.prepare_end, t.segment_start) << ','
       << microseconds(t.segment_start, t.segment_end) << ','
       << microseconds(t.segment_end, t.released) << ','
       << microseconds(t.released, t.publish_start) << ','
       << microseconds(t.publish_start, published) << ',' << microseconds(arrival, published)
       << '\n';
}

void FrameTraceWriter::close() {
  std::lock_guard lock(mutex_);
  if (out_.is_open()) out_.close();
}

}  // namespace findmug::daemon
