// src/common/csv_rows.hpp — the rows of a small comma-separated file with a header: label
// mappings, per-frame extrinsics and gravity, the NYU-894 -> 40 table. One reader, so that
// every such file skips the same comments, trims the same way and names the same place
// (FILE:LINE) in its errors.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace findmug::detail {

struct CsvRow {
  std::string where;                // "SOURCE:LINE", for the caller's own checks
  std::vector<std::string> fields;  // trimmed of spaces, tabs and CR
};

// The data rows of `text` (`source` names it in errors). Blank lines and lines starting
// with '#' are skipped. The first other line must be the header `header` (column names
// joined by commas; a column spelled `*` takes any name); every row after it must have
// as many fields as the header. Throws findmug::Error "SOURCE:LINE: expected header 'H',
// found 'X'", "SOURCE:LINE: expected N fields, found M" or "SOURCE: empty (expected
// header 'H')".
std::vector<CsvRow> readCsvRows(std::string_view text, const std::string& source,
                                const std::string& header);

// Fields of one line split at commas, each trimmed.
std::vector<std::string> splitCsvFields(std::string_view line);

}  // namespace findmug::detail
