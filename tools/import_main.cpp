// findmug-import — turns a folder of one's own RGB-D frames into a findmug dataset folder
// (rgb/NAME.png, depth/NAME.png in uint16 millimetres, intrinsics.yaml) that
// `dataset:DIR` replays and findmug-grab publishes. No labels are needed for replay.
//
// Two input layouts:
//   * TUM RGB-D style: rgb.txt and depth.txt ("timestamp path" lines, '#' comments);
//     each colour image is paired with the depth image closest in time, within --max-dt
//     (the TUM benchmark's association rule), and frames are numbered in colour order;
//   * plain: rgb/NAME.png and depth/NAME.png paired by NAME.
// Depth is rescaled from --depth-scale units per metre (TUM: 5000) to millimetres; 0 stays
// "no depth". intrinsics.yaml is always written: without it the folder would be read with
// NYU's calibration and NYU's border mask, which belong to another camera.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/common/numbers.hpp"
#include "findmug/frame/image_io.hpp"
#include "findmug_cli.hpp"

namespace fs = std::filesystem;
using findmug::Error;

namespace {

struct Stamped {
  double time = 0.0;
  std::string path;  // relative to the input folder
};

std::vector<Stamped> readTumList(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw Error(file.string() + ": cannot open");
  std::vector<Stamped> rows;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream fields(line);
    Stamped row;
    if (!(fields >> row.time >> row.path) || !std::isfinite(row.time)) {
      throw Error(file.string() + ":" + std::to_string(number) +
                  ": expected 'timestamp path', found '" + line + "'");
    }
    rows.push_back(row);
  }
  if (rows.empty()) throw Error(file.string() + ": no frames listed");
  return rows;
}

struct Pair {
  std::string name, rgb, depth;  // rgb/depth absolute paths
};

std::vector<Pair> associateTum(const fs::path& in, double max_dt) {
  const auto rgb = readTumList(in / "rgb.txt");
  auto depth = readTumList(in / "depth.txt");
  std::sort(depth.begin(), depth.end(),
            [](const Stamped& a, const Stamped& b) { return a.time < b.time; });
  std::vector<Pair> pairs;
  std::set<std::size_t> used;  // a depth image serves one colour image at most
  for (const auto& colour : rgb) {
    auto it = std::lower_bound(depth.begin(), depth.end(), colour.time,
                               [](const Stamped& d, double t) { return d.time < t; });
    std::size_t best = depth.size();
    double best_dt = max_dt;
    for (auto c : {it, it == depth.begin() ? it : it - 1}) {
      if (c == depth.end()) continue;
      const double dt = std::abs(c->time - colour.time);
      const auto index = static_cast<std::size_t>(c - depth.begin());
      if (dt <= best_dt && !used.count(index)) {
        best = index;
        best_dt = dt;
      }
    }
    if (best == depth.size()) continue;
    used.insert(best);
    char name[32];
    std::snprintf(name, sizeof(name), "%06zu", pairs.size());
    pairs.push_back({name, (in / colour.path).string(), (in / depth[best].path).string()});
  }
  return pairs;
}

std::vector<Pair> pairByName(const fs::path& in) {
  for (const char* sub : {"rgb", "depth"}) {
    if (!fs::is_directory(in / sub)) {
      throw Error(in.string() + ": neither rgb.txt + depth.txt (TUM) nor rgb/ + depth/ folders");
    }
  }
  std::vector<Pair> pairs;
  for (const auto& entry : fs::directory_iterator(in / "rgb")) {
    if (entry.path().extension() != ".png") continue;
    const fs::path depth = in / "depth" / entry.path().filename();
    if (fs::exists(depth)) {
      pairs.push_back({entry.path().stem().string(), entry.path().string(), depth.string()});
    }
  }
  std::sort(pairs.begin(), pairs.end(),
            [](const Pair& a, const Pair& b) { return a.name < b.name; });
  return pairs;
}

std::vector<double> parseIntrinsics(const std::string& text) {
  std::vector<double> values;
  std::istringstream in(text);
  std::string part;
  while (std::getline(in, part, ',')) {
    const auto v = findmug::parseNumber(part);
    if (!v) throw Error("--intrinsics: '" + part + "' is not a number");
    values.push_back(*v);
  }
  if (values.size() != 4 || values[0] <= 0 || values[1] <= 0) {
    throw Error("--intrinsics: expected fx,fy,cx,cy with positive focal lengths, got '" + text +
                "'");
  }
  return values;
}

}  // namespace

