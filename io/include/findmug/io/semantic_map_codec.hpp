// findmug/io/semantic_map_codec.hpp — the fused semantic map <-> semantic_map_t (LCM).
//
// The map message carries every occupied voxel with its most voted label and that label's
// share of the votes (lcmtypes/semantic_map_t.lcm), zlib-compressed. The decoder trusts
// nothing, as those of lcm_codec.hpp: it walks the wire layout before LCM allocates,
// caps the voxel count, inflates to exactly the announced size, and checks every label,
// the order of the voxels and the header values; any problem is a findmug::Error naming
// the channel and the field.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "findmug/map/semantic_map.hpp"
#include "findmug_lcm/semantic_map_t.hpp"

namespace findmug::io {

struct SemanticMapVoxel {
  std::int16_t i = 0, j = 0, k = 0;  // voxel indices: centre = (i, j, k) * voxel_size_m
  std::uint8_t label = 0;            // 0..7
  std::uint8_t confidence = 0;       // share of the votes, 0..255 = 0..1
  friend bool operator==(const SemanticMapVoxel&, const SemanticMapVoxel&) = default;
};

struct SemanticMapMessage {
  std::uint64_t utime = 0;  // last fused frame's
  std::int64_t seq = 0;
  std::int64_t frames = 0;
  float voxel_size_m = 0.05f;
  std::vector<SemanticMapVoxel> voxels;  // ascending by (i, j, k)
};

// At most this many voxels in a message (32 MB of records): the decoder refuses more.
inline constexpr std::int32_t kMaxSemanticMapVoxels = 4 * 1024 * 1024;

// The map's occupied voxels with votes, as a message (voxels beyond 16-bit indices left out).
SemanticMapMessage semanticMapMessage(const SemanticMap& map, std::uint64_t utime,
                                      std::int64_t seq);
findmug_lcm::semantic_map_t encodeSemanticMap(const SemanticMapMessage& message,
                                              bool compress = true);
SemanticMapMessage decodeSemanticMap(const findmug_lcm::semantic_map_t& message,
                                     std::string_view channel);
// Walks the wire layout first (every length against the bytes really there).
SemanticMapMessage decodeSemanticMap(const void* data, std::size_t size, std::string_view channel);

}  // namespace findmug::io
