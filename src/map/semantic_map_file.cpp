// semantic_map_file.cpp — the semantic map as bytes and as a file, and back, checked field by
// field (see semantic_map.hpp for the format).
#include <zlib.h>

#include <bit>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>

#include "findmug/common/error.hpp"
#include "findmug/map/semantic_map.hpp"
#include "semantic_map_internal.hpp"

namespace findmug {

using namespace semantic_map_detail;

namespace {

static_assert(std::endian::native == std::endian::little,
              "the semantic map file is written in the host's (little-endian) byte order");

constexpr char kMagic[16] = {'F', 'I', 'N', 'D', 'M', 'U', 'G',  '-',
                             'S', 'E', 'M', 'M', 'A', 'P', '\0', '\n'};

// ---- binary writing and reading ----------------------------------------------------------

class Writer {
 public:
  template <class T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const std::uint8_t*>(&value);
    bytes.insert(bytes.end(), p, p + sizeof(T));
  }
  std::vector<std::uint8_t> bytes;
};

class Reader {
 public:
  Reader(const std::vector<std::uint8_t>& bytes, std::size_t end, std::string path)
      : bytes_(bytes), end_(end), path_(std::move(path)) {}

  template <class T>
  T get(const char* what) {
    static_assert(std::is_trivially_copyable_v<T>);
    if (end_ - pos_ < sizeof(T)) fail(std::string("truncated while reading ") + what);
    T value;
    std::memcpy(&value, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }
  // A count of items of `item_bytes` each: refused when the bytes left cannot hold them.
  std::uint64_t count(std::uint64_t n, std::size_t item_bytes, const char* what) {
    if (n > (end_ - pos_) / item_bytes) {
      fail(std::string("claims ") + std::to_string(n) + " " + what + " but only " +
           std::to_string(end_ - pos_) + " bytes follow");
    }
    return n;
  }
  bool atEnd() const { return pos_ == end_; }
  [[noreturn]] void fail(const std::string& problem) const {
    throw Error("semantic map " + path_ + ": " + problem);
  }

 private:
  const std::vector<std::uint8_t>& bytes_;
  std::size_t end_;
  std::size_t pos_ = 0;
  std::string path_;
};

}  // namespace

// ---- save and load ----------------------------------------------------------------------------

std::vector<std::uint8_t> SemanticMap::toBytes() const {
  Writer w;
  for (char c : kMagic) w.put(c);
  w.put(kFileVersion);
  w.put(map_config_.voxel_size_m);
  w.put(frame_number_);
  w.put(last_utime_);
  w.put(dropped_total_);
  w.put(carved_total_);
  w.put(static_cast<std::int32_t>(next_table_id_));
  // Voxels by key, so that one map always gives the same bytes.
  std::vector<std::uint64_t> keys;
  keys.reserve(voxels_.size());
  for (const auto& entry : voxels_) keys.push_back(entry.first);
  std::sort(keys.begin(), keys.end());
  w.put(static_cast<std::uint64_t>(keys.size()));
  for (std::uint64_t key : keys) {
    const Voxel& v = voxels_.at(key);
    w.put(key);
    for (std::uint16_t votes : v.votes) w.put(votes);
    w.put(v.occupancy);
    w.put(v.frames);
    w.put(v.last_hit);
  }
  w.put(static_cast<std::uint32_t>(previous_tables_.size()));
  for (const MappedId& t : previous_tables_) {
    w.put(static_cast<std::int32_t>(t.id));
    w.put(static_cast<std::uint32_t>(t.hull.size()));
    for (const auto& p : t.hull) {
      w.put(p.x());
      w.put(p.y());
    }
  }
  w.put(static_cast<std::uint32_t>(support_.size()));
  for (const SupportRecord& r : support_) {
    w.put(r.viewpoint);
    w.put(static_cast<std::uint32_t>(r.table_cells.size()));
    for (const auto& [cell, count] : r.table_cells) {
      w.put(cell);
      w.put(count);
    }
  }
  const auto crc =
      static_cast<std::uint32_t>(crc32(0L, w.bytes.data(), static_cast<uInt>(w.bytes.size())));
  w.put(crc);
  return std::move(w.bytes);
}

void SemanticMap::save(const std::string& path) const {
  const std::vector<std::uint8_t> bytes = toBytes();
  const std::string temporary = path + ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw Error("semantic map " + path + ": cannot open " + temporary + " for writing");
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
    out.flush();
    if (!out) {
      std::remove(temporary.c_str());
      throw Error("semantic map " + path + ": writing " + temporary + " failed");
    }
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) {
    std::remove(temporary.c_str());
    throw Error("semantic map " + path + ": cannot rename " + temporary + " into place");
  }
}

void SemanticMap::load(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("semantic map " + path + ": cannot open the file");
  std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                  std::istreambuf_iterator<char>());
  if (in.bad()) throw Error("semantic map " + path + ": read error");
  loadBytes(bytes, path);
}

void SemanticMap::loadBytes(const std::vector<std::uint8_t>& bytes, const std::string& name) {
  SemanticMap loaded(map_config_, table_config_);
  loaded.deserialise(bytes, name);
  *this = std::move(loaded);
}

