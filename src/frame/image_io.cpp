// PNG reading and writing with libpng's classic API.
//
// Readers never convert silently: a depth PNG must be 16-bit grey, a label
// PNG 8-bit grey, a colour PNG 8-bit RGB(A). Anything else is reported with
// the file name and what was actually found, because a quietly rescaled depth
// image or a palette label image gives wrong results much later and far away.
//
// libpng reports errors through longjmp. The error callback stores the
// message and longjmps back into a small function (runRead/runWrite) whose
// state lives in a caller-owned job struct; the caller then throws
// findmug::Error and the job's destructor frees the libpng structs.
#include "findmug/frame/image_io.hpp"

#include <png.h>

#include <cerrno>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

#include "findmug/common/error.hpp"

namespace findmug {

namespace {

// Kinect-class images are 640x480; refuse sizes that can only be corruption
// before allocating memory for them.
constexpr png_uint_32 kMaxPngDimension = 16384;

struct PngErrorState {
  std::string message;
};

void onPngError(png_structp png, png_const_charp msg) {
  auto* state = static_cast<PngErrorState*>(png_get_error_ptr(png));
  if (state) state->message = msg ? msg : "unknown libpng error";
  png_longjmp(png, 1);
}

void onPngWarning(png_structp, png_const_charp) {
  // Warnings (e.g. a bad CRC in an ancillary chunk, unknown iCCP profile)
  // do not affect pixel data; stay quiet rather than spam a daemon's log.
}

std::string colourTypeName(int colour_type) {
  switch (colour_type) {
    case PNG_COLOR_TYPE_GRAY:
      return "grey";
    case PNG_COLOR_TYPE_GRAY_ALPHA:
      return "grey+alpha";
    case PNG_COLOR_TYPE_RGB:
      return "RGB";
    case PNG_COLOR_TYPE_RGB_ALPHA:
      return "RGBA";
    case PNG_COLOR_TYPE_PALETTE:
      return "palette";
    default:
      return "colour type " + std::to_string(colour_type);
  }
}

// What a reader wants; decides the check and the output layout.
enum class Want { Grey8, Grey16, Rgb8 };

std::string wantName(Want want) {
  switch (want) {
    case Want::Grey8:
      return "8-bit single-channel PNG";
    case Want::Grey16:
      return "16-bit single-channel PNG";
    case Want::Rgb8:
      return "8-bit RGB or RGBA PNG";
  }
  return "?";
}

bool accepts(Want want, int bit_depth, int colour_type) {
  switch (want) {
    case Want::Grey8:
      return bit_depth == 8 && colour_type == PNG_COLOR_TYPE_GRAY;
    case Want::Grey16:
      return bit_depth == 16 && colour_type == PNG_COLOR_TYPE_GRAY;
    case Want::Rgb8:
      return bit_depth == 8 &&
             (colour_type == PNG_COLOR_TYPE_RGB || colour_type == PNG_COLOR_TYPE_RGB_ALPHA);
  }
  return false;
}

// Source of PNG bytes: either a FILE* or a memory buffer.
struct MemoryReader {
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
  std::size_t offset = 0;
};

void readFromMemory(png_structp png, png_bytep out, png_size_t length) {
  auto* reader = static_cast<MemoryReader*>(png_get_io_ptr(png));
  if (reader->size - reader->offset < length) {
    png_error(png, "truncated PNG data");
  }
  std::memcpy(out, reader->data + reader->offset, length);
  reader->offset += length;
}

struct FileCloser {
  void operator()(std::FILE* f) const {
    if (f) std::fclose(f);
  }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

// Decoded raw rows plus the header fields.
struct Decoded {
  png_uint_32 width = 0;
  png_uint_32 height = 0;
  int bit_depth = 0;
  int colour_type = 0;
  std::size_t row_bytes = 0;
  std::vector<std::uint8_t> bytes;  // height * row_bytes, after transforms
};

// Everything one decode needs, owned by the caller. The libpng calls run in
// runRead(), whose own locals are plain values that are not modified after
// setjmp, so a longjmp skips no destructor and clobbers nothing.
struct ReadJob {
  png_structp png = nullptr;
  png_infop info = nullptr;
  std::FILE* file = nullptr;
  MemoryReader* memory = nullptr;
  Want want = Want::Grey8;
  std::string what;
  PngErrorState state;
  Decoded out;
  std::string format_error;  // set instead of throwing when the format is wrong
  ~ReadJob() {
    if (png) png_destroy_read_struct(&png, info ? &info : nullptr, nullptr);
  }
};

bool isLittleEndianHost() {
  const std::uint16_t probe = 1;
  std::uint8_t first_byte = 0;
  std::memcpy(&first_byte, &probe, 1);
  return first_byte == 1;
}

// Returns false when libpng reported an error (message in job->state).
bool runRead(ReadJob* job) {
  if (setjmp(png_jmpbuf(job->png))) return false;
  png_structp png = job->png;
  png_infop info = job->info;
  if (job->memory) {
    png_set_read_fn(png, job->memory, readFromMemory);
  } else {
    png_init_io(png, job->file);
  }
  png_set_user_limits(png, kMaxPngDimension, kMaxPngDimension);
  png_read_info(png, info);
  Decoded& out = job->out;
  int interlace = 0;
  png_get_IHDR(png, info, &out.width, &out.height, &out.bit_depth, &out.colour_type, &interlace,
               nullptr, nullptr);
  if (!accepts(job->want, out.bit_depth, out.colour_type)) {
    job->format_error = job->what + ": expected " + wantName(job->want) + ", found " +
                        std::to_string(out.bit_depth) + "-bit " + colourTypeName(out.colour_type);
    return true;
  }
  // PNG stores 16-bit samples big-endian; ask libpng for host order.
  if (job->want == Want::Grey16 && isLittleEndianHost()) png_set_swap(png);
  if (job->want == Want::Rgb8 && out.colour_type == PNG_COLOR_TYPE_RGB_ALPHA) {
    png_set_strip_alpha(png);
  }
  const int passes = png_set_interlace_handling(png);
  png_read_update_info(png, info);
  out.row_bytes = png_get_rowbytes(png, info);
  out.bytes.resize(out.row_bytes * out.height);
  for (int pass = 0; pass < passes; ++pass) {
    for (png_uint_32 y = 0; y < out.height; ++y) {
      png_read_row(png, out.bytes.data() + y * out.row_bytes, nullptr);
    }
  }
  png_read_end(png, nullptr);
  return true;
}

// Decodes the whole image, checking the format against `want` right after
// the header. `file` or `memory` supplies the bytes; `what` names the source.
Decoded decode(std::FILE* file, MemoryReader* memory, const std::string& what, Want want) {
  ReadJob job;
  job.file = file;
  job.memory = memory;
  job.want = want;
  job.what = what;
  job.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &job.state, onPngError, onPngWarning);
  if (!job.png) throw Error(what + ": cannot allocate PNG reader");
  job.info = png_create_info_struct(job.png);
  if (!job.info) throw Error(what + ": cannot allocate PNG info");
  if (!runRead(&job)) throw Error(what + ": not a valid PNG (" + job.state.message + ")");
  if (!job.format_error.empty()) throw Error(job.format_error);
  return std::move(job.out);
}

Decoded decodeFile(const std::string& path, Want want) {
  FilePtr file(std::fopen(path.c_str(), "rb"));
  if (!file) throw Error(path + ": cannot open (" + std::strerror(errno) + ")");
  std::uint8_t signature[8] = {};
  const std::size_t got = std::fread(signature, 1, sizeof(signature), file.get());
  if (got != sizeof(signature) || png_sig_cmp(signature, 0, sizeof(signature)) != 0) {
    throw Error(path + ": not a PNG file (bad signature)");
  }
  std::rewind(file.get());
  return decode(file.get(), nullptr, path, want);
}

template <typename T>
Image<T> makeImage(const Decoded& d) {
  Image<T> image;
  image.width = static_cast<int>(d.width);
  image.height = static_cast<int>(d.height);
  image.pixels.resize(static_cast<std::size_t>(d.width) * d.height);
  const std::size_t packed = sizeof(T) * d.width;
  if (packed != d.row_bytes && d.height > 0) {
    throw Error("internal: PNG row size " + std::to_string(d.row_bytes) +
                " != " + std::to_string(packed));
  }
  if (!image.pixels.empty()) std::memcpy(image.pixels.data(), d.bytes.data(), d.bytes.size());
  return image;
}

// Output side: a FILE* or a growing byte vector.
void writeToVector(png_structp png, png_bytep data, png_size_t length) {
  auto* out = static_cast<std::vector<std::uint8_t>*>(png_get_io_ptr(png));
  out->insert(out->end(), data, data + length);
}
void flushNothing(png_structp) {}

template <typename T>
void checkWritable(const Image<T>& image, const std::string& what) {
  if (image.width <= 0 || image.height <= 0 ||
      static_cast<png_uint_32>(image.width) > kMaxPngDimension ||
      static_cast<png_uint_32>(image.height) > kMaxPngDimension) {
    throw Error(what + ": cannot write image of size " + std::to_string(image.width) + "x" +
                std::to_string(image.height));
  }
  const auto expected = static_cast<std::size_t>(image.width) * image.height;
  if (image.pixels.size() != expected) {
    throw Error(what + ": image has " + std::to_string(image.pixels.size()) + " pixels, expected " +
                std::to_string(expected) + " (" + std::to_string(image.width) + "x" +
                std::to_string(image.height) + ")");
  }
}

struct WriteJob {
  png_structp png = nullptr;
  png_infop info = nullptr;
  std::FILE* file = nullptr;
  std::vector<std::uint8_t>* memory = nullptr;
  PngErrorState state;
  int width = 0, height = 0, bit_depth = 8, colour_type = PNG_COLOR_TYPE_GRAY;
  const std::uint8_t* data = nullptr;
  std::size_t row_bytes = 0;
  ~WriteJob() {
    if (png) png_destroy_write_struct(&png, info ? &info : nullptr);
  }
};

// Returns false when libpng reported an error (message in job->state).
bool runWrite(WriteJob* job) {
  if (setjmp(png_jmpbuf(job->png))) return false;
  png_structp png = job->png;
  if (job->memory) {
    png_set_write_fn(png, job->memory, writeToVector, flushNothing);
  } else {
    png_init_io(png, job->file);
  }
  // Level 1 is far faster than the default and costs little size on noisy
  // sensor images; the grabber writes frames at camera rate.
  png_set_compression_level(png, 1);
  png_set_IHDR(png, job->info, static_cast<png_uint_32>(job->width),
               static_cast<png_uint_32>(job->height), job->bit_depth, job->colour_type,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, job->info);
  // Host order in memory, big-endian in the file.
  if (job->bit_depth == 16 && isLittleEndianHost()) png_set_swap(png);
  for (int y = 0; y < job->height; ++y) {
    png_write_row(png, job->data + static_cast<std::size_t>(y) * job->row_bytes);
  }
  png_write_end(png, nullptr);
  return true;
}

// Encodes rows of `row_bytes` bytes each. `bit_depth`/`colour_type` describe
// the pixel layout; for 16 bit the caller's samples are in host order.
void encode(std::FILE* file, std::vector<std::uint8_t>* memory, const std::string& what, int width,
            int height, int bit_depth, int colour_type, const std::uint8_t* data,
            std::size_t row_bytes) {
  WriteJob job;
  job.file = file;
  job.memory = memory;
  job.width = width;
  job.height = height;
  job.bit_depth = bit_depth;
  job.colour_type = colour_type;
  job.data = data;
  job.row_bytes = row_bytes;
  job.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &job.state, onPngError, onPngWarning);
  if (!job.png) throw Error(what + ": cannot allocate PNG writer");
  job.info = png_create_info_struct(job.png);
  if (!job.info) throw Error(what + ": cannot allocate PNG info");
  if (!runWrite(&job)) throw Error(what + ": PNG write failed (" + job.state.message + ")");
}

template <typename T>
void writeFile(const std::string& path, const Image<T>& image, int bit_depth, int colour_type) {
  checkWritable(image, path);
  FilePtr file(std::fopen(path.c_str(), "wb"));
  if (!file) throw Error(path + ": cannot open for writing (" + std::strerror(errno) + ")");
  encode(file.get(), nullptr, path, image.width, image.height, bit_depth, colour_type,
         reinterpret_cast<const std::uint8_t*>(image.pixels.data()), sizeof(T) * image.width);
  if (std::fflush(file.get()) != 0 || std::ferror(file.get())) {
    throw Error(path + ": write failed (" + std::strerror(errno) + ")");
  }
  std::FILE* raw = file.release();
  if (std::fclose(raw) != 0) throw Error(path + ": close failed (" + std::strerror(errno) + ")");
}

}  // namespace

