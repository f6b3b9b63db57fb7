// findmug/io/lcm_codec.hpp — findmug types <-> LCM messages (lcmtypes/*.lcm).
//
// Encoding compresses: depth with zlib, colour as JPEG or PNG (or raw), labels
// and confidence with zlib. Decoding trusts nothing: every message comes from
// the network or a log file, so the decoders check the wire layout before LCM
// allocates anything (a corrupt size field could otherwise ask for gigabytes),
// then dimensions, size fields against array lengths, compression ids, the
// decompressed sizes and the payload values. Any problem throws findmug::Error
// whose message names the channel and the field, e.g.
//   "FINDMUG_RGBD: rgbd_frame_t.depth_data: zlib stream inflates to 614399 bytes, expected 614400".
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "findmug/frame/frame.hpp"
#include "findmug/io/messages.hpp"
#include "findmug/labels/label_image.hpp"
#include "findmug/tables/tables.hpp"
#include "findmug_lcm/command_t.hpp"
#include "findmug_lcm/label_image_t.hpp"
#include "findmug_lcm/rgbd_frame_t.hpp"
#include "findmug_lcm/robot_pose_t.hpp"
#include "findmug_lcm/status_t.hpp"
#include "findmug_lcm/tables_t.hpp"

namespace findmug::io {

// ---- raw messages -------------------------------------------------------------

// Decodes an LCM message of type Msg from `size` bytes after checking, field by
// field, that every length fits in the buffer (and the type hash matches, and
// nothing trails the message). `channel` names the source in errors.
// Defined for rgbd_frame_t, label_image_t, tables_t, status_t, robot_pose_t, command_t
// (and objects_t, declared in lcm_codec_objects.hpp).
template <typename Msg>
Msg decodeMessage(const void* data, std::size_t size, std::string_view channel);
template <>
findmug_lcm::rgbd_frame_t decodeMessage<findmug_lcm::rgbd_frame_t>(const void*, std::size_t,
                                                                   std::string_view);
template <>
findmug_lcm::label_image_t decodeMessage<findmug_lcm::label_image_t>(const void*, std::size_t,
                                                                     std::string_view);
template <>
findmug_lcm::tables_t decodeMessage<findmug_lcm::tables_t>(const void*, std::size_t,
                                                           std::string_view);
template <>
findmug_lcm::status_t decodeMessage<findmug_lcm::status_t>(const void*, std::size_t,
                                                           std::string_view);
template <>
findmug_lcm::robot_pose_t decodeMessage<findmug_lcm::robot_pose_t>(const void*, std::size_t,
                                                                   std::string_view);

template <>
findmug_lcm::command_t decodeMessage<findmug_lcm::command_t>(const void*, std::size_t,
                                                             std::string_view);

template <typename Msg>
std::vector<std::uint8_t> encodeMessage(const Msg& message) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

// ---- RGB-D frames -------------------------------------------------------------

enum class DepthCompression : std::int8_t { None = 0, Zlib = 1 };
enum class ColorCompression : std::int8_t { None = 0, Jpeg = 1, Png = 2 };

struct RgbdEncodeOptions {
  DepthCompression depth = DepthCompression::Zlib;
  ColorCompression color = ColorCompression::Jpeg;
  int zlib_level = 1;     // 1 = fastest; depth compresses about 2-4x already there
  int jpeg_quality = 90;  // 1..100
};

// Parses "none"/"zlib" and "none"/"jpeg"/"png" (flags, config); throws on others.
DepthCompression parseDepthCompression(std::string_view name);
ColorCompression parseColorCompression(std::string_view name);

// Validates `frame` (validateFrame) and encodes it. Throws findmug::Error.
findmug_lcm::rgbd_frame_t encodeRgbdFrame(const RgbdFrame& frame,
                                          const RgbdEncodeOptions& options = {});
// Decodes and validates; the returned frame's `source` is "<channel>: <message source>".
RgbdFrame decodeRgbdFrame(const findmug_lcm::rgbd_frame_t& message, std::string_view channel);
RgbdFrame decodeRgbdFrame(const void* data, std::size_t size, std::string_view channel);
// The seq of an encoded rgbd_frame_t without decoding it: the fingerprint and
// the fixed-size head (utime, seq) only. nullopt when the bytes are too short
// or carry another type's fingerprint (decodeRgbdFrame then says what is wrong).
std::optional<std::int64_t> peekRgbdFrameSeq(const void* data, std::size_t size);

// ---- label images (LabelImageMessage: messages.hpp) ----------------------------

// Labels must be < kNumLabels or kVoidLabel; confidence (if given and
// `with_confidence`) in [0, 1], quantised to 0..255.
findmug_lcm::label_image_t encodeLabelImage(const LabelImageMessage& labels,
                                            bool with_confidence = true);
// The same from an image held elsewhere: the daemon encodes each frame's
// label image where it lies, rather than copying it (1.5 MB) into a message.
findmug_lcm::label_image_t encodeLabelImage(const LabelImage& image, std::uint64_t utime,
                                            std::int64_t seq, std::int64_t latency_us,
                                            bool with_confidence = true);
// Checks label names against kLabelNames and every label id.
LabelImageMessage decodeLabelImage(const findmug_lcm::label_image_t& message,
                                   std::string_view channel);
LabelImageMessage decodeLabelImage(const void* data, std::size_t size, std::string_view channel);
// The camera fields of a label image (label_image_t.has_camera): the frame's intrinsics
// and the camera-to-base transform the daemon used for it.
void setCameraView(findmug_lcm::label_image_t& message, const CameraIntrinsics& intrinsics,
                   const Eigen::Isometry3d& camera_to_base);
// The frame's colour image as a JPEG of `quality` (1..100) in the label image
// (COLOR_JPEG); `rgb` must be width x height of the message. Throws findmug::Error.
void setColorJpeg(findmug_lcm::label_image_t& message, const std::vector<Rgb8>& rgb, int quality);
// The colour image a decoded label image carries (empty when it has none), decoded in
// full; a corrupt JPEG or one of another size throws findmug::Error naming the channel.
std::vector<Rgb8> decodeLabelImageColor(const LabelImageMessage& message,
                                        std::string_view channel);

// ---- tables ---------------------------------------------------------------------
// (RobotPose, TablesMessage & co.: messages.hpp)

// Fills the map_ fields from `message.map_pose` when set (map_tables is
// ignored). Throws findmug::Error when map_info is neither empty nor one per
// table, or when a Map message breaks the rules decodeTables checks.
findmug_lcm::tables_t encodeTables(const TablesMessage& message);
// The same from the message's parts, the tables held elsewhere (the daemon
// encodes a frame's tables where they lie: copying them into a message
// copied every table's pixel list).
findmug_lcm::tables_t encodeTables(std::uint64_t utime, std::int64_t seq, TablesContent content,
                                   std::span<const TableCluster> tables,
                                   const std::optional<RobotPose>& map_pose,
                                   std::span<const TableMapInfo> map_info);
// Checks finiteness, counts, unit axes, the content id and the map entries
// (map_id >= 0, sightings >= 0, 0 <= viewpoints <= sightings, confirmed only with
// a map_id; a Map message needs has_map_pose and id == map_id > 0 for every
// table); fills map_tables when has_map_pose, and map_info always.
TablesMessage decodeTables(const findmug_lcm::tables_t& message, std::string_view channel);
TablesMessage decodeTables(const void* data, std::size_t size, std::string_view channel);

findmug_lcm::robot_pose_t encodeRobotPose(const RobotPose& pose);
RobotPose decodeRobotPose(const void* data, std::size_t size, std::string_view channel);

// ---- commands to the daemon (CommandMessage: messages.hpp) ----------------------

// The longest command name and argument a command_t may carry.
inline constexpr std::size_t kMaxCommandName = 32;
inline constexpr std::size_t kMaxCommandArgument = 1024;
// Checks the message as decodeCommand does; throws findmug::Error naming the field.
findmug_lcm::command_t encodeCommand(const CommandMessage& command);
// Refuses a negative utime or request_id, a command that is empty, longer than
// kMaxCommandName or not made of [a-z_], and an argument longer than
// kMaxCommandArgument or holding a control character. Whether the command is
// one the daemon knows is the daemon's business.
CommandMessage decodeCommand(const void* data, std::size_t size, std::string_view channel);

// The argument of the command "teach": "NAME SEQ INDEX", one space apart: the
// taught object's name ([a-z0-9_-]{1,32}, validateObjectModelName), the seq of
// the frame whose objects_t showed the candidate (>= 0) and the candidate's
// index in that message (0..kMaxTeachIndex). encodeCommand and decodeCommand
// refuse a teach command whose argument is not this.
struct TeachRequest {
  std::string name;
  std::int64_t seq = 0;
  int index = 0;
};
inline constexpr int kMaxTeachIndex = 9999;
// Throws findmug::Error naming `where` and what is wrong.
TeachRequest parseTeachArgument(const std::string& argument, std::string_view where = "teach");
std::string teachArgument(const TeachRequest& request);

}  // namespace findmug::io
