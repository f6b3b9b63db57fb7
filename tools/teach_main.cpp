// findmug-teach: teach the robot an object ("my mug") from 1 to 10 frames of a
// dataset folder, and write its model file (*.fmo, objects/object_model.hpp)
// for findmugd's daemon.objects_dir.
//
// Each named frame goes through the Segmenter as findmugd runs it (--model,
// --config, --set), then the table-top object stage (findTableObjects); the
// candidate under the pixel given with --at FRAME:X,Y is taken, else the one
// over the image centre, else the one nearest it (a person holds the object up
// to the camera's middle), the larger on a tie. A frame without a table or
// without a candidate there is an error naming the frame and why: a model
// taught from the wrong thing would be found everywhere but where it is.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/common/numbers.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/learner/forest.hpp"
#include "findmug/objects/object_model.hpp"
#include "findmug/objects/table_objects.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "findmug/settings/config.hpp"
#include "findmug_cli.hpp"

namespace findmug {
namespace {

constexpr const char* kDescription =
    "Teach an object from 1 to 10 frames of a dataset folder: the table-top candidate under\n"
    "the given pixel (--at FRAME:X,Y; default: over or nearest the image centre) of each\n"
    "frame becomes one view of the model file (--out NAME.fmo) that findmugd reads from\n"
    "daemon.objects_dir.";

struct Flags {
  std::string name;
  std::string data;
  std::vector<std::string> frames;
  std::vector<std::string> at;
  std::string out;
  std::string model = "models/findmug.fmf";
  cli::ConfigFlags config;
};

struct Pixel {
  int x = 0, y = 0;
};

// "FRAME:X,Y" for each --at; throws naming the bad one.
std::map<std::string, Pixel> parsePixels(const std::vector<std::string>& specs) {
  std::map<std::string, Pixel> out;
  for (const auto& spec : specs) {
    const auto colon = spec.rfind(':');
    const auto comma = spec.find(',', colon == std::string::npos ? 0 : colon);
    std::optional<long long> x, y;
    if (colon != std::string::npos && comma != std::string::npos) {
      x = parseInteger(spec.substr(colon + 1, comma - colon - 1));
      y = parseInteger(spec.substr(comma + 1));
    }
    if (!x || !y || *x < 0 || *y < 0 || *x > 100000 || *y > 100000) {
      throw Error("--at " + spec + ": expected FRAME:X,Y with pixel coordinates X, Y >= 0");
    }
    out[spec.substr(0, colon)] = {static_cast<int>(*x), static_cast<int>(*y)};
  }
  return out;
}

double distanceToPixels(const TableObject& c, int width, Pixel p) {
  double best = std::numeric_limits<double>::infinity();
  for (int i : c.pixels) best = std::min(best, std::hypot(i % width - p.x, i / width - p.y));
  return best;
}

// The candidate under `p` (within 3 pixels: depth holes leave gaps), or
// nullopt. With `nearest`, the nearest one wherever it is.
std::optional<std::size_t> candidateAt(const std::vector<TableObject>& candidates, int width,
                                       Pixel p, bool nearest) {
  std::optional<std::size_t> best;
  double best_distance = 0.0;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const double d = distanceToPixels(candidates[i], width, p);
    const bool closer =
        !best || d < best_distance ||
        (d == best_distance && candidates[i].point_count > candidates[*best].point_count);
    if (closer) {
      best = i;
      best_distance = d;
    }
  }
  if (best && !nearest && best_distance > 3.0) return std::nullopt;
  return best;
}

std::string describe(const TableObject& c) {
  std::ostringstream s;
  s.precision(3);
  s << "candidate " << c.id << " on table " << c.table << ", " << c.point_count
    << " points, height " << c.height_above_top << " m, footprint " << 2 * c.extents.x() << " x "
    << 2 * c.extents.y() << " m";
  return s.str();
}

ObjectView teachFrom(const Segmenter& segmenter, const TableObjectConfig& objects_config,
                     const LabeledFrame& frame, const std::optional<Pixel>& at) {
  const std::string& name = frame.name;
  LabelledFrame labelled = segmenter.process(frame.frame);
  const OrganizedCloud& cloud = labelled.segmented.prepared.cloud_ground;
  if (labelled.tables.empty() || cloud.size() == 0) {
    std::string why;
    for (const auto& d : labelled.table_diagnostics) why += "; " + d;
    throw Error("frame " + name + ": no table found" + why);
  }
  const TableObjectDetection detection =
      findTableObjects(cloud, labelled.labels, labelled.tables, objects_config);
  if (detection.objects.empty()) {
    throw Error("frame " + name + ": no object on its " + std::to_string(labelled.tables.size()) +
                " table(s) (" + std::to_string(detection.points_above_tops) +
                " points above the tops)");
  }
  const Pixel centre{cloud.width / 2, cloud.height / 2};
  const auto chosen =
      candidateAt(detection.objects, cloud.width, at.value_or(centre), !at.has_value());
  if (!chosen) {
    throw Error("frame " + name + ": no object candidate at " + std::to_string(at->x) + "," +
                std::to_string(at->y) + " (" + std::to_string(detection.objects.size()) +
                " candidates elsewhere)");
  }
  const TableObject& candidate = detection.objects[*chosen];
  std::cout << name << ": " << describe(candidate) << "\n";
  try {
    return makeObjectView(cloud, candidate);
  } catch (const Error& e) {
    throw Error("frame " + name + ": " + e.what());
  }
}

int run(int argc, char** argv) {
  Flags f;
  auto app = cli::makeApp("findmug-teach", kDescription);
  app->add_option("--name", f.name, "the object's name, [a-z0-9_-]{1,32}")->required();
  app->add_option("--data", f.data, "dataset folder (rgb/, depth/)")->type_name("DIR")->required();
  app->add_option("--frames", f.frames, "frames to teach from, 1 to 10")
      ->type_name("A,B,C")
      ->delimiter(',')
      ->required();
  app->add_option("--at", f.at, "the object's pixel in a frame (repeatable)")
      ->type_name("FRAME:X,Y");
  app->add_option("--out", f.out, "the model file to write")->type_name("FILE.fmo")->required();
  cli::addModelFlag(*app, f.model, "forest model the frames are segmented with");
  cli::addConfigFlags(*app, f.config, "YAML config (the daemon's, daemon/findmugd.yaml)");
  if (auto code = cli::parse(*app, argc, argv)) return *code;
  if (f.config.help_settings) {
    std::cout << cli::coreSettingsHelp();
    return 0;
  }

  validateObjectModelName(f.name);
  if (f.frames.empty() || f.frames.size() > static_cast<std::size_t>(kMaxObjectViews)) {
    throw Error("--frames: " + std::to_string(f.frames.size()) + " frames, need 1 to " +
                std::to_string(kMaxObjectViews));
  }
  const auto pixels = parsePixels(f.at);
  for (const auto& [frame, p] : pixels) {
    if (std::find(f.frames.begin(), f.frames.end(), frame) == f.frames.end()) {
      throw Error("--at " + frame + ":...: frame " + frame + " is not one of --frames");
    }
  }
  const Config config = cli::configFrom(f.config);
  auto forest = std::make_shared<const RandomForest>(RandomForest::load(f.model));
  const Segmenter segmenter(config.segmenter, forest);
  DatasetOptions options;
  options.require_labels = false;
  const DatasetFolder folder(f.data, options);

  ObjectModel model{f.name, {}};
  for (const auto& name : f.frames) {
    const auto& names = folder.names();
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end()) throw Error("frame " + name + ": not in " + f.data);
    const LabeledFrame frame = folder.load(static_cast<std::size_t>(it - names.begin()));
    const auto at = pixels.find(name);
    model.views.push_back(
        teachFrom(segmenter, config.segmenter.table_objects, frame,
                  at == pixels.end() ? std::nullopt : std::optional<Pixel>(at->second)));
  }
  saveObjectModel(f.out, model);
  std::cout << "wrote " << f.out << ": \"" << model.name << "\", " << model.views.size()
            << " view(s)\n";
  return 0;
}

}  // namespace
}  // namespace findmug

int main(int argc, char** argv) {
  try {
    return findmug::run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "findmug-teach: error: " << e.what() << "\n";
    return 1;
  }
}
