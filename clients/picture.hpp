// picture.hpp — the pictures findmug's clients draw for people: a label legend, table
// hulls, numbered search positions and object candidates over the camera image, and a top-down
// table map (PNG and SVG) with the robot's pose. Plain RGB canvases; text in a built-in 5x7 font
// (no font library on a robot PC).
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "findmug/frame/frame.hpp"
#include "findmug/frame/image_io.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/labels/labels.hpp"

namespace findmug::clients {

class Canvas {
 public:
  Canvas(int width, int height, Rgb8 background);
  explicit Canvas(Image<Rgb8> image) : image_(std::move(image)) {}
  int width() const { return image_.width; }
  int height() const { return image_.height; }
  const Image<Rgb8>& image() const { return image_; }

  void pixel(int x, int y, Rgb8 colour);  // ignored outside
  void fillRect(int x, int y, int w, int h, Rgb8 colour);
  void line(double x0, double y0, double x1, double y1, Rgb8 colour, int thickness = 1);
  void disc(double cx, double cy, double radius, Rgb8 colour);
  void circle(double cx, double cy, double radius, Rgb8 colour, int thickness = 1);
  // Upper-case 5x7 glyphs (letters are drawn upper-case), `scale` pixels per dot.
  void text(int x, int y, const std::string& text, Rgb8 colour, int scale = 1);
  static int textWidth(const std::string& text, int scale = 1) {
    return text.empty() ? 0 : static_cast<int>(text.size()) * 6 * scale - scale;
  }
  static int textHeight(int scale = 1) { return 7 * scale; }
  // `other` copied with its top-left corner at (x, y).
  void paste(const Image<Rgb8>& other, int x, int y);

 private:
  Image<Rgb8> image_;
};

// The label overlay with a legend panel to its right: one swatch per class, void, and
// the search-position markers.
Image<Rgb8> withLegend(const Image<Rgb8>& overlay);

// Search positions of a tables message, numbered 1.. in the visiting order from the robot
// (base frame: the origin; map frame: map_pose), unreachable ones after them unnumbered.
struct NumberedPosition {
  int table = 0;
  SearchPosition position;  // in the frame asked for
  int order = 0;            // 1.. visiting order; 0 = unreachable
};
std::vector<NumberedPosition> numberedPositions(const io::TablesMessage& message, bool map_frame);

// Table hulls (at table-top height) and search positions (on the floor) of `tables`
// (base frame) projected into the image of a camera mounted as `extrinsics`.
// Returns how many tables had at least one hull point in front of the camera.
// With the frame's depth (millimetres, same size as the canvas), a search position that
// lies behind what the camera saw there (occluded, e.g. beyond the table) is drawn as a
// ring only, so that it is not mistaken for a spot on the surface in front of it.
int drawTablesInImage(Canvas& canvas, const io::TablesMessage& tables,
                      const CameraIntrinsics& intrinsics, const CameraExtrinsics& extrinsics,
                      const std::vector<std::uint16_t>* depth_mm = nullptr);
// The same for a camera at `camera_to_base` (p_base = camera_to_base * p_camera), as the
// daemon reports it with each label image (label_image_t.camera_to_base).
int drawTablesInImage(Canvas& canvas, const io::TablesMessage& tables,
                      const CameraIntrinsics& intrinsics, const Eigen::Isometry3d& camera_to_base,
                      const std::vector<std::uint16_t>* depth_mm = nullptr);

// The object candidates of an objects message (base frame) as markers at their centroids
// projected into the image of a camera at `camera_to_base`: a disc in the candidate's mean
// colour inside a white ring, its id ("O<id>") beside it. Returns how many were in front of
// the camera. The candidates' pixels are not on the wire, hence a marker, not an outline.
int drawObjectsInImage(Canvas& canvas, const io::ObjectsMessage& objects,
                       const CameraIntrinsics& intrinsics, const Eigen::Isometry3d& camera_to_base);
// The same for a camera mounted as `extrinsics` (older daemons: the colour frame's mount).
int drawObjectsInImage(Canvas& canvas, const io::ObjectsMessage& objects,
                       const CameraIntrinsics& intrinsics, const CameraExtrinsics& extrinsics);

// Top-down view of a tables message: the map frame with the robot at map_pose when the
// message has one (FINDMUG_TABLE_MAP), else the base frame with the robot at the origin.
// x to the right, y up, a 1 m grid; hulls, ids, numbered search positions, the robot.
Image<Rgb8> tableMapPng(const io::TablesMessage& tables, int size_px = 600);
std::string tableMapSvg(const io::TablesMessage& tables, int size_px = 600);

}  // namespace findmug::clients
