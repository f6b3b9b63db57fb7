// bench_support.hpp — what the benchmark programs with their own main() share: count
// flags (--repeat N, FINDMUG_BENCH_FRAMES) read with the core's strict number parser,
// the median of a series, and the main() that turns an exception into
// "NAME: error: ..." and exit code 1.
#pragma once

#include <algorithm>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/common/numbers.hpp"

namespace findmug::bench {

// A whole number >= 1; anything else ("", "3x", "0", "nan") is an error naming the flag.
inline int positiveCount(const char* flag, const char* text) {
  const auto n = parseInteger(text);
  if (!n || *n < 1 || *n > 1000000) {
    throw Error(std::string(flag) + ": expected a whole number >= 1, got '" + text + "'");
  }
  return static_cast<int>(*n);
}

// Median of the values (0 for none); the mean of the middle two for an even count.
inline double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The body of a benchmark's main(): run(argc, argv), or a message and 1 when it throws.
inline int benchMain(const char* name, int (*run)(int, char**), int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", name, e.what());
    return 1;
  }
}

}  // namespace findmug::bench
