#include "compression.hpp"

#include <jpeglib.h>
#include <libdeflate.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "findmug/common/error.hpp"

namespace findmug::io::detail {

// ---- zlib -----------------------------------------------------------------------

std::vector<std::uint8_t> zlibCompress(const std::uint8_t* data, std::size_t size, int level) {
  if (size > std::numeric_limits<uInt>::max()) throw Error("zlib: input too large");
  z_stream zs{};
  if (deflateInit2(&zs, level, Z_DEFLATED, 15, 8, Z_DEFAULT_STRATEGY) != Z_OK) {
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

namespace {

// ---- zlibCompressRuns: deflate (RFC 1951) for images made of runs ----------
//
// The data becomes tokens: a run of one byte value is the byte as a literal,
// then matches at distance 1 (lengths 3..258) for its other copies. One
// block with Huffman codes fitted to this image's tokens (a label image uses
// a handful of literals and length symbols, so they cost a few bits each),
// or stored blocks when that would be larger.

constexpr int kMinMatch = 3;
constexpr int kMaxMatch = 258;
constexpr int kEndOfBlock = 256;
constexpr int kLitLenSymbols = 286;  // 0..255 literals, 256 end, 257..285 lengths
constexpr int kMaxCodeBits = 15;
constexpr int kCodeLengthSymbols = 19;
constexpr int kMaxCodeLengthBits = 7;

// Length symbols 257..285: base lengths and extra bit counts (RFC 1951 3.2.5).
constexpr int kLengthBase[29] = {3,  4,  5,  6,  7,  8,  9,  10, 11,  13,  15,  17,  19,  23, 27,
                                 31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
constexpr int kLengthExtra[29] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
                                  2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};

// Index into kLengthBase of each match length.
struct LengthTable {
  LengthTable() {
    for (int length = kMinMatch; length <= kMaxMatch; ++length) {
      int k = 28;
      while (kLengthBase[k] > length) --k;
      index[length] = static_cast<std::uint8_t>(k);
    }
  }
  std::array<std::uint8_t, kMaxMatch + 1> index{};
};

// LSB-first bit writer into a buffer the caller sized: whole 32-bit words
// are stored as soon as they are full. Huffman codes go in bit-reversed
// (deflate sends them most significant bit first).
class BitWriter {
 public:
  explicit BitWriter(std::uint8_t* out) : out_(out) {}
  void put(std::uint32_t value, std::uint32_t count) {  // count <= 32
    pending_ |= static_cast<std::uint64_t>(value) << count_;
    count_ += count;
    if (count_ >= 32) {
      const auto word = static_cast<std::uint32_t>(pending_);
      for (int k = 0; k < 4; ++k) out_[k] = static_cast<std::uint8_t>(word >> (8 * k));
      out_ += 4;
      pending_ >>= 32;
      count_ -= 32;
    }
  }
  // Pads to a whole byte and returns the end of the output.
  std::uint8_t* finish() {
    while (count_ > 0) {
      *out_++ = static_cast<std::uint8_t>(pending_);
      pending_ >>= 8;
      count_ = count_ > 8 ? count_ - 8 : 0;
    }
    return out_;
  }

 private:
  std::uint8_t* out_;
  std::uint64_t pending_ = 0;
  std::uint32_t count_ = 0;
};

// Huffman code lengths for counts[0..n) (n <= kLitLenSymbols), none longer
// than max_bits: Huffman's construction (two queues over the symbols sorted
// by count), and while the deepest code is too long, the counts halved (kept
// above 0) and the code built again. Symbols of count 0 get length 0. At
// least two symbols get a code (a one-symbol code is not a complete prefix
// code; deflate decoders reject most incomplete ones), so a lone symbol is
// paired with another. Fixed-size arrays on the stack: no allocation per
// image.
void huffmanLengths(const std::uint32_t* counts, int n, int max_bits, std::uint8_t* lengths) {
  constexpr int kMaxNodes = 2 * kLitLenSymbols - 1;
  std::array<std::uint32_t, kLitLenSymbols> freq{};
  std::copy(counts, counts + n, freq.begin());
  int used = 0;
  for (int s = 0; s < n; ++s) used += freq[s] > 0 ? 1 : 0;
  for (int s = 0; s < n && used < 2; ++s) {
    if (freq[s] == 0) {
      freq[s] = 1;
      ++used;
    }
  }
  std::array<int, kLitLenSymbols> leaves{};
  std::array<int, kMaxNodes> parent{}, depth{};
  std::array<std::uint64_t, kMaxNodes> weight{};
  while (true) {
    int m = 0;
    for (int s = 0; s < n; ++s) {
      if (freq[s] > 0) leaves[m++] = s;
    }
    std::sort(leaves.begin(), leaves.begin() + m,
              [&](int a, int b) { return freq[a] != freq[b] ? freq[a] < freq[b] : a < b; });
    // Nodes 0..m-1 are the leaves in sorted order, m.. the merged ones in
    // the order they are made (their weights never decrease).
    for (int k = 0; k < m; ++k) weight[k] = freq[leaves[k]];
    int next_leaf = 0, next_merged = m;
    const auto take = [&](int made) {
      if (next_leaf < m && (next_merged >= made || weight[next_leaf] <= weight[next_merged])) {
        return next_leaf++;
      }
      return next_merged++;
    };
    for (int made = m; made < 2 * m - 1; ++made) {
      const int a = take(made);
      const int b = take(made);
      weight[made] = weight[a] + weight[b];
      parent[a] = parent[b] = made;
    }
    // Depths, from the root (the last node) down.
    depth[2 * m - 2] = 0;
    int deepest = 0;
    for (int k = 2 * m - 3; k >= 0; --k) {
      depth[k] = depth[parent[k]] + 1;
      if (k < m) deepest = std::max(deepest, depth[k]);
    }
    if (deepest <= max_bits) {
      for (int s = 0; s < n; ++s) lengths[s] = 0;
      for (int k = 0; k < m; ++k) lengths[leaves[k]] = static_cast<std::uint8_t>(depth[k]);
      return;
    }
    for (int s = 0; s < n; ++s) {
      if (freq[s] > 0) freq[s] = (freq[s] + 1) / 2;
    }
  }
}

// Canonical codes of `lengths` (RFC 1951 3.2.2), bit-reversed for BitWriter.
void canonicalCodes(const std::uint8_t* lengths, int n, std::uint32_t* codes) {
  int count[kMaxCodeBits + 1] = {};
  for (int s = 0; s < n; ++s) ++count[lengths[s]];
  count[0] = 0;
  std::uint32_t next[kMaxCodeBits + 2] = {};
  std::uint32_t code = 0;
  for (int bits = 1; bits <= kMaxCodeBits; ++bits) {
    code = (code + static_cast<std::uint32_t>(count[bits - 1])) << 1;
    next[bits] = code;
  }
  for (int s = 0; s < n; ++s) {
    const int len = lengths[s];
    if (len == 0) {
      codes[s] = 0;
      continue;
    }
    const std::uint32_t c = next[len]++;
    std::uint32_t reversed = 0;
    for (int b = 0; b < len; ++b) reversed |= ((c >> b) & 1u) << (len - 1 - b);
    codes[s] = reversed;
  }
}

// End of the run of data[i]'s value that starts at i (i < size).
std::size_t runEnd(const std::uint8_t* data, std::size_t i, std::size_t size) {
  const std::uint8_t v = data[i];
  std::size_t end = i + 1;
#if defined(__SSE2__)
  const __m128i value = _mm_set1_epi8(static_cast<char>(v));
  for (; end + 16 <= size; end += 16) {
    const __m128i bytes = _mm_loadu_si128(reinterpret_cast<const __m128i*>(data + end));
    const int same = _mm_movemask_epi8(_mm_cmpeq_epi8(bytes, value));
    if (same != 0xffff) return end + static_cast<std::size_t>(__builtin_ctz(~same & 0xffff));
  }
#endif
  while (end < size && data[end] == v) ++end;
  return end;
}

constexpr std::uint8_t kZlibHeader[2] = {0x78, 0x01};  // deflate, 32 KiB window; no dictionary

void putAdler32(std::uint32_t adler, std::uint8_t* out) {  // big-endian (RFC 1950)
  for (int k = 0; k < 4; ++k) out[k] = static_cast<std::uint8_t>(adler >> (24 - 8 * k));
}

// The zlib stream of `data` in stored blocks (RFC 1951 3.2.4) into `out`;
// returns its end.
std::uint8_t* storedZlib(const std::uint8_t* data, std::size_t size, std::uint8_t* out) {
  *out++ = kZlibHeader[0];
  *out++ = kZlibHeader[1];
  std::size_t done = 0;
  do {
    const std::size_t length = std::min<std::size_t>(size - done, 65535);
    *out++ = done + length == size ? 1 : 0;  // BFINAL, BTYPE 00, padding
    const auto len = static_cast<std::uint16_t>(length);
    const auto nlen = static_cast<std::uint16_t>(~len);
    *out++ = static_cast<std::uint8_t>(len);
    *out++ = static_cast<std::uint8_t>(len >> 8);
    *out++ = static_cast<std::uint8_t>(nlen);
    *out++ = static_cast<std::uint8_t>(nlen >> 8);
    if (length > 0) std::memcpy(out, data + done, length);
    out += length;
    done += length;
  } while (done < size);
  putAdler32(static_cast<std::uint32_t>(libdeflate_adler32(1, data, size)), out);
  return out + 4;
}

// A token: a literal byte (< 256) or a match at distance 1 of length
// token - 256 + kMinMatch.
std::uint16_t matchToken(std::size_t length) {
  return static_cast<std::uint16_t>(256 + length - kMinMatch);
}

}  // namespace

std::vector<std::uint8_t> zlibCompressRuns(const std::uint8_t* data, std::size_t size) {
  static const LengthTable length_table;
  // Per thread, grown to the largest image and then kept: no allocation per
  // image but the result.
  thread_local std::vector<std::uint16_t> tokens;
  thread_local std::vector<std::uint8_t> scratch;
  tokens.resize(size + 1);

  // Tokens and the counts of the literal/length symbols.
  std::array<std::uint32_t, kLitLenSymbols> lit_freq{};
  std::size_t count = 0;
  for (std::size_t i = 0; i < size;) {
    const std::size_t end = runEnd(data, i, size);
    const std::uint8_t value = data[i];
    tokens[count++] = value;
    ++lit_freq[value];
    std::size_t left = end - i - 1;  // copies of the value after the literal
    while (left >= kMinMatch) {
      std::size_t length = std::min<std::size_t>(left, kMaxMatch);
      // Never leave 1 or 2 behind a full match when a shorter one avoids it.
      if (left > length && left - length < kMinMatch) length -= kMinMatch;
      tokens[count++] = matchToken(length);
      ++lit_freq[257 + length_table.index[length]];
      left -= length;
    }
    for (; left > 0; --left) {
      tokens[count++] = value;
      ++lit_freq[value];
    }
    i = end;
  }
  lit_freq[kEndOfBlock] = 1;

  // Codes: literal/length from the counts; distance: codes 0 and 1 of one
  // bit each (only code 0, distance 1, is used; two make a complete code).
  std::uint8_t lengths[kLitLenSymbols + 2];
  huffmanLengths(lit_freq.data(), kLitLenSymbols, kMaxCodeBits, lengths);
  int hlit = kLitLenSymbols;
  while (hlit > 257 && lengths[hlit - 1] == 0) --hlit;
  lengths[hlit] = 1;
  lengths[hlit + 1] = 1;
  std::uint32_t lit_code[kLitLenSymbols];
  canonicalCodes(lengths, hlit, lit_code);
  // The two lengths sequences, run-length coded: 0..15 as themselves, runs
  // of zeros as 17 (3..10, 3 extra bits) and 18 (11..138, 7 extra bits).
  const int total = hlit + 2;
  std::uint8_t cl_symbol[kLitLenSymbols + 2], cl_extra[kLitLenSymbols + 2];
  int cl_count = 0;
  std::array<std::uint32_t, kCodeLengthSymbols> cl_freq{};
  for (int k = 0; k < total;) {
    int zeros = 0;
    while (k + zeros < total && lengths[k + zeros] == 0 && zeros < 138) ++zeros;
    if (zeros >= 11) {
      cl_symbol[cl_count] = 18, cl_extra[cl_count++] = static_cast<std::uint8_t>(zeros - 11);
      k += zeros;
    } else if (zeros >= 3) {
      cl_symbol[cl_count] = 17, cl_extra[cl_count++] = static_cast<std::uint8_t>(zeros - 3);
      k += zeros;
    } else {
      cl_symbol[cl_count] = lengths[k], cl_extra[cl_count++] = 0;
      ++k;
    }
    ++cl_freq[cl_symbol[cl_count - 1]];
  }
  std::uint8_t cl_lengths[kCodeLengthSymbols];
  huffmanLengths(cl_freq.data(), kCodeLengthSymbols, kMaxCodeLengthBits, cl_lengths);
  std::uint32_t cl_code[kCodeLengthSymbols];
  canonicalCodes(cl_lengths, kCodeLengthSymbols, cl_code);
  static constexpr int kClOrder[kCodeLengthSymbols] = {16, 17, 18, 0, 8,  7, 9,  6, 10, 5,
                                                       11, 4,  12, 3, 13, 2, 14, 1, 15};
  int hclen = kCodeLengthSymbols;
  while (hclen > 4 && cl_lengths[kClOrder[hclen - 1]] == 0) --hclen;

  // The stream, into scratch sized for the worst case or the stored form:
  // a token takes at most 15 + 5 + 1 bits (a match), the header and the
  // tables under 600 bytes (288 code lengths of at most 7 + 7 bits).
  const std::size_t stored_size = size + 5 * (size / 65535 + 1) + 6;
  const std::size_t coded_bound = (count + 1) * 3 + 600;
  if (scratch.size() < std::max(stored_size, coded_bound)) {
    scratch.resize(std::max(stored_size, coded_bound));
  }
  std::uint8_t* const begin = scratch.data();
  begin[0] = kZlibHeader[0];
  begin[1] = kZlibHeader[1];
  BitWriter writer(begin + 2);
  writer.put(1 | (2 << 1), 3);  // BFINAL = 1, BTYPE = 10 (dynamic Huffman codes)
  writer.put(static_cast<std::uint32_t>(hlit - 257), 5);
  writer.put(1, 5);  // HDIST: two distance codes
  writer.put(static_cast<std::uint32_t>(hclen - 4), 4);
  for (int k = 0; k < hclen; ++k) writer.put(cl_lengths[kClOrder[k]], 3);
  for (int k = 0; k < cl_count; ++k) {
    const int sym = cl_symbol[k];
    writer.put(cl_code[sym], cl_lengths[sym]);
    if (sym == 17) writer.put(cl_extra[k], 3);
    if (sym == 18) writer.put(cl_extra[k], 7);
  }
  const std::uint32_t distance_bits = 1;  // code 0 of a one-bit code: the bit 0
  for (std::size_t t = 0; t < count; ++t) {
    const std::uint16_t token = tokens[t];
    if (token < 256) {
      writer.put(lit_code[token], lengths[token]);
      continue;
    }
    const int length = token - 256 + kMinMatch;
    const int k = length_table.index[length];
    writer.put(lit_code[257 + k], lengths[257 + k]);
    if (kLengthExtra[k] > 0) {
      writer.put(static_cast<std::uint32_t>(length - kLengthBase[k]),
                 static_cast<std::uint32_t>(kLengthExtra[k]));
    }
    writer.put(0, distance_bits);
  }
  writer.put(lit_code[kEndOfBlock], lengths[kEndOfBlock]);
  std::uint8_t* end = writer.finish();
  if (static_cast<std::size_t>(end - begin) + 4 > stored_size) {
    end = storedZlib(data, size, begin);
  } else {
    putAdler32(static_cast<std::uint32_t>(libdeflate_adler32(1, data, size)), end);
    end += 4;
  }
  return std::vector<std::uint8_t>(begin, end);
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
