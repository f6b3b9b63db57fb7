// findmug/objects/object_model.hpp — a taught object ("my mug") and its file.
//
// A person shows the robot an object from 1 to 10 views; each view is a
// table-top candidate (table_objects.hpp) of one frame. What is kept per view
// is what the matcher (object_matcher.hpp) compares, in the order it compares
// it: the size (height above the top, footprint), the colour histogram, and a
// global shape descriptor (PCL's Ensemble of Shape Functions, 640 bins, on the
// view's points about their centroid: needs no normals and does not depend on
// the scale, which the size gate checks). The view's points (at most
// kMaxObjectViewPoints, with colour) are kept too, so that a later descriptor
// can be computed from the file without teaching again.
//
// The model file (*.fmo, "findmug object") is a versioned little-endian
// binary file: the magic "FMOBJECT", u32 format version, u32 name length and
// the name, u32 view count, then per view: f32 height above the top, f32
// footprint half-lengths (2), f32 colour histogram (28), f32 shape
// descriptor (640), f32 roundness (from version 2), u32 point count and per
// point f32 x, y, z and u8 r, g, b. Nothing may follow. Loading checks every
// field and throws findmug::Error naming the file, the field and the value
// (bad magic, unknown version, truncation, NaN, counts out of range, a
// histogram not summing to 1, trailing bytes); a folder of models read by a
// daemon can then refuse a bad file with its reason and keep the good ones.
// A version 1 file loads with each view's roundness and shape descriptor
// computed from its stored points (version 1's ESF ran on all of them).
//
// Core code: no LCM, no threads. PCL stays in the .cpp.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/labels/labels.hpp"
#include "findmug/objects/table_objects.hpp"

namespace findmug {

// PCL's ESF signature: ten 64-bin shape-function histograms, here
// normalised so that all 640 bins sum to 1.
inline constexpr int kObjectShapeBins = 640;
using ObjectShapeDescriptor = std::array<float, kObjectShapeBins>;

inline constexpr int kMaxObjectViews = 10;
inline constexpr int kMaxObjectNameLength = 32;
// A view's points are subsampled (evenly, in pixel order) to at most this.
inline constexpr int kMaxObjectViewPoints = 2000;
// Fewer points do not make a shape (ESF samples point triples).
inline constexpr int kMinObjectViewPoints = 20;
// ESF runs on at most this many of a view's or candidate's points
// (object_recognition_eval: fewer cost less at the same accuracy).
inline constexpr int kObjectShapePoints = 500;
// Version 2 added each view's roundness; version 1 files load with it
// computed from the stored points (objectRoundnessResidual).
inline constexpr std::uint32_t kObjectModelFormatVersion = 2;
// The value of objectRoundnessResidual that says "not a vertical cylinder".
inline constexpr float kNotRound = 1.0f;

struct ObjectView {
  float height_above_top = 0.0f;  // metres, as TableObject::height_above_top
  // Footprint half-lengths along its first and second principal axes (first >= second).
  Eigen::Vector2f extents = Eigen::Vector2f::Zero();
  ObjectColourHistogram colour_histogram{};
  ObjectShapeDescriptor shape{};
  // objectRoundnessResidual of `points`: ~0.01-0.05 for a cylinder, more for a box.
  float roundness = kNotRound;
  // Ground-frame axes (z up), metres, about the view's centroid; same length.
  std::vector<Eigen::Vector3f> points;
  std::vector<Rgb8> colors;
};

struct ObjectModel {
  std::string name;               // [a-z0-9_-]{1,32}
  std::vector<ObjectView> views;  // 1..kMaxObjectViews
};

// Throws findmug::Error naming the name when it is not [a-z0-9_-]{1,32}.
void validateObjectModelName(const std::string& name);

// The ESF descriptor of `points` (any frame; they are centred here), of at
// most `max_points` of them taken evenly, normalised to sum 1. Deterministic:
// the same points give the same bits. Throws findmug::Error when there are
// fewer than kMinObjectViewPoints finite points or they do not span a
// surface (all on one line).
ObjectShapeDescriptor objectShapeDescriptor(const std::vector<Eigen::Vector3f>& points,
                                            int max_points = kObjectShapePoints);

// How far the side points of `points` (ground-frame axes, z up; below the top
// fifth of their height and above the lowest tenth) are from a vertical
// cylinder: a circle fitted to their x, y (RANSAC, then least squares on the
// points within 12 mm), and the RMS over 15-degree bins around it of each
// bin's mean distance off the circle (of the bin's middle half, less what its
// noise alone would give), relative to the radius. A cylinder gives about
// 0.01-0.05 near, a box's L of faces 0.08 or more; a single face (a circle
// much wider than the points) or too few side points give kNotRound, the
// largest value. In [0, kNotRound]; deterministic; about a millisecond.
float objectRoundnessResidual(const std::vector<Eigen::Vector3f>& points);

// Half the L1 distance of two shape descriptors: 0 equal, 1 disjoint.
float shapeDescriptorDistance(const ObjectShapeDescriptor& a, const ObjectShapeDescriptor& b);

// The finite points of `pixels` in `cloud`, evenly subsampled to at most
// `max_points`, with their colours (pixel order).
void objectPointsOf(const OrganizedCloud& cloud, const std::vector<int>& pixels, int max_points,
                    std::vector<Eigen::Vector3f>& points, std::vector<Rgb8>& colors);

// One taught view of `candidate` (a table-top candidate of `cloud_ground`):
// its size and colour histogram as the candidate has them, its points
// (candidate.pixels) about their centroid and their shape descriptor.
// Throws findmug::Error when a pixel is outside the cloud or the candidate
// has too few points for a shape.
ObjectView makeObjectView(const OrganizedCloud& cloud_ground, const TableObject& candidate);
// The same from the candidate's points already taken out of the cloud
// (objectPointsOf with kMaxObjectViewPoints, ground frame): what a caller that
// keeps candidates past their frame (findmugd's teacher) holds. The overload
// above is this after objectPointsOf, so both give the same view. Throws
// findmug::Error for too few points, more than kMaxObjectViewPoints, or
// colours not one per point.
ObjectView makeObjectView(const TableObject& candidate, std::vector<Eigen::Vector3f> points,
                          std::vector<Rgb8> colors);

// Adds `view` to the model `name` in the file `path`: a new model when the
// file does not exist, else one more view of the model it holds. Written with
// saveObjectModel (temporary file, rename). Returns the model's view count
// now. Throws findmug::Error when the name is not valid, the file holds
// another name or cannot be read, or the model has kMaxObjectViews already.
int addObjectViewToFile(const std::string& path, const std::string& name, ObjectView view);

// Throws findmug::Error ("object model WHAT: FIELD = VALUE: rule") when a
// field is outside what a file may hold (the checks loading makes).
void validateObjectModel(const ObjectModel& model, const std::string& what);

// The file's bytes, and back. decodeObjectModel names `what` (the file) in
// its errors and refuses anything loadObjectModel refuses.
std::vector<std::uint8_t> encodeObjectModel(const ObjectModel& model);
ObjectModel decodeObjectModel(const std::uint8_t* data, std::size_t size, const std::string& what);

// Writes `path` through a temporary file in the same folder renamed over it,
// so that a reader never sees half a file. Validates the model first.
void saveObjectModel(const std::string& path, const ObjectModel& model);
ObjectModel loadObjectModel(const std::string& path);

}  // namespace findmug
