// tests/support/object_scenes.hpp — rendered table-top scenes with chosen
// objects, and table-top candidates taken from the renderer's ground truth,
// for the taught-object tests and tests/bench/object_recognition_eval.
//
// A candidate here is made from the pixels the renderer says show one object
// (RenderedFrame::object), not by findTableObjects: recognition is then
// measured alone, whatever the segmentation gets wrong.
// tableObjectFromPixels fills a TableObject the way table_objects.hpp
// describes it (centroid, height above the top, footprint PCA axes and
// half-lengths, mean colour, the colour histogram by the stage's own
// objectColourHistogram, the border bit) from ground-truth pixels, for tests
// that measure recognition without the segmentation's errors.
#pragma once

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/ground/ground.hpp"
#include "findmug/objects/object_model.hpp"
#include "findmug/objects/table_objects.hpp"
#include "findmug/synth/synth.hpp"

namespace findmug::test {

// A TableObject of `pixels` of an organized ground-frame cloud on a table
// whose top is at `top_z` (metres above the floor). Pixels without depth are
// left out; returns point_count 0 when none is left.
inline TableObject tableObjectFromPixels(const OrganizedCloud& cloud,
                                         const std::vector<int>& pixels, float top_z, int id = 0) {
  TableObject o;
  o.id = id;
  std::vector<Rgb8> rgb;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  float max_z = -1e9f;
  for (int p : pixels) {
    if (!cloud.valid(p)) continue;
    o.pixels.push_back(p);
    sum += cloud.points[p].cast<double>();
    max_z = std::max(max_z, cloud.points[p].z());
    rgb.push_back(cloud.colors[p]);
    const int x = p % cloud.width, y = p / cloud.width;
    if (x < 2 || y < 2 || x >= cloud.width - 2 || y >= cloud.height - 2) {
      o.truncation |= kTruncatedBorder;
    }
  }
  o.point_count = static_cast<int>(o.pixels.size());
  if (o.point_count == 0) return o;
  o.centroid = (sum / o.point_count).cast<float>();
  o.height_above_top = max_z - top_z;
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (int p : o.pixels) {
    const Eigen::Vector2d d = (cloud.points[p].head<2>() - o.centroid.head<2>()).cast<double>();
    cov += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
  o.major_axis = eig.eigenvectors().col(1).cast<float>().normalized();
  const Eigen::Vector2f minor(-o.major_axis.y(), o.major_axis.x());
  Eigen::Vector2f lo(1e9f, 1e9f), hi(-1e9f, -1e9f);
  for (int p : o.pixels) {
    const Eigen::Vector2f q = cloud.points[p].head<2>();
    const Eigen::Vector2f uv(q.dot(o.major_axis), q.dot(minor));
    lo = lo.cwiseMin(uv);
    hi = hi.cwiseMax(uv);
  }
  o.extents = (hi - lo) / 2.0f;
  const Eigen::Vector2f mid = (hi + lo) / 2.0f;
  o.center = mid.x() * o.major_axis + mid.y() * minor;
  Eigen::Vector3f mean_rgb = Eigen::Vector3f::Zero();
  for (const auto& c : rgb) mean_rgb += Eigen::Vector3f(c.r, c.g, c.b);
  o.mean_rgb = mean_rgb / static_cast<float>(rgb.size());
  o.colour_histogram = objectColourHistogram(rgb);
  return o;
}

// A model without rendering: `views` views of the front half of a cylinder
// (radius 4 cm, `height` m, `points` points each, turned a little per view),
// all one colour bin (`colour_bin`). For file and folder tests.
inline ObjectModel sampleObjectModel(const std::string& name, int views, int points = 200,
                                     float height = 0.10f, int colour_bin = 1) {
  ObjectModel m;
  m.name = name;
  for (int v = 0; v < views; ++v) {
    ObjectView view;
    view.height_above_top = height;
    view.extents = {0.045f, 0.025f};
    view.colour_histogram[colour_bin] = 1.0f;
    for (int i = 0; i < points; ++i) {
      const float a = 3.14159265f * ((i % 20) / 19.0f) + 0.1f * v;
      const float z = height * ((i / 20) % 10) / 9.0f - height / 2;
      view.points.emplace_back(0.04f * std::cos(a), 0.04f * std::sin(a), z);
      view.colors.push_back(Rgb8{200, 40, static_cast<std::uint8_t>(40 + i % 7)});
    }
    view.shape = objectShapeDescriptor(view.points);
    view.roundness = objectRoundnessResidual(view.points);
    m.views.push_back(std::move(view));
  }
  return m;
}

// ------------------------------------------------------------- scenes ----

struct TableScene {
  synth::SynthScene scene;
  Eigen::Vector2d table_center{3.0, 3.0};
  double top_z = 0.75;
};

// An empty 6 x 6 m room with one 1.4 x 0.9 m table (top at 0.75 m) in the middle.
inline TableScene makeTableScene() {
  TableScene t;
  t.scene = synth::makeEmptyRoom({6.0, 6.0, 2.6});
  const synth::Material wood{{150, 105, 65}, synth::Texture::Plain, 0.2f};
  std::vector<synth::Primitive> parts;
  auto box = [&](Eigen::Vector3d c, Eigen::Vector3d half) {
    synth::Primitive p;
    p.shape = synth::Shape::Box;
    p.center = c;
    p.half_extent = half;
    p.material = wood;
    parts.push_back(p);
  };
  const double cx = t.table_center.x(), cy = t.table_center.y();
  box({cx, cy, t.top_z - 0.015}, {0.7, 0.45, 0.015});
  for (int sx : {-1, 1})
    for (int sy : {-1, 1})
      box({cx + sx * 0.64, cy + sy * 0.39, (t.top_z - 0.03) / 2},
          {0.025, 0.025, (t.top_z - 0.03) / 2});
  synth::addObject(t.scene, "table", Label::Table, std::move(parts));
  return t;
}

inline synth::Primitive cylinderPart(Eigen::Vector3d c, double r, double half_h, Rgb8 colour) {
  synth::Primitive p;
  p.shape = synth::Shape::Cylinder;
  p.center = c;
  p.half_extent = {r, r, half_h};
  p.material = {colour, synth::Texture::Plain, 0.2f};
  return p;
}

inline synth::Primitive boxPart(Eigen::Vector3d c, double yaw, Eigen::Vector3d half, Rgb8 colour) {
  synth::Primitive p;
  p.shape = synth::Shape::Box;
  p.center = c;
  p.yaw = yaw;
  p.half_extent = half;
  p.material = {colour, synth::Texture::Plain, 0.2f};
  return p;
}

// A mug as findmug_synth's apartments make them: a cylinder and a handle.
inline int addMug(TableScene& t, Eigen::Vector2d xy, double radius, double height,
                  double handle_yaw, Rgb8 colour) {
  const double z = t.top_z;
  const Eigen::Vector2d h =
      xy + (radius + 0.012) * Eigen::Vector2d(std::cos(handle_yaw), std::sin(handle_yaw));
  return synth::addObject(
      t.scene, "mug", Label::Object,
      {cylinderPart({xy.x(), xy.y(), z + height / 2}, radius, height / 2, colour),
       boxPart({h.x(), h.y(), z + height * 0.55}, handle_yaw, {0.014, 0.006, height * 0.28},
               colour)});
}

// A box (or an upright book: kind "book") standing on the top.
inline int addBox(TableScene& t, const std::string& kind, Eigen::Vector2d xy, double yaw,
                  Eigen::Vector3d half, Rgb8 colour) {
  return synth::addObject(t.scene, kind, Label::Object,
                          {boxPart({xy.x(), xy.y(), t.top_z + half.z()}, yaw, half, colour)});
}

// A camera `distance` metres from the table centre on the floor, at bearing
// `bearing` (rad), 1.2 m high, looking at the table centre.
inline synth::CameraPose cameraAround(const TableScene& t, double bearing, double distance,
                                      double height = 1.2) {
  synth::CameraPose pose;
  pose.xy = t.table_center - distance * Eigen::Vector2d(std::cos(bearing), std::sin(bearing));
  pose.yaw = bearing;
  pose.height_m = height;
  pose.pitch_rad = std::atan2(height - t.top_z, distance);
  return pose;
}

struct RenderedTable {
  synth::RenderedFrame frame;
  OrganizedCloud cloud_ground;
};

inline RenderedTable renderTable(const TableScene& t, const synth::CameraPose& pose,
                                 std::uint64_t noise_seed) {
  RenderedTable r;
  r.frame = synth::render(t.scene, pose, synth::RenderOptions{}, noise_seed);
  const OrganizedCloud camera = frameToCloud(r.frame.labeled.frame);
  const GroundPlane ground = groundFromExtrinsics(*r.frame.labeled.frame.extrinsics);
  r.cloud_ground = transformCloud(camera, ground.camera_to_ground);
  return r;
}

// The candidate of scene object `object` in `r` (point_count 0 when unseen).
inline TableObject candidateOf(const RenderedTable& r, int object, float top_z, int id = 0) {
  std::vector<int> pixels;
  for (std::size_t i = 0; i < r.frame.object.size(); ++i) {
    if (r.frame.object[i] == object) pixels.push_back(static_cast<int>(i));
  }
  return tableObjectFromPixels(r.cloud_ground, pixels, top_z, id);
}

}  // namespace findmug::test
