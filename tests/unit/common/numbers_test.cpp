// The one strict number parser (findmug/common/numbers.hpp): what is a number and what is not.
#include "findmug/common/numbers.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace findmug {
namespace {

TEST(Numbers, AcceptsDecimalNumbers) {
  EXPECT_EQ(parseNumber("3"), 3.0);
  EXPECT_EQ(parseNumber("1.5"), 1.5);
  EXPECT_EQ(parseNumber("-2.25"), -2.25);
  EXPECT_EQ(parseNumber("2e-3"), 0.002);
  EXPECT_EQ(parseNumber("1E3"), 1000.0);
  EXPECT_EQ(parseNumber(".5"), 0.5);
  EXPECT_EQ(parseNumber("5."), 5.0);
  EXPECT_EQ(parseNumber("1.7976931348623157e308"), std::numeric_limits<double>::max());
}

TEST(Numbers, MinusZeroIsZeroWithItsSign) {
  const auto v = parseNumber("-0");
  ASSERT_TRUE(v);
  EXPECT_EQ(*v, 0.0);
  EXPECT_TRUE(std::signbit(*v));
  EXPECT_EQ(parseInteger("-0"), 0);
}

TEST(Numbers, RefusesNonFinite) {
  for (const char* text :
       {"nan", "NaN", "-nan", "nan(1)", "inf", "-inf", "INF", "infinity", "Infinity"}) {
    EXPECT_FALSE(parseNumber(text)) << text;
  }
}

TEST(Numbers, RefusesOutOfRange) {
  EXPECT_FALSE(parseNumber("1e999"));
  EXPECT_FALSE(parseNumber("-1e999"));
  EXPECT_FALSE(parseNumber("1e-999"));  // underflow: not silently 0
  EXPECT_FALSE(parseInteger("9223372036854775808"));
  EXPECT_FALSE(parseInteger("-9223372036854775809"));
  EXPECT_EQ(parseInteger("9223372036854775807"), std::numeric_limits<long long>::max());
  EXPECT_FALSE(parseUnsigned("18446744073709551616"));
  EXPECT_EQ(parseUnsigned("18446744073709551615"), std::numeric_limits<unsigned long long>::max());
}

TEST(Numbers, RefusesEmptyAndJunk) {
  for (const char* text : {"", " ", "12abc", "1.5x", "3 ", " 3", "\t3", "3\n", "1,5", "1.2.3",
                           "--1", "-", ".", "e5", "abc", "1e", "0x10", "0x1p3", "+3"}) {
    EXPECT_FALSE(parseNumber(text)) << "'" << text << "'";
    EXPECT_FALSE(parseInteger(text)) << "'" << text << "'";
    EXPECT_FALSE(parseUnsigned(text)) << "'" << text << "'";
  }
}

TEST(Numbers, IntegersRefuseFractionsAndExponents) {
  EXPECT_EQ(parseInteger("42"), 42);
  EXPECT_EQ(parseInteger("-7"), -7);
  EXPECT_EQ(parseInteger("007"), 7);
  EXPECT_FALSE(parseInteger("1.0"));
  EXPECT_FALSE(parseInteger("1e3"));
  EXPECT_FALSE(parseInteger("nan"));
}

TEST(Numbers, UnsignedRefusesAnySign) {
  EXPECT_EQ(parseUnsigned("0"), 0u);
  EXPECT_EQ(parseUnsigned("123"), 123u);
  EXPECT_FALSE(parseUnsigned("-1"));
  EXPECT_FALSE(parseUnsigned("-0"));
}

TEST(Numbers, ParsesOnlyTheViewNotWhatFollowsIt) {
  // A string_view into a longer text: the parser must stop at the view's end.
  const std::string text = "12345";
  EXPECT_EQ(parseInteger(std::string_view(text).substr(0, 2)), 12);
  EXPECT_EQ(parseNumber(std::string_view(text).substr(1, 3)), 234.0);
}

}  // namespace
}  // namespace findmug
