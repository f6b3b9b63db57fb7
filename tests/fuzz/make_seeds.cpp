// findmug-fuzz-seeds OUTDIR — writes the seed corpora of the fuzz targets
// (OUTDIR/<target>/<seed>) with the project's own encoders and writers, and
// checks that each seed decodes. Run by scripts/fuzz-seeds.sh, which commits
// nothing itself: the corpora under tests/fuzz/corpus/ are its output.
//
// Frames are small (32x24) and synthetic (a tilted plane in front of the
// camera, colour gradient), so that the fuzzer mutates a few kB, not a VGA frame.
#include <hdf5.h>
#include <pcl/io/lzf_image_io.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/frame/image_io.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/lcm_codec_find.hpp"
#include "findmug/io/lcm_codec_objects.hpp"
#include "findmug/io/pcl_frames.hpp"
#include "findmug/io/semantic_map_codec.hpp"
#include "findmug/learner/forest.hpp"
#include "findmug/map/semantic_map.hpp"
#include "findmug/objects/object_model.hpp"
#include "findmug/offline/nyu_mat.hpp"
#include "findmug/settings/config.hpp"
#include "findmug_cli.hpp"
#include "program_settings.hpp"
#include "fuzz_support.hpp"
#include "lcm_samples.hpp"
#include "object_scenes.hpp"

// After the LCM types: tiff.h defines COMPRESSION_* macros that clash with their constants.
#include <tiffio.h>

namespace fs = std::filesystem;
using namespace findmug;

