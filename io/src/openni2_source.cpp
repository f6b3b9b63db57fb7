// OpenNI2 device and .oni playback.
//
// One class serves both: a .oni file is an OpenNI2 "device" too, so opening,
// stream set-up, frame pairing and conversion are shared; only end-of-stream
// (playback) and loss/reconnection (live device) differ.
//
// Live device: depth registered to colour, colour/depth frame sync, 640x480
// at 30 fps when offered (else the device's own mode, logged). Frames carry
// the host time at which the pair was complete (device clocks are not host
// time). The device is a Device inside a DeviceSource (device_source.hpp):
// a live device that is absent, fails or stops delivering frames is closed
// and re-opened there with exponential back-off; a .oni file that fails ends
// the source as Failed.
#include <OpenNI.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <cstring>
#include <deque>
#include <filesystem>
#include <mutex>
#include <thread>

#include "findmug/common/error.hpp"
#include "findmug/io/device_source.hpp"
#include "sources_internal.hpp"

namespace findmug::io::detail {

namespace {

using openni::OpenNI;
using openni::Status;

void initializeOpenNi() {
  static std::once_flag once;
  static Status status = openni::STATUS_OK;
  static std::string error;
  std::call_once(once, [] {
    status = OpenNI::initialize();
    if (status != openni::STATUS_OK) error = OpenNI::getExtendedError();
  });
  if (status != openni::STATUS_OK) throw Error("OpenNI2 initialisation failed: " + error);
}

std::string oniError(const std::string& what, Status status) {
  std::string detail = OpenNI::getExtendedError();
  while (!detail.empty() && (detail.back() == '\n' || detail.back() == ' ')) detail.pop_back();
  return what + " failed (status " + std::to_string(static_cast<int>(status)) + ")" +
         (detail.empty() ? "" : ": " + detail);
}

// Depth and colour frames are paired when their device timestamps are this close.
constexpr std::uint64_t kPairToleranceUs = 16000;
// Unpaired images kept per stream while waiting for a partner (about 130 ms at 30 fps).
constexpr std::size_t kPairHistory = 4;

struct CapturedImage {
  bool valid = false;
  std::uint64_t device_timestamp = 0;
  int frame_index = 0;
  int width = 0, height = 0;
  std::vector<std::uint16_t> depth;  // depth stream
  std::vector<Rgb8> rgb;             // colour stream
};

class Openni2Device : public Device {
 public:
  Openni2Device(std::string target, SourceOptions options, bool playback)
      : target_(std::move(target)), options_(std::move(options)), playback_(playback) {
    if (playback_) {
      description_ = "openni2:" + target_ + " (" +
                     (options_.realtime ? "recorded speed" : "as fast as possible") +
                     (options_.loop ? ", loop" : "") + ")";
    } else {
      description_ = "openni2:" + (target_.empty() ? std::string("<first device>") : target_);
    }
  }

  ~Openni2Device() override { close(); }

  // Includes the device's own name once it has been opened ("openni2:<first
  // device> (PrimeSense Carmine 1.09, uri ...)"), for logs and findmugd --check.
  std::string describe() const override {
    std::lock_guard<std::mutex> lock(device_name_mutex_);
    return device_name_.empty() ? description_ : description_ + " (" + device_name_ + ")";
  }

