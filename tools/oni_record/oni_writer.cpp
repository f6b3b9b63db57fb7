// OpenNI 1.5 recorder with mock nodes; see oni_writer.hpp for why and how.
#include "oni_writer.hpp"

#include <XnCppWrapper.h>
#include <XnPropNames.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "findmug/common/error.hpp"

namespace findmug::oni {

namespace {

constexpr const char* kDepthNode = "Depth1";
constexpr const char* kImageNode = "Image1";

}  // namespace

DepthCodec parseDepthCodec(const std::string& name) {
  if (name == "16z") return DepthCodec::Z16;
  if (name == "raw" || name == "none") return DepthCodec::Raw;
  throw Error("depth codec '" + name + "' (expected 16z or raw)");
}

ColorCodec parseColorCodec(const std::string& name) {
  if (name == "jpeg") return ColorCodec::Jpeg;
  if (name == "raw" || name == "none") return ColorCodec::Raw;
  throw Error("colour codec '" + name + "' (expected jpeg or raw)");
}

struct OniWriter::Impl {
  xn::Context context;
  xn::MockDepthGenerator depth;
  xn::MockImageGenerator image;
  xn::Recorder recorder;
  bool open = false;
};

namespace {

// Throws with the OpenNI status text when `status` is not OK.
void check(XnStatus status, const std::string& path, const std::string& what) {
  if (status != XN_STATUS_OK) {
    throw Error(path + ": OpenNI 1.5 " + what + " failed: " + xnGetStatusString(status));
  }
}

}  // namespace

OniWriter::OniWriter(const std::string& path, int width, int height,
                     const CameraIntrinsics& intrinsics, const OniWriterOptions& options)
    : impl_(std::make_unique<Impl>()), path_(path), width_(width), height_(height) {
  if (width < 1 || height < 1 || width > 4096 || height > 4096) {
    throw Error(path + ": frame size " + std::to_string(width) + "x" + std::to_string(height) +
                " outside 1..4096");
  }
  if (!(intrinsics.fx > 0 && intrinsics.fy > 0) || !std::isfinite(intrinsics.fx) ||
      !std::isfinite(intrinsics.fy)) {
    throw Error(path + ": intrinsics fx=" + std::to_string(intrinsics.fx) +
                " fy=" + std::to_string(intrinsics.fy) + " are not positive");
  }
  if (options.nominal_fps < 1 || options.nominal_fps > 120) {
    throw Error(path + ": nominal fps " + std::to_string(options.nominal_fps) + " outside 1..120");
  }
  Impl& m = *impl_;
  check(m.context.Init(), path, "context initialisation");
  check(m.depth.Create(m.context, kDepthNode), path, "creating the mock depth node");
  check(m.image.Create(m.context, kImageNode), path, "creating the mock image node");

  XnMapOutputMode mode{static_cast<XnUInt32>(width), static_cast<XnUInt32>(height),
                       static_cast<XnUInt32>(options.nominal_fps)};
  // Field of view from the pinhole model; OpenNI2 inverts exactly this.
  XnFieldOfView fov{2.0 * std::atan(width / (2.0 * intrinsics.fx)),
                    2.0 * std::atan(height / (2.0 * intrinsics.fy))};
  for (xn::MapGenerator* node : {static_cast<xn::MapGenerator*>(&m.depth),
                                 static_cast<xn::MapGenerator*>(&m.image)}) {
    const std::string name = node->GetName();
    // Declared so that the recorder's mirror-change registration succeeds
    // (a mock says it has every capability until it is "state ready").
    check(node->SetIntProperty(XN_CAPABILITY_MIRROR, 1), path, name + " mirror capability");
    check(node->SetIntProperty(XN_PROP_SUPPORTED_MAP_OUTPUT_MODES_COUNT, 1), path,
          name + " output mode count");
    check(node->SetGeneralProperty(XN_PROP_SUPPORTED_MAP_OUTPUT_MODES, sizeof(mode), &mode), path,
          name + " supported output modes");
    check(node->SetMapOutputMode(mode), path, name + " output mode");
    check(node->SetGeneralProperty(XN_PROP_FIELD_OF_VIEW, sizeof(fov), &fov), path,
          name + " field of view");
  }
  check(m.image.SetPixelFormat(XN_PIXEL_FORMAT_RGB24), path, "image pixel format");
  check(m.depth.SetIntProperty(XN_PROP_DEVICE_MAX_DEPTH, 10000), path, "maximum depth");

  check(m.recorder.Create(m.context), path,
        "creating the recorder (is libnimRecorder registered in /var/lib/ni/modules.xml?)");
  check(m.recorder.SetDestination(XN_RECORD_MEDIUM_FILE, path.c_str()), path, "opening");
  check(m.recorder.AddNodeToRecording(
            m.depth, options.depth == DepthCodec::Z16 ? XN_CODEC_16Z_EMB_TABLES
                                                      : XN_CODEC_UNCOMPRESSED),
        path, "adding the depth node to the recording");
  check(m.recorder.AddNodeToRecording(
            m.image, options.color == ColorCodec::Jpeg ? XN_CODEC_JPEG : XN_CODEC_UNCOMPRESSED),
        path, "adding the image node to the recording");
  m.open = true;
}

OniWriter::~OniWriter() {
  try {
    close();
  } catch (const Error&) {
    // Destructors must not throw; call close() to see the error.
  }
}

void OniWriter::write(const RgbdFrame& frame, std::uint64_t timestamp_us) {
  Impl& m = *impl_;
  if (!m.open) throw Error(path_ + ": write after close");
  if (frame.width != width_ || frame.height != height_) {
    throw Error(path_ + ": frame '" + frame.source + "' is " + std::to_string(frame.width) + "x" +
                std::to_string(frame.height) + ", the recording is " + std::to_string(width_) +
                "x" + std::to_string(height_));
  }
  const std::size_t pixels = static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_);
  if (frame.depth_mm.size() != pixels || frame.rgb.size() != pixels) {
    throw Error(path_ + ": frame '" + frame.source + "' has " +
                std::to_string(frame.depth_mm.size()) + " depth and " +
                std::to_string(frame.rgb.size()) + " colour pixels, expected " +
                std::to_string(pixels));
  }
  if (frames_ > 0 && timestamp_us <= last_timestamp_) {
    throw Error(path_ + ": timestamp " + std::to_string(timestamp_us) +
                " us does not increase (previous " + std::to_string(last_timestamp_) + ")");
  }
  static_assert(sizeof(Rgb8) == 3, "Rgb8 must be packed R, G, B");
  const auto frame_id = static_cast<XnUInt32>(frames_ + 1);
  check(m.depth.SetData(frame_id, timestamp_us, static_cast<XnUInt32>(pixels * 2),
                        frame.depth_mm.data()),
        path_, "setting depth data");
  check(m.image.SetData(frame_id, timestamp_us, static_cast<XnUInt32>(pixels * 3),
                        reinterpret_cast<const XnUInt8*>(frame.rgb.data())),
        path_, "setting image data");
  check(m.recorder.Record(), path_, "recording frame " + std::to_string(frame_id));
  ++frames_;
  last_timestamp_ = timestamp_us;
}

void OniWriter::close() {
  Impl& m = *impl_;
  if (!m.open) return;
  m.open = false;
  // Releasing the recorder writes the seek tables and the final header.
  m.recorder.Release();
  m.image.Release();
  m.depth.Release();
  m.context.Release();
}

}  // namespace findmug::oni