namespace {

constexpr int kW = 32, kH = 24;

RgbdFrame syntheticFrame() {
  RgbdFrame f;
  f.width = kW;
  f.height = kH;
  f.intrinsics = CameraIntrinsics{26.0, 26.0, 15.5, 11.5};
  f.utime = 1700000000000000ULL;
  f.seq = 7;
  f.source = "findmug-fuzz-seeds";
  for (int v = 0; v < kH; ++v) {
    for (int u = 0; u < kW; ++u) {
      const bool hole = (u == 3 && v == 4);
      f.depth_mm.push_back(hole ? 0 : static_cast<std::uint16_t>(1200 + 20 * v + 3 * u));
      f.rgb.push_back(Rgb8{static_cast<std::uint8_t>(8 * u), static_cast<std::uint8_t>(10 * v),
                           static_cast<std::uint8_t>(128)});
    }
  }
  return f;
}

std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

struct SeedWriter {
  fs::path root;
  int count = 0;
  // Writes one seed and runs `check` on its bytes (must not throw).
  void write(const std::string& target, const std::string& name, const std::string& bytes,
             const std::function<void(const std::string&)>& check) {
    fs::create_directories(root / target);
    std::ofstream(root / target / name, std::ios::binary) << bytes;
    try {
      check(bytes);
    } catch (const std::exception& e) {
      throw Error("seed " + target + "/" + name + " does not decode: " + e.what());
    }
    ++count;
  }
};

std::string asString(const std::vector<std::uint8_t>& v) { return std::string(v.begin(), v.end()); }
const std::uint8_t* bytesOf(const std::string& s) {
  return reinterpret_cast<const std::uint8_t*>(s.data());
}

void lcmSeeds(SeedWriter& w) {
  const RgbdFrame frame = syntheticFrame();
  const struct {
    const char* name;
    io::DepthCompression depth;
    io::ColorCompression color;
  } variants[] = {{"raw", io::DepthCompression::None, io::ColorCompression::None},
                  {"zlib-jpeg", io::DepthCompression::Zlib, io::ColorCompression::Jpeg},
                  {"zlib-png", io::DepthCompression::Zlib, io::ColorCompression::Png}};
  for (const auto& v : variants) {
    io::RgbdEncodeOptions options;
    options.depth = v.depth;
    options.color = v.color;
    const auto bytes = asString(io::encodeMessage(io::encodeRgbdFrame(frame, options)));
    w.write("rgbd_frame", v.name, bytes, [](const std::string& b) {
      (void)io::decodeRgbdFrame(b.data(), b.size(), "seed");
    });
  }

  io::LabelImageMessage labels;
  labels.image.width = kW;
  labels.image.height = kH;
  for (int i = 0; i < kW * kH; ++i) {
    labels.image.labels.push_back(i % 7 == 0 ? kVoidLabel : static_cast<std::uint8_t>(i % kNumLabels));
    labels.image.confidence.push_back(labels.image.labels.back() == kVoidLabel ? 0.0f : 0.75f);
  }
  labels.utime = frame.utime;
  labels.seq = frame.seq;
  labels.latency_us = 180000;
  for (bool confidence : {true, false}) {
    const auto bytes = asString(io::encodeMessage(io::encodeLabelImage(labels, confidence)));
    w.write("label_image", confidence ? "with-confidence" : "labels-only", bytes,
            [](const std::string& b) { (void)io::decodeLabelImage(b.data(), b.size(), "seed"); });
  }
  {
    // With the camera the daemon used and its colour image (daemon.publish_color).
    auto message = io::encodeLabelImage(labels);
    Eigen::Isometry3d camera_to_base = Eigen::Isometry3d::Identity();
    camera_to_base.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
    camera_to_base.translation() = Eigen::Vector3d(0, 0, 1.2);
    io::setCameraView(message, frame.intrinsics, camera_to_base);
    io::setColorJpeg(message, frame.rgb, 80);
    w.write("label_image", "camera-and-colour", asString(io::encodeMessage(message)),
            [](const std::string& b) {
              const auto m = io::decodeLabelImage(b.data(), b.size(), "seed");
              (void)io::decodeLabelImageColor(m, "seed");
            });
  }
  // label_deflate takes any bytes: the raw label bytes above, and runs of
  // every length up to past two maximal deflate matches.
  w.write("label_deflate", "labels", asString(labels.image.labels), [](const std::string&) {});
  std::string runs;
  for (int length = 1; length <= 520; length += 7) runs.append(static_cast<std::size_t>(length),
                                                                static_cast<char>(length % 9));
  w.write("label_deflate", "runs", runs, [](const std::string&) {});

  io::TablesMessage tables;
  tables.utime = frame.utime;
  tables.seq = frame.seq;
  TableCluster t;
  t.id = 1;
  t.centroid = Eigen::Vector3f(1.5f, 0.2f, 0.72f);
  t.top_height = 0.72f;
  t.extents = Eigen::Vector2f(0.6f, 0.4f);
  t.center = Eigen::Vector2f(1.5f, 0.2f);
  t.hull = {{0.9f, -0.2f}, {2.1f, -0.2f}, {2.1f, 0.6f}, {0.9f, 0.6f}};
  t.point_count = 900;
  t.mean_confidence = 0.8f;
  SearchPosition p;
  p.xy = Eigen::Vector2f(1.5f, -0.9f);
  p.yaw = 1.57f;
  SearchPosition q = p;
  q.xy = Eigen::Vector2f(1.5f, 1.3f);
  q.reachable = false;
  q.reason = "no observed floor";
  t.search_positions = {p, q};
  tables.tables = {t};
  const auto frame_tables = asString(io::encodeMessage(io::encodeTables(tables)));
  auto decodeTables = [](const std::string& b) { (void)io::decodeTables(b.data(), b.size(), "seed"); };
  w.write("tables", "frame", frame_tables, decodeTables);
  tables.content = io::TablesContent::Map;
  tables.map_pose = io::RobotPose{frame.utime, {2.0, -1.0, 0.3}};
  tables.map_info = {io::TableMapInfo{1, true, 5, 3}};
  w.write("tables", "map", asString(io::encodeMessage(io::encodeTables(tables))), decodeTables);

  // Objects on that table: none (looked, nothing), a mug with the map pose known, and the
  // tests' sample (two tables, a cut-off candidate).
  auto decodeObjects = [](const std::string& b) {
    (void)io::decodeObjects(b.data(), b.size(), "seed");
  };
  w.write("objects", "empty",
          asString(io::encodeMessage(io::encodeObjects(
              frame.utime, frame.seq, TableObjectDetection{}, tables.tables, std::nullopt, {}))),
          decodeObjects);
  {
    TableObjectDetection objects;
    TableObject mug;
    mug.centroid = Eigen::Vector3f(1.4f, 0.3f, 0.8f);
    mug.height_above_top = 0.1f;
    mug.extents = Eigen::Vector2f(0.04f, 0.035f);
    mug.center = Eigen::Vector2f(1.4f, 0.3f);
    mug.point_count = 80;
    mug.mean_rgb = Eigen::Vector3f(30.0f, 60.0f, 200.0f);
    mug.colour_histogram[16] = 0.75f;
    mug.colour_histogram[26] = 0.25f;
    mug.truncation = kTruncatedOutline;
    objects.objects = {mug};
    w.write("objects", "mug",
            asString(io::encodeMessage(
                io::encodeObjects(frame.utime, frame.seq, objects, tables.tables,
                                  io::RobotPose{frame.utime, {2.0, -1.0, 0.3}}, tables.map_info))),
            decodeObjects);
  }
  w.write("objects", "sample", asString(io::encodeMessage(test::sampleObjects())), decodeObjects);
  // The object map (FINDMUG_OBJECT_MAP, same decoder): a named mug on a confirmed table
  // and an object whose table is not confirmed.
  w.write("objects", "object_map", asString(io::encodeMessage(test::sampleObjectMap())),
          decodeObjects);

  // Answers to "find mug": seen with where to stand, and the places to look.
  auto decodeFind = [](const std::string& b) {
    (void)io::decodeFindResult(b.data(), b.size(), "seed");
  };
  {
    io::FindResultMessage seen;
    seen.utime = frame.utime;
    seen.request_id = 7;
    seen.name = "mug";
    seen.result = io::FindResult::Seen;
    seen.summary = "mug seen at (3.1, 1.0, 0.8) on table 2";
    seen.seen_object_id = 4;
    seen.seen_position = Eigen::Vector3d(3.1, 1.0, 0.8);
    seen.seen_table_id = 2;
    seen.seen_utime = frame.utime;
    seen.seen_score = 0.8f;
    SearchPosition stand;
    stand.xy = Eigen::Vector2f(3.1f, 1.8f);
    stand.yaw = -1.57f;
    seen.stand_here = stand;
    seen.taught_names = {"book", "mug"};
    w.write("find_result", "seen", asString(io::encodeMessage(io::encodeFindResult(seen))),
            decodeFind);
    io::FindResultMessage look = seen;
    look.result = io::FindResult::LookAt;
    look.summary = "mug not seen yet";
    look.seen_object_id = look.seen_table_id = 0;
    look.seen_position = Eigen::Vector3d::Zero();
    look.seen_utime = 0;
    look.seen_score = 0.0f;
    look.stand_here.reset();
    PlaceToLook place;
    place.table_id = 1;
    place.position = stand;
    place.seen_here_before = true;
    look.places = {place, place};
    look.places[1].table_id = 3;
    look.places[1].searched = true;
    look.places[0].look_closer = true;
    w.write("find_result", "look_at", asString(io::encodeMessage(io::encodeFindResult(look))),
            decodeFind);
  }

  const auto pose = asString(io::encodeMessage(io::encodeRobotPose(io::RobotPose{frame.utime, {2.0, -1.0, 0.3}})));
  w.write("robot_pose", "pose", pose,
          [](const std::string& b) { (void)io::decodeRobotPose(b.data(), b.size(), "seed"); });

  auto decodeCommand = [](const std::string& b) {
    (void)io::decodeCommand(b.data(), b.size(), "seed");
  };
  w.write("command", "reload_model",
          asString(io::encodeMessage(
              io::encodeCommand(io::CommandMessage{frame.utime, 7, "reload_model", ""}))),
          decodeCommand);
  w.write("command", "with_argument",
          asString(io::encodeMessage(io::encodeCommand(
              io::CommandMessage{frame.utime, 8, "save_frame", "kitchen, two mugs"}))),
          decodeCommand);
  w.write("command", "teach",
          asString(io::encodeMessage(io::encodeCommand(
              io::CommandMessage{frame.utime, 9, "teach", "mug 41 2"}))),
          decodeCommand);

  // A small fused map: a 20 x 20 patch of floor and a table top seen from above.
  {
    SemanticMap map;
    OrganizedCloud cloud;
    LabelImage labels;
    cloud.width = labels.width = 20;
    cloud.height = labels.height = 20;
    for (int y = 0; y < 20; ++y) {
      for (int x = 0; x < 20; ++x) {
        const bool top = x >= 5 && x < 15 && y >= 5 && y < 15;
        // Camera frame: looking straight down from 1.5 m (z forward = down in the map).
        cloud.points.emplace_back(0.05f * static_cast<float>(x - 10),
                                  0.05f * static_cast<float>(y - 10), top ? 0.75f : 1.5f);
        cloud.colors.push_back(Rgb8{});
        labels.labels.push_back(static_cast<std::uint8_t>(top ? Label::Table : Label::Floor));
        labels.confidence.push_back(0.8f);
      }
    }
    Eigen::Isometry3d camera = Eigen::Isometry3d::Identity();
    camera.linear() << 1, 0, 0, 0, -1, 0, 0, 0, -1;  // z down, x along the map's x
    camera.translation() = Eigen::Vector3d(1.0, 2.0, 1.5);
    map.integrate(cloud, labels, camera, frame.utime);
    map.integrate(cloud, labels, camera, frame.utime + 100000);
    (void)map.tables();
    const auto message = io::semanticMapMessage(map, frame.utime, frame.seq);
    auto decodeMap = [](const std::string& b) {
      (void)io::decodeSemanticMap(b.data(), b.size(), "seed");
    };
    w.write("semantic_map", "zlib", asString(io::encodeMessage(io::encodeSemanticMap(message))),
            decodeMap);
    w.write("semantic_map", "raw",
            asString(io::encodeMessage(io::encodeSemanticMap(message, false))), decodeMap);
    w.write("semantic_map_file", "map", asString(map.toBytes()), [](const std::string& b) {
      SemanticMap m;
      m.loadBytes(std::vector<std::uint8_t>(b.begin(), b.end()), "seed");
    });
  }

  findmug_lcm::status_t s = findmug::test::sampleStatus();
  s.utime = frame.utime;
  s.window_s = 10.0;
  s.model_id = "findmug.fmf:0123abcd";
  w.write("status", "status", asString(io::encodeMessage(s)), [](const std::string& b) {
    (void)io::decodeMessage<findmug_lcm::status_t>(b.data(), b.size(), "seed");
  });
}

// Taught objects (*.fmo): one view of the fewest points a view may have, and
// two views, so that the fuzzer mutates a few kB.
void objectModelSeeds(SeedWriter& w) {
  auto decodes = [](const std::string& b) {
    (void)decodeObjectModel(bytesOf(b), b.size(), "seed");
  };
  w.write("object_model", "one_view",
          asString(encodeObjectModel(test::sampleObjectModel("mug", 1, kMinObjectViewPoints))),
          decodes);
  w.write("object_model", "two_views",
          asString(encodeObjectModel(test::sampleObjectModel("red_mug-2", 2, 40))), decodes);
}

void modelSeeds(SeedWriter& w, const fs::path& scratch) {
  TrainingSet data;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int i = 0; i < 60; ++i) {
    FeatureVector x{};
    for (auto& v : x) v = u(rng);
    data.features.push_back(x);
    data.labels.push_back(static_cast<std::uint8_t>((x[0] > 0.5f ? 1 : 0) + (x[3] > 0.5f ? 2 : 0)));
  }
  ForestParams params;
  params.num_trees = 2;
  params.max_depth = 3;
  params.num_threads = 1;
  auto forest = RandomForest::train(data, params);
  const auto plain = scratch / "plain.fmf";
  forest.save(plain.string());
  auto check = [&scratch](const std::string& b) {
    const auto path = scratch / "check.fmf";
    std::ofstream(path, std::ios::binary) << b;
    (void)RandomForest::load(path.string());
  };
  w.write("model", "plain", readFile(plain), check);
  forest.setExtractionSettings(extractionSettings(SegmenterConfig{}));
  const auto with_settings = scratch / "settings.fmf";
  forest.save(with_settings.string());
  w.write("model", "with-settings", readFile(with_settings), check);
  // Format 4 with gradient-boosted trees: the booster's bytes behind the checksum.
  XGBoostParams boosted_params;
  boosted_params.rounds = 2;
  boosted_params.max_depth = 2;
  const auto boosted_model = RandomForest::trainBoosted(data, labelClasses(), boosted_params, true, 1);
  const auto boosted = scratch / "boosted.fmf";
  boosted_model.save(boosted.string());
  w.write("model", "boosted", readFile(boosted), check);
}