  // Opens device and streams; returns an error message, empty on success.
  std::string open() override {
    close();
    const char* uri = target_.empty() ? openni::ANY_DEVICE : target_.c_str();
    if (Status s = device_.open(uri); s != openni::STATUS_OK) {
      device_.close();
      return oniError("opening device " + (target_.empty() ? std::string("(any)") : target_), s);
    }
    for (auto [sensor, stream, name] : {std::tuple{openni::SENSOR_DEPTH, &depth_, "depth"},
                                        std::tuple{openni::SENSOR_COLOR, &color_, "colour"}}) {
      if (!device_.hasSensor(sensor)) {
        close();
        return std::string("device has no ") + name + " sensor";
      }
      if (Status s = stream->create(device_, sensor); s != openni::STATUS_OK) {
        close();
        return oniError(std::string("creating the ") + name + " stream", s);
      }
    }
    if (!playback_) {
      if (std::string error = configureLive(); !error.empty()) {
        close();
        return error;
      }
    } else if (auto* control = device_.getPlaybackControl()) {
      // Speed -1: "manual", a frame becomes available when the previous one is read.
      control->setSpeed(options_.realtime ? 1.0f : -1.0f);
      control->setRepeatEnabled(options_.loop);
      playback_frames_ = control->getNumberOfFrames(depth_);
    }
    for (auto [stream, name] : {std::pair{&depth_, "depth"}, std::pair{&color_, "colour"}}) {
      if (Status s = stream->start(); s != openni::STATUS_OK) {
        close();
        return oniError(std::string("starting the ") + name + " stream", s);
      }
    }
    const auto depth_mode = depth_.getVideoMode();
    const auto color_mode = color_.getVideoMode();
    if (depth_mode.getPixelFormat() != openni::PIXEL_FORMAT_DEPTH_1_MM &&
        depth_mode.getPixelFormat() != openni::PIXEL_FORMAT_DEPTH_100_UM) {
      close();
      return "depth pixel format " + std::to_string(depth_mode.getPixelFormat()) +
             " is not millimetres / 100 um";
    }
    if (color_mode.getPixelFormat() != openni::PIXEL_FORMAT_RGB888) {
      close();
      return "colour pixel format " + std::to_string(color_mode.getPixelFormat()) +
             " is not RGB888";
    }
    intrinsics_ = intrinsicsFromFov(color_mode.getResolutionX(), color_mode.getResolutionY());
    spdlog::info("{}: depth {}x{} @ {} fps, colour {}x{} @ {} fps, fx={:.1f} fy={:.1f}",
                 description_, depth_mode.getResolutionX(), depth_mode.getResolutionY(),
                 depth_mode.getFps(), color_mode.getResolutionX(), color_mode.getResolutionY(),
                 color_mode.getFps(), intrinsics_.fx, intrinsics_.fy);
    {
      const openni::DeviceInfo& info = device_.getDeviceInfo();
      std::lock_guard<std::mutex> lock(device_name_mutex_);
      device_name_ =
          std::string(info.getVendor()) + " " + info.getName() + ", uri " + info.getUri();
    }
    last_depth_ = {};
    last_color_ = {};
    recent_[0].clear();
    recent_[1].clear();
    ended_ = false;
    return {};
  }

  void close() override {
    const bool streaming = depth_.isValid() || color_.isValid();
    depth_.stop();
    color_.stop();
    // A driver's frame thread may still touch a stream for about one frame
    // period after stop() (OpenNI2's own Dummy driver crashes with a
    // use-after-free otherwise). close() is rare — loss, shutdown — so wait
    // three frame periods before freeing the streams.
    if (streaming) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    depth_.destroy();
    color_.destroy();
    device_.close();
  }

  // One wait for either stream: a whole depth/colour pair is a Frame; an
  // image that does not complete a pair is Pending; the end of a .oni
  // recording is Ended.
  DeviceRead read(std::chrono::milliseconds limit) override {
    if (ended_) return DeviceRead::with(DeviceRead::Kind::Ended);
    openni::VideoStream* streams[] = {&depth_, &color_};
    int ready = -1;
    const Status s = OpenNI::waitForAnyStream(streams, 2, &ready, static_cast<int>(limit.count()));
    if (s == openni::STATUS_TIME_OUT) {
      if (playback_ && atEndOfPlayback()) ended_ = true;
      return DeviceRead::with(ended_ ? DeviceRead::Kind::Ended : DeviceRead::Kind::Idle);
    }
    if (s != openni::STATUS_OK || ready < 0 || ready > 1) {
      return DeviceRead::with(DeviceRead::Kind::Lost, oniError("waiting for frames", s));
    }
    openni::VideoFrameRef ref;
    if (Status rs = streams[ready]->readFrame(&ref); rs != openni::STATUS_OK || !ref.isValid()) {
      return DeviceRead::with(DeviceRead::Kind::Lost, oniError("reading a frame", rs));
    }
    try {
      recent_[ready].push_back(ready == 0 ? copyDepth(ref) : copyColor(ref));
    } catch (const Error& e) {
      return DeviceRead::with(DeviceRead::Kind::Rejected, e.what());
    }
    std::uint64_t dropped = 0;
    if (!pairNewest(ready, dropped)) {
      DeviceRead pending = DeviceRead::with(DeviceRead::Kind::Pending);
      pending.dropped = dropped;
      return pending;
    }
    DeviceRead got;
    try {
      got = DeviceRead::of(assemble());
    } catch (const Error& e) {
      got = DeviceRead::with(DeviceRead::Kind::Rejected, e.what());
    }
    got.dropped = dropped;
    if (playback_ && playback_frames_ > 0 && !options_.loop &&
        last_depth_.frame_index >= playback_frames_) {
      ended_ = true;  // this was the last pair; the next read ends the stream
    }
    last_depth_.valid = last_color_.valid = false;
    return got;
  }

