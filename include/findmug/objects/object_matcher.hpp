// findmug/objects/object_matcher.hpp — which taught object (object_model.hpp),
// if any, each table-top candidate of a frame is.
//
// Per candidate and model, three gates in order, each against the model's
// views (a candidate passes a gate when one view passes it; the shape and
// colour distances are the minimum over the views):
//   1. size: the candidate's height above the top and the longer footprint
//      side are each within size_tolerance (relative) + size_tolerance_m of a
//      view's. A candidate cut by the image border or a depth hole
//      (TableObject::truncation) is only refused as too big: what is missing
//      may be the rest of the object.
//   2. colour: colourHistogramDistance (table_objects.hpp) at most
//      max_colour_distance.
//   3. shape: shapeDescriptorDistance of the candidate's ESF descriptor (of
//      its pixels' points in the cloud) at most max_shape_distance.
// A candidate that passes all three for some models is that model with the
// highest score, 1 - (colour/max_colour + shape/max_shape) / 2 (in [0, 1];
// ties: the first model in the list). Otherwise the result names the model
// that came nearest (through the most gates, then by the smallest excess over
// the failed gate's limit) and why it was refused, with the numbers, so that
// "why was my mug not found" can be answered from a log line. The shipped
// thresholds come from tests/bench/object_recognition_eval.cpp.
//
// Cost: the shape gate's ESF is about 27 ms per candidate that reaches it
// (up to 2000 points; one core of the development host), the other gates
// microseconds: a caller at frame rate should match off the frame's thread.
//
// Core code: plain types in and out, no LCM, no threads; deterministic.
#pragma once

#include <string>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/objects/object_model.hpp"
#include "findmug/objects/table_objects.hpp"
#include "findmug/settings/settings.hpp"

namespace findmug {

// Defaults from object_recognition_eval (30 rendered scenes, 4 unseen views
// each with and without the mug, ground-truth candidates): the taught mug's
// colour distance is at most 0.02 at the 95th percentile, other-coloured
// mugs' at least 0.26 at the 5th, so 0.20 sits between with room for real
// light. Its shape distance is at most 0.29 (3 taught views) or 0.23 (10) at
// the 95th percentile; 0.25 keeps a recall of 0.92 (3 views). ESF does not
// tell a mug from a box of its size and colour (their distances overlap);
// larger look-alikes are refused by size, which real segmentations' ragged
// outlines need 25 % + 2 cm of room for.
struct ObjectMatcherConfig {
  float size_tolerance = 0.25f;       // object_matcher.size_tolerance: relative part
  float size_tolerance_m = 0.02f;     // object_matcher.size_tolerance_m: absolute part
  float max_colour_distance = 0.20f;  // object_matcher.max_colour_distance (0..1)
  float max_shape_distance = 0.25f;   // object_matcher.max_shape_distance (0..1)
};

// Throws findmug::Error naming the setting (`object_matcher.KEY = value: rule`).
void validateObjectMatcherConfig(const ObjectMatcherConfig& config);

// The `object_matcher:` section of the config file, one key per field above.
const SettingsTable<ObjectMatcherConfig>& objectMatcherSettings();

struct ObjectMatch {
  // The model matched, or when none was: the nearest model ("" without models).
  std::string name;
  float score = 0.0f;  // in [0, 1] when matched; 0 when not
  // "" when matched; else why the nearest model refused it, beginning with
  // "too big", "too small", "wrong colour", "wrong shape", "too few points"
  // or "no models", then the numbers.
  std::string rejection;

  bool matched() const { return rejection.empty(); }
};

// One result per candidate, in the candidates' order. Throws findmug::Error
// when the config is out of range or a candidate's pixel is outside the cloud.
std::vector<ObjectMatch> matchObjects(const OrganizedCloud& cloud_ground,
                                      const std::vector<TableObject>& candidates,
                                      const std::vector<ObjectModel>& models,
                                      const ObjectMatcherConfig& config);

}  // namespace findmug
