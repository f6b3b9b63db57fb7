#include "compression.hpp"

#include <jpeglib.h>
#include <libdeflate.h>
#include <zlib.h>

#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>

#include "findmug/error.hpp"

namespace findmug::io::detail {

// ---- zlib -----------------------------------------------------------------------

std::vector<std::uint8_t> zlibCompress(const std::uint8_t* data, std::size_t size, int level,
                                       bool run_length) {
  if (size > std::numeric_limits<uInt>::max()) throw Error("zlib: input too large");
  z_stream zs{};
  if (deflateInit2(&zs, level, Z_DEFLATED, 15, 8, run_length ? Z_RLE : Z_DEFAULT_STRATEGY) !=
      Z_OK) {
    throw Error("zlib: deflateInit2 failed (level " + std::to_string(level) + ")");
  }
  std::vector<std::uint8_t> out(deflateBound(&zs, static_cast<uLong>(size)));
  zs.next_in = const_cast<Bytef*>(data);
  zs.avail_in = static_cast<uInt>(size);
  zs.next_out = out.data();
  zs.avail_out = static_cast<uInt>(out.size());
  const int rc = deflate(&zs, Z_FINISH);
  const std::size_t written = zs.total_out;
  deflateEnd(&zs);
  if (rc != Z_STREAM_END) throw Error("zlib: deflate failed with code " + std::to_string(rc));
  out.resize(written);
  return out;
}

std::vector<std::uint8_t> zlibDecompress(const std::uint8_t* data, std::size_t size,
                                         std::size_t expected_size, const std::string& what) {
  std::vector<std::uint8_t> out(expected_size);
  zlibDecompressInto(data, size, out.data(), expected_size, what);
  return out;
}

void zlibDecompressInto(const std::uint8_t* data, std::size_t size, std::uint8_t* out,
                        std::size_t expected_size, const std::string& what) {
  if (size > std::numeric_limits<std::uint32_t>::max() ||
      expected_size > std::numeric_limits<std::uint32_t>::max()) {
    throw Error(what + ": zlib stream or expected size too large");
  }
  // One decompressor per thread (a few kB of tables, allocated once).
  thread_local const std::unique_ptr<libdeflate_decompressor, void (*)(libdeflate_decompressor*)>
      decompressor(libdeflate_alloc_decompressor(), &libdeflate_free_decompressor);
  if (!decompressor) throw Error(what + ": cannot allocate a zlib decompressor");
  std::size_t used = 0;
  std::size_t produced = 0;
  const libdeflate_result rc = libdeflate_zlib_decompress_ex(
      decompressor.get(), data, size, out, expected_size, &used, &produced);
  switch (rc) {
    case LIBDEFLATE_SUCCESS:
      if (produced != expected_size) {
        throw Error(what + ": zlib stream inflates to " + std::to_string(produced) +
                    " bytes, expected " + std::to_string(expected_size));
      }
      if (used != size) {
        throw Error(what + ": " + std::to_string(size - used) +
                    " bytes after the end of the zlib stream");
      }
      return;
    case LIBDEFLATE_INSUFFICIENT_SPACE:
      throw Error(what + ": zlib stream inflates to more than the expected " +
                  std::to_string(expected_size) + " bytes");
    default:  // LIBDEFLATE_BAD_DATA (libdeflate also reports a cut stream so)
      throw Error(what + ": corrupt zlib stream (" + std::to_string(size) +
                  " bytes: invalid, cut short, or the checksum does not match)");
  }
}

// ---- JPEG -----------------------------------------------------------------------
//
// libjpeg reports errors through a callback that must not return; the usual
// C way out is longjmp. The functions below keep only trivially destructible
// objects alive between setjmp and any longjmp, so skipping their scopes is safe.

namespace {

struct JpegErrorManager {
  jpeg_error_mgr base;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
  int warnings;
};

[[noreturn]] void jpegErrorExit(j_common_ptr info) {
  auto* err = reinterpret_cast<JpegErrorManager*>(info->err);
  (*info->err->format_message)(info, err->message);
  std::longjmp(err->jump, 1);
}

// Warnings (level < 0) mean corrupt data; keep the first, print nothing.
void jpegEmitMessage(j_common_ptr info, int level) {
  auto* err = reinterpret_cast<JpegErrorManager*>(info->err);
  if (level < 0) {
    if (err->warnings++ == 0) (*info->err->format_message)(info, err->message);
  }
}

void installErrorManager(JpegErrorManager& err) {
  jpeg_std_error(&err.base);
  err.base.error_exit = jpegErrorExit;
  err.base.emit_message = jpegEmitMessage;
  err.message[0] = '\0';
  err.warnings = 0;
}

// Returns 0 on success, else writes a message into err.message.
// `out` must hold width*height*3 bytes.
int decodeJpegInto(const unsigned char* data, unsigned long size, unsigned char* out, int width,
                   int height, JpegErrorManager& err, int& found_width, int& found_height) {
  jpeg_decompress_struct cinfo;
  cinfo.err = &err.base;
  installErrorManager(err);
  cinfo.err->error_exit = jpegErrorExit;
  if (setjmp(err.jump)) {
    jpeg_destroy_decompress(&cinfo);
    return 1;
  }
  jpeg_create_decompress(&cinfo);
  jpeg_mem_src(&cinfo, data, size);
  if (jpeg_read_header(&cinfo, TRUE) != JPEG_HEADER_OK) {
    std::snprintf(err.message, sizeof(err.message), "no JPEG image in the data");
    jpeg_destroy_decompress(&cinfo);
    return 1;
  }
  found_width = static_cast<int>(cinfo.image_width);
  found_height = static_cast<int>(cinfo.image_height);
  if (found_width != width || found_height != height) {
    std::snprintf(err.message, sizeof(err.message), "JPEG is %dx%d, message says %dx%d",
                  found_width, found_height, width, height);
    jpeg_destroy_decompress(&cinfo);
    return 1;
  }
  cinfo.out_color_space = JCS_RGB;
  jpeg_start_decompress(&cinfo);
  if (cinfo.output_components != 3) {
    std::snprintf(err.message, sizeof(err.message), "JPEG decodes to %d components, expected 3",
                  cinfo.output_components);
    jpeg_destroy_decompress(&cinfo);
    return 1;
  }
  while (cinfo.output_scanline < cinfo.output_height) {
    JSAMPROW row = out + static_cast<std::size_t>(cinfo.output_scanline) * width * 3;
    jpeg_read_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_decompress(&cinfo);
  jpeg_destroy_decompress(&cinfo);
  if (err.warnings > 0) return 1;  // corrupt or truncated data, message already kept
  return 0;
}

// Returns 0 on success; *out is malloc'ed by libjpeg (caller frees).
int encodeJpeg(const unsigned char* rgb, int width, int height, int quality, unsigned char** out,
               unsigned long* out_size, JpegErrorManager& err) {
  jpeg_compress_struct cinfo;
  cinfo.err = &err.base;
  installErrorManager(err);
  if (setjmp(err.jump)) {
    jpeg_destroy_compress(&cinfo);
    return 1;
  }
  jpeg_create_compress(&cinfo);
  jpeg_mem_dest(&cinfo, out, out_size);
  cinfo.image_width = static_cast<JDIMENSION>(width);
  cinfo.image_height = static_cast<JDIMENSION>(height);
  cinfo.input_components = 3;
  cinfo.in_color_space = JCS_RGB;
  jpeg_set_defaults(&cinfo);
  jpeg_set_quality(&cinfo, quality, TRUE);
  jpeg_start_compress(&cinfo, TRUE);
  while (cinfo.next_scanline < cinfo.image_height) {
    // libjpeg's API is not const-correct; it only reads the row.
    JSAMPROW row =
        const_cast<unsigned char*>(rgb) + static_cast<std::size_t>(cinfo.next_scanline) * width * 3;
    jpeg_write_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_compress(&cinfo);
  jpeg_destroy_compress(&cinfo);
  return 0;
}

}  // namespace

std::vector<std::uint8_t> jpegCompressRgb(const std::vector<Rgb8>& pixels, int width, int height,
                                          int quality) {
  static_assert(sizeof(Rgb8) == 3, "Rgb8 must be packed RGB");
  if (quality < 1 || quality > 100) {
    throw Error("JPEG quality " + std::to_string(quality) + " outside 1..100");
  }
  if (width <= 0 || height <= 0 || pixels.size() != static_cast<std::size_t>(width) * height) {
    throw Error("JPEG encode: " + std::to_string(pixels.size()) + " pixels for " +
                std::to_string(width) + "x" + std::to_string(height));
  }
  JpegErrorManager err;
  unsigned char* buffer = nullptr;
  unsigned long buffer_size = 0;
  const int rc = encodeJpeg(reinterpret_cast<const unsigned char*>(pixels.data()), width, height,
                            quality, &buffer, &buffer_size, err);
  std::vector<std::uint8_t> out;
  if (rc == 0 && buffer) out.assign(buffer, buffer + buffer_size);
  std::free(buffer);
  if (rc != 0) throw Error(std::string("JPEG encode failed: ") + err.message);
  return out;
}

std::vector<Rgb8> jpegDecompressRgb(const std::uint8_t* data, std::size_t size, int width,
                                    int height, const std::string& what) {
  if (size == 0) throw Error(what + ": empty JPEG data");
  std::vector<Rgb8> out(static_cast<std::size_t>(width) * height);
  JpegErrorManager err;
  int found_w = 0, found_h = 0;
  const int rc = decodeJpegInto(data, static_cast<unsigned long>(size),
                                reinterpret_cast<unsigned char*>(out.data()), width, height, err,
                                found_w, found_h);
  if (rc != 0) throw Error(what + ": bad JPEG: " + err.message);
  return out;
}

}  // namespace findmug::io::detail
