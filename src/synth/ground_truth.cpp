// Ground truth files (DIR/ground_truth.yaml) and whole-sequence writing.
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "findmug/common/error.hpp"
#include "findmug/synth/synth.hpp"
#include "synth_internal.hpp"

namespace findmug::synth {

namespace fs = std::filesystem;

namespace {

constexpr const char* kFormat = "findmug-synth-ground-truth";
constexpr int kVersion = 1;

const char* shapeName(TableShape s) { return s == TableShape::Round ? "round" : "rectangular"; }

void emitVec(YAML::Emitter& out, std::initializer_list<double> values) {
  out << YAML::Flow << YAML::BeginSeq;
  for (double v : values) out << v;
  out << YAML::EndSeq;
}

// Reading helpers: every failure names the file and the field.
struct Reader {
  std::string path;

  YAML::Node child(const YAML::Node& node, const std::string& key, const std::string& where) const {
    const YAML::Node c = node[key];
    if (!c) throw Error(path + ": missing '" + key + "' in " + where);
    return c;
  }
  double number(const YAML::Node& node, const std::string& key, const std::string& where) const {
    const YAML::Node c = child(node, key, where);
    double v = 0.0;
    try {
      v = c.as<double>();
    } catch (const YAML::Exception&) {
      throw Error(path + ": '" + key + "' in " + where + " is not a number");
    }
    if (!std::isfinite(v)) throw Error(path + ": '" + key + "' in " + where + " is not finite");
    return v;
  }
  std::vector<double> numbers(const YAML::Node& node, const std::string& key, std::size_t n,
                              const std::string& where) const {
    const YAML::Node c = child(node, key, where);
    if (!c.IsSequence() || c.size() != n)
      throw Error(path + ": '" + key + "' in " + where + " must be a list of " + std::to_string(n) +
                  " numbers");
    std::vector<double> v;
    for (std::size_t i = 0; i < n; ++i) {
      try {
        v.push_back(c[i].as<double>());
      } catch (const YAML::Exception&) {
        throw Error(path + ": '" + key + "' in " + where + " has a non-number at index " +
                    std::to_string(i));
      }
      if (!std::isfinite(v.back()))
        throw Error(path + ": '" + key + "' in " + where + " is not finite");
    }
    return v;
  }
  std::string text(const YAML::Node& node, const std::string& key, const std::string& where) const {
    try {
      return child(node, key, where).as<std::string>();
    } catch (const YAML::Exception&) {
      throw Error(path + ": '" + key + "' in " + where + " is not a string");
    }
  }
};

}  // namespace

std::string frameName(int index) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%06d", index);
  return buffer;
}

