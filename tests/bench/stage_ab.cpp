// stage_ab — one stage of the core library from two builds, A and B, in one
// process, call by call: both shared libraries are loaded side by side
// (dlopen with RTLD_LOCAL | RTLD_DEEPBIND, so each calls its own code), and
// every frame runs A, B, A, B, ... `--reps` times each. On a virtual machine
// whose speed drifts by 10-40 % from one minute to the next, runs of two
// builds minutes apart (frame_cpu_compare.sh) bound a 5 % change only
// loosely; calls microseconds apart see the same machine.
//
//   stage_ab LIB_A LIB_B STAGE [--reps N] [--data DIR]
//
// LIB_A, LIB_B: two builds' libfindmug_core.so (copy them out of the build
// trees first: a rebuild overwrites the file). STAGE: normals, oversegmentation
// (the organized oversegmenter), features (14-D), scene (scene features) or
// tables (detectTables). Frames: the NYU labelled frames (default
// FINDMUG_DATA/nyuv2_labeled), inputs made once by this program's own core;
// tables also run on ten rendered apartment frames (seeds 1 and 3), the
// table-rich views of tables_bench. Prints per-frame medians of A and B, the
// geometric mean of B/A over the frames, and whether the two builds' outputs
// are the same bits (a changed output is reported, not hidden).
//
// The core library keeps its thread_locals in the initial-exec TLS model
// (perf-log §9j), which dlopen() can only place in the static TLS
// surplus: the program re-executes itself with
// GLIBC_TUNABLES=glibc.rtld.optional_static_tls=1048576 when that is not set.
#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/common/error.hpp"
#include "findmug/features/features.hpp"
#include "findmug/features/scene_features.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/ground/ground.hpp"
#include "findmug/oversegmentation/oversegmentation.hpp"
#include "findmug/synth/synth.hpp"
#include "findmug/tables/tables.hpp"
#include "test_data.hpp"

