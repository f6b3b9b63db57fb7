// findmug/io/frame_source.hpp — where RGB-D frames come from.
//
// A FrameSource hides the device, file set or LCM channel behind one blocking
// call, next(). The daemon's capture thread runs
//
//     while (auto frame = source->next()) queue.push(std::move(*frame));
//
// and another thread may call stop(), state() and stats() at any time.
//
// Error policy (why a source never throws out of next() for bad input):
//   * a transient problem — device unplugged, a corrupt file in a sequence, a
//     bad LCM message — is logged, counted in stats(), and retried (with
//     back-off) or skipped; state() shows it (Reconnecting, last_error);
//   * a source that cannot go on (every frame of a sequence is bad, the
//     device is unusable for good) enters Failed and next() returns nullopt;
//   * configuration errors (unknown kind, missing directory, empty sequence,
//     malformed spec) are thrown as findmug::Error by makeSource() at start-up,
//     where a human is watching.
//
// Spec strings (daemon.source, findmug-grab --source):
//   openni2                    first OpenNI2 device (e.g. a Kinect / Xtion)
//   openni2:URI                a given device URI
//   openni2:/path/file.oni     .oni playback (realtime=1: recorded speed)
//   lcm:CHANNEL                rgbd_frame_t messages on CHANNEL (default FINDMUG_RGBD)
//   dataset:/dir               DatasetFolder (rgb/, depth/; label8/ or label40/ optional)
//   pcd:/dir                   organized x y z rgb(a) PCD files, in name order
//   pclzf:/dir                 PCL LZF triplets NAME_depth.pclzf, NAME_rgb.pclzf, NAME.xml
//   tiff:/dir                  NAME_depth.tiff (uint16 mm) + NAME_rgb.tiff (RGB8) pairs
// followed by options: ?rate_hz=5&loop=1&realtime=0&url=memq://
// (openni2 also: reconnect_ms=500&reconnect_max_ms=5000&frame_timeout_ms=2000,
// the back-off and loss detection of device_source.hpp)
// (`url` must come last: its value is the rest of the string, since LCM URLs
// carry their own '?' and '&').
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>

#include "findmug/frame/frame.hpp"

namespace findmug::io {

// Numeric values equal findmug_lcm::status_t::SOURCE_* (status_t.lcm).
enum class SourceState : std::int8_t {
  Starting = 0,      // opening the device / files / channel
  Running = 1,       // delivering frames
  Reconnecting = 2,  // device lost or not present yet; retrying with back-off
  EndOfStream = 3,   // finite source exhausted (loop off)
  Stopped = 4,       // stop() was called
  Failed = 5,        // gave up; stats().last_error says why
};

// "starting", "running", "reconnecting", "end_of_stream", "stopped", "failed".
std::string_view sourceStateName(SourceState state);

struct SourceStats {
  std::uint64_t frames_delivered = 0;  // returned by next()
  std::uint64_t frames_rejected = 0;   // bad input skipped (corrupt file / message / frame)
  std::uint64_t frames_dropped = 0;  // good frames discarded because next() was not called in time
  std::uint64_t reconnects = 0;      // times the device was (re)opened after a loss
  // Frames the publisher numbered (seq) that never arrived: lost on the way
  // (LCM sources; transit_loss.hpp). Not part of frames_dropped: never received.
  std::uint64_t frames_lost_in_transit = 0;
  std::string last_error;            // most recent problem, empty if none
  std::uint64_t last_error_utime = 0;  // when (microseconds, host clock), 0 if none
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;

  // Blocks until the next frame and returns it, validated (validateFrame),
  // with utime (capture time, host clock, microseconds) and seq set.
  // Returns std::nullopt at the end of a finite stream, after stop(), or
  // when the source has failed for good; state() tells which.
  virtual std::optional<RgbdFrame> next() = 0;

  // Makes a blocked next() return nullopt promptly (well under a second) and
  // every later call too. Thread-safe, idempotent.
  virtual void stop() = 0;

  // One line for logs and status: kind, target and the essentials
  // ("dataset:/data/nyu (31 frames, 5 Hz, loop)").
  virtual std::string describe() const = 0;

