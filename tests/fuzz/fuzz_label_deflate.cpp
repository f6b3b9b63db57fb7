// Fuzz target label_deflate: the label images' own deflate (zlibCompressRuns,
// io/src/compression.hpp) on any bytes must give a zlib stream that zlib's
// inflate and the codec's own decoder (libdeflate) both turn back into those
// very bytes. A round trip, not a decoder: any mismatch aborts.
#include <zlib.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "compression.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::vector<std::uint8_t> stream = findmug::io::detail::zlibCompressRuns(data, size);
  // Never much larger than the data (stored blocks bound it).
  if (stream.size() > size + 5 * (size / 65535 + 1) + 6) {
    std::fprintf(stderr, "label_deflate: %zu bytes compress to %zu\n", size, stream.size());
    std::abort();
  }
  std::vector<std::uint8_t> out(size + 1);
  uLongf out_size = static_cast<uLongf>(out.size());
  const int rc = uncompress(out.data(), &out_size, stream.data(), static_cast<uLong>(stream.size()));
  if (rc != Z_OK || out_size != size || (size > 0 && std::memcmp(out.data(), data, size) != 0)) {
    std::fprintf(stderr, "label_deflate: zlib inflate gives rc %d, %lu of %zu bytes\n", rc,
                 static_cast<unsigned long>(out_size), size);
    std::abort();
  }
  const std::vector<std::uint8_t> again =
      findmug::io::detail::zlibDecompress(stream.data(), stream.size(), size, "label_deflate");
  if (size > 0 && std::memcmp(again.data(), data, size) != 0) {
    std::fprintf(stderr, "label_deflate: libdeflate gives other bytes\n");
    std::abort();
  }
  return 0;
}
