// command_t (FINDMUG_COMMAND): encodeCommand / decodeCommand round trip, and
// every field rule the daemon relies on refused with an error naming the field.
#include <gtest/gtest.h>

#include <string>

#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/objects/object_model.hpp"

namespace findmug::io {
namespace {

std::vector<std::uint8_t> raw(std::int64_t utime, std::int64_t id, const std::string& command,
                              const std::string& argument) {
  findmug_lcm::command_t m;
  m.utime = utime;
  m.request_id = id;
  m.command = command;
  m.argument = argument;
  return encodeMessage(m);
}

// Decoding `bytes` throws findmug::Error whose message holds `what`.
void expectRefused(const std::vector<std::uint8_t>& bytes, const std::string& what) {
  try {
    (void)decodeCommand(bytes.data(), bytes.size(), "FINDMUG_COMMAND");
    ADD_FAILURE() << "accepted; expected an error naming " << what;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("FINDMUG_COMMAND"), std::string::npos) << e.what();
  }
}

TEST(CommandCodec, RoundTrip) {
  const CommandMessage sent{123456, 42, "reload_model", ""};
  const auto bytes = encodeMessage(encodeCommand(sent));
  const CommandMessage got = decodeCommand(bytes.data(), bytes.size(), "C");
  EXPECT_EQ(got.utime, sent.utime);
  EXPECT_EQ(got.request_id, 42);
  EXPECT_EQ(got.command, "reload_model");
  EXPECT_EQ(got.argument, "");
  const CommandMessage with_argument{1, 0, "save_frame", "kitchen frame, 2 mugs"};
  const auto b2 = encodeMessage(encodeCommand(with_argument));
  EXPECT_EQ(decodeCommand(b2.data(), b2.size(), "C").argument, "kitchen frame, 2 mugs");
}

TEST(CommandCodec, EveryFieldRuleIsEnforced) {
  expectRefused(raw(-1, 0, "reload_model", ""), "command_t.utime");
  expectRefused(raw(0, -5, "reload_model", ""), "command_t.request_id");
  expectRefused(raw(0, 0, "", ""), "command_t.command");
  expectRefused(raw(0, 0, std::string(kMaxCommandName + 1, 'a'), ""), "command_t.command");
  expectRefused(raw(0, 0, "Reload", ""), "command_t.command");
  expectRefused(raw(0, 0, "reload model", ""), "command_t.command");
  // (lcm-gen writes a string up to its first NUL: the rest trails the message.)
  expectRefused(raw(0, 0, std::string("reload\0x", 8), ""), "command_t");
  expectRefused(raw(0, 0, "reload_model", std::string(kMaxCommandArgument + 1, 'x')),
                "command_t.argument");
  expectRefused(raw(0, 0, "reload_model", "a\nb"), "command_t.argument");
  expectRefused(raw(0, 0, "reload_model", "a\x7f"), "command_t.argument");
  // The longest allowed values pass.
  const auto longest = raw(0, 0, std::string(kMaxCommandName, 'z'),
                           std::string(kMaxCommandArgument, 'x'));
  EXPECT_NO_THROW((void)decodeCommand(longest.data(), longest.size(), "C"));
  // The encoder refuses what the decoder would.
  EXPECT_THROW((void)encodeCommand(CommandMessage{0, 0, "BAD", ""}), Error);
}

TEST(CommandCodec, TeachTakesANameAFrameSeqAndACandidateIndex) {
  const auto good = raw(1, 2, "teach", "my-mug_2 41 3");
  const CommandMessage got = decodeCommand(good.data(), good.size(), "C");
  const TeachRequest request = parseTeachArgument(got.argument);
  EXPECT_EQ(request.name, "my-mug_2");
  EXPECT_EQ(request.seq, 41);
  EXPECT_EQ(request.index, 3);
  EXPECT_EQ(teachArgument(request), "my-mug_2 41 3");
  // Each malformed argument is refused on decoding, naming what is wrong.
  expectRefused(raw(0, 0, "teach", ""), "three words");
  expectRefused(raw(0, 0, "teach", "mug 41"), "three words");
  expectRefused(raw(0, 0, "teach", "mug 41 2 7"), "three words");
  expectRefused(raw(0, 0, "teach", "mug  41 2"), "three words");
  expectRefused(raw(0, 0, "teach", "Mug 41 2"), "teach NAME");
  expectRefused(raw(0, 0, "teach", std::string(kMaxObjectNameLength + 1, 'm') + " 41 2"),
                "teach NAME");
  expectRefused(raw(0, 0, "teach", "../mug 41 2"), "teach NAME");
  expectRefused(raw(0, 0, "teach", "mug -1 2"), "teach SEQ");
  expectRefused(raw(0, 0, "teach", "mug 041 2"), "teach SEQ");
  expectRefused(raw(0, 0, "teach", "mug 1234567890123456789 2"), "teach SEQ");
  expectRefused(raw(0, 0, "teach", "mug 41 x"), "teach INDEX");
  expectRefused(raw(0, 0, "teach", "mug 41 10000"), "teach INDEX");
  expectRefused(raw(0, 0, "teach", "mug 41 2 "), "three words");
  // The largest values pass; the encoder refuses what the decoder would.
  const auto largest = raw(0, 0, "teach", "mug 999999999999999999 9999");
  EXPECT_NO_THROW((void)decodeCommand(largest.data(), largest.size(), "C"));
  EXPECT_THROW((void)encodeCommand(CommandMessage{0, 0, "teach", "mug"}), Error);
  // Other commands' arguments are not read as teach's.
  const auto other = raw(0, 0, "save_frame", "mug");
  EXPECT_NO_THROW((void)decodeCommand(other.data(), other.size(), "C"));
}

TEST(CommandCodec, OtherTypesAndTruncationAreRefused) {
  const auto pose = encodeMessage(encodeRobotPose(RobotPose{1, {2, 3, 0.5}}));
  expectRefused(pose, "command_t");
  const auto good = raw(1, 2, "reload_model", "");
  for (std::size_t n = 0; n < good.size(); ++n) {
    EXPECT_THROW((void)decodeCommand(good.data(), n, "C"), Error) << n << " bytes";
  }
}

}  // namespace
}  // namespace findmug::io
