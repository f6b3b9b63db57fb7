// findmug/objects/table_objects.hpp — the objects standing on table tops.
//
// The stage after tables (tables.hpp): for every table of a frame, the points
// above its top are clustered into object candidates, the things a robot
// asked to "find my mug" must look at. Per frame, in the ground-aligned frame
// of ground.hpp (z up, floor at z = 0): plain types in, plain types out, no
// LCM, no threads, no logging (diagnostics are returned).
//
// Steps of findTableObjects, per table:
//   1. points above the top: finite points whose height above the table's top
//      (the local top under them, see top_cell_m) is within
//      [min_height_m, max_height_m] and whose floor position lies
//      inside the table's hull grown by outline_margin_m (so that an object at
//      the edge, whose footprint hides the top under it, still counts). Points
//      labelled floor, wall or ceiling are left out: a wall behind a table
//      rises through the grown outline but stands on nothing.
//   2. Euclidean clustering of those points with cluster_tolerance_m (the
//      exact partition of euclideanClusterLabels, tables.hpp; with
//      point_stride > 1 a sample of them linked on the image grid, the others
//      joining a sampled image neighbour's cluster); clusters with fewer than min_points points
//      are dropped and counted.
//   3. a cluster is a candidate when it stands on the top: its lowest point is
//      at most max_base_height_m above the top, its footprint centroid is
//      inside the hull (not only in the margin), and its footprint is at most
//      max_extent_m along its longer principal axis (a chair back at the table
//      edge or a monitor wall behind it are not objects on the table). A
//      cluster that fails and holds several labels (clutter joined through
//      unlabelled or table points between the things) is split by label:
//      each label's points but the table's are clustered alone and the parts
//      that stand are candidates (a mug labelled half table, half object stands as one
//      cluster and is never split).
//   4. per candidate: centroid, height above the top, footprint axes and
//      half-lengths, point count, mean colour and colour histogram, and why it
//      may be incomplete (truncation flags below).
// A point is in at most one table's candidates: the first table (by index)
// whose grown outline and height band (widened by max_base_height_m for the
// local tops) hold it.
//
// relabelTableObjects then labels a candidate's pixels Object where the label
// image says Table (the forest often calls a mug on a table "table"; other
// labels are left as they are).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/labels/label_image.hpp"
#include "findmug/tables/tables.hpp"

