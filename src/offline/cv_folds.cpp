// Cross-validation folds, training subsets and the learning-curve trend (see cv_folds.hpp).
#include "findmug/offline/cv_folds.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numeric>
#include <random>
#include <sstream>

#include "findmug/common/error.hpp"
#include "findmug/common/numbers.hpp"

namespace findmug {

namespace {

std::vector<std::string> splitCsvLine(const std::string& line) {
  std::vector<std::string> fields;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, ',')) fields.push_back(field);
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

std::string trimmed(std::string s) {
  while (!s.empty() && (s.back() == '\r' || s.back() == ' ')) s.pop_back();
  std::size_t start = 0;
  while (start < s.size() && s[start] == ' ') ++start;
  return s.substr(start);
}

}  // namespace

std::map<std::string, FrameListing> parseFrameListing(const std::string& csv_text,
                                                      const std::string& source) {
  std::istringstream in(csv_text);
  std::string line;
  if (!std::getline(in, line)) throw Error(source + ": empty (expected a header with 'frame')");
  std::vector<std::string> header = splitCsvLine(line);
  for (auto& h : header) h = trimmed(h);
  int frame_col = -1, index_col = -1, scene_col = -1;
  for (std::size_t c = 0; c < header.size(); ++c) {
    if (header[c] == "frame") frame_col = static_cast<int>(c);
    if (header[c] == "nyu_index") index_col = static_cast<int>(c);
    if (header[c] == "scene") scene_col = static_cast<int>(c);
  }
  if (frame_col < 0) throw Error(source + ": line 1: header has no 'frame' column");
  std::map<std::string, FrameListing> out;
  int line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    if (trimmed(line).empty()) continue;
    const std::vector<std::string> fields = splitCsvLine(line);
    const std::string where = source + ": line " + std::to_string(line_no);
    if (fields.size() != header.size()) {
      throw Error(where + ": " + std::to_string(fields.size()) + " fields, header has " +
                  std::to_string(header.size()));
    }
    const std::string name = trimmed(fields[static_cast<std::size_t>(frame_col)]);
    if (name.empty()) throw Error(where + ": empty frame name");
    FrameListing listing;
    if (index_col >= 0) {
      const std::string text = trimmed(fields[static_cast<std::size_t>(index_col)]);
      const auto index = parseInteger(text);
      if (!index || *index < 1) throw Error(where + ": nyu_index '" + text + "' is not >= 1");
      listing.nyu_index = static_cast<long>(*index);
    }
    if (scene_col >= 0) {
      listing.scene = trimmed(fields[static_cast<std::size_t>(scene_col)]);
      if (listing.scene.empty()) throw Error(where + ": empty scene for frame " + name);
    }
    if (!out.emplace(name, listing).second) throw Error(where + ": frame " + name + " listed twice");
  }
  return out;
}

std::map<std::string, FrameListing> loadFrameListing(const std::string& dir) {
  const std::filesystem::path path = std::filesystem::path(dir) / "frames.csv";
  if (!std::filesystem::exists(path)) return {};
  std::ifstream in(path);
  if (!in) throw Error(path.string() + ": cannot read");
  std::ostringstream text;
  text << in.rdbuf();
  return parseFrameListing(text.str(), path.string());
}

std::vector<std::string> nyuIndexRunScenes(const std::vector<long>& nyu_indices, int gap) {
  if (gap < 0) throw Error("scene gap " + std::to_string(gap) + ": must be >= 0");
  std::vector<std::size_t> order(nyu_indices.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return nyu_indices[a] < nyu_indices[b]; });
  std::vector<std::string> scenes(nyu_indices.size());
  long run_start = 0, previous = 0;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const long index = nyu_indices[order[k]];
    if (k == 0 || index - previous > gap) run_start = index;
    previous = index;
    scenes[order[k]] = "nyu" + std::to_string(run_start);
  }
  return scenes;
}

std::vector<long> parseNyuTestIndices(const std::string& text, const std::string& source) {
  std::istringstream in(text);
  std::vector<long> out;
  std::string token;
  while (in >> token) {
    const auto index = parseInteger(token);
    if (!index || *index < 1 || *index > 100000000) {
      throw Error(source + ": '" + token + "' is not an NYU index (an integer >= 1), entry " +
                  std::to_string(out.size() + 1));
    }
    out.push_back(static_cast<long>(*index));
  }
  if (out.empty()) throw Error(source + ": no index");
  return out;
}

std::vector<long> loadNyuTestIndices(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot read the NYU test indices");
  std::ostringstream text;
  text << in.rdbuf();
  return parseNyuTestIndices(text.str(), path);
}

std::vector<std::string> nyuSplitRunScenes(const std::vector<long>& nyu_indices,
                                           const std::vector<long>& test_indices) {
  long last = 0;
  for (long i : nyu_indices) {
    if (i < 1) throw Error("NYU index " + std::to_string(i) + ": must be >= 1");
    last = std::max(last, i);
  }
  std::vector<bool> is_test(static_cast<std::size_t>(last) + 1, false);
  for (long t : test_indices) {
    if (t >= 1 && t <= last) is_test[static_cast<std::size_t>(t)] = true;
  }
  // run_start[i]: first index of the same-side run holding i.
  std::vector<long> run_start(static_cast<std::size_t>(last) + 1, 1);
  for (long i = 2; i <= last; ++i) {
    const auto k = static_cast<std::size_t>(i);
    run_start[k] = is_test[k] == is_test[k - 1] ? run_start[k - 1] : i;
  }
  std::vector<std::string> scenes;
  for (long i : nyu_indices) {
    scenes.push_back("nyu" + std::to_string(run_start[static_cast<std::size_t>(i)]));
  }
  return scenes;
}