void configSeeds(SeedWriter& w, const fs::path& source_dir) {
  // Read as findmugd reads them: the segmenter's sections and every other table of the file.
  auto schemaOf = [](Config& c) {
    SettingsSchema schema;
    bindCoreSettings(schema, c);
    cli::acceptSharedFileSettings(schema);
    return schema;
  };
  auto checkYaml = [schemaOf](const std::string& b) {
    Config c;
    const SettingsSchema schema = schemaOf(c);
    schema.readYaml(b, "seed");
    schema.validate("seed");
  };
  w.write("config_yaml", "defaults", dumpConfig(Config{}), checkYaml);
  w.write("config_yaml", "findmugd", readFile(source_dir / "daemon/findmugd.yaml"), checkYaml);
  const std::string sets =
      "cloud.max_depth_m=8\nmrf.max_iterations=5\nnormals.window_radius_px=3\n"
      "oversegmentation.method=organized\n"
      "daemon.source=lcm:?url=memq://\ndaemon.queue_capacity=4\ndaemon.log_level=debug\n";
  auto checkSets = [schemaOf](const std::string& b) {
    Config c;
    SettingsSchema schema = schemaOf(c);
    schema.onWarning([](const std::string&) {});
    std::istringstream lines(b);
    std::string line;
    while (std::getline(lines, line)) schema.applyOverride(line);
    schema.validate("<flags>");
  };
  w.write("config_set", "overrides", sets, checkSets);
  // Renamed keys by their old names (renamedSettings): the alias path.
  w.write("config_set", "old_names",
          "overseg.method=organized\nforest.num_threads=1\nforest.class_weighting=false\n",
          checkSets);
  w.write("label_csv", "nyu40_to_findmug8", readFile(source_dir / "models/nyu40_to_findmug8.csv"),
          [](const std::string& b) { (void)parseLabelMapping(b, "seed"); });
}

