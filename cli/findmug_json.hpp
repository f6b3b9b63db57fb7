// findmug_json.hpp — the one JSON writer of the findmug programs (findmug-eval's
// report, findmug-nav-client --json, findmug-replay-probe's report).
//
// The programs lay out their objects themselves (their field order and spacing
// are part of what scripts read); what must be the same everywhere is how a
// string and a number become JSON text:
//   * jsonString: quoted; '"' and '\' escaped, '\n' and '\t' as \n and \t, every
//     other byte below 0x20 as \u00XX; bytes from 0x80 pass through unchanged, so
//     UTF-8 text stays UTF-8 (it is not validated: findmug's strings are its own
//     names, paths and messages).
//   * jsonNumber: fixed-point with the given number of decimals; NaN and
//     infinities, which JSON cannot write, become null (a report with a
//     missing figure must still parse).
#pragma once

#include <string>
#include <string_view>

namespace findmug::cli {

std::string jsonString(std::string_view text);

std::string jsonNumber(double value, int decimals);

}  // namespace findmug::cli
