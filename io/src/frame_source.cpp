#include "findmug/io/frame_source.hpp"

#include <spdlog/spdlog.h>

#include <charconv>
#include <cmath>

#include "findmug/common/error.hpp"
#include "findmug/common/numbers.hpp"
#include "sources_internal.hpp"

namespace findmug::io {

std::string_view sourceStateName(SourceState state) {
  switch (state) {
    case SourceState::Starting:
      return "starting";
    case SourceState::Running:
      return "running";
    case SourceState::Reconnecting:
      return "reconnecting";
    case SourceState::EndOfStream:
      return "end_of_stream";
    case SourceState::Stopped:
      return "stopped";
    case SourceState::Failed:
      return "failed";
  }
  return "unknown";
}

std::uint64_t hostUtimeNow() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                        std::chrono::system_clock::now().time_since_epoch())
                                        .count());
}

// ---- FrameSourceBase ------------------------------------------------------------------

void FrameSourceBase::stop() {
  {
    std::lock_guard lock(mutex_);
    if (stop_requested_) return;
    stop_requested_ = true;
    state_ = SourceState::Stopped;
  }
  wake_.notify_all();
  onStop();
}

SourceState FrameSourceBase::state() const {
  std::lock_guard lock(mutex_);
  return state_;
}

SourceStats FrameSourceBase::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

bool FrameSourceBase::stopRequested() const {
  std::lock_guard lock(mutex_);
  return stop_requested_;
}

void FrameSourceBase::setState(SourceState state) {
  std::lock_guard lock(mutex_);
  // Stopped is final: a worker finishing late must not make it look alive.
  if (!stop_requested_) state_ = state;
}

void FrameSourceBase::recordError(const std::string& message) {
  spdlog::error("{}: {}", describe(), message);
  std::lock_guard lock(mutex_);
  stats_.last_error = message;
  stats_.last_error_utime = hostUtimeNow();
}

void FrameSourceBase::recordRejected(const std::string& message) {
  std::uint64_t rejected = 0;
  {
    std::lock_guard lock(mutex_);
    rejected = ++stats_.frames_rejected;
    stats_.last_error = message;
    stats_.last_error_utime = hostUtimeNow();
  }
  // A stream of garbage (a wrong publisher on our channel) must not flood the
  // log: the first ten, then every hundredth; the count is in stats() anyway.
  if (rejected <= 10 || rejected % 100 == 0) {
    spdlog::warn("{}: skipped bad input ({} so far): {}", describe(), rejected, message);
  }
}

void FrameSourceBase::recordDelivered() {
  std::lock_guard lock(mutex_);
  ++stats_.frames_delivered;
  if (!stop_requested_) state_ = SourceState::Running;
}

void FrameSourceBase::recordDropped(std::uint64_t count) {
  std::lock_guard lock(mutex_);
  stats_.frames_dropped += count;
}

void FrameSourceBase::recordLostInTransit(std::uint64_t total) {
  std::lock_guard lock(mutex_);
  stats_.frames_lost_in_transit = total;
}

void FrameSourceBase::recordReconnect() {
  std::lock_guard lock(mutex_);
  ++stats_.reconnects;
}

bool FrameSourceBase::sleepUntil(Clock::time_point deadline) {
  std::unique_lock lock(mutex_);
  wake_.wait_until(lock, deadline, [&] { return stop_requested_; });
  return !stop_requested_;
}

bool FrameSourceBase::pace(double rate_hz) {
  if (!(rate_hz > 0.0)) return !stopRequested();
  const auto period =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / rate_hz));
  const auto now = Clock::now();
  Clock::time_point slot = now;
  {
    std::lock_guard lock(mutex_);
    // Next slot one period after the previous one; if we fell behind (slow
    // consumer), restart from now instead of bursting to catch up.
    if (last_paced_ && *last_paced_ + period > now) slot = *last_paced_ + period;
    last_paced_ = slot;
  }
  return sleepUntil(slot);
}

void FrameSourceBase::finishFrame(RgbdFrame& frame, const SourceOptions& options) const {
  if (options.intrinsics) frame.intrinsics = *options.intrinsics;
  if (options.extrinsics && !frame.extrinsics) frame.extrinsics = options.extrinsics;
  if (frame.utime == 0) frame.utime = hostUtimeNow();
  validateFrame(frame);
}

// ---- spec parsing ---------------------------------------------------------------------

