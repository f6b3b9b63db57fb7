// semantic_map_picture.hpp — findmugd's fused semantic map (FINDMUG_SEMANTIC_MAP,
// semantic_map_t) drawn top-down for people: findmug-label-viewer's semantic_map.png and
// the raster findmug-web's live page lays under its table map.
//
// Looking down on a room, the ceiling hides everything and the floor is under everything;
// what a person wants to see in a floor cell is the top of what stands there. So each
// floor cell (voxel column i, j) shows its highest occupied voxel that is below
// kTopDownMaxHeightM and not labelled ceiling: the floor where nothing stands, a table top,
// a chair seat, a wall. Its colour is the label's (the paper's palette), faded towards
// white by how little the map is sure of it (the share of the votes the label has).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "findmug/frame/image_io.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/semantic_map_codec.hpp"
#include "findmug/labels/labels.hpp"

namespace findmug::clients {

// Voxels whose centre is this high or higher are not drawn (door frames, lamps, the
// ceiling's underside mislabelled as wall).
inline constexpr float kTopDownMaxHeightM = 2.0f;
// A cell without a shown voxel.
inline constexpr std::uint8_t kNoCell = 255;

// The map's floor cells as a raster, row 0 the highest j (y up is the image's up),
// column 0 the lowest i: cell (i, j) is at [(max_j - j) * width + (i - min_i)].
struct TopDownCells {
  float voxel_size_m = 0.05f;
  int min_i = 0, max_j = 0;  // the raster's corner cell
  int width = 0, height = 0;
  std::vector<std::uint8_t> label;       // width * height, kNoCell where none
  std::vector<std::uint8_t> confidence;  // 0..255, 0 where none
  std::size_t cells = 0;                 // cells with a label
};
TopDownCells topDownCells(const io::SemanticMapMessage& map);

// The label's colour faded towards white: confidence 255 is the full colour, 0 a quarter
// of it (still tells which label).
Rgb8 shadedLabelColor(std::uint8_t label, std::uint8_t confidence);

// Where the picture puts the map frame: square, `margin` pixels around a view that holds
// the cells, the table hulls and the robot with 0.5 m to spare.
struct TopDownView {
  double min_x = 0.0, max_y = 0.0, scale = 100.0;  // scale: pixels per metre
  int margin = 30;
  Eigen::Vector2d px(double x, double y) const {
    return {margin + (x - min_x) * scale, margin + (max_y - y) * scale};
  }
};
TopDownView semanticMapView(const TopDownCells& cells, const io::TablesMessage* table_map,
                            int size_px);

// The picture: the cells, a 1 m grid, the tables of `table_map` (FINDMUG_TABLE_MAP, drawn
// in the map frame with their ids and, from the semantic map, the frames and viewpoints
// that support them; null or without a map pose: none) and the robot at the table map's
// pose. The view covers the cells and the tables, square, `size_px` pixels a side.
Image<Rgb8> semanticMapPng(const io::SemanticMapMessage& map, const io::TablesMessage* table_map,
                           int size_px = 600);

}  // namespace findmug::clients