namespace {

using namespace findmug;

constexpr const char* kTunable = "glibc.rtld.optional_static_tls=1048576";

using NormalsFn = void (*)(const OrganizedCloud&, const NormalConfig&, NormalImage&);
using MakeOversegmenterFn = std::unique_ptr<Oversegmenter> (*)(const OversegmentationConfig&);
using FeaturesFn = void (*)(const OrganizedCloud&, const NormalImage&, const Oversegmentation&,
                            SegmentFeatures&);
using SceneFn = void (*)(const OrganizedCloud&, const Oversegmentation&, const SegmentFeatures&,
                         const Eigen::Vector3f&, const SceneConfig&, std::vector<float>&);
using TablesFn = TableDetection (*)(const OrganizedCloud&, const LabelImage&, const TableConfig&,
                                    const NormalImage*);

// The mangled name of `fn` in this program's own core, to look it up in A and B.
std::string symbolOf(void* fn) {
  Dl_info info{};
  if (!dladdr(fn, &info) || !info.dli_sname) throw Error("stage_ab: no symbol for a core function");
  return info.dli_sname;
}

struct Build {
  void* handle = nullptr;
  NormalsFn normals = nullptr;
  std::unique_ptr<Oversegmenter> oversegmenter;
  FeaturesFn features = nullptr;
  SceneFn scene = nullptr;
  TablesFn tables = nullptr;
};

template <typename Fn>
Fn lookup(void* handle, Fn own, const char* path) {
  const std::string name = symbolOf(reinterpret_cast<void*>(own));
  void* found = dlsym(handle, name.c_str());
  if (!found) throw Error(std::string("stage_ab: ") + path + " has no " + name);
  return reinterpret_cast<Fn>(found);
}

Build load(const char* path, const OversegmentationConfig& oc) {
  Build b;
  b.handle = dlopen(path, RTLD_NOW | RTLD_LOCAL | RTLD_DEEPBIND);
  if (!b.handle) throw Error(std::string("stage_ab: cannot load ") + path + ": " + dlerror());
  b.normals = lookup<NormalsFn>(b.handle, &computeNormals, path);
  b.oversegmenter = lookup<MakeOversegmenterFn>(b.handle, &makeOversegmenter, path)(oc);
  b.features = lookup<FeaturesFn>(b.handle, &computeFeaturesInto, path);
  b.scene = lookup<SceneFn>(b.handle, &computeSceneFeaturesInto, path);
  b.tables = lookup<TablesFn>(b.handle, &detectTables, path);
  return b;
}

// One frame's inputs to every stage.
struct Input {
  std::string name;
  OrganizedCloud cloud;  // camera frame (normals, oversegmentation, features, scene)
  NormalImage normals;
  Oversegmentation segmentation;
  SegmentFeatures features;
  OrganizedCloud cloud_ground;  // tables
  LabelImage labels;
  bool has_tables_input = false;
};

bool sameBits(const void* a, const void* b, std::size_t bytes) { return !std::memcmp(a, b, bytes); }

// Whether two detections are the same to the bit in what the stage decides.
bool sameTables(const TableDetection& a, const TableDetection& b) {
  if (a.tables.size() != b.tables.size()) return false;
  for (std::size_t k = 0; k < a.tables.size(); ++k) {
    const TableCluster& x = a.tables[k];
    const TableCluster& y = b.tables[k];
    if (x.pixels != y.pixels || x.hull.size() != y.hull.size() ||
        x.search_positions.size() != y.search_positions.size() ||
        !sameBits(x.centroid.data(), y.centroid.data(), sizeof(float) * 3) ||
        !sameBits(x.center.data(), y.center.data(), sizeof(float) * 2) ||
        !sameBits(x.extents.data(), y.extents.data(), sizeof(float) * 2) ||
        !sameBits(x.major_axis.data(), y.major_axis.data(), sizeof(float) * 2) ||
        !sameBits(&x.top_height, &y.top_height, sizeof(float)) ||
        !sameBits(&x.top_area_m2, &y.top_area_m2, sizeof(float))) {
      return false;
    }
    for (std::size_t h = 0; h < x.hull.size(); ++h) {
      if (!sameBits(x.hull[h].data(), y.hull[h].data(), sizeof(float) * 2)) return false;
    }
    for (std::size_t p = 0; p < x.search_positions.size(); ++p) {
      const SearchPosition& s = x.search_positions[p];
      const SearchPosition& t = y.search_positions[p];
      if (!sameBits(s.xy.data(), t.xy.data(), sizeof(float) * 2) || s.reachable != t.reachable) {
        return false;
      }
    }
  }
  return true;
}

// Runs `stage` of build v on `in`; the output stays in `out_*[v]` for the check.
struct Outputs {
  NormalImage normals;
  Oversegmentation segmentation;
  SegmentFeatures features;
  std::vector<float> scene;
  TableDetection tables;
};

void runStage(const std::string& stage, Build& b, const Input& in, Outputs& out) {
  if (stage == "normals") {
    b.normals(in.cloud, NormalConfig{}, out.normals);
  } else if (stage == "oversegmentation") {
    b.oversegmenter->segmentInto(in.cloud, in.normals, out.segmentation);
  } else if (stage == "features") {
    b.features(in.cloud, in.normals, in.segmentation, out.features);
  } else if (stage == "scene") {
    b.scene(in.cloud, in.segmentation, in.features, Eigen::Vector3f::Zero(), SceneConfig{},
            out.scene);
  } else {
    out.tables = b.tables(in.cloud_ground, in.labels, TableConfig{}, nullptr);
  }
}

bool sameOutput(const std::string& stage, const Outputs& a, const Outputs& b) {
  if (stage == "normals") {
    return a.normals.normals.size() == b.normals.normals.size() &&
           sameBits(a.normals.normals.data(), b.normals.normals.data(),
                    a.normals.normals.size() * sizeof(Eigen::Vector3f));
  }
  if (stage == "oversegmentation") {
    return a.segmentation.pixel_segment == b.segmentation.pixel_segment;
  }
  if (stage == "features") {
    if (a.features.features.size() != b.features.features.size()) return false;
    for (std::size_t s = 0; s < a.features.features.size(); ++s) {
      if (!sameBits(a.features.features[s].data(), b.features.features[s].data(),
                    sizeof(FeatureVector))) {
        return false;
      }
    }
    return true;
  }
  if (stage == "scene") {
    return a.scene.size() == b.scene.size() &&
           sameBits(a.scene.data(), b.scene.data(), a.scene.size() * sizeof(float));
  }
  return sameTables(a.tables, b.tables);
}

std::vector<Input> nyuInputs(const std::string& dir, bool tables) {
  std::vector<Input> out;
  const DatasetFolder dataset(dir);
  OversegmentationConfig oc;
  oc.kind = OversegmenterKind::Organized;
  const auto oversegmenter = makeOversegmenter(oc);
  for (std::size_t i = 0; i < dataset.size(); ++i) {
    const LabeledFrame frame = dataset.load(i);
    Input in;
    in.name = "nyu/" + frame.name;
    in.cloud = frameToCloud(frame.frame);
    in.normals = computeNormals(in.cloud, NormalConfig{});
    in.segmentation = oversegmenter->segment(in.cloud, in.normals);
    in.features = computeFeatures(in.cloud, in.normals, in.segmentation);
    if (tables) {
      // As tables_bench: ground-truth labels, the floor fitted to them.
      const auto ground = fitGroundToLabels(in.cloud, frame.labels, GroundConfig{});
      if (!ground) continue;
      in.cloud_ground = transformCloud(in.cloud, ground->camera_to_ground);
      in.labels.width = in.cloud.width;
      in.labels.height = in.cloud.height;
      in.labels.labels = frame.labels;
      in.labels.confidence.assign(frame.labels.size(), 0.8f);
      in.has_tables_input = true;
    }
    out.push_back(std::move(in));
  }
  return out;
}

void addSynthTables(std::vector<Input>& out) {
  for (std::uint64_t seed : {1u, 3u}) {
    const synth::SynthScene scene = synth::makeApartment(seed);
    const auto path = synth::cameraPath(scene, 200, 10.0);
    for (std::size_t f = 0; f < path.size(); f += 40) {
      const auto rendered = synth::render(scene, path[f], synth::RenderOptions{}, seed * 100 + f);
      const RgbdFrame& frame = rendered.labeled.frame;
      const GroundPlane ground = groundFromExtrinsics(frame.extrinsics.value());
      Input in;
      in.name = "synth/" + std::to_string(seed) + "_" + std::to_string(f);
      in.cloud_ground = transformCloud(frameToCloud(frame), ground.camera_to_ground);
      in.labels.width = frame.width;
      in.labels.height = frame.height;
      in.labels.labels = rendered.labeled.labels;
      in.labels.confidence.assign(in.labels.labels.size(), 0.8f);
      in.has_tables_input = true;
      out.push_back(std::move(in));
    }
  }
}

int run(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr,
                 "usage: stage_ab LIB_A LIB_B normals|oversegmentation|features|scene|tables "
                 "[--reps N] [--data DIR]\n");
    return 2;
  }
  const std::string stage = argv[3];
  if (stage != "normals" && stage != "oversegmentation" && stage != "features" &&
      stage != "scene" && stage != "tables") {
    std::fprintf(stderr, "stage_ab: unknown stage '%s'\n", stage.c_str());
    return 2;
  }
  int reps = 10;
  std::string data = (test::dataRoot() / "nyuv2_labeled").string();
  for (int i = 4; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--reps")) {
      reps = std::max(1, std::atoi(argv[i + 1]));
    } else if (!std::strcmp(argv[i], "--data")) {
      data = argv[i + 1];
    } else {
      std::fprintf(stderr, "stage_ab: unknown flag %s\n", argv[i]);
      return 2;
    }
  }
  OversegmentationConfig oc;
  oc.kind = OversegmenterKind::Organized;
  Build builds[2] = {load(argv[1], oc), load(argv[2], oc)};
  std::vector<Input> inputs = nyuInputs(data, stage == "tables");
  if (stage == "tables") addSynthTables(inputs);

  std::printf("stage %s, A %s, B %s, %d calls each per frame, alternating\n\n", stage.c_str(),
              argv[1], argv[2], reps);
  std::printf("| frame | A ms (median) | B ms (median) | B / A | same output |\n|---|---:|---:|---:|---|\n");
  double log_sum = 0.0;
  int frames = 0, differing = 0;
  std::vector<double> medians[2];
  for (const Input& in : inputs) {
    if (stage == "tables" && !in.has_tables_input) continue;
    Outputs out[2];
    std::vector<double> times[2];
    for (int r = 0; r < reps; ++r) {
      for (int v = 0; v < 2; ++v) {
        const auto t0 = std::chrono::steady_clock::now();
        runStage(stage, builds[v], in, out[v]);
        times[v].push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count());
      }
    }
    double m[2];
    for (int v = 0; v < 2; ++v) {
      std::sort(times[v].begin(), times[v].end());
      m[v] = times[v][times[v].size() / 2];
      medians[v].push_back(m[v]);
    }
    const bool same = sameOutput(stage, out[0], out[1]);
    differing += same ? 0 : 1;
    std::printf("| %s | %.3f | %.3f | %.3f | %s |\n", in.name.c_str(), m[0], m[1], m[1] / m[0],
                same ? "yes" : "**no**");
    if (m[0] > 0.0 && m[1] > 0.0) {
      log_sum += std::log(m[1] / m[0]);
      ++frames;
    }
  }
  if (frames == 0) throw Error("stage_ab: no frames");
  for (auto& v : medians) std::sort(v.begin(), v.end());
  std::printf("\n%d frames: median of the per-frame medians A %.3f ms, B %.3f ms; geometric mean "
              "of B / A %.3f; outputs differ on %d frames\n",
              frames, medians[0][medians[0].size() / 2], medians[1][medians[1].size() / 2],
              std::exp(log_sum / frames), differing);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  if (!tunables || !std::strstr(tunables, "optional_static_tls")) {
    std::string value = tunables ? std::string(tunables) + ":" + kTunable : kTunable;
    setenv("GLIBC_TUNABLES", value.c_str(), 1);
    execv("/proc/self/exe", argv);
    std::perror("stage_ab: re-executing with GLIBC_TUNABLES");
    return 1;
  }
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
}
