// findmug-learn-layout: counts the label-layout prior of the MRF
// (mrf.pairwise = layout, findmug/mrf/layout_prior.hpp) on dense NYU label
// maps, leaving out every map that shows a scene of the evaluation frames.
//
//   findmug-learn-layout --labels DIR/label40 --nyu-split split_test_indices.txt
//       [--exclude-scenes-of DATASET ...] [--mapping CSV] [--offset 10]
//       [--smoothing 1] --out models/nyu-layout-prior.csv
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/common/numbers.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/frame/image_io.hpp"
#include "findmug/offline/cv_folds.hpp"
#include "findmug/offline/layout_counts.hpp"
#include "findmug_cli.hpp"
#include "tool_common.hpp"

namespace {

constexpr const char* kDescription =
    "Counts which labels meet one above the other and side by side on dense NYU label maps\n"
    "(NNNN.png, NNNN the NYU index, NYU-40 ids mapped to findmug's labels) and writes the\n"
    "label-layout prior of mrf.pairwise = layout. Maps whose scene (a run of NYU indices on one\n"
    "side of --nyu-split) holds a frame of an --exclude-scenes-of dataset (its frames.csv\n"
    "nyu_index column) are left out, so that the prior knows nothing of the evaluation rooms.";

struct Flags {
  std::string labels, nyu_split, mapping, out;
  std::vector<std::string> exclude;
  int offset = 10;
  double smoothing = 1.0;
};

int run(int argc, char** argv) {
  using namespace findmug;
  namespace fs = std::filesystem;
  Flags f;
  auto app = cli::makeApp("findmug-learn-layout", kDescription);
  app->add_option("--labels", f.labels, "folder of NYU-40 label maps NNNN.png")->required();
  app->add_option("--nyu-split", f.nyu_split, "NYU's test indices (split_test_indices.txt)")
      ->required();
  app->add_option("--exclude-scenes-of", f.exclude,
                  "dataset folder whose frames' scenes are left out (repeatable)");
  app->add_option("--mapping", f.mapping,
                  "NYU-40 -> findmug label CSV (default: models/nyu40_to_findmug8.csv, compiled in)");
  app->add_option("--offset", f.offset, "pixel distance of a counted pair")
      ->check(CLI::Range(1, 1000));
  app->add_option("--smoothing", f.smoothing, "add-K pseudo-count of every pair")
      ->check(CLI::Range(0.0, 1e9));
  app->add_option("--out", f.out, "prior file to write")->required();
  if (auto code = cli::parse(*app, argc, argv)) return *code;

  const LabelMapping mapping = f.mapping.empty() ? defaultNyu40Mapping() : loadLabelMapping(f.mapping);
  const std::vector<long> test_indices = loadNyuTestIndices(f.nyu_split);

  std::vector<long> evaluation;
  for (const std::string& dir : f.exclude) {
    const auto listing = loadFrameListing(dir);
    if (listing.empty()) throw Error(dir + ": no frames.csv (needed to know its frames' scenes)");
    for (const auto& [name, row] : listing) {
      if (!row.nyu_index)
        throw Error(dir + "/frames.csv: frame " + name + " has no nyu_index");
      evaluation.push_back(*row.nyu_index);
    }
  }

  std::vector<long> candidates;
  std::error_code ec;
  if (!fs::is_directory(f.labels, ec)) throw Error(f.labels + ": not a folder");
  for (const auto& entry : fs::directory_iterator(f.labels)) {
    if (entry.path().extension() != ".png") continue;
    const std::string stem = entry.path().stem().string();
    const auto index = parseInteger(stem);
    if (!index || *index < 1)
      throw Error(entry.path().string() + ": name is not an NYU index (expected NNNN.png)");
    candidates.push_back(static_cast<long>(*index));
  }
  std::sort(candidates.begin(), candidates.end());
  if (candidates.empty()) throw Error(f.labels + ": no label maps NNNN.png");
  const std::vector<long> kept = indicesOutsideScenes(candidates, evaluation, test_indices);
  if (kept.empty()) throw Error(f.labels + ": every label map shows an excluded scene");

  LayoutCounts counts;
  counts.offset_px = f.offset;
  counts.smoothing = f.smoothing;
  char name[32];
  for (long index : kept) {
    std::snprintf(name, sizeof name, "%04ld.png", index);
    const std::string path = (fs::path(f.labels) / name).string();
    Image<std::uint8_t> map = readPng8(path);
    for (std::uint8_t& v : map.pixels) {
      const int to = mapping.to_findmug[v];
      if (to < 0)
        throw Error(path + ": label id " + std::to_string(v) + " is not in " + mapping.source);
      v = static_cast<std::uint8_t>(to);
    }
    addLayoutPairs(map, f.offset, counts);
  }
  // The prior must be usable: refuse what loadLayoutPrior would refuse.
  layoutPriorFromCounts(counts);

  const std::vector<std::string> comment = {
      "Label-layout prior of the MRF (mrf.pairwise = layout; findmug/mrf/layout_prior.hpp).",
      "Made by findmug-learn-layout from " + std::to_string(kept.size()) + " of " +
          std::to_string(candidates.size()) + " label maps in " + fs::path(f.labels).filename().string() +
          " (" + std::to_string(candidates.size() - kept.size()) +
          " left out: scenes of " + std::to_string(evaluation.size()) + " evaluation frames).",
      "Counts of pixel pairs offset_px apart whose labels differ; see models/README.md."};
  std::ofstream out(f.out, std::ios::binary);
  if (!out) throw Error(f.out + ": cannot write");
  out << formatLayoutCounts(counts, comment);
  out.close();
  if (!out) throw Error(f.out + ": write failed");
  std::cout << "findmug-learn-layout: " << kept.size() << " of " << candidates.size()
            << " label maps counted (" << candidates.size() - kept.size()
            << " share a scene with the " << evaluation.size() << " evaluation frames) -> "
            << f.out << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "findmug-learn-layout: error: " << e.what() << "\n";
    return 1;
  }
}