void pngSeeds(SeedWriter& w, const fs::path& scratch) {
  const RgbdFrame f = syntheticFrame();
  Image<Rgb8> rgb{kW, kH, f.rgb};
  w.write("png", "rgb", asString(encodePngRgb(rgb)),
          [](const std::string& b) { (void)decodePngRgb({b.begin(), b.end()}, "seed"); });
  auto fileCheck = [&scratch](auto reader) {
    return [&scratch, reader](const std::string& b) {
      const auto path = scratch / "check.png";
      std::ofstream(path, std::ios::binary) << b;
      (void)reader(path.string());
    };
  };
  const auto depth_png = scratch / "depth.png";
  writePng16(depth_png.string(), Image<std::uint16_t>{kW, kH, f.depth_mm});
  w.write("png", "depth16", readFile(depth_png), fileCheck(readPng16));
  Image<std::uint8_t> labels{kW, kH, std::vector<std::uint8_t>(kW * kH, 3)};
  const auto label_png = scratch / "label.png";
  writePng8(label_png.string(), labels);
  w.write("png", "label8", readFile(label_png), fileCheck(readPng8));
}

void pclSeeds(SeedWriter& w, const fs::path& scratch) {
  const RgbdFrame f = syntheticFrame();
  const auto& k = f.intrinsics;
  pcl::PointCloud<pcl::PointXYZRGBA> cloud(kW, kH);
  for (int v = 0; v < kH; ++v) {
    for (int u = 0; u < kW; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * kW + u;
      auto& p = cloud(u, v);
      const float z = f.depth_mm[i] * 0.001f;
      if (f.depth_mm[i] == 0) {
        p.x = p.y = p.z = std::numeric_limits<float>::quiet_NaN();
      } else {
        p.x = static_cast<float>((u - k.cx) * z / k.fx);
        p.y = static_cast<float>((v - k.cy) * z / k.fy);
        p.z = z;
      }
      p.r = f.rgb[i].r;
      p.g = f.rgb[i].g;
      p.b = f.rgb[i].b;
      p.a = 255;
    }
  }
  cloud.is_dense = false;
  auto checkPcd = [&scratch](const std::string& b) {
    const auto path = scratch / "check.pcd";
    std::ofstream(path, std::ios::binary) << b;
    (void)io::readPcdFrame(path.string());
  };
  const auto binary = scratch / "binary.pcd", compressed = scratch / "compressed.pcd";
  pcl::io::savePCDFileBinary(binary.string(), cloud);
  pcl::io::savePCDFileBinaryCompressed(compressed.string(), cloud);
  w.write("pcd", "binary", readFile(binary), checkPcd);
  w.write("pcd", "binary_compressed", readFile(compressed), checkPcd);

  // PCLZF: PCL's own LZF writers, as its grabbers record.
  std::vector<char> depth(reinterpret_cast<const char*>(f.depth_mm.data()),
                          reinterpret_cast<const char*>(f.depth_mm.data() + f.depth_mm.size()));
  std::vector<char> rgb;
  for (const auto& c : f.rgb) {
    rgb.push_back(static_cast<char>(c.r));
    rgb.push_back(static_cast<char>(c.g));
    rgb.push_back(static_cast<char>(c.b));
  }
  const auto depth_lzf = scratch / "f_depth.pclzf", rgb_lzf = scratch / "f_rgb.pclzf",
             xml = scratch / "f.xml";
  pcl::io::LZFDepth16ImageWriter depth_writer;
  pcl::io::LZFRGB24ImageWriter rgb_writer;
  pcl::io::CameraParameters params{k.fx, k.fy, k.cx, k.cy};
  depth_writer.write(depth.data(), kW, kH, depth_lzf.string());
  depth_writer.writeParameters(params, xml.string());
  rgb_writer.write(rgb.data(), kW, kH, rgb_lzf.string());
  w.write("pclzf", "frame",
          fuzz::joinParts({readFile(depth_lzf), readFile(rgb_lzf), readFile(xml)}),
          [&scratch](const std::string& b) {
            const auto parts = fuzz::splitParts(bytesOf(b), b.size(), 3);
            const auto d = scratch / "c_depth.pclzf", r = scratch / "c_rgb.pclzf",
                       x = scratch / "c.xml";
            std::ofstream(d, std::ios::binary) << parts[0];
            std::ofstream(r, std::ios::binary) << parts[1];
            std::ofstream(x, std::ios::binary) << parts[2];
            (void)io::readPclzfFrame(d.string(), r.string(), x.string());
          });

  // TIFF: libtiff, uint16 depth and RGB8 strips, as PCL's TIFF recordings.
  auto writeTiff = [](const fs::path& path, const void* pixels, int samples, int bits) {
    TIFF* tif = TIFFOpen(path.string().c_str(), "w");
    if (!tif) throw Error(path.string() + ": cannot create");
    TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, kW);
    TIFFSetField(tif, TIFFTAG_IMAGELENGTH, kH);
    TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, samples);
    TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, bits);
    TIFFSetField(tif, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
    TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, samples == 3 ? PHOTOMETRIC_RGB : PHOTOMETRIC_MINISBLACK);
    TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, 8);
    const std::size_t row = static_cast<std::size_t>(kW) * samples * bits / 8;
    for (int y = 0; y < kH; ++y) {
      TIFFWriteScanline(tif, const_cast<char*>(static_cast<const char*>(pixels) + y * row), y, 0);
    }
    TIFFClose(tif);
  };
  const auto depth_tif = scratch / "f_depth.tiff", rgb_tif = scratch / "f_rgb.tiff";
  writeTiff(depth_tif, f.depth_mm.data(), 1, 16);
  writeTiff(rgb_tif, rgb.data(), 3, 8);
  w.write("tiff", "frame", fuzz::joinParts({readFile(depth_tif), readFile(rgb_tif)}),
          [&scratch](const std::string& b) {
            const auto parts = fuzz::splitParts(bytesOf(b), b.size(), 2);
            const auto d = scratch / "c_depth.tiff", r = scratch / "c_rgb.tiff";
            std::ofstream(d, std::ios::binary) << parts[0];
            std::ofstream(r, std::ios::binary) << parts[1];
            (void)io::readTiffFrame(d.string(), r.string(), CameraIntrinsics{});
          });
}