std::vector<int> blockFolds(std::size_t frames, int folds) {
  if (folds < 1) throw Error("folds " + std::to_string(folds) + ": must be >= 1");
  std::vector<int> fold(frames);
  for (std::size_t i = 0; i < frames; ++i) {
    fold[i] = static_cast<int>(i * static_cast<std::size_t>(folds) / frames);
  }
  return fold;
}

std::vector<int> sceneFolds(const std::vector<std::string>& scene_of_frame, int folds) {
  if (folds < 1) throw Error("folds " + std::to_string(folds) + ": must be >= 1");
  // Scenes in order of their first frame, with their frames.
  std::vector<std::string> names;
  std::map<std::string, std::size_t> id;
  std::vector<std::vector<std::size_t>> members;
  for (std::size_t i = 0; i < scene_of_frame.size(); ++i) {
    const auto [it, added] = id.emplace(scene_of_frame[i], names.size());
    if (added) {
      names.push_back(scene_of_frame[i]);
      members.emplace_back();
    }
    members[it->second].push_back(i);
  }
  std::vector<std::size_t> order(names.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return members[a].size() > members[b].size();
  });
  std::vector<std::size_t> load(static_cast<std::size_t>(folds), 0);
  std::vector<int> fold(scene_of_frame.size(), 0);
  for (std::size_t s : order) {
    const auto target = static_cast<std::size_t>(std::min_element(load.begin(), load.end()) -
                                                 load.begin());
    load[target] += members[s].size();
    for (std::size_t i : members[s]) fold[i] = static_cast<int>(target);
  }
  return fold;
}

std::vector<std::size_t> chooseTrainingSubset(const std::vector<std::size_t>& candidates,
                                              const std::vector<std::string>& scene_of_frame,
                                              int n, std::uint64_t seed) {
  if (n < 1) throw Error("training subset of " + std::to_string(n) + " frames: must be >= 1");
  std::vector<std::size_t> sorted = candidates;
  std::sort(sorted.begin(), sorted.end());
  if (static_cast<std::size_t>(n) >= sorted.size()) return sorted;
  std::vector<std::string> names;
  std::map<std::string, std::size_t> id;
  std::vector<std::vector<std::size_t>> members;
  for (std::size_t i : sorted) {
    if (i >= scene_of_frame.size()) {
      throw Error("training subset: frame " + std::to_string(i) + " has no scene (" +
                  std::to_string(scene_of_frame.size()) + " frames)");
    }
    const auto [it, added] = id.emplace(scene_of_frame[i], names.size());
    if (added) {
      names.push_back(scene_of_frame[i]);
      members.emplace_back();
    }
    members[it->second].push_back(i);
  }
  // Fisher-Yates with the generator's raw output: the same order on every
  // standard library (std::shuffle's use of the generator is unspecified).
  std::mt19937_64 rng(seed);
  std::vector<std::size_t> order(names.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  for (std::size_t k = order.size(); k > 1; --k) {
    std::swap(order[k - 1], order[static_cast<std::size_t>(rng() % k)]);
  }
  const auto want = static_cast<std::size_t>(n);
  std::vector<std::size_t> chosen;
  std::vector<bool> taken(names.size(), false);
  for (std::size_t s : order) {
    if (chosen.size() + members[s].size() > want) continue;
    chosen.insert(chosen.end(), members[s].begin(), members[s].end());
    taken[s] = true;
  }
  for (std::size_t s : order) {
    if (taken[s]) continue;
    for (std::size_t i : members[s]) {
      if (chosen.size() == want) break;
      chosen.push_back(i);
    }
  }
  std::sort(chosen.begin(), chosen.end());
  return chosen;
}

double LogTrend::at(double x) const { return a + b * std::log(x); }

LogTrend fitLogTrend(const std::vector<double>& x, const std::vector<double>& y) {
  if (x.size() != y.size()) {
    throw Error("trend fit: " + std::to_string(x.size()) + " x values and " +
                std::to_string(y.size()) + " y values");
  }
  std::vector<double> u, v;
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!(x[i] > 0.0) || !std::isfinite(x[i])) {
      throw Error("trend fit: x = " + std::to_string(x[i]) + " is not a positive number");
    }
    if (std::isnan(y[i])) continue;
    u.push_back(std::log(x[i]));
    v.push_back(y[i]);
  }
  const double n = static_cast<double>(u.size());
  const double mu = u.empty() ? 0.0 : std::accumulate(u.begin(), u.end(), 0.0) / n;
  const double mv = v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / n;
  double suu = 0.0, suv = 0.0, svv = 0.0;
  for (std::size_t i = 0; i < u.size(); ++i) {
    suu += (u[i] - mu) * (u[i] - mu);
    suv += (u[i] - mu) * (v[i] - mv);
    svv += (v[i] - mv) * (v[i] - mv);
  }
  if (u.size() < 2 || !(suu > 0.0)) {
    throw Error("trend fit: needs at least two distinct x with a value, got " +
                std::to_string(u.size()) + " points");
  }
  LogTrend fit;
  fit.b = suv / suu;
  fit.a = mv - fit.b * mu;
  fit.points = static_cast<int>(u.size());
  double residual = 0.0;
  for (std::size_t i = 0; i < u.size(); ++i) {
    const double r = v[i] - (fit.a + fit.b * u[i]);
    residual += r * r;
  }
  fit.r2 = svv > 0.0 ? 1.0 - residual / svv : std::numeric_limits<double>::quiet_NaN();
  return fit;
}

}  // namespace findmug
