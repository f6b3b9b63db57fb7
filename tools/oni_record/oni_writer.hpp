// oni_writer.hpp — writes RGB-D frames into an OpenNI .oni recording, no camera needed.
//
// OpenNI2 can play .oni files but cannot write one without a device: its
// Recorder attaches to live VideoStreams. OpenNI 1.5 can: "mock" depth and
// image generators take frames from the application (SetData), and its
// Recorder node records any generator, mock or not. OpenNI2's file driver
// (OniFile) reads exactly that OpenNI 1.x container format, so a file written
// here opens with openni::Device::open("x.oni") and therefore with findmug's
// `openni2:/path/x.oni` frame source.
//
// What the file holds:
//   * a depth node (DEPTH_1_MM, lossless: 16z with embedded tables, or raw)
//     and an image node (RGB888: JPEG or raw), both width x height;
//   * each frame pair with the same timestamp (microseconds from the first),
//     so players pair them exactly and replay at the recorded rate;
//   * the field of view of both nodes from the intrinsics: OpenNI2 derives
//     fx = width / (2 tan(hfov / 2)) and fy likewise. The format has no
//     principal point: players assume the image centre, so cx, cy are lost,
//     and so are camera extrinsics (height, pitch), which .oni cannot carry.
//
// Three details of OpenNI 1.5.4's mock nodes that the recorder needs (found by
// reading its node watcher; without them AddNodeToRecording fails with "not
// implemented"): a mock claims every capability until its state is "ready",
// so the mirror capability is declared explicitly; the supported map output
// modes must be listed; and the node's properties travel through the mock's
// extended serialisation, which is how the image node's field of view
// reaches the file (the depth node's is recorded anyway).
//
// Not thread-safe. Errors (OpenNI status, size changes, I/O) throw
// findmug::Error naming the file.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "findmug/frame/frame.hpp"

namespace findmug::oni {

enum class DepthCodec { Z16, Raw };   // both lossless; Z16 is OpenNI's 16-bit delta codec
enum class ColorCodec { Jpeg, Raw };  // Jpeg is what OpenNI's own recorders use

struct OniWriterOptions {
  DepthCodec depth = DepthCodec::Z16;
  ColorCodec color = ColorCodec::Jpeg;
  int nominal_fps = 30;  // stored in the map output mode (1..120); timing comes from timestamps
};

// "16z"/"raw" and "jpeg"/"raw"; throws findmug::Error on anything else.
DepthCodec parseDepthCodec(const std::string& name);
ColorCodec parseColorCodec(const std::string& name);

class OniWriter {
 public:
  // Creates `path` (overwriting it). Every frame must be width x height.
  OniWriter(const std::string& path, int width, int height, const CameraIntrinsics& intrinsics,
            const OniWriterOptions& options = {});
  ~OniWriter();  // closes (finalises) the file if close() was not called
  OniWriter(const OniWriter&) = delete;
  OniWriter& operator=(const OniWriter&) = delete;

  // Appends one frame. `timestamp_us` must increase from frame to frame.
  void write(const RgbdFrame& frame, std::uint64_t timestamp_us);
  // Writes the index and header; the file is complete afterwards.
  void close();

  int framesWritten() const { return frames_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string path_;
  int width_, height_;
  int frames_ = 0;
  std::uint64_t last_timestamp_ = 0;
};

}  // namespace findmug::oni
