// findmug-depth-holes: where the depth holes of RGB-D frames are, to compare
// raw camera depth with the raw-like copies of depth_degradation.hpp.
//
//   findmug-depth-holes --data DIR [--data DIR ...] [--degrade] [--seeds N]
//                       [--out DIR] [--config FILE] [--set key=value ...]
//
// For each folder (rgb/ and depth/, labels not needed) it prints the share
// of zero-depth pixels inside NYU's projection mask, and that share by grey
// value, by the local depth spread (near edges), by local range, with the
// side of row hole runs that separate a near from a far surface, and the
// mean length of hole runs. With --degrade the frames are first made
// raw-like (degrade.* settings), N seeds each; --out writes each degraded
// depth image (16-bit PNG, mm).
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "findmug/common/error.hpp"
#include "findmug/frame/image_io.hpp"
#include "findmug/offline/depth_degradation.hpp"
#include "findmug/offline/training.hpp"
#include "findmug_cli.hpp"
#include "tool_common.hpp"

namespace findmug::tools {
namespace {

constexpr const char* kDescription =
    "Measures where the depth holes of dataset folders are (share by brightness, depth-edge\n"
    "spread, range; shadow side; run length), optionally after the raw-depth model (--degrade).";

struct Flags {
  std::vector<std::string> data;
  std::string out;
  bool degrade = false;
  int seeds = 1;
  cli::ConfigFlags config;
};

void add(HoleStatistics& sum, const HoleStatistics& s) {
  sum.pixels += s.pixels;
  sum.holes += s.holes;
  for (int b = 0; b < HoleStatistics::kBrightnessBins; ++b)
    for (int k = 0; k < 2; ++k) sum.by_brightness[b][k] += s.by_brightness[b][k];
  for (int b = 0; b < HoleStatistics::kSpreadBins; ++b)
    for (int k = 0; k < 2; ++k) sum.by_spread[b][k] += s.by_spread[b][k];
  for (int b = 0; b < HoleStatistics::kRangeBins; ++b)
    for (int k = 0; k < 2; ++k) sum.by_range[b][k] += s.by_range[b][k];
  sum.isolated += s.isolated;
  sum.far_left_runs += s.far_left_runs;
  sum.far_right_runs += s.far_right_runs;
}

std::string share(std::size_t holes, std::size_t pixels) {
  std::ostringstream out;
  if (pixels == 0) return "-";
  out << std::fixed << std::setprecision(1) << 100.0 * holes / pixels << " %";
  return out.str();
}

void print(const std::string& what, const HoleStatistics& s, double mean_run, int frames) {
  std::cout << "## " << what << " (" << frames << " frames)\n";
  std::cout << "holes: " << share(s.holes, s.pixels) << " of " << s.pixels << " px\n";
  for (int b = 0; b < HoleStatistics::kBrightnessBins; ++b)
    std::cout << "  " << std::setw(14) << brightnessBinName(b) << ": "
              << share(s.by_brightness[b][1], s.by_brightness[b][0]) << " (of "
              << share(s.by_brightness[b][0], s.pixels) << " of the pixels)\n";
  for (int b = 0; b < HoleStatistics::kSpreadBins; ++b)
    std::cout << "  " << std::setw(14) << spreadBinName(b) << ": "
              << share(s.by_spread[b][1], s.by_spread[b][0]) << " (of "
              << share(s.by_spread[b][0], s.pixels) << ")\n";
  for (int b = 0; b < HoleStatistics::kRangeBins; ++b)
    std::cout << "  " << std::setw(14) << rangeBinName(b) << ": "
              << share(s.by_range[b][1], s.by_range[b][0]) << " (of "
              << share(s.by_range[b][0], s.pixels) << ")\n";
  std::cout << "  no measured neighbour: " << share(s.isolated, s.pixels) << " of the pixels\n";
  std::cout << "  runs between near and far: far side left " << s.far_left_runs << ", right "
            << s.far_right_runs << "\n";
  std::cout << "  mean hole run along rows: " << std::fixed << std::setprecision(1) << mean_run
            << " px\n\n";
}

int run(int argc, char** argv) {
  Flags f;
  auto app = cli::makeApp("findmug-depth-holes", kDescription);
  app->add_option("--data", f.data, "dataset folder, rgb/ and depth/ (repeatable)")
      ->type_name("DIR")
      ->required()
      ->allow_extra_args(false);
  app->add_flag("--degrade", f.degrade, "measure raw-like copies (degrade.* settings)");
  app->add_option("--seeds", f.seeds, "raw-like copies per frame with --degrade")
      ->type_name("N")
      ->check(CLI::Range(1, 100));
  app->add_option("--out", f.out, "write the degraded depth images here")->type_name("DIR");
  cli::addConfigFlags(*app, f.config, "YAML config (degrade.* settings)");
  if (auto code = cli::parse(*app, argc, argv)) return *code;
  if (f.config.help_settings) {
    std::cout << cli::coreSettingsHelp();
    return 0;
  }
  const Config config = cli::configFrom(f.config);
  DatasetOptions options;
  options.require_labels = false;
  // NYU's projection mask (DatasetOptions' default border), for every folder.
  StatisticsWindow window{options.border_left, options.border_top, 640 - options.border_right,
                          480 - options.border_bottom, 5};
  for (const auto& dir : f.data) {
    const DatasetFolder folder(dir, options);
    HoleStatistics sum;
    double run_sum = 0;
    int frames = 0;
    for (std::size_t i = 0; i < folder.size(); ++i) {
      const LabeledFrame frame = folder.load(i);
      if (frame.frame.width != 640 || frame.frame.height != 480)
        throw Error(dir + ": frame " + frame.name + " is not 640x480");
      for (int k = 0; k < (f.degrade ? f.seeds : 1); ++k) {
        RgbdFrame measured = frame.frame;
        if (f.degrade) {
          DegradationReport report;
          measured = degradeDepth(frame.frame, config.offline.degrade,
                                  degradationSeed(static_cast<std::uint64_t>(k) + 1, i), &report);
          if (report.skipped) std::cerr << frame.name << ": raw already, left as it is\n";
          if (!f.out.empty()) {
            std::filesystem::create_directories(f.out);
            const std::string stem =
                (std::filesystem::path(f.out) / (std::filesystem::path(dir).filename().string() +
                                                 "_" + frame.name + "_" + std::to_string(k)))
                    .string();
            writePng16(stem + "_depth.png", {640, 480, measured.depth_mm});
          }
        }
        const HoleStatistics s = holeStatistics(measured, window);
        add(sum, s);
        run_sum += s.mean_run_px;
        ++frames;
      }
    }
    print(dir + (f.degrade ? " (raw-like)" : ""), sum, frames ? run_sum / frames : 0.0, frames);
  }
  return 0;
}

}  // namespace
}  // namespace findmug::tools

int main(int argc, char** argv) {
  try {
    return findmug::tools::run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "findmug-depth-holes: error: " << e.what() << "\n";
    return 1;
  }
}