void writeGroundTruth(const std::string& path, const SequenceGroundTruth& truth) {
  if (truth.poses.size() != truth.frame_names.size() ||
      truth.poses.size() != truth.frame_utimes.size())
    throw Error(path + ": ground truth has " + std::to_string(truth.poses.size()) + " poses, " +
                std::to_string(truth.frame_names.size()) + " names and " +
                std::to_string(truth.frame_utimes.size()) + " timestamps");
  YAML::Emitter out;
  out.SetDoublePrecision(10);
  out << YAML::BeginMap;
  out << YAML::Key << "format" << YAML::Value << kFormat;
  out << YAML::Key << "version" << YAML::Value << kVersion;
  out << YAML::Key << "seed" << YAML::Value << truth.seed;
  out << YAML::Key << "fps" << YAML::Value << truth.fps;
  out << YAML::Key << "world_frame" << YAML::Value
      << "z up, floor z=0, room [0,X]x[0,Y]x[0,H] m; camera_to_world = T(x,y,height)*Rz(yaw)*"
         "Ry(pitch)*R0*Rz(roll), see include/findmug/synth/synth.hpp";
  out << YAML::Key << "image" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "width" << YAML::Value << truth.width;
  out << YAML::Key << "height" << YAML::Value << truth.height;
  out << YAML::Key << "fx" << YAML::Value << truth.intrinsics.fx;
  out << YAML::Key << "fy" << YAML::Value << truth.intrinsics.fy;
  out << YAML::Key << "cx" << YAML::Value << truth.intrinsics.cx;
  out << YAML::Key << "cy" << YAML::Value << truth.intrinsics.cy;
  out << YAML::EndMap;
  out << YAML::Key << "room_size" << YAML::Value;
  emitVec(out, {truth.room_size.x(), truth.room_size.y(), truth.room_size.z()});

  out << YAML::Key << "tables" << YAML::Value << YAML::BeginSeq;
  for (const auto& t : truth.tables) {
    out << YAML::BeginMap;
    out << YAML::Key << "id" << YAML::Value << t.id;
    out << YAML::Key << "kind" << YAML::Value << t.kind;
    out << YAML::Key << "shape" << YAML::Value << shapeName(t.shape);
    out << YAML::Key << "center" << YAML::Value;
    emitVec(out, {t.center_xy.x(), t.center_xy.y()});
    out << YAML::Key << "yaw" << YAML::Value << t.yaw;
    out << YAML::Key << "size" << YAML::Value;
    emitVec(out, {t.size.x(), t.size.y()});
    out << YAML::Key << "height" << YAML::Value << t.height;
    out << YAML::Key << "top_polygon" << YAML::Value << YAML::BeginSeq;
    for (const auto& v : t.top_polygon) emitVec(out, {v.x(), v.y()});
    out << YAML::EndSeq;
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;

  out << YAML::Key << "obstacles" << YAML::Value << YAML::BeginSeq;
  for (const auto& o : truth.obstacles) {
    out << YAML::BeginMap;
    out << YAML::Key << "object" << YAML::Value << o.object;
    out << YAML::Key << "top_z" << YAML::Value << o.top_z;
    out << YAML::Key << "polygon" << YAML::Value << YAML::BeginSeq;
    for (const auto& v : o.polygon) emitVec(out, {v.x(), v.y()});
    out << YAML::EndSeq;
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;

  out << YAML::Key << "frames" << YAML::Value << YAML::BeginSeq;
  for (std::size_t i = 0; i < truth.poses.size(); ++i) {
    const CameraPose& p = truth.poses[i];
    out << YAML::BeginMap;
    out << YAML::Key << "name" << YAML::Value << YAML::DoubleQuoted << truth.frame_names[i];
    out << YAML::Key << "utime" << YAML::Value << truth.frame_utimes[i];
    out << YAML::Key << "xy" << YAML::Value;
    emitVec(out, {p.xy.x(), p.xy.y()});
    out << YAML::Key << "yaw" << YAML::Value << p.yaw;
    out << YAML::Key << "height" << YAML::Value << p.height_m;
    out << YAML::Key << "pitch" << YAML::Value << p.pitch_rad;
    out << YAML::Key << "roll" << YAML::Value << p.roll_rad;
    const Eigen::Isometry3d m = cameraToWorld(p);
    out << YAML::Key << "camera_to_world" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) out << m.matrix()(r, c);
    out << YAML::EndSeq;
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::EndMap;
  if (!out.good()) throw Error(path + ": YAML emitter failed (" + out.GetLastError() + ")");

  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  file << out.c_str() << "\n";
  file.close();
  if (!file) throw Error(path + ": cannot write ground truth");
}

SequenceGroundTruth readGroundTruth(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw Error(path + ": cannot read ground truth YAML (" + e.what() + ")");
  }
  const Reader r{path};
  if (!root.IsMap()) throw Error(path + ": ground truth is not a YAML map");
  if (r.text(root, "format", "the top level") != kFormat)
    throw Error(path + ": 'format' is not " + kFormat);
  if (r.number(root, "version", "the top level") != kVersion)
    throw Error(path + ": unsupported ground truth version (expected " + std::to_string(kVersion) +
                ")");
  SequenceGroundTruth t;
  const double seed = r.number(root, "seed", "the top level");
  if (seed < 0) throw Error(path + ": negative 'seed'");
  t.seed = r.child(root, "seed", "the top level").as<std::uint64_t>();
  t.fps = r.number(root, "fps", "the top level");
  if (!(t.fps > 0)) throw Error(path + ": 'fps' must be positive");
  const YAML::Node image = r.child(root, "image", "the top level");
  t.width = static_cast<int>(r.number(image, "width", "image"));
  t.height = static_cast<int>(r.number(image, "height", "image"));
  t.intrinsics = {r.number(image, "fx", "image"), r.number(image, "fy", "image"),
                  r.number(image, "cx", "image"), r.number(image, "cy", "image")};
  const auto room = r.numbers(root, "room_size", 3, "the top level");
  t.room_size = {room[0], room[1], room[2]};

  const YAML::Node tables = r.child(root, "tables", "the top level");
  if (!tables.IsSequence()) throw Error(path + ": 'tables' is not a list");
  for (std::size_t i = 0; i < tables.size(); ++i) {
    const std::string where = "tables[" + std::to_string(i) + "]";
    const YAML::Node n = tables[i];
    TableTruth tt;
    tt.id = static_cast<int>(r.number(n, "id", where));
    tt.kind = r.text(n, "kind", where);
    const std::string shape = r.text(n, "shape", where);
    if (shape == "round")
      tt.shape = TableShape::Round;
    else if (shape == "rectangular")
      tt.shape = TableShape::Rectangular;
    else
      throw Error(path + ": 'shape' in " + where + " is '" + shape + "' (rectangular or round)");
    const auto c = r.numbers(n, "center", 2, where);
    tt.center_xy = {c[0], c[1]};
    tt.yaw = r.number(n, "yaw", where);
    const auto s = r.numbers(n, "size", 2, where);
    tt.size = {s[0], s[1]};
    tt.height = r.number(n, "height", where);
    const YAML::Node poly = r.child(n, "top_polygon", where);
    if (!poly.IsSequence() || poly.size() < 3)
      throw Error(path + ": 'top_polygon' in " + where + " needs at least 3 points");
    for (std::size_t k = 0; k < poly.size(); ++k) {
      YAML::Node wrapper;
      wrapper["p"] = poly[k];
      const auto v = r.numbers(wrapper, "p", 2, where + ".top_polygon[" + std::to_string(k) + "]");
      tt.top_polygon.push_back({v[0], v[1]});
    }
    t.tables.push_back(tt);
  }

  // Optional: files written before obstacles were recorded have none.
  if (const YAML::Node obstacles = root["obstacles"]) {
    if (!obstacles.IsSequence()) throw Error(path + ": 'obstacles' is not a list");
    for (std::size_t i = 0; i < obstacles.size(); ++i) {
      const std::string where = "obstacles[" + std::to_string(i) + "]";
      const YAML::Node n = obstacles[i];
      Obstacle o;
      o.object = static_cast<int>(r.number(n, "object", where));
      o.top_z = r.number(n, "top_z", where);
      const YAML::Node poly = r.child(n, "polygon", where);
      if (!poly.IsSequence() || poly.size() < 3)
        throw Error(path + ": 'polygon' in " + where + " needs at least 3 points");
      for (std::size_t k = 0; k < poly.size(); ++k) {
        YAML::Node wrapper;
        wrapper["p"] = poly[k];
        const auto v = r.numbers(wrapper, "p", 2, where + ".polygon[" + std::to_string(k) + "]");
        o.polygon.push_back({v[0], v[1]});
      }
      t.obstacles.push_back(o);
    }
  }

  const YAML::Node frames = r.child(root, "frames", "the top level");
  if (!frames.IsSequence()) throw Error(path + ": 'frames' is not a list");
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const std::string where = "frames[" + std::to_string(i) + "]";
    const YAML::Node n = frames[i];
    t.frame_names.push_back(r.text(n, "name", where));
    const double utime = r.number(n, "utime", where);
    if (utime < 0) throw Error(path + ": negative 'utime' in " + where);
    t.frame_utimes.push_back(r.child(n, "utime", where).as<std::uint64_t>());
    CameraPose p;
    const auto xy = r.numbers(n, "xy", 2, where);
    p.xy = {xy[0], xy[1]};
    p.yaw = r.number(n, "yaw", where);
    p.height_m = r.number(n, "height", where);
    p.pitch_rad = r.number(n, "pitch", where);
    p.roll_rad = r.number(n, "roll", where);
    p.time_s = static_cast<double>(t.frame_utimes.back()) * 1e-6;
    t.poses.push_back(p);
  }
  return t;
}

