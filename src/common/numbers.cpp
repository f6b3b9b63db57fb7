#include "findmug/common/numbers.hpp"

#include <charconv>
#include <cmath>
#include <system_error>

namespace findmug {

namespace {

// std::from_chars already refuses '+', spaces and hex prefixes in the default
// (decimal / general) formats; what is left to check is that all of the text
// was used and that the value is in range.
template <typename T>
std::optional<T> parseWhole(std::string_view text) {
  if (text.empty()) return std::nullopt;
  T value{};
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end) return std::nullopt;
  return value;
}

}  // namespace

std::optional<double> parseNumber(std::string_view text) {
  // from_chars accepts "nan", "inf" and "infinity" (any case); none is a number here.
  const auto value = parseWhole<double>(text);
  if (!value || !std::isfinite(*value)) return std::nullopt;
  return value;
}

std::optional<long long> parseInteger(std::string_view text) { return parseWhole<long long>(text); }

std::optional<unsigned long long> parseUnsigned(std::string_view text) {
  return parseWhole<unsigned long long>(text);
}

}  // namespace findmug
