// findmug/io/pcl_frames.hpp — single RGB-D frames from PCL's recording formats.
//
// These are the three layouts PCL's grabbers write (and its test data uses):
//   PCD    an organized cloud (binary or binary_compressed) with float x y z
//          and rgb or rgba; depth = z in mm, intrinsics fitted to the points
//          (they are a pinhole projection); read by our own bounds-checked
//          reader, since PCL's reads past the end of truncated compressed files;
//   PCLZF  NAME_depth.pclzf (LZF-compressed uint16 depth, "depth16"),
//          NAME_rgb.pclzf ("rgb24") and NAME.xml (intrinsics, depth scale);
//   TIFF   NAME_depth.tiff (uint16 mm) + NAME_rgb.tiff (RGB8); no calibration
//          in the files, so `intrinsics` is used.
// Readers throw findmug::Error naming the file and what is wrong (truncated,
// wrong type/size, not organized, corrupt compression).
#pragma once

#include <string>
#include <vector>

#include "findmug/frame/frame.hpp"

namespace findmug::io {

RgbdFrame readPcdFrame(const std::string& path);
RgbdFrame readPclzfFrame(const std::string& depth_path, const std::string& rgb_path,
                         const std::string& xml_path);
RgbdFrame readTiffFrame(const std::string& depth_path, const std::string& rgb_path,
                        const CameraIntrinsics& intrinsics);

// The frames of a sequence directory in name order: for each, the file(s) to
// pass to the reader above. Throws when the directory is missing, holds no
// frame, or a frame lacks one of its files (e.g. a depth without its rgb).
enum class PclFormat { Pcd, Pclzf, Tiff };
struct PclSequenceItem {
  std::string name;                // common stem, e.g. frame_20121214T142255.814212
  std::vector<std::string> files;  // pcd: {cloud}; pclzf: {depth, rgb, xml}; tiff: {depth, rgb}
};
std::vector<PclSequenceItem> listPclSequence(const std::string& dir, PclFormat format);

}  // namespace findmug::io
