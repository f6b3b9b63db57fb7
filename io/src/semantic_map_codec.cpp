// The semantic map message (semantic_map_codec.hpp).
#include "findmug/io/semantic_map_codec.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <tuple>

#include "compression.hpp"
#include "findmug/common/error.hpp"

namespace findmug::io {

namespace {

constexpr std::string_view kType = "semantic_map_t";
constexpr std::size_t kRecordBytes = 8;

std::string field(std::string_view channel, std::string_view name) {
  return std::string(channel) + ": " + std::string(kType) + "." + std::string(name);
}

auto order(const SemanticMapVoxel& v) { return std::make_tuple(v.i, v.j, v.k); }

void putInt16(std::uint8_t* out, std::int16_t value) {
  const auto u = static_cast<std::uint16_t>(value);
  out[0] = static_cast<std::uint8_t>(u & 0xFF);
  out[1] = static_cast<std::uint8_t>(u >> 8);
}

std::int16_t getInt16(const std::uint8_t* in) {
  return static_cast<std::int16_t>(static_cast<std::uint16_t>(in[0] | (in[1] << 8)));
}

// The wire layout before LCM's decode(): hash, utime, seq, frames, voxel_size_m,
// num_voxels, compression, data_size, data.
void walk(const std::uint8_t* data, std::size_t size, std::string_view channel) {
  auto fail = [&](std::string_view name, const std::string& what) {
    throw Error(field(channel, name) + ": " + what + " (message of " + std::to_string(size) +
                " bytes)");
  };
  constexpr std::size_t kFixed = 8 + 3 * 8 + 4 + 4 + 1;
  if (size < 8) fail("<hash>", "truncated");
  if (size > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) {
    fail("<size>", "larger than an LCM message can be");
  }
  std::uint64_t hash = 0;
  for (int b = 0; b < 8; ++b) hash = (hash << 8) | data[b];
  if (static_cast<std::int64_t>(hash) != findmug_lcm::semantic_map_t::getHash()) {
    throw Error(std::string(channel) + ": not a findmug_lcm.semantic_map_t message (type hash "
                "mismatch, " + std::to_string(size) + " bytes)");
  }
  if (size < kFixed + 4) fail("data_size", "truncated before it");
  std::uint32_t n = 0;
  for (std::size_t b = 0; b < 4; ++b) n = (n << 8) | data[kFixed + b];
  const auto count = static_cast<std::int32_t>(n);
  if (count < 0) fail("data_size", "negative count " + std::to_string(count));
  const std::size_t left = size - kFixed - 4;
  if (static_cast<std::size_t>(count) != left) {
    fail("data_size", std::to_string(count) + " bytes announced, " + std::to_string(left) +
                          " follow");
  }
}

}  // namespace

SemanticMapMessage semanticMapMessage(const SemanticMap& map, std::uint64_t utime,
                                      std::int64_t seq) {
  SemanticMapMessage out;
  out.utime = utime;
  out.seq = seq;
  out.frames = static_cast<std::int64_t>(map.stats().frames);
  out.voxel_size_m = map.config().voxel_size_m;
  const double inv = 1.0 / map.config().voxel_size_m;
  map.forEachVoxel([&](const Eigen::Vector3d& centre, const SemanticMap::Voxel& voxel) {
    if (!map.occupied(voxel)) return;
    float confidence = 0.0f;
    const std::uint8_t label = SemanticMap::labelOf(voxel, &confidence);
    if (label == kVoidLabel) return;
    const Eigen::Vector3d index = (centre * inv).array().round().matrix();
    if ((index.array().abs() > 32767.0).any()) return;
    out.voxels.push_back({static_cast<std::int16_t>(index.x()),
                          static_cast<std::int16_t>(index.y()),
                          static_cast<std::int16_t>(index.z()), label,
                          static_cast<std::uint8_t>(std::lround(confidence * 255.0f))});
  });
  std::sort(out.voxels.begin(), out.voxels.end(),
            [](const SemanticMapVoxel& a, const SemanticMapVoxel& b) { return order(a) < order(b); });
  return out;
}

findmug_lcm::semantic_map_t encodeSemanticMap(const SemanticMapMessage& message, bool compress) {
  if (message.voxels.size() > static_cast<std::size_t>(kMaxSemanticMapVoxels)) {
    throw Error("semantic_map_t: " + std::to_string(message.voxels.size()) +
                " voxels, above the message's limit of " + std::to_string(kMaxSemanticMapVoxels));
  }
  std::vector<std::uint8_t> records(message.voxels.size() * kRecordBytes);
  for (std::size_t n = 0; n < message.voxels.size(); ++n) {
    const SemanticMapVoxel& v = message.voxels[n];
    std::uint8_t* r = records.data() + n * kRecordBytes;
    putInt16(r, v.i);
    putInt16(r + 2, v.j);
    putInt16(r + 4, v.k);
    r[6] = v.label;
    r[7] = v.confidence;
  }
  findmug_lcm::semantic_map_t msg;
  msg.utime = static_cast<std::int64_t>(message.utime);
  msg.seq = message.seq;
  msg.frames = message.frames;
  msg.voxel_size_m = message.voxel_size_m;
  msg.num_voxels = static_cast<std::int32_t>(message.voxels.size());
  if (compress) {
    msg.compression = findmug_lcm::semantic_map_t::COMPRESSION_ZLIB;
    msg.data = detail::zlibCompress(records.data(), records.size(), 6);
  } else {
    msg.compression = findmug_lcm::semantic_map_t::COMPRESSION_NONE;
    msg.data = std::move(records);
  }
  msg.data_size = static_cast<std::int32_t>(msg.data.size());
  return msg;
}

SemanticMapMessage decodeSemanticMap(const findmug_lcm::semantic_map_t& msg,
                                     std::string_view channel) {
  if (msg.data_size < 0 || static_cast<std::size_t>(msg.data_size) != msg.data.size()) {
    throw Error(field(channel, "data_size") + ": " + std::to_string(msg.data_size) +
                ", data holds " + std::to_string(msg.data.size()) + " bytes");
  }
  if (msg.utime < 0) {
    throw Error(field(channel, "utime") + ": negative time " + std::to_string(msg.utime));
  }
  if (msg.frames < 0) {
    throw Error(field(channel, "frames") + ": negative count " + std::to_string(msg.frames));
  }
  if (!std::isfinite(msg.voxel_size_m) || msg.voxel_size_m < 0.01f || msg.voxel_size_m > 1.0f) {
    throw Error(field(channel, "voxel_size_m") + ": " + std::to_string(msg.voxel_size_m) +
                " m (expected 0.01..1)");
  }
  if (msg.num_voxels < 0 || msg.num_voxels > kMaxSemanticMapVoxels) {
    throw Error(field(channel, "num_voxels") + ": " + std::to_string(msg.num_voxels) +
                " (expected 0.." + std::to_string(kMaxSemanticMapVoxels) + ")");
  }
  const std::size_t expected = static_cast<std::size_t>(msg.num_voxels) * kRecordBytes;
  std::vector<std::uint8_t> records;
  switch (msg.compression) {
    case findmug_lcm::semantic_map_t::COMPRESSION_NONE:
      if (msg.data.size() != expected) {
        throw Error(field(channel, "data") + ": " + std::to_string(msg.data.size()) +
                    " bytes, expected " + std::to_string(expected) + " for " +
                    std::to_string(msg.num_voxels) + " voxels");
      }
      records = msg.data;
      break;
    case findmug_lcm::semantic_map_t::COMPRESSION_ZLIB:
      records = detail::zlibDecompress(msg.data.data(), msg.data.size(), expected,
                                       field(channel, "data"));
      break;
    default:
      throw Error(field(channel, "compression") + ": unknown compression id " +
                  std::to_string(msg.compression) + " (expected 0 none or 1 zlib)");
  }
  SemanticMapMessage out;
  out.utime = static_cast<std::uint64_t>(msg.utime);
  out.seq = msg.seq;
  out.frames = msg.frames;
  out.voxel_size_m = msg.voxel_size_m;
  out.voxels.resize(static_cast<std::size_t>(msg.num_voxels));
  for (std::size_t n = 0; n < out.voxels.size(); ++n) {
    const std::uint8_t* r = records.data() + n * kRecordBytes;
    SemanticMapVoxel& v = out.voxels[n];
    v.i = getInt16(r);
    v.j = getInt16(r + 2);
    v.k = getInt16(r + 4);
    v.label = r[6];
    v.confidence = r[7];
    if (v.label >= kNumLabels) {
      throw Error(field(channel, "data") + ": voxel " + std::to_string(n) + " has label id " +
                  std::to_string(v.label) + " (expected 0.." + std::to_string(kNumLabels - 1) +
                  ")");
    }
    if (n > 0 && !(order(out.voxels[n - 1]) < order(v))) {
      throw Error(field(channel, "data") + ": voxel " + std::to_string(n) +
                  " out of order or repeated (voxels must ascend by i, j, k)");
    }
  }
  return out;
}

SemanticMapMessage decodeSemanticMap(const void* data, std::size_t size, std::string_view channel) {
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  walk(bytes, size, channel);
  findmug_lcm::semantic_map_t msg;
  if (msg.decode(bytes, 0, static_cast<int>(size)) != static_cast<int>(size)) {
    throw Error(std::string(channel) + ": semantic_map_t: LCM decode failed (" +
                std::to_string(size) + " bytes)");
  }
  return decodeSemanticMap(msg, channel);
}

}  // namespace findmug::io