void SemanticMap::deserialise(const std::vector<std::uint8_t>& bytes, const std::string& path) {
  const std::size_t header = sizeof(kMagic) + sizeof(std::uint32_t);
  Reader magic_reader(bytes, bytes.size(), path);
  if (bytes.size() < sizeof(kMagic) || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) {
    magic_reader.fail("not a findmug semantic map (bad magic)");
  }
  if (bytes.size() < header) magic_reader.fail("truncated while reading the version");
  std::uint32_t version = 0;
  std::memcpy(&version, bytes.data() + sizeof(kMagic), sizeof(version));
  if (version != kFileVersion) {
    magic_reader.fail("file version " + std::to_string(version) + ", this build reads version " +
                      std::to_string(kFileVersion));
  }
  if (bytes.size() < header + sizeof(std::uint32_t)) magic_reader.fail("truncated (no checksum)");
  const std::size_t body = bytes.size() - sizeof(std::uint32_t);
  std::uint32_t stored_crc = 0;
  std::memcpy(&stored_crc, bytes.data() + body, sizeof(stored_crc));
  const auto crc = static_cast<std::uint32_t>(crc32(0L, bytes.data(), static_cast<uInt>(body)));
  if (crc != stored_crc) {
    magic_reader.fail("checksum mismatch (the file is truncated or corrupt)");
  }

  Reader r(bytes, body, path);
  for (std::size_t i = 0; i < sizeof(kMagic); ++i) r.get<char>("the magic");
  r.get<std::uint32_t>("the version");
  const auto voxel_size = r.get<float>("the voxel size");
  if (voxel_size != map_config_.voxel_size_m) {
    r.fail("made with semantic_map.voxel_size_m = " + fmt(voxel_size) + ", the setting is " +
           fmt(map_config_.voxel_size_m));
  }
  frame_number_ = r.get<std::uint32_t>("the frame count");
  last_utime_ = r.get<std::uint64_t>("the last time");
  dropped_total_ = r.get<std::uint64_t>("the dropped count");
  carved_total_ = r.get<std::uint64_t>("the carved count");
  next_table_id_ = r.get<std::int32_t>("the next table id");
  if (next_table_id_ < 1) r.fail("next table id " + std::to_string(next_table_id_) + " below 1");

  const auto max_occupancy = static_cast<int>(std::lround(map_config_.max_logodds * kLogOddsScale));
  const std::uint64_t n_voxels = r.count(r.get<std::uint64_t>("the voxel count"), 32, "voxels");
  if (n_voxels > static_cast<std::uint64_t>(map_config_.max_voxels)) {
    r.fail(std::to_string(n_voxels) + " voxels, above semantic_map.max_voxels (" +
           std::to_string(map_config_.max_voxels) + ")");
  }
  voxels_.reserve(n_voxels);
  std::uint64_t previous_key = 0;
  for (std::uint64_t i = 0; i < n_voxels; ++i) {
    const auto key = r.get<std::uint64_t>("a voxel key");
    if (i > 0 && key <= previous_key) r.fail("voxel " + std::to_string(i) + ": keys not ascending");
    previous_key = key;
    Voxel v;
    for (auto& votes : v.votes) votes = r.get<std::uint16_t>("a voxel's votes");
    v.occupancy = r.get<std::int16_t>("a voxel's occupancy");
    v.frames = r.get<std::uint16_t>("a voxel's frame count");
    v.last_hit = r.get<std::uint32_t>("a voxel's last hit");
    if (unpackIndices(key).cast<double>().abs().maxCoeff() * voxel_size >
        kMaxPoseDistanceM + 100.0) {
      r.fail("voxel " + std::to_string(i) + ": more than 10 km from the map's origin");
    }
    if (v.occupancy <= 0 || v.occupancy > max_occupancy) {
      r.fail("voxel " + std::to_string(i) + ": occupancy " + std::to_string(v.occupancy) +
             " outside (0, " + std::to_string(max_occupancy) + "]");
    }
    if (v.last_hit > frame_number_ || v.frames == 0) {
      r.fail("voxel " + std::to_string(i) + ": frame numbers inconsistent with the map's " +
             std::to_string(frame_number_) + " frames");
    }
    voxels_.emplace(key, v);
  }

  const std::uint32_t n_tables =
      static_cast<std::uint32_t>(r.count(r.get<std::uint32_t>("the table count"), 8, "tables"));
  for (std::uint32_t i = 0; i < n_tables; ++i) {
    MappedId t;
    t.id = r.get<std::int32_t>("a table id");
    if (t.id < 1 || t.id >= next_table_id_) {
      r.fail("table id " + std::to_string(t.id) + " outside [1, " + std::to_string(next_table_id_) +
             ")");
    }
    const auto n_hull = r.count(r.get<std::uint32_t>("a hull size"), 8, "hull points");
    for (std::uint64_t k = 0; k < n_hull; ++k) {
      const float x = r.get<float>("a hull point");
      const float y = r.get<float>("a hull point");
      if (!std::isfinite(x) || !std::isfinite(y))
        r.fail("table " + std::to_string(t.id) + ": hull point not finite");
      t.hull.emplace_back(x, y);
    }
    previous_tables_.push_back(std::move(t));
  }

  const auto n_records = r.count(r.get<std::uint32_t>("the support count"), 12, "support records");
  for (std::uint64_t i = 0; i < n_records; ++i) {
    SupportRecord record;
    record.viewpoint = r.get<std::uint64_t>("a viewpoint");
    const auto n_cells = r.count(r.get<std::uint32_t>("a cell count"), 12, "table cells");
    record.table_cells.reserve(n_cells);
    for (std::uint64_t k = 0; k < n_cells; ++k) {
      const auto cell = r.get<std::uint64_t>("a table cell");
      const auto count = r.get<std::uint32_t>("a table cell's count");
      if (!record.table_cells.empty() && cell <= record.table_cells.back().first) {
        r.fail("support record " + std::to_string(i) + ": cells not ascending");
      }
      record.table_cells.emplace_back(cell, count);
    }
    support_.push_back(std::move(record));
  }
  while (static_cast<int>(support_.size()) > map_config_.support_frames) support_.pop_front();
  if (!r.atEnd()) r.fail("unexpected bytes after the support records");
}

}  // namespace findmug
