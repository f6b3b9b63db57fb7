// Test support: figures read back from findmug-eval's JSON report.
#pragma once

#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace findmug::test {

// Pixel counts per ground-truth class (the rows of the forest+MRF confusion
// matrix), in label order; fewer than 8 when the report is not whole.
inline std::vector<double> mrfClassTotals(const std::string& json) {
  const auto mrf_at = json.find("\"mrf\": {");
  if (mrf_at == std::string::npos) return {};
  const auto at = json.find("\"confusion\": [", mrf_at);
  if (at == std::string::npos) return {};
  std::vector<double> totals;
  const std::string rest = json.substr(at + 14);
  const std::regex row(R"(\[([0-9, ]+)\])");
  for (std::sregex_iterator it(rest.begin(), rest.end(), row), end; it != end && totals.size() < 8;
       ++it) {
    double sum = 0;
    std::stringstream cells((*it)[1].str());
    std::string cell;
    while (std::getline(cells, cell, ',')) sum += std::stod(cell);
    totals.push_back(sum);
  }
  return totals;
}

// The majority baseline of those totals: labelling every pixel with the commonest
// class gives global = largest / all and class average = 1 / (classes present).
struct MajorityBaseline {
  double global = 0, class_average = 0;
};
inline MajorityBaseline majorityBaseline(const std::vector<double>& totals) {
  double all = 0, largest = 0;
  int present = 0;
  for (double t : totals) {
    all += t;
    largest = t > largest ? t : largest;
    present += t > 0;
  }
  MajorityBaseline b;
  if (all > 0) b.global = largest / all;
  if (present > 0) b.class_average = 1.0 / present;
  return b;
}

}  // namespace findmug::test
