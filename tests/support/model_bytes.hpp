// Test support: editing a model file's bytes by its documented layout
// (src/learner/forest_format.hpp), to build files that are intact (valid checksum)
// but wrong in one field. For unit tests, which see the core's internal headers.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "file_bytes.hpp"
#include "findmug/common/error.hpp"
#include "findmug/learner/forest.hpp"
#include "learner/forest_format.hpp"

namespace findmug::test {

// Rewrites the trailing FNV-1a checksum over everything before it.
inline void fixChecksum(std::vector<std::uint8_t>& bytes) {
  const std::size_t body = bytes.size() - forest_format::kChecksumSize;
  const std::uint64_t h = forest_format::fnv1a64(bytes.data(), body);
  for (int i = 0; i < 8; ++i) bytes[body + i] = static_cast<std::uint8_t>(h >> (8 * i));
}

// Little-endian fields, as the format stores them.
inline void putU32(std::vector<std::uint8_t>& bytes, std::size_t offset, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) bytes[offset + i] = static_cast<std::uint8_t>(v >> (8 * i));
}
inline void putU64(std::vector<std::uint8_t>& bytes, std::size_t offset, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) bytes[offset + i] = static_cast<std::uint8_t>(v >> (8 * i));
}

// Writes `bytes` to `path` and expects RandomForest::load to refuse it with a
// message naming the file and containing `word`.
inline void expectModelRefused(const std::string& path, const std::vector<std::uint8_t>& bytes,
                               const std::string& word) {
  writeBytes(path, bytes);
  try {
    RandomForest::load(path);
    ADD_FAILURE() << "load accepted a bad file; expected an error mentioning '" << word << "'";
  } catch (const Error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find(word), std::string::npos) << msg;
  }
}

}  // namespace findmug::test