 private:
  std::string configureLive() {
    // Prefer 640x480 at 30 fps in the formats we use; otherwise keep the
    // device's default mode (logged by open()).
    for (auto [stream, format, name] :
         {std::tuple{&depth_, openni::PIXEL_FORMAT_DEPTH_1_MM, "depth"},
          std::tuple{&color_, openni::PIXEL_FORMAT_RGB888, "colour"}}) {
      const auto& modes = stream->getSensorInfo().getSupportedVideoModes();
      bool found = false;
      for (int i = 0; i < modes.getSize() && !found; ++i) {
        if (modes[i].getResolutionX() == 640 && modes[i].getResolutionY() == 480 &&
            modes[i].getFps() == 30 && modes[i].getPixelFormat() == format) {
          found = stream->setVideoMode(modes[i]) == openni::STATUS_OK;
        }
      }
      if (!found)
        spdlog::warn("{}: no 640x480@30 {} mode; using the device default", description_, name);
    }
    if (device_.isImageRegistrationModeSupported(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR)) {
      if (Status s = device_.setImageRegistrationMode(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR);
          s != openni::STATUS_OK) {
        return oniError("enabling depth-to-colour registration", s);
      }
    } else {
      spdlog::warn("{}: device cannot register depth to colour; pixels will not align exactly",
                   description_);
    }
    if (device_.setDepthColorSyncEnabled(true) != openni::STATUS_OK) {
      spdlog::warn("{}: depth/colour frame sync not available", description_);
    }
    return {};
  }

  CameraIntrinsics intrinsicsFromFov(int width, int height) const {
    const double hfov = color_.getHorizontalFieldOfView();
    const double vfov = color_.getVerticalFieldOfView();
    CameraIntrinsics k;
    if (std::isfinite(hfov) && std::isfinite(vfov) && hfov > 0.1 && hfov < 3.0 && vfov > 0.1 &&
        vfov < 3.0) {
      k.fx = width / 2.0 / std::tan(hfov / 2.0);
      k.fy = height / 2.0 / std::tan(vfov / 2.0);
    } else {
      // Kinect-class default, scaled to the resolution; logged because it is a guess.
      k.fx = 525.0 * width / 640.0;
      k.fy = 525.0 * height / 480.0;
      spdlog::warn("{}: no valid field of view from the device; assuming fx={} fy={}", description_,
                   k.fx, k.fy);
    }
    k.cx = (width - 1) / 2.0;
    k.cy = (height - 1) / 2.0;
    return k;
  }

  // Pairs the newest image of stream `stream` with the image of the other
  // stream closest in device time, into last_depth_ / last_color_. Keeping a
  // few recent images per stream matters: when one stream lags the other by a
  // frame (a loaded machine, a driver without hardware sync), matching only
  // the latest of each would never pair again and the source would deliver
  // nothing while frames keep arriving. Images older than a pair, or pushed
  // out of the history, can no longer pair and are counted as dropped.
  bool pairNewest(int stream, std::uint64_t& dropped) {
    auto& mine = recent_[stream];
    auto& other = recent_[1 - stream];
    const CapturedImage& newest = mine.back();
    auto best = other.end();
    std::uint64_t best_dt = 0;
    for (auto it = other.begin(); it != other.end(); ++it) {
      const std::uint64_t dt = newest.device_timestamp > it->device_timestamp
                                   ? newest.device_timestamp - it->device_timestamp
                                   : it->device_timestamp - newest.device_timestamp;
      if (best == other.end() || dt < best_dt) {
        best = it;
        best_dt = dt;
      }
    }
    if (best == other.end() || best_dt > kPairToleranceUs) {
      if (mine.size() > kPairHistory) {
        mine.pop_front();
        ++dropped;
      }
      return false;
    }
    CapturedImage& depth = stream == 0 ? mine.back() : *best;
    CapturedImage& color = stream == 0 ? *best : mine.back();
    last_depth_ = std::move(depth);
    last_color_ = std::move(color);
    const auto older_in_other = static_cast<std::uint64_t>(best - other.begin());
    dropped += older_in_other + (mine.size() - 1);
    other.erase(other.begin(), best + 1);
    mine.clear();
    return true;
  }

  bool atEndOfPlayback() const {
    return !options_.loop && playback_frames_ > 0 && last_depth_.frame_index >= playback_frames_;
  }

