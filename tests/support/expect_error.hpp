// Test support: checking that a call refuses its input with findmug::Error.
//
// errorOf(f) runs f and returns the message of the findmug::Error it throws
// (and fails the test when it throws nothing), so a test can assert that the
// message names what was wrong; EXPECT_CONTAINS checks one part of it.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "findmug/common/error.hpp"

namespace findmug::test {

template <typename F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected findmug::Error";
  return {};
}

}  // namespace findmug::test

#define EXPECT_CONTAINS(haystack, needle) \
  EXPECT_NE(std::string(haystack).find(needle), std::string::npos) << (haystack)