bool robotFits(const Eigen::Vector3d& room_size, const std::vector<Obstacle>& obstacles,
               const Eigen::Vector2d& xy, double robot_radius) {
  if (xy.x() < robot_radius || xy.y() < robot_radius || xy.x() > room_size.x() - robot_radius ||
      xy.y() > room_size.y() - robot_radius) {
    return false;
  }
  for (const auto& o : obstacles) {
    if (detail::insideConvex(o.polygon, xy, robot_radius)) return false;
  }
  return true;
}

SequenceGroundTruth writeSequence(const std::string& dir, const SequenceSpec& spec,
                                  const std::function<void(int, int)>& progress) {
  validate(spec.render);
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_empty(dir, ec))
    throw Error(dir + ": output folder exists and is not empty (refusing to mix sequences)");
  fs::create_directories(dir, ec);
  if (ec) throw Error(dir + ": cannot create (" + ec.message() + ")");

  SynthScene scene;
  std::vector<CameraPose> poses;
  if (spec.multi_room) {
    MultiRoomApartment apartment = makeMultiRoomApartment(spec.seed, spec.multi_room_params);
    poses = apartmentViews(apartment, spec.frames, spec.seed, spec.path);
    for (CameraPose& pose : poses) pose.time_s /= spec.fps;
    scene = std::move(apartment.scene);
  } else {
    scene = makeApartment(spec.seed, spec.apartment);
    poses = cameraPath(scene, spec.frames, spec.fps, spec.path);
  }
  SequenceGroundTruth truth;
  truth.seed = spec.seed;
  truth.fps = spec.fps;
  truth.width = spec.render.width;
  truth.height = spec.render.height;
  truth.intrinsics = spec.render.intrinsics;
  truth.room_size = scene.room_size;
  truth.tables = scene.tables;
  truth.obstacles = scene.obstacles;
  truth.poses = poses;
  for (int i = 0; i < spec.frames; ++i) {
    RenderedFrame r = render(scene, poses[i], spec.render, detail::hash3(spec.seed, i, 0xf4a3e));
    LabeledFrame& lf = r.labeled;
    // A multi-room apartment's frames carry its seed: several apartments train one model,
    // and the trainer wants every frame name once.
    lf.name = (spec.multi_room ? "apartment" + std::to_string(spec.seed) + "-" : "") + frameName(i);
    lf.frame.seq = i;
    lf.frame.utime = static_cast<std::uint64_t>(std::llround(i * 1e6 / spec.fps));
    lf.frame.source = (fs::path(dir) / "rgb" / (lf.name + ".png")).string();
    writeLabeledFrame(dir, lf);
    truth.frame_names.push_back(lf.name);
    truth.frame_utimes.push_back(lf.frame.utime);
    if (progress) progress(i + 1, spec.frames);
  }
  writeGroundTruth((fs::path(dir) / "ground_truth.yaml").string(), truth);
  return truth;
}

}  // namespace findmug::synth
