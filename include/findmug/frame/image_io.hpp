// findmug/frame/image_io.hpp — PNG reading and writing for frames, labels, overlays.
//
// Readers check bit depth and channel count and throw findmug::Error naming
// the file and what was found, so that "depth stored as 8-bit" or "label image
// is RGB" is caught at the edge.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "findmug/labels/labels.hpp"

namespace findmug {

template <typename T>
struct Image {
  int width = 0;
  int height = 0;
  std::vector<T> pixels;  // row-major
};

Image<std::uint16_t> readPng16(const std::string& path);  // single channel, 16 bit
Image<std::uint8_t> readPng8(const std::string& path);    // single channel, 8 bit
Image<Rgb8> readPngRgb(const std::string& path);          // RGB or RGBA 8 bit (alpha dropped)

void writePng16(const std::string& path, const Image<std::uint16_t>& image);
void writePng8(const std::string& path, const Image<std::uint8_t>& image);
void writePngRgb(const std::string& path, const Image<Rgb8>& image);

// In-memory PNG (for LCM colour compression).
std::vector<std::uint8_t> encodePngRgb(const Image<Rgb8>& image);
Image<Rgb8> decodePngRgb(const std::vector<std::uint8_t>& bytes, const std::string& what);

}  // namespace findmug
