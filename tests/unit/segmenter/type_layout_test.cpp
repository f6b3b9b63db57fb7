// The core library lays out its types as its callers do (type_layout.hpp).
// Where the loader picks the x86-64-v3 copy of the core (this machine, if its
// CPU has AVX2), this compares that copy's layouts with the plain x86-64
// build's, which this test is compiled as. Built without
// EIGEN_MAX_ALIGN_BYTES=16, the copy gives GroundPlane 32-byte alignment, and
// this test fails.
#include <gtest/gtest.h>

#include "segmenter/type_layout.hpp"

namespace findmug {
namespace {

TEST(TypeLayout, LibraryAndCallerAgree) {
  const std::vector<detail::TypeLayout> library = detail::coreTypeLayouts();
  const std::vector<detail::TypeLayout> here = detail::typeLayoutsHere();
  ASSERT_EQ(library.size(), here.size());
  for (std::size_t i = 0; i < here.size(); ++i) {
    SCOPED_TRACE(here[i].name);
    EXPECT_STREQ(library[i].name, here[i].name);
    EXPECT_EQ(library[i].size, here[i].size);
    EXPECT_EQ(library[i].align, here[i].align);
    EXPECT_EQ(library[i].offset, here[i].offset);
  }
}

}  // namespace
}  // namespace findmug