namespace findmug {

// Colour histogram of a candidate's pixels, normalised to sum 1. Chromatic
// pixels (HSV saturation >= 0.2 and value >= 0.15) fall into one of 12 hue
// sectors of 30° (sector 0: hue [0°, 30°), red) x 2 saturation bands
// ([0.2, 0.5), [0.5, 1]): bin 2 * sector + band (0..23); the others into 4
// bands of value by quarters (bins 24..27: black, dark grey, light grey,
// white). Hue and saturation change little with the light's brightness; value does.
inline constexpr int kObjectColourBins = 28;
using ObjectColourHistogram = std::array<float, kObjectColourBins>;

// Why a candidate may be only part of the object (bits of TableObject::truncation).
enum TableObjectTruncation : std::uint8_t {
  kTruncatedOutline = 1,  // points within 1 cm of the grown outline: may go on past it
  kTruncatedBorder = 2,   // pixels on the image border (2 px)
  kTruncatedDepthHole = 4,  // a quarter or more of its edge pixels border missing depth
};

struct TableObject {
  int id = 0;     // 0..n-1 within the frame, by table then decreasing point count
  int table = 0;  // index of the table it stands on in the frame's tables
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();  // mean of its points
  // Its highest point above the top (the local top under it, top_cell_m), metres.
  float height_above_top = 0.0f;
  // Footprint on the floor: first principal axis (unit; the second is it
  // turned +90°) and half-lengths along them, about the footprint's box centre.
  Eigen::Vector2f major_axis = Eigen::Vector2f::UnitX();
  Eigen::Vector2f extents = Eigen::Vector2f::Zero();
  Eigen::Vector2f center = Eigen::Vector2f::Zero();
  int point_count = 0;
  Eigen::Vector3f mean_rgb = Eigen::Vector3f::Zero();  // 0..255
  ObjectColourHistogram colour_histogram{};
  std::uint8_t truncation = 0;  // TableObjectTruncation bits
  // Image pixels (y * width + x) of its points, ascending.
  std::vector<int> pixels;
};

struct TableObjectConfig {
  bool enabled = true;            // table_objects.enabled
  float min_height_m = 0.01f;     // above the top: less is the top itself (depth noise)
  float max_height_m = 0.40f;     // above the top: more is a shelf, a lamp shade, a person
  float outline_margin_m = 0.05f; // the top's hull grown by this
  float cluster_tolerance_m = 0.025f;
  int min_points = 30;            // a 5 cm mug 3 m away covers about 60 pixels
  float max_base_height_m = 0.05f;  // lowest point at most this above the top: it stands there
  float max_extent_m = 0.6f;      // longer footprint side (2 x half-length) at most this
  // > 0: heights are taken above the local top, the mean height of the
  // table's points within max_base_height_m of its top height in each cell of
  // this size (m) on the floor (cells with fewer than 3: the top height). A
  // top seen a few degrees tilted (NYU's gravity is 0.75..6.35° off) otherwise
  // rises above min_height_m at one end. 0 (default): above the table's top
  // height everywhere. Off by default: on quantised Kinect depth (steps of 1-2
  // cm at 2-3 m) a cell's mean lies between the steps and the upper step of
  // the top becomes candidates (rendered frames: 55 of 140 candidates mostly
  // not object pixels with 0.1 m cells, 2 of 94 without).
  float top_cell_m = 0.0f;
  // > 1: step 2 clusters only every point_stride-th pixel of every
  // point_stride-th row, on the image grid (sampled points up to 2 sampled
  // steps apart in the image and within cluster_tolerance_m are linked), and
  // each other point joins the cluster of a sampled image neighbour (of the
  // four around it, else of the twelve around those) within
  // cluster_tolerance_m, or none (clusterSampled in
  // table_objects.cpp). The candidates keep all their points. 1: the exact
  // Euclidean clustering of every point. See BENCHMARKS.md section 8 for
  // what each costs and finds.
  int point_stride = 2;
  // Label a candidate's table-labelled pixels Object (relabelTableObjects).
  bool relabel = false;
};

struct TableObjectDetection {
  std::vector<TableObject> objects;
  std::vector<std::string> diagnostics;  // one line per reason something was dropped
  int points_above_tops = 0;             // points that passed step 1
  int clusters_too_small = 0;            // step 2
  int clusters_not_standing = 0;         // step 3: base too high, centroid off the top, too big
};

// Throws findmug::Error naming the setting (`table_objects.KEY = value: rule`).
void validateTableObjectConfig(const TableObjectConfig& config);

// The candidates on `tables` (as detectTables found them in `cloud_ground`
// with `labels`). Throws findmug::Error when the cloud and the label image
// differ in size or a setting is out of range. An empty cloud or no tables:
// no candidates. With config.enabled false: no candidates, nothing computed.
TableObjectDetection findTableObjects(const OrganizedCloud& cloud_ground, const LabelImage& labels,
                                      const std::vector<TableCluster>& tables,
                                      const TableObjectConfig& config);
// The same into `out`, whose objects (from an earlier frame) lend their
// buffers; every field of `out` is replaced.
void findTableObjectsInto(const OrganizedCloud& cloud_ground, const LabelImage& labels,
                          const std::vector<TableCluster>& tables,
                          const TableObjectConfig& config, TableObjectDetection& out);

// Labels Object each candidate pixel that `labels` has as Table; returns how
// many pixels changed. Throws findmug::Error when a pixel is out of range.
int relabelTableObjects(const std::vector<TableObject>& objects, LabelImage& labels);

// The colour histogram of `rgb` values (see ObjectColourHistogram); all zero
// when `rgb` is empty.
ObjectColourHistogram objectColourHistogram(const std::vector<Rgb8>& rgb);

// 1 - the Bhattacharyya coefficient of two histograms (each summing to 1):
// 0 for equal colours, 1 for colours with no bin in common. A histogram that
// is all zero (no pixels) is at distance 1 from everything.
// (src/objects/colour_distance.cpp)
float colourHistogramDistance(const ObjectColourHistogram& a, const ObjectColourHistogram& b);

}  // namespace findmug
