// command_t <-> CommandMessage and the teach argument (findmug/io/lcm_codec.hpp).
#include <optional>
#include <string>

#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/objects/object_model.hpp"
#include "lcm_codec_checks.hpp"

namespace findmug::io {

using detail::checkArraySize;
using detail::checkDimensions;
using detail::checkFinite;
using detail::field;
using detail::finite;

namespace {

void checkCommand(const CommandMessage& c, std::string_view channel) {
  const auto where = [&](std::string_view name) { return field(channel, "command_t", name); };
  if (c.request_id < 0) {
    throw Error(where("request_id") + ": negative id " + std::to_string(c.request_id));
  }
  if (c.command.empty() || c.command.size() > kMaxCommandName) {
    throw Error(where("command") + ": " + std::to_string(c.command.size()) +
                " characters, expected 1.." + std::to_string(kMaxCommandName));
  }
  for (const char ch : c.command) {
    if (!((ch >= 'a' && ch <= 'z') || ch == '_')) {
      throw Error(where("command") + ": character " +
                  std::to_string(static_cast<unsigned char>(ch)) + " is not one of [a-z_]");
    }
  }
  if (c.argument.size() > kMaxCommandArgument) {
    throw Error(where("argument") + ": " + std::to_string(c.argument.size()) +
                " characters, at most " + std::to_string(kMaxCommandArgument));
  }
  for (const char ch : c.argument) {
    const auto u = static_cast<unsigned char>(ch);
    if (u < 0x20 || u == 0x7f) {
      throw Error(where("argument") + ": control character " + std::to_string(u));
    }
  }
  if (c.command == "teach") (void)parseTeachArgument(c.argument, where("argument"));
}

// A decimal number of at most `max_digits` digits, no sign, no leading zero but "0".
std::optional<std::int64_t> plainNumber(std::string_view text, std::size_t max_digits) {
  if (text.empty() || text.size() > max_digits) return std::nullopt;
  if (text.size() > 1 && text[0] == '0') return std::nullopt;
  std::int64_t v = 0;
  for (const char ch : text) {
    if (ch < '0' || ch > '9') return std::nullopt;
    v = v * 10 + (ch - '0');
  }
  return v;
}

}  // namespace

TeachRequest parseTeachArgument(const std::string& argument, std::string_view where) {
  std::string quoted(1, '\'');
  quoted.append(argument, 0, 80);
  quoted.push_back('\'');
  const auto first = argument.find(' ');
  const auto second = first == std::string::npos ? first : argument.find(' ', first + 1);
  if (second == std::string::npos || argument.find(' ', second + 1) != std::string::npos) {
    throw Error(std::string(where) + ": teach takes \"NAME SEQ INDEX\" (three words, one space " +
                "apart), got " + quoted);
  }
  TeachRequest out;
  out.name = argument.substr(0, first);
  try {
    validateObjectModelName(out.name);
  } catch (const Error& e) {
    throw Error(std::string(where) + ": teach NAME: " + e.what());
  }
  const std::string_view text(argument);
  const auto seq = plainNumber(text.substr(first + 1, second - first - 1), 18);
  if (!seq) {
    throw Error(std::string(where) + ": teach SEQ: not a frame number (0..10^18) in " + quoted);
  }
  const auto index = plainNumber(text.substr(second + 1), 4);
  if (!index || *index > kMaxTeachIndex) {
    throw Error(std::string(where) + ": teach INDEX: not a candidate index (0.." +
                std::to_string(kMaxTeachIndex) + ") in " + quoted);
  }
  out.seq = *seq;
  out.index = static_cast<int>(*index);
  return out;
}

std::string teachArgument(const TeachRequest& request) {
  return request.name + " " + std::to_string(request.seq) + " " + std::to_string(request.index);
}

findmug_lcm::command_t encodeCommand(const CommandMessage& command) {
  checkCommand(command, "encodeCommand");
  findmug_lcm::command_t msg;
  msg.utime = static_cast<std::int64_t>(command.utime);
  msg.request_id = command.request_id;
  msg.command = command.command;
  msg.argument = command.argument;
  return msg;
}

CommandMessage decodeCommand(const void* data, std::size_t size, std::string_view channel) {
  const findmug_lcm::command_t msg = decodeMessage<findmug_lcm::command_t>(data, size, channel);
  if (msg.utime < 0) {
    throw Error(field(channel, "command_t", "utime") + ": negative time " +
                std::to_string(msg.utime));
  }
  CommandMessage out{static_cast<std::uint64_t>(msg.utime), msg.request_id, msg.command,
                     msg.argument};
  checkCommand(out, channel);
  return out;
}

}  // namespace findmug::io
