// compression.hpp (internal to findmug_io) — zlib and JPEG in memory.
//
// Decoders take the exact size the result must have (known from the message
// header) and throw findmug::Error, prefixed with `what` (channel + field),
// when the data is corrupt, truncated, or decodes to a different size.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "findmug/labels/labels.hpp"

namespace findmug::io::detail {

// A zlib stream of `data` at `level` (zlib's default strategy): depth images.
std::vector<std::uint8_t> zlibCompress(const std::uint8_t* data, std::size_t size, int level);
// A zlib stream of `data` made for piecewise-constant images (labels,
// quantised confidences), several times faster than zlib's own Z_RLE at
// level 1 at a similar size: one deflate block whose Huffman codes are
// fitted to the image, coding each run of one byte as the byte and matches
// at distance 1 (RFC 1951). Data without runs goes into stored blocks
// instead, so the stream is never more than a few bytes per 64 KiB larger
// than the data. Any inflate reads it.
std::vector<std::uint8_t> zlibCompressRuns(const std::uint8_t* data, std::size_t size);
// Inflates into exactly `expected_size` bytes: a stream that ends early, runs
// past that size, is corrupt, or has bytes after its end is an error.
std::vector<std::uint8_t> zlibDecompress(const std::uint8_t* data, std::size_t size,
                                         std::size_t expected_size, const std::string& what);
// The same into `out` (exactly `expected_size` bytes), e.g. straight into a
// frame's depth buffer. Both inflate with libdeflate (whole buffer, about
// twice zlib's speed; the bytes are the same).
void zlibDecompressInto(const std::uint8_t* data, std::size_t size, std::uint8_t* out,
                        std::size_t expected_size, const std::string& what);

std::vector<std::uint8_t> jpegCompressRgb(const std::vector<Rgb8>& pixels, int width, int height,
                                          int quality);
// Decodes a JPEG that must be width x height; any libjpeg error or warning
// (corrupt or truncated data) is an error rather than a grey-filled image.
std::vector<Rgb8> jpegDecompressRgb(const std::uint8_t* data, std::size_t size, int width,
                                    int height, const std::string& what);

}  // namespace findmug::io::detail
