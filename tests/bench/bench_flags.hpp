// bench_flags.hpp — the benchmark programs' count flags (--repeat N, FINDMUG_BENCH_FRAMES),
// read with the core's strict number parser.
#pragma once

#include <string>

#include "findmug/error.hpp"
#include "findmug/numbers.hpp"

namespace findmug::bench {

// A whole number >= 1; anything else ("", "3x", "0", "nan") is an error naming the flag.
inline int positiveCount(const char* flag, const char* text) {
  const auto n = parseInteger(text);
  if (!n || *n < 1 || *n > 1000000) {
    throw Error(std::string(flag) + ": expected a whole number >= 1, got '" + text + "'");
  }
  return static_cast<int>(*n);
}

}  // namespace findmug::bench