// A two-frame nyu_depth_v2_labeled.mat in the MATLAB v7.3 layout (HDF5 sees
// N x 3 x W x H images, N x W x H depths and labels), and a CSV mapping the
// 894 ids onto the 40 NYU-40 classes.
void nyuSeeds(SeedWriter& w, const fs::path& scratch) {
  constexpr hsize_t n = 2, W = 16, H = 12;
  const auto mat = scratch / "labeled.mat";
  const hid_t file = H5Fcreate(mat.string().c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  auto put = [file](const char* name, hid_t file_type, hid_t mem_type, std::vector<hsize_t> dims,
                    const void* data) {
    const hid_t space = H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr);
    // No modification times in the object headers: the same seeds every run.
    const hid_t create = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_obj_track_times(create, false);
    const hid_t set = H5Dcreate2(file, name, file_type, space, H5P_DEFAULT, create, H5P_DEFAULT);
    H5Pclose(create);
    H5Dwrite(set, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data);
    H5Dclose(set);
    H5Sclose(space);
  };
  std::vector<std::uint8_t> images(n * 3 * W * H);
  for (std::size_t i = 0; i < images.size(); ++i) images[i] = static_cast<std::uint8_t>(i * 7);
  std::vector<float> depths(n * W * H);
  for (std::size_t i = 0; i < depths.size(); ++i) depths[i] = 1.0f + 0.01f * (i % 50);
  std::vector<std::uint16_t> labels(n * W * H);
  for (std::size_t i = 0; i < labels.size(); ++i) labels[i] = static_cast<std::uint16_t>(i % 5);
  put("images", H5T_STD_U8LE, H5T_NATIVE_UINT8, {n, 3, W, H}, images.data());
  put("depths", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, {n, W, H}, depths.data());
  put("labels", H5T_STD_U16LE, H5T_NATIVE_UINT16, {n, W, H}, labels.data());
  H5Fclose(file);
  std::string csv = "nyu894_id,name,nyu40_id,nyu40_name\n";
  for (int id = 1; id <= 894; ++id) {
    const int id40 = 1 + (id - 1) % 40;
    csv += std::to_string(id) + ",class" + std::to_string(id) + "," + std::to_string(id40) +
           ",nyu40class" + std::to_string(id40) + "\n";
  }
  auto check = [&scratch](const std::string& b) {
    const auto parts = fuzz::splitParts(bytesOf(b), b.size(), 2);
    const auto c = scratch / "c.csv", m = scratch / "c.mat";
    std::ofstream(c, std::ios::binary) << parts[0];
    std::ofstream(m, std::ios::binary) << parts[1];
    NyuMatFile f(m.string(), c.string());
    for (std::size_t i = 0; i < f.size(); ++i) (void)f.load(i);
  };
  w.write("nyu_mat", "two-frames", fuzz::joinParts({csv, readFile(mat)}), check);
  // The same file with a mapping of just the ids its labels use (0..4): most
  // of the bytes are then the HDF5 file, where the mutations should go.
  std::string short_csv = "nyu894_id,name,nyu40_id,nyu40_name\n";
  for (int id = 1; id <= 4; ++id)
    short_csv += std::to_string(id) + ",c" + std::to_string(id) + "," + std::to_string(id) + ",n\n";
  w.write("nyu_mat", "short-mapping", fuzz::joinParts({short_csv, readFile(mat)}), check);
}

