// findmug-web's settings; see web_config.hpp.
#include "web_config.hpp"

#include <sys/stat.h>

#include <cstdio>
#include <fstream>

#include "findmug/common/error.hpp"

namespace findmug::web {

bool isDefaultLoopback(const std::string& address) {
  return address == "127.0.0.1" || address == "::1" || address == "localhost";
}

bool isLoopbackAddress(const std::string& address) {
  return address.rfind("127.", 0) == 0 || address == "::1" ||
         address.rfind("::ffff:127.", 0) == 0;
}

std::string readTokenFile(const std::filesystem::path& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw Error(path.string() + ": cannot read the token file");
  if ((st.st_mode & (S_IRWXG | S_IRWXO)) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof(mode), "%03o", static_cast<unsigned>(st.st_mode & 0777));
    throw Error(path.string() + ": the token file must be readable by its owner only (mode " +
                mode + ")");
  }
  std::ifstream in(path);
  std::string token;
  if (!in || !std::getline(in, token)) throw Error(path.string() + ": cannot read the token file");
  const auto first = token.find_first_not_of(" \t\r");
  const auto last = token.find_last_not_of(" \t\r");
  token = first == std::string::npos ? "" : token.substr(first, last - first + 1);
  if (token.size() < 16) {
    throw Error(path.string() + ": the token is " + std::to_string(token.size()) +
                " characters long, at least 16 are needed");
  }
  for (char c : token) {
    if (c <= ' ' || c > '~') throw Error(path.string() + ": the token holds a blank or control character");
  }
  return token;
}

}  // namespace findmug::web
