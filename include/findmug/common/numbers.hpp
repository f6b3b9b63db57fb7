// findmug/common/numbers.hpp — the one strict parser of numbers written as text.
//
// Every number findmug reads from text (config values, --set and flag values,
// source specs, CSV and XML fields) goes through these functions, so that
// "what is a number" is the same everywhere. A text is a number only if all of
// it is one:
//   * decimal only: optional '-', digits, optional fraction and exponent
//     ("1.5", "-0", "2e-3"); no leading '+', no hex ("0x10"), no spaces around;
//   * nothing after the number ("12abc", "3 ", "1,5" are refused);
//   * finite and representable: "nan", "inf", "1e999" (overflow) and "1e-999"
//     (underflow to zero) are refused, as is an integer outside its type;
//   * the empty text is refused.
// The functions return std::nullopt for a refused text instead of throwing, so
// that each caller can name its own file, field or flag in its error message.
#pragma once

#include <optional>
#include <string_view>

namespace findmug {

// A finite double, or nullopt.
std::optional<double> parseNumber(std::string_view text);

// A signed integer (no fraction, no exponent) that fits a long long, or nullopt.
std::optional<long long> parseInteger(std::string_view text);

// A non-negative integer (no sign) that fits an unsigned long long, or nullopt.
std::optional<unsigned long long> parseUnsigned(std::string_view text);

}  // namespace findmug
