#include "common/csv_rows.hpp"

#include <cstddef>

#include "findmug/common/error.hpp"

namespace findmug::detail {
namespace {

std::string_view trimmed(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t\r\n");
  return s.substr(first, last - first + 1);
}

bool headerMatches(const std::vector<std::string>& found,
                   const std::vector<std::string>& expected) {
  if (found.size() != expected.size()) return false;
  for (std::size_t i = 0; i < found.size(); ++i) {
    if (expected[i] != "*" && found[i] != expected[i]) return false;
  }
  return true;
}

}  // namespace

std::vector<std::string> splitCsvFields(std::string_view line) {
  std::vector<std::string> fields;
  std::size_t start = 0;
  while (true) {
    const auto comma = line.find(',', start);
    fields.emplace_back(trimmed(line.substr(start, comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return fields;
}

std::vector<CsvRow> readCsvRows(std::string_view text, const std::string& source,
                                const std::string& header) {
  const std::vector<std::string> columns = splitCsvFields(header);
  std::vector<CsvRow> rows;
  bool header_seen = false;
  int line_number = 0;
  std::size_t start = 0;
  while (start < text.size()) {
    const auto end = text.find('\n', start);
    const std::string_view line =
        trimmed(text.substr(start, end == std::string_view::npos ? end : end - start));
    start = end == std::string_view::npos ? text.size() : end + 1;
    ++line_number;
    if (line.empty() || line[0] == '#') continue;
    CsvRow row{source + ":" + std::to_string(line_number), splitCsvFields(line)};
    if (!header_seen) {
      if (!headerMatches(row.fields, columns)) {
        throw Error(row.where + ": expected header '" + header + "', found '" + std::string(line) +
                    "'");
      }
      header_seen = true;
      continue;
    }
    if (row.fields.size() != columns.size()) {
      throw Error(row.where + ": expected " + std::to_string(columns.size()) + " fields, found " +
                  std::to_string(row.fields.size()));
    }
    rows.push_back(std::move(row));
  }
  if (!header_seen) throw Error(source + ": empty (expected header '" + header + "')");
  return rows;
}

}  // namespace findmug::detail
