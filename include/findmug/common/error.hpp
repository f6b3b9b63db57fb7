// findmug/common/error.hpp — the one exception type the core library throws.
//
// Every message names what was wrong and where (file, field, value), so that
// a daemon log line or a tool's stderr is enough to find the bad input.
#pragma once

#include <stdexcept>
#include <string>

namespace findmug {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace findmug