  CapturedImage copyDepth(const openni::VideoFrameRef& ref) const {
    CapturedImage out;
    out.width = ref.getWidth();
    out.height = ref.getHeight();
    checkSize(out.width, out.height, "depth");
    const auto format = ref.getVideoMode().getPixelFormat();
    const int stride = ref.getStrideInBytes();
    if (stride < out.width * 2 || ref.getDataSize() < stride * out.height) {
      throw Error(description_ + ": depth frame of " + std::to_string(ref.getDataSize()) +
                  " bytes too small for " + std::to_string(out.width) + "x" +
                  std::to_string(out.height) + " (stride " + std::to_string(stride) + ")");
    }
    out.depth.resize(static_cast<std::size_t>(out.width) * out.height);
    const auto* base = static_cast<const std::uint8_t*>(ref.getData());
    for (int y = 0; y < out.height; ++y) {
      std::memcpy(&out.depth[static_cast<std::size_t>(y) * out.width],
                  base + static_cast<std::size_t>(y) * stride,
                  static_cast<std::size_t>(out.width) * 2);
    }
    if (format == openni::PIXEL_FORMAT_DEPTH_100_UM) {
      for (auto& d : out.depth) d = static_cast<std::uint16_t>((d + 5) / 10);
    }
    out.device_timestamp = ref.getTimestamp();
    out.frame_index = ref.getFrameIndex();
    out.valid = true;
    return out;
  }

  CapturedImage copyColor(const openni::VideoFrameRef& ref) const {
    CapturedImage out;
    out.width = ref.getWidth();
    out.height = ref.getHeight();
    checkSize(out.width, out.height, "colour");
    const int stride = ref.getStrideInBytes();
    if (stride < out.width * 3 || ref.getDataSize() < stride * out.height) {
      throw Error(description_ + ": colour frame of " + std::to_string(ref.getDataSize()) +
                  " bytes too small for " + std::to_string(out.width) + "x" +
                  std::to_string(out.height));
    }
    out.rgb.resize(static_cast<std::size_t>(out.width) * out.height);
    const auto* base = static_cast<const std::uint8_t*>(ref.getData());
    for (int y = 0; y < out.height; ++y) {
      std::memcpy(&out.rgb[static_cast<std::size_t>(y) * out.width],
                  base + static_cast<std::size_t>(y) * stride,
                  static_cast<std::size_t>(out.width) * 3);
    }
    out.device_timestamp = ref.getTimestamp();
    out.frame_index = ref.getFrameIndex();
    out.valid = true;
    return out;
  }

  void checkSize(int width, int height, const char* what) const {
    if (width < 1 || height < 1 || width > 4096 || height > 4096) {
      throw Error(description_ + ": " + what + " frame has absurd size " + std::to_string(width) +
                  "x" + std::to_string(height));
    }
  }

  RgbdFrame assemble() {
    if (last_depth_.width != last_color_.width || last_depth_.height != last_color_.height) {
      throw Error(description_ + ": depth " + std::to_string(last_depth_.width) + "x" +
                  std::to_string(last_depth_.height) + " and colour " +
                  std::to_string(last_color_.width) + "x" + std::to_string(last_color_.height) +
                  " differ; registration needs one grid");
    }
    RgbdFrame frame;
    frame.width = last_depth_.width;
    frame.height = last_depth_.height;
    frame.depth_mm = std::move(last_depth_.depth);
    frame.rgb = std::move(last_color_.rgb);
    frame.intrinsics = intrinsics_;
    frame.utime = hostUtimeNow();
    frame.source = description_ + " frame " + std::to_string(last_depth_.frame_index);
    return frame;
  }

  std::string target_;
  SourceOptions options_;
  bool playback_ = false;
  std::string description_;
  // Vendor, name and URI of the opened device; written on open() (source
  // thread), read by describe() from any thread.
  mutable std::mutex device_name_mutex_;
  std::string device_name_;
  openni::Device device_;
  openni::VideoStream depth_, color_;
  CameraIntrinsics intrinsics_;
  CapturedImage last_depth_, last_color_;  // the pair being delivered
  std::deque<CapturedImage> recent_[2];    // unpaired images: 0 depth, 1 colour
  int playback_frames_ = 0;
  bool ended_ = false;
};

}  // namespace

std::unique_ptr<FrameSource> makeOpenni2Source(const SourceSpec& spec) {
  initializeOpenNi();
  std::error_code ec;
  const bool playback = !spec.target.empty() && std::filesystem::is_regular_file(spec.target, ec);
  DeviceSourceSettings settings;
  settings.reconnect_initial = spec.options.reconnect_initial;
  settings.reconnect_max = spec.options.reconnect_max;
  settings.frame_timeout = spec.options.frame_timeout;
  settings.reconnect = !playback;                            // a file cannot come back
  settings.rate_hz = playback ? spec.options.rate_hz : 0.0;  // a camera has its own rate
  return std::make_unique<DeviceSource>(
      std::make_unique<Openni2Device>(spec.target, spec.options, playback), settings, spec.options);
}

}  // namespace findmug::io::detail
