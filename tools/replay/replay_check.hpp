// replay_check.hpp — what a replay run must satisfy, and what it measured.
//
// The replay test and the daemon benchmark both watch a running daemon from
// the outside, over LCM: frames go in on FINDMUG_RGBD, label images and status
// come out. ReplayCheck collects those observations and turns them into
//
//   * correctness verdicts (violations), which hold on any machine however
//     loaded, because they are about *which* frames came out, never about *when*:
//       - every label image belongs to a replayed frame (seq and utime match,
//         same image size),
//       - label images come out in frame order, none twice,
//       - frames in = frames published + frames dropped (+ rejected, which
//         must be zero for valid frames), from the daemon's final status,
//       - every label image the daemon says it published was received;
//   * figures (latency percentiles and histogram, output fps, drops, per-stage
//     times from status), which are reported, never asserted.
//
// Latency of a frame = time its label image was received minus time the
// frame itself was received, both stamped by the same LCM receiver on this
// host (recv_utime of the two messages). That is "publish time minus frame
// time" as a client sees it, independent of the utime stored in a recorded
// log (which is the time of recording, not of replay).
//
// Pure bookkeeping: no LCM, no threads; unit-tested in replay_check_test.cpp.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

namespace findmug::replay {

// A frame that was put on the bus (from the recorded log, or seen live).
struct FrameInfo {
  std::int64_t seq = 0;
  std::uint64_t utime = 0;  // the frame's own utime field
  int width = 0;
  int height = 0;
};

// One label_image_t as received.
struct LabelInfo {
  std::int64_t seq = 0;
  std::uint64_t utime = 0;
  int width = 0;
  int height = 0;
  std::int64_t recv_utime = 0;         // when this process received it (host clock)
  std::int64_t daemon_latency_us = 0;  // label_image_t.latency_us (arrival -> publish, in-daemon)
  bool all_void = false;  // no pixel labelled (e.g. no ground plane found): a cheap frame
};

// The parts of a status_t the checks need.
struct StatusInfo {
  std::int64_t utime = 0;
  std::int64_t frames_received = 0;
  std::int64_t frames_processed = 0;
  std::int64_t frames_dropped = 0;
  std::int64_t frames_rejected = 0;
  int source_state = -1;  // status_t::SOURCE_*
  // The semantic map sink (daemon.semantic_map; 0 when off): frames fused, frames it
  // skipped (fell behind), voxels.
  std::int64_t semantic_map_frames = 0, semantic_map_skipped = 0, semantic_map_voxels = 0;
  // The object work (status_t.object_*): frames it took and skipped, candidates matched and
  // named, objects mapped, object maps published.
  std::int64_t object_frames = 0, object_frames_skipped = 0, object_candidates = 0,
               objects_named = 0, mapped_objects = 0, object_map_publishes = 0;
  struct Stage {
    std::string name;
    double p50_ms = 0, p95_ms = 0, max_ms = 0;
  };
  std::vector<Stage> stages;
};

inline constexpr int kSourceStopped = 4;  // status_t::SOURCE_STOPPED

struct Percentiles {
  std::size_t count = 0;
  double mean = 0, p50 = 0, p90 = 0, p99 = 0, max = 0;
};

// Nearest-rank percentiles of `values` (any order); all zero when empty.
Percentiles percentiles(std::vector<double> values);

struct HistogramBin {
  double from_ms = 0, to_ms = 0;  // [from, to); the last bin is open-ended
  std::size_t count = 0;
};

// Fixed-width bins of `bin_ms` from 0, the last one (">= bins * bin_ms")
// collecting everything beyond.
std::vector<HistogramBin> histogram(const std::vector<double>& values_ms, double bin_ms,
                                    std::size_t bins);

struct CheckOptions {
  // Require the daemon's final status (source_state STOPPED) to have arrived;
  // without it the accounting check cannot be made.
  bool require_final_status = true;
  // Frames with valid content must not be rejected.
  bool expect_no_rejects = true;
  // At least this many label images must come out (guards against a run
  // that passes by publishing nothing).
  std::int64_t min_published = 1;
};

struct Report {
  std::vector<std::string> violations;  // empty = all invariants hold

  std::int64_t frames_in = 0;            // frames replayed
  std::int64_t frames_seen = 0;          // of those, seen on the bus by this receiver
  std::int64_t labels_received = 0;
  std::optional<StatusInfo> final_status;  // last status received
  std::int64_t dropped_by_seq_gap = 0;   // replayed frames without a label image
  std::int64_t labels_all_void = 0;      // label images with no labelled pixel

  Percentiles latency_ms;          // label received - frame received
  Percentiles daemon_latency_ms;   // label_image_t.latency_us
  std::vector<double> latencies_ms;
  double input_fps = 0;   // frames seen on the bus, first to last
  double output_fps = 0;  // label images received, first to last
  double span_s = 0;      // first frame seen to last label received

  bool ok() const { return violations.empty(); }
};

class ReplayCheck {
 public:
  // The replayed frames, in replay order (call once per frame; a seq given
  // twice is a broken recording and becomes a violation).
  void addReplayedFrame(const FrameInfo& frame);
  // A frame seen on the bus at `recv_utime` (latency reference). Frames not
  // announced with addReplayedFrame are added (live sources, no log).
  void frameSeen(const FrameInfo& frame, std::int64_t recv_utime, bool add_if_unknown);
  void labelReceived(const LabelInfo& label);
  void statusReceived(const StatusInfo& status);
  // A problem found by the caller (e.g. a label image that does not decode).
  void addViolation(std::string violation) { external_errors_.push_back(std::move(violation)); }

  std::int64_t framesReplayed() const { return static_cast<std::int64_t>(order_.size()); }
  std::int64_t labelsReceived() const { return static_cast<std::int64_t>(labels_.size()); }
  const std::optional<StatusInfo>& lastStatus() const { return last_status_; }
  // True once the last status accounts for `frames_in` frames
  // (processed + dropped + rejected >= frames_in): nothing is left inside.
  bool drained(std::int64_t frames_in) const;

  // `frames_in`: how many frames were replayed in total (normally
  // framesReplayed(); more when the same log was played several times).
  Report evaluate(std::int64_t frames_in, const CheckOptions& options) const;

 private:
  struct Frame {
    FrameInfo info;
    std::optional<std::int64_t> seen_utime;
  };
  std::map<std::int64_t, Frame> frames_;  // by seq
  std::vector<std::int64_t> order_;       // seqs in replay order
  std::vector<std::string> recording_errors_;
  std::vector<std::string> external_errors_;
  std::vector<LabelInfo> labels_;
  std::optional<StatusInfo> last_status_;
};

// Human-readable summary (several lines) and a JSON object of the figures.
void printReport(std::ostream& out, const std::string& name, const Report& report);
void writeJson(std::ostream& out, const std::string& name, const Report& report);
// CSV "from_ms,to_ms,count" plus a text bar chart of the latency histogram.
void writeHistogram(std::ostream& csv, std::ostream& chart, const std::string& name,
                    const Report& report, double bin_ms, std::size_t bins);

}  // namespace findmug::replay