// udpm: records of [u8 sender][u16 big-endian length][datagram] (fuzz_udpm.cpp):
// a frame message cut into LCM fragments, a short message, and the two
// datagrams that crash liblcm 1.3.1 (a wrapping fragment offset).
void udpmSeeds(SeedWriter& w) {
  const auto be32 = [](std::string& b, std::uint32_t v) {
    for (int k = 3; k >= 0; --k) b.push_back(static_cast<char>(v >> (8 * k)));
  };
  const auto be16 = [](std::string& b, std::uint16_t v) {
    b.push_back(static_cast<char>(v >> 8));
    b.push_back(static_cast<char>(v));
  };
  const auto record = [&](std::string& out, std::uint8_t sender, const std::string& d) {
    out.push_back(static_cast<char>(sender));
    be16(out, static_cast<std::uint16_t>(d.size()));
    out += d;
  };
  const auto fragment = [&](std::uint32_t seq, std::uint32_t size, std::uint32_t offset,
                            std::uint16_t number, std::uint16_t count, const std::string& payload) {
    std::string d;
    be32(d, 0x4c433033);
    be32(d, seq);
    be32(d, size);
    be32(d, offset);
    be16(d, number);
    be16(d, count);
    if (number == 0) d += std::string("FINDMUG_RGBD") + '\0';
    return d + payload;
  };
  const std::string message = asString(io::encodeMessage(io::encodeRgbdFrame(syntheticFrame())));
  const std::size_t chunk = 1000;
  const auto count = static_cast<std::uint16_t>((message.size() + chunk - 1) / chunk);
  std::string frames;
  for (std::uint16_t i = 0; i < count; ++i) {
    const std::size_t off = i * chunk;
    record(frames, 1, fragment(5, static_cast<std::uint32_t>(message.size()),
                               static_cast<std::uint32_t>(off), i, count,
                               message.substr(off, chunk)));
  }
  std::string short_message;
  be32(short_message, 0x4c433032);
  be32(short_message, 6);
  short_message += std::string("FUZZ") + '\0' + "payload";
  std::string mixed;
  record(mixed, 2, short_message);
  std::string killer;
  record(killer, 3, fragment(7, 100000, 0, 0, 100, std::string(100, 'x')));
  record(killer, 3, fragment(7, 100000, 0xFFFFFF00u, 1, 100, std::string(0x200, 'y')));
  const auto check = [](const std::string&) {};
  w.write("udpm", "frame-fragments", frames, check);
  w.write("udpm", "short", mixed, check);
  w.write("udpm", "liblcm-wrap", killer, check);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: findmug-fuzz-seeds SOURCE_DIR OUTDIR\n"
                 "  writes the fuzz seed corpora (OUTDIR/<target>/<seed>); SOURCE_DIR is the\n"
                 "  findmug checkout (daemon/findmugd.yaml and models/*.csv are seeds too)\n";
    return 2;
  }
  try {
    SeedWriter w{fs::path(argv[2])};
    const fs::path scratch = fs::temp_directory_path() / ("findmug-seeds-" + std::to_string(::getpid()));
    fs::create_directories(scratch);
    lcmSeeds(w);
    udpmSeeds(w);
    modelSeeds(w, scratch);
    objectModelSeeds(w);
    configSeeds(w, argv[1]);
    pngSeeds(w, scratch);
    pclSeeds(w, scratch);
    nyuSeeds(w, scratch);
    fs::remove_all(scratch);
    std::cout << w.count << " seeds written to " << argv[2] << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "findmug-fuzz-seeds: " << e.what() << "\n";
    return 1;
  }
}