int main(int argc, char** argv) {
  auto app = findmug::cli::makeApp(
      "findmug-import",
      "Converts a folder of RGB-D PNGs (TUM rgb.txt/depth.txt, or rgb/ + depth/ by name) into a "
      "findmug dataset folder that dataset:DIR replays");
  std::string in_dir, out_dir, intrinsics_text = "525,525,319.5,239.5";
  double depth_scale = 5000.0, max_dt = 0.02;
  int count = 0;
  app->add_option("--in", in_dir, "input folder")->required()->type_name("DIR");
  app->add_option("--out", out_dir, "output dataset folder (created; must be empty)")
      ->required()
      ->type_name("DIR");
  app->add_option("--depth-scale", depth_scale,
                  "depth PNG units per metre (TUM: 5000; millimetre PNGs: 1000)")
      ->check(findmug::cli::positive())
      ->capture_default_str();
  app->add_option("--max-dt", max_dt, "largest colour/depth time difference paired, seconds (TUM)")
      ->check(findmug::cli::nonNegative())
      ->capture_default_str();
  app->add_option("--intrinsics", intrinsics_text,
                  "colour camera fx,fy,cx,cy in pixels (default: TUM's for registered depth)")
      ->type_name("FX,FY,CX,CY")
      ->capture_default_str();
  app->add_option("--count", count, "convert at most N frames (0: all)")
      ->check(findmug::cli::nonNegative());
  if (auto code = findmug::cli::parse(*app, argc, argv)) return *code;

  try {
    const auto k = parseIntrinsics(intrinsics_text);
    const fs::path in(in_dir), out(out_dir);
    if (!fs::is_directory(in)) throw Error(in_dir + ": input folder does not exist");
    if (fs::exists(out) && !fs::is_empty(out)) throw Error(out_dir + ": exists and is not empty");
    const bool tum = fs::exists(in / "rgb.txt") || fs::exists(in / "depth.txt");
    auto pairs = tum ? associateTum(in, max_dt) : pairByName(in);
    if (pairs.empty()) {
      throw Error(in_dir + (tum ? ": no colour image has a depth image within --max-dt " +
                                      std::to_string(max_dt) + " s"
                                : ": no NAME.png in both rgb/ and depth/"));
    }
    if (count > 0 && pairs.size() > static_cast<std::size_t>(count)) pairs.resize(count);
    fs::create_directories(out / "rgb");
    fs::create_directories(out / "depth");
    const double to_mm = 1000.0 / depth_scale;
    std::size_t clipped = 0;
    for (const auto& pair : pairs) {
      const auto rgb = findmug::readPngRgb(pair.rgb);
      auto depth = findmug::readPng16(pair.depth);
      if (depth.width != rgb.width || depth.height != rgb.height) {
        throw Error(pair.depth + " is " + std::to_string(depth.width) + "x" +
                    std::to_string(depth.height) + " but " + pair.rgb + " is " +
                    std::to_string(rgb.width) + "x" + std::to_string(rgb.height));
      }
      for (auto& d : depth.pixels) {
        const double mm = std::round(d * to_mm);
        if (mm > 65535.0) ++clipped;
        d = mm > 65535.0 ? 0 : static_cast<std::uint16_t>(mm);  // beyond 65 m: no depth
      }
      findmug::writePngRgb((out / "rgb" / (pair.name + ".png")).string(), rgb);
      findmug::writePng16((out / "depth" / (pair.name + ".png")).string(), depth);
    }
    std::ofstream yaml(out / "intrinsics.yaml");
    yaml.precision(17);
    yaml << "# colour camera intrinsics in pixels, written by findmug-import\n"
         << "fx: " << k[0] << "\nfy: " << k[1] << "\ncx: " << k[2] << "\ncy: " << k[3] << "\n";
    if (!yaml) throw Error((out / "intrinsics.yaml").string() + ": cannot write");
    std::cout << "findmug-import: " << pairs.size() << " frames ("
              << (tum ? "TUM association" : "paired by name") << ", depth / " << depth_scale
              << " per metre -> mm) in " << out_dir << "\n";
    if (clipped > 0)
      std::cout << "findmug-import: " << clipped << " depth pixels beyond 65.535 m set to 0\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "findmug-import: " << e.what() << "\n";
    return 1;
  }
}