static_assert(sizeof(Rgb8) == 3, "Rgb8 must be packed as three bytes for PNG rows");

Image<std::uint16_t> readPng16(const std::string& path) {
  return makeImage<std::uint16_t>(decodeFile(path, Want::Grey16));
}

Image<std::uint8_t> readPng8(const std::string& path) {
  return makeImage<std::uint8_t>(decodeFile(path, Want::Grey8));
}

Image<Rgb8> readPngRgb(const std::string& path) {
  return makeImage<Rgb8>(decodeFile(path, Want::Rgb8));
}

void writePng16(const std::string& path, const Image<std::uint16_t>& image) {
  writeFile(path, image, 16, PNG_COLOR_TYPE_GRAY);
}

void writePng8(const std::string& path, const Image<std::uint8_t>& image) {
  writeFile(path, image, 8, PNG_COLOR_TYPE_GRAY);
}

void writePngRgb(const std::string& path, const Image<Rgb8>& image) {
  writeFile(path, image, 8, PNG_COLOR_TYPE_RGB);
}

std::vector<std::uint8_t> encodePngRgb(const Image<Rgb8>& image) {
  checkWritable(image, "in-memory PNG");
  std::vector<std::uint8_t> bytes;
  bytes.reserve(image.pixels.size());  // compressed colour is usually well under 1 byte/pixel
  encode(nullptr, &bytes, "in-memory PNG", image.width, image.height, 8, PNG_COLOR_TYPE_RGB,
         reinterpret_cast<const std::uint8_t*>(image.pixels.data()), 3 * image.width);
  return bytes;
}

Image<Rgb8> decodePngRgb(const std::vector<std::uint8_t>& bytes, const std::string& what) {
  if (bytes.size() < 8 || png_sig_cmp(bytes.data(), 0, 8) != 0) {
    throw Error(what + ": not a PNG (" + std::to_string(bytes.size()) + " bytes, bad signature)");
  }
  MemoryReader reader{bytes.data(), bytes.size(), 0};
  return makeImage<Rgb8>(decode(nullptr, &reader, what, Want::Rgb8));
}

}  // namespace findmug
