// fuzz_support.hpp — what the fuzz targets in tests/fuzz share.
//
// Every target defines LLVMFuzzerTestOneInput and hands the bytes to one
// decoder of outside bytes. A findmug::Error is the expected answer to a bad
// input; anything else escaping (std::bad_alloc, std::out_of_range, a
// third-party exception) is a finding: it terminates the run like a crash.
//
// Readers that take file names get the bytes through a per-process scratch
// file; readers of several files (PCLZF: depth, rgb, xml) get them through a
// container: n-1 little-endian uint32 lengths, then the parts, the last part
// taking what is left (see splitParts; the seed maker writes the same layout).
#pragma once

#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

namespace findmug::fuzz {

// Scratch directory: $FINDMUG_FUZZ_TMP, else /dev/shm (no disk wear), else the temp dir.
inline const std::string& scratchDir() {
  static const std::string dir = [] {
    std::filesystem::path base;
    if (const char* env = std::getenv("FINDMUG_FUZZ_TMP"); env && *env) {
      base = env;
    } else if (std::filesystem::is_directory("/dev/shm")) {
      base = "/dev/shm";
    } else {
      base = std::filesystem::temp_directory_path();
    }
    auto dir = base / ("findmug-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    return dir.string();
  }();
  // Removed at exit: every replay of the corpus by ctest is a process of its own.
  static const struct Cleanup {
    ~Cleanup() {
      std::error_code ignored;
      std::filesystem::remove_all(dir, ignored);
    }
  } cleanup;
  return dir;
}

// Writes `bytes` to scratchDir()/name and returns the path (the same file every call).
inline std::string scratchFile(const std::string& name, std::string_view bytes) {
  const std::string path = scratchDir() + "/" + name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) {
    std::fprintf(stderr, "cannot write the scratch file %s\n", path.c_str());
    std::abort();
  }
  return path;
}

// Splits a container into `n` parts (see the top of this file). Missing bytes
// make parts short or empty: a truncated container is a valid fuzz input.
inline std::vector<std::string_view> splitParts(const std::uint8_t* data, std::size_t size,
                                                std::size_t n) {
  std::vector<std::string_view> parts(n);
  const auto* chars = reinterpret_cast<const char*>(data);
  std::size_t header = 4 * (n - 1);
  if (size < header) return parts;
  std::size_t pos = header;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const std::uint8_t* p = data + 4 * i;
    const std::size_t length = static_cast<std::size_t>(p[0]) | (static_cast<std::size_t>(p[1]) << 8) |
                               (static_cast<std::size_t>(p[2]) << 16) |
                               (static_cast<std::size_t>(p[3]) << 24);
    const std::size_t take = std::min(length, size - pos);
    parts[i] = std::string_view(chars + pos, take);
    pos += take;
  }
  parts[n - 1] = std::string_view(chars + pos, size - pos);
  return parts;
}

// The inverse of splitParts (for the seed maker).
inline std::string joinParts(const std::vector<std::string>& parts) {
  std::string out;
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    const auto length = static_cast<std::uint32_t>(parts[i].size());
    for (int b = 0; b < 4; ++b) out.push_back(static_cast<char>((length >> (8 * b)) & 0xFF));
  }
  for (const auto& part : parts) out += part;
  return out;
}

}  // namespace findmug::fuzz
