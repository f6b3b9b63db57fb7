#include "findmug/io/channels.hpp"

#include <cctype>

#include "findmug/common/error.hpp"

namespace findmug::io {

void checkChannelSuffix(std::string_view suffix) {
  if (suffix.empty()) return;
  bool ok = suffix.front() != '_';
  for (char c : suffix) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) ok = false;
  }
  if (!ok) {
    throw Error("channel suffix '" + std::string(suffix) +
                "': only letters, digits and '_' allowed, not starting with '_'");
  }
}

std::string channelName(std::string_view base, std::string_view suffix) {
  if (suffix.empty()) return std::string(base);
  checkChannelSuffix(suffix);
  return std::string(base) + "_" + std::string(suffix);
}

}  // namespace findmug::io