namespace {

[[noreturn]] void specError(const std::string& spec, const std::string& what) {
  throw Error("frame source '" + spec + "': " + what +
              " (expected KIND[:TARGET][?key=value&...], KIND one of openni2, lcm, dataset, "
              "pcd, pclzf, tiff; keys rate_hz, loop, realtime, queue, reconnect_ms, "
              "reconnect_max_ms, frame_timeout_ms, url)");
}

bool parseBool(const std::string& spec, const std::string& key, const std::string& value) {
  if (value == "1" || value == "true" || value == "yes" || value == "on") return true;
  if (value == "0" || value == "false" || value == "no" || value == "off") return false;
  specError(spec, key + "=" + value + " is not a boolean");
}

double parseNumber(const std::string& spec, const std::string& key, const std::string& value) {
  const auto v = findmug::parseNumber(value);
  if (!v) specError(spec, key + "=" + value + " is not a number");
  return *v;
}

}  // namespace

SourceSpec parseSourceSpec(const std::string& text) {
  SourceSpec spec;
  spec.text = text;
  const auto question = text.find('?');
  const std::string head = text.substr(0, question);
  const auto colon = head.find(':');
  spec.kind = head.substr(0, colon);
  if (colon != std::string::npos) spec.target = head.substr(colon + 1);
  static const char* kKinds[] = {"openni2", "lcm", "dataset", "pcd", "pclzf", "tiff"};
  bool known = false;
  for (const char* k : kKinds) known = known || spec.kind == k;
  if (!known) specError(text, "unknown kind '" + spec.kind + "'");
  const bool needs_target =
      spec.kind == "dataset" || spec.kind == "pcd" || spec.kind == "pclzf" || spec.kind == "tiff";
  if (needs_target && spec.target.empty()) specError(text, spec.kind + " needs a directory");

  if (question == std::string::npos) return spec;
  std::string rest = text.substr(question + 1);
  while (!rest.empty()) {
    const auto eq = rest.find('=');
    if (eq == std::string::npos) specError(text, "option '" + rest + "' has no value");
    const std::string key = rest.substr(0, eq);
    std::string value;
    if (key == "url") {  // takes the rest: LCM URLs have their own '?' and '&'
      value = rest.substr(eq + 1);
      rest.clear();
    } else {
      const auto amp = rest.find('&', eq);
      value = rest.substr(eq + 1, amp == std::string::npos ? std::string::npos : amp - eq - 1);
      rest = amp == std::string::npos ? std::string() : rest.substr(amp + 1);
    }
    if (key == "rate_hz") {
      spec.options.rate_hz = parseNumber(text, key, value);
      if (spec.options.rate_hz < 0.0 || spec.options.rate_hz > 1000.0) {
        specError(text, "rate_hz=" + value + " outside 0..1000");
      }
    } else if (key == "loop") {
      spec.options.loop = parseBool(text, key, value);
    } else if (key == "realtime") {
      spec.options.realtime = parseBool(text, key, value);
    } else if (key == "queue") {
      const double q = parseNumber(text, key, value);
      if (q < 1 || q > 1000 || q != std::floor(q))
        specError(text, "queue=" + value + " not in 1..1000");
      spec.options.lcm_queue_size = static_cast<int>(q);
    } else if (key == "reconnect_ms" || key == "reconnect_max_ms" || key == "frame_timeout_ms") {
      if (spec.kind != "openni2") specError(text, key + "= only applies to openni2 sources");
      const double ms = parseNumber(text, key, value);
      if (ms < 1 || ms > 3'600'000 || ms != std::floor(ms)) {
        specError(text, key + "=" + value + " not in 1..3600000 (milliseconds)");
      }
      const std::chrono::milliseconds v{static_cast<std::int64_t>(ms)};
      (key == "reconnect_ms"       ? spec.options.reconnect_initial
       : key == "reconnect_max_ms" ? spec.options.reconnect_max
                                   : spec.options.frame_timeout) = v;
    } else if (key == "url") {
      if (spec.kind != "lcm") specError(text, "url= only applies to lcm sources");
      spec.options.lcm_url = value;
    } else {
      specError(text, "unknown option '" + key + "'");
    }
  }
  if (spec.options.reconnect_max < spec.options.reconnect_initial) {
    specError(text, "reconnect_max_ms is below reconnect_ms (" +
                        std::to_string(spec.options.reconnect_initial.count()) + " ms)");
  }
  return spec;
}

std::unique_ptr<FrameSource> makeSource(const SourceSpec& spec) {
  if (spec.kind == "openni2") return detail::makeOpenni2Source(spec);
  if (spec.kind == "lcm") return detail::makeLcmSource(spec);
  if (spec.kind == "dataset") return detail::makeDatasetSource(spec);
  if (spec.kind == "pcd" || spec.kind == "pclzf" || spec.kind == "tiff") {
    return detail::makePclSequenceSource(spec);
  }
  specError(spec.text, "unknown kind '" + spec.kind + "'");
}

std::unique_ptr<FrameSource> makeSource(const std::string& spec) {
  return makeSource(parseSourceSpec(spec));
}

}  // namespace findmug::io
