// Bookkeeping and verdicts for replay runs; see replay_check.hpp.
#include "replay_check.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <numeric>
#include <sstream>

#include "findmug_json.hpp"

namespace findmug::replay {

namespace {

// More than this many violations of one run are summarised, not listed.
constexpr std::size_t kMaxListedViolations = 20;

std::string frameName(std::int64_t seq, std::uint64_t utime) {
  return "seq " + std::to_string(seq) + " (utime " + std::to_string(utime) + ")";
}

std::string fixed(double v, int digits = 1) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

using cli::jsonNumber;
using cli::jsonString;

void jsonPercentiles(std::ostream& out, const Percentiles& p) {
  out << "{\"count\": " << p.count << ", \"mean\": " << jsonNumber(p.mean, 2)
      << ", \"p50\": " << jsonNumber(p.p50, 2) << ", \"p90\": " << jsonNumber(p.p90, 2)
      << ", \"p99\": " << jsonNumber(p.p99, 2) << ", \"max\": " << jsonNumber(p.max, 2) << "}";
}

}  // namespace

Percentiles percentiles(std::vector<double> values) {
  Percentiles p;
  p.count = values.size();
  if (values.empty()) return p;
  std::sort(values.begin(), values.end());
  auto rank = [&](double q) {
    const auto idx = static_cast<std::size_t>(std::ceil(q * static_cast<double>(values.size())));
    return values[std::clamp<std::size_t>(idx, 1, values.size()) - 1];
  };
  p.mean = std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(values.size());
  p.p50 = rank(0.50);
  p.p90 = rank(0.90);
  p.p99 = rank(0.99);
  p.max = values.back();
  return p;
}

std::vector<HistogramBin> histogram(const std::vector<double>& values_ms, double bin_ms,
                                    std::size_t bins) {
  std::vector<HistogramBin> out;
  if (bins == 0 || !(bin_ms > 0)) return out;
  for (std::size_t i = 0; i < bins; ++i) {
    out.push_back({bin_ms * static_cast<double>(i),
                   i + 1 == bins ? std::numeric_limits<double>::infinity()
                                 : bin_ms * static_cast<double>(i + 1),
                   0});
  }
  for (double v : values_ms) {
    const double index = std::floor(std::max(v, 0.0) / bin_ms);
    const auto i = index >= static_cast<double>(bins - 1) ? bins - 1
                                                           : static_cast<std::size_t>(index);
    ++out[i].count;
  }
  return out;
}

void ReplayCheck::addReplayedFrame(const FrameInfo& frame) {
  if (frames_.count(frame.seq)) {
    recording_errors_.push_back("replayed frames: " + frameName(frame.seq, frame.utime) +
                                " appears twice in the replayed sequence");
    return;
  }
  frames_[frame.seq] = Frame{frame, std::nullopt};
  order_.push_back(frame.seq);
}

void ReplayCheck::frameSeen(const FrameInfo& frame, std::int64_t recv_utime, bool add_if_unknown) {
  auto it = frames_.find(frame.seq);
  if (it == frames_.end()) {
    if (!add_if_unknown) return;  // not one of ours (e.g. another publisher): ignored
    addReplayedFrame(frame);
    it = frames_.find(frame.seq);
  }
  // A recorded log replayed twice would show the same seq again; the first
  // sighting is the reference (labels come out once per seq anyway).
  if (it->second.info.utime == frame.utime && !it->second.seen_utime) {
    it->second.seen_utime = recv_utime;
  }
}

void ReplayCheck::labelReceived(const LabelInfo& label) { labels_.push_back(label); }

void ReplayCheck::statusReceived(const StatusInfo& status) { last_status_ = status; }

bool ReplayCheck::drained(std::int64_t frames_in) const {
  if (!last_status_) return false;
  const StatusInfo& s = *last_status_;
  return s.frames_processed + s.frames_dropped + s.frames_rejected >= frames_in;
}

Report ReplayCheck::evaluate(std::int64_t frames_in, const CheckOptions& options) const {
  Report r;
  r.frames_in = frames_in;
  r.labels_received = static_cast<std::int64_t>(labels_.size());
  r.final_status = last_status_;
  std::vector<std::string> violations = recording_errors_;
  violations.insert(violations.end(), external_errors_.begin(), external_errors_.end());

  // Position of each seq in replay order.
  std::map<std::int64_t, std::size_t> position;
  for (std::size_t i = 0; i < order_.size(); ++i) position[order_[i]] = i;

  std::vector<double> daemon_latencies;
  std::vector<bool> labelled(order_.size(), false);
  std::optional<std::size_t> last_position;
  std::optional<std::int64_t> last_seq;
  for (const LabelInfo& label : labels_) {
    const std::string name = "label image for " + frameName(label.seq, label.utime);
    const auto it = frames_.find(label.seq);
    if (it == frames_.end()) {
      violations.push_back(name + ": no replayed frame has this seq");
      continue;
    }
    const FrameInfo& frame = it->second.info;
    if (frame.utime != label.utime) {
      violations.push_back(name + ": the replayed frame with this seq has utime " +
                           std::to_string(frame.utime));
      continue;
    }
    if (frame.width != label.width || frame.height != label.height) {
      violations.push_back(name + ": " + std::to_string(label.width) + "x" +
                           std::to_string(label.height) + " but the frame is " +
                           std::to_string(frame.width) + "x" + std::to_string(frame.height));
    }
    const std::size_t pos = position.at(label.seq);
    if (last_position && pos == *last_position) {
      violations.push_back(name + ": published twice");
    } else if (last_position && pos < *last_position) {
      violations.push_back(name + ": out of order (after the label image for seq " +
                           std::to_string(*last_seq) + ", which was replayed later)");
    }
    if (!last_position || pos > *last_position) {
      last_position = pos;
      last_seq = label.seq;
    }
    labelled[pos] = true;
    if (label.all_void) ++r.labels_all_void;
    if (it->second.seen_utime) {
      r.latencies_ms.push_back(static_cast<double>(label.recv_utime - *it->second.seen_utime) /
                               1000.0);
    }
    daemon_latencies.push_back(static_cast<double>(label.daemon_latency_us) / 1000.0);
  }
  r.dropped_by_seq_gap =
      static_cast<std::int64_t>(std::count(labelled.begin(), labelled.end(), false));

  // Accounting against the daemon's own counters.
  if (!last_status_) {
    if (options.require_final_status) {
      violations.push_back("no status message received: frames cannot be accounted for");
    }
  } else {
    const StatusInfo& s = *last_status_;
    if (options.require_final_status && s.source_state != kSourceStopped) {
      violations.push_back("the last status received is not the daemon's final one (source_state " +
                           std::to_string(s.source_state) + ", expected STOPPED = " +
                           std::to_string(kSourceStopped) + ")");
    }
    const std::int64_t accounted = s.frames_processed + s.frames_dropped + s.frames_rejected;
    if (accounted != frames_in) {
      violations.push_back("accounting: " + std::to_string(frames_in) + " frames replayed but " +
                           std::to_string(s.frames_processed) + " published + " +
                           std::to_string(s.frames_dropped) + " dropped + " +
                           std::to_string(s.frames_rejected) + " rejected = " +
                           std::to_string(accounted) + " (status frames_received " +
                           std::to_string(s.frames_received) + ")");
    }
    if (options.expect_no_rejects && s.frames_rejected != 0) {
      violations.push_back(std::to_string(s.frames_rejected) +
                           " valid frames were rejected by the daemon");
    }
    if (s.frames_processed != r.labels_received) {
      violations.push_back("the daemon published " + std::to_string(s.frames_processed) +
                           " label images but " + std::to_string(r.labels_received) +
                           " were received");
    }
  }
  if (r.labels_received < options.min_published) {
    violations.push_back("only " + std::to_string(r.labels_received) +
                         " label images were published (at least " +
                         std::to_string(options.min_published) + " expected)");
  }

  if (violations.size() > kMaxListedViolations) {
    const std::size_t more = violations.size() - kMaxListedViolations;
    violations.resize(kMaxListedViolations);
    violations.push_back("... and " + std::to_string(more) + " more violations");
  }
  r.violations = std::move(violations);

  // Figures.
  r.latency_ms = percentiles(r.latencies_ms);
  r.daemon_latency_ms = percentiles(daemon_latencies);
  std::vector<std::int64_t> seen;
  for (const auto& [seq, f] : frames_) {
    if (f.seen_utime) seen.push_back(*f.seen_utime);
  }
  std::sort(seen.begin(), seen.end());
  r.frames_seen = static_cast<std::int64_t>(seen.size());
  if (seen.size() >= 2) {
    r.input_fps = static_cast<double>(seen.size() - 1) /
                  (static_cast<double>(seen.back() - seen.front()) / 1e6);
  }
  if (labels_.size() >= 2) {
    const double span = static_cast<double>(labels_.back().recv_utime - labels_.front().recv_utime);
    if (span > 0) r.output_fps = static_cast<double>(labels_.size() - 1) / (span / 1e6);
  }
  if (!seen.empty() && !labels_.empty()) {
    r.span_s = static_cast<double>(labels_.back().recv_utime - seen.front()) / 1e6;
  }
  return r;
}

void printReport(std::ostream& out, const std::string& name, const Report& r) {
  out << "== " << name << ": " << (r.ok() ? "OK" : "FAILED") << "\n";
  out << "   frames replayed " << r.frames_in << " (seen on the bus " << r.frames_seen
      << "), label images " << r.labels_received << ", frames without a label "
      << r.dropped_by_seq_gap << ", all-void label images " << r.labels_all_void << "\n";
  if (r.final_status) {
    const StatusInfo& s = *r.final_status;
    out << "   daemon status: received " << s.frames_received << ", published "
        << s.frames_processed << ", dropped " << s.frames_dropped << ", rejected "
        << s.frames_rejected << ", source_state " << s.source_state << "\n";
    if (s.semantic_map_frames > 0 || s.semantic_map_skipped > 0) {
      out << "   semantic map: fused " << s.semantic_map_frames << ", skipped "
          << s.semantic_map_skipped << ", voxels " << s.semantic_map_voxels << "\n";
    }
    if (s.object_frames > 0) {
      out << "   objects: frames " << s.object_frames << ", skipped " << s.object_frames_skipped
          << ", candidates " << s.object_candidates << ", named " << s.objects_named
          << ", mapped " << s.mapped_objects << ", object maps published "
          << s.object_map_publishes << "\n";
    }
  }
  out << "   input " << fixed(r.input_fps, 2) << " fps, output " << fixed(r.output_fps, 2)
      << " fps\n";
  out << "   latency ms (label received - frame received): p50 " << fixed(r.latency_ms.p50)
      << ", p90 " << fixed(r.latency_ms.p90) << ", p99 " << fixed(r.latency_ms.p99) << ", max "
      << fixed(r.latency_ms.max) << " over " << r.latency_ms.count << " frames\n";
  out << "   in-daemon latency ms (label_image_t.latency_us): p50 "
      << fixed(r.daemon_latency_ms.p50) << ", p99 " << fixed(r.daemon_latency_ms.p99)
      << ", max " << fixed(r.daemon_latency_ms.max) << "\n";
  for (const std::string& v : r.violations) out << "   VIOLATION: " << v << "\n";
}

void writeJson(std::ostream& out, const std::string& name, const Report& r) {
  out << "{\n  \"name\": " << jsonString(name) << ",\n  \"ok\": " << (r.ok() ? "true" : "false")
      << ",\n  \"frames_in\": " << r.frames_in << ",\n  \"frames_seen\": " << r.frames_seen
      << ",\n  \"labels_received\": " << r.labels_received
      << ",\n  \"frames_without_label\": " << r.dropped_by_seq_gap
      << ",\n  \"labels_all_void\": " << r.labels_all_void
      << ",\n  \"input_fps\": " << jsonNumber(r.input_fps, 3)
      << ",\n  \"output_fps\": " << jsonNumber(r.output_fps, 3)
      << ",\n  \"span_s\": " << jsonNumber(r.span_s, 3) << ",\n  \"latency_ms\": ";
  jsonPercentiles(out, r.latency_ms);
  out << ",\n  \"daemon_latency_ms\": ";
  jsonPercentiles(out, r.daemon_latency_ms);
  out << ",\n  \"status\": ";
  if (!r.final_status) {
    out << "null";
  } else {
    const StatusInfo& s = *r.final_status;
    out << "{\"frames_received\": " << s.frames_received
        << ", \"frames_processed\": " << s.frames_processed
        << ", \"frames_dropped\": " << s.frames_dropped
        << ", \"frames_rejected\": " << s.frames_rejected
        << ", \"source_state\": " << s.source_state
        << ", \"semantic_map_frames\": " << s.semantic_map_frames
        << ", \"semantic_map_skipped\": " << s.semantic_map_skipped
        << ", \"semantic_map_voxels\": " << s.semantic_map_voxels
        << ", \"object_frames\": " << s.object_frames
        << ", \"object_frames_skipped\": " << s.object_frames_skipped
        << ", \"object_candidates\": " << s.object_candidates
        << ", \"objects_named\": " << s.objects_named
        << ", \"mapped_objects\": " << s.mapped_objects
        << ", \"object_map_publishes\": " << s.object_map_publishes << ", \"stages\": [";
    for (std::size_t i = 0; i < s.stages.size(); ++i) {
      const auto& st = s.stages[i];
      out << (i ? ", " : "") << "{\"name\": " << jsonString(st.name)
          << ", \"p50_ms\": " << jsonNumber(st.p50_ms, 2)
          << ", \"p95_ms\": " << jsonNumber(st.p95_ms, 2)
          << ", \"max_ms\": " << jsonNumber(st.max_ms, 2) << "}";
    }
    out << "]}";
  }
  out << ",\n  \"violations\": [";
  for (std::size_t i = 0; i < r.violations.size(); ++i) {
    out << (i ? ", " : "") << jsonString(r.violations[i]);
  }
  out << "]\n}\n";
}

void writeHistogram(std::ostream& csv, std::ostream& chart, const std::string& name,
                    const Report& r, double bin_ms, std::size_t bins) {
  const auto h = histogram(r.latencies_ms, bin_ms, bins);
  csv << "from_ms,to_ms,count\n";
  std::size_t most = 0;
  for (const auto& b : h) {
    csv << fixed(b.from_ms, 0) << "," << (std::isinf(b.to_ms) ? std::string("inf") : fixed(b.to_ms, 0))
        << "," << b.count << "\n";
    most = std::max(most, b.count);
  }
  chart << "Latency histogram, " << name << " (label received - frame received, "
        << r.latency_ms.count << " frames; p50 " << fixed(r.latency_ms.p50) << " ms, p99 "
        << fixed(r.latency_ms.p99) << " ms, max " << fixed(r.latency_ms.max) << " ms)\n";
  constexpr std::size_t kWidth = 50;
  for (const auto& b : h) {
    const std::string range = std::isinf(b.to_ms)
                                  ? ">= " + fixed(b.from_ms, 0) + " ms"
                                  : fixed(b.from_ms, 0) + "-" + fixed(b.to_ms, 0) + " ms";
    const std::size_t bar = most ? (b.count * kWidth + most - 1) / most : 0;
    chart << std::setw(16) << range << " | " << std::string(bar, '#') << " " << b.count << "\n";
  }
}

}  // namespace findmug::replay