  // Thread-safe.
  virtual SourceState state() const = 0;
  virtual SourceStats stats() const = 0;
};

struct SourceOptions {
  // File sources (dataset, pcd, pclzf, tiff, .oni): frames per second; 0 =
  // as fast as next() is called (.oni with realtime: the recorded timing).
  double rate_hz = 0.0;
  // File sources: start again after the last frame instead of ending.
  bool loop = false;
  // .oni playback: true = at recorded speed, false = as fast as possible.
  bool realtime = true;
  // lcm source: provider URL; empty = LCM's default (env LCM_DEFAULT_URL).
  std::string lcm_url;
  // lcm source: frames buffered while next() is not being called; older
  // ones are dropped (counted in frames_dropped) so that latency stays bounded.
  int lcm_queue_size = 2;
  // Overrides the intrinsics a source would otherwise report (file formats
  // without calibration, a calibrated device).
  std::optional<CameraIntrinsics> intrinsics;
  // The camera mount, attached to every frame that has none (a robot knows it).
  std::optional<CameraExtrinsics> extrinsics;
  // openni2 device: waits between reconnection attempts, doubling from the
  // first to the second (spec keys reconnect_ms, reconnect_max_ms).
  std::chrono::milliseconds reconnect_initial{500};
  std::chrono::milliseconds reconnect_max{5000};
  // openni2 device / .oni: no image for this long = the device is lost
  // (spec key frame_timeout_ms).
  std::chrono::milliseconds frame_timeout{2000};
};

struct SourceSpec {
  std::string kind;    // openni2, lcm, dataset, pcd, pclzf, tiff
  std::string target;  // device URI / .oni path / channel / directory; may be empty
  SourceOptions options;
  std::string text;  // the spec as given, for messages
};

// Parses the spec syntax above; throws findmug::Error naming the spec and the
// bad part (unknown kind or option, unparsable number, missing target).
SourceSpec parseSourceSpec(const std::string& spec);

// Opens the source. Throws findmug::Error on configuration errors (missing
// directory, no frames, unknown kind). An absent OpenNI2 device is not an
// error: the source starts in Reconnecting and keeps trying.
std::unique_ptr<FrameSource> makeSource(const SourceSpec& spec);
std::unique_ptr<FrameSource> makeSource(const std::string& spec);

// ---------------------------------------------------------------------------
// For implementations: state, statistics, stop flag and interruptible waits,
// all thread-safe. Subclasses implement next() and describe().
class FrameSourceBase : public FrameSource {
 public:
  void stop() override;
  SourceState state() const override;
  SourceStats stats() const override;

 protected:
  using Clock = std::chrono::steady_clock;

  bool stopRequested() const;
  void setState(SourceState state);
  // Logs `message` as an error (with the source's description) and records it.
  void recordError(const std::string& message);
  // A bad frame / message was skipped; logs and records it.
  void recordRejected(const std::string& message);
  void recordDelivered();
  void recordDropped(std::uint64_t count = 1);
  void recordReconnect();
  void recordLostInTransit(std::uint64_t total);
  // Sleeps until `deadline` or stop(); returns false when stopped.
  bool sleepUntil(Clock::time_point deadline);
  // Paces delivery at `rate_hz` (no-op for <= 0): waits until one period
  // after the previous call. Returns false when stopped while waiting.
  bool pace(double rate_hz);
  // Called with the lock released after stop() flips the flag, so that a
  // subclass blocked elsewhere (LCM queue, device read) can wake up.
  virtual void onStop() {}

  // Final touches every source applies: seq/utime when unset, option
  // overrides, validateFrame(). Throws findmug::Error when invalid.
  void finishFrame(RgbdFrame& frame, const SourceOptions& options) const;

 private:
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_requested_ = false;
  SourceState state_ = SourceState::Starting;
  SourceStats stats_;
  std::optional<Clock::time_point> last_paced_;
};

// Microseconds since the Unix epoch, host clock.
std::uint64_t hostUtimeNow();

}  // namespace findmug::io
