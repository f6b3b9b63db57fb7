// Matching table-top candidates against taught objects (object_matcher.hpp):
// size, then colour, then shape, cheapest first, so that the ESF descriptor
// (milliseconds) is computed only for a candidate some model's size and colour
// let through.
#include "findmug/objects/object_matcher.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <sstream>

#include "findmug/common/error.hpp"

namespace findmug {
namespace {

[[noreturn]] void badMatcherSetting(const char* key, float value, const char* rule) {
  std::ostringstream msg;
  msg << "object_matcher." << key << " = " << value << ": " << rule;
  throw Error(msg.str());
}

std::string metres(float v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.3f m", static_cast<double>(v));
  return buf;
}

std::string number(float v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.3f", static_cast<double>(v));
  return buf;
}

// How far a candidate got with one model: the gates passed (0..3) and, for
// the gate it failed, how far beyond the limit, relative to the limit.
struct Verdict {
  int gates_passed = 0;
  float excess = 0.0f;
  float score = 0.0f;
  std::string rejection;
};

// The size gate against one view: the worst of the two dimensions.
struct SizeCheck {
  float violation = -std::numeric_limits<float>::infinity();  // > 0: out by this (m)
  float allowed = 1.0f;
  const char* dimension = "height";
  float measured = 0.0f, taught = 0.0f;
};

SizeCheck checkSizeAgainstView(const TableObject& c, const ObjectView& v, bool may_be_larger,
                               const ObjectMatcherConfig& config) {
  const float c_length = 2.0f * std::max(c.extents.x(), c.extents.y());
  const float v_length = 2.0f * v.extents.x();
  const float measured[2] = {c.height_above_top, c_length};
  const float taught[2] = {v.height_above_top, v_length};
  const char* names[2] = {"height", "footprint length"};
  SizeCheck worst;
  for (int d = 0; d < 2; ++d) {
    const float allowed = config.size_tolerance * taught[d] + config.size_tolerance_m;
    const float diff = measured[d] - taught[d];
    // A truncated candidate may be a part of a bigger object: smaller is no evidence.
    const float violation = (diff < 0.0f && may_be_larger) ? -allowed : std::abs(diff) - allowed;
    if (violation > worst.violation) {
      worst = {violation, allowed, names[d], measured[d], taught[d]};
    }
  }
  return worst;
}

std::optional<Verdict> sizeRejection(const TableObject& c, const ObjectModel& model,
                                     const ObjectMatcherConfig& config) {
  const bool truncated = (c.truncation & (kTruncatedBorder | kTruncatedDepthHole)) != 0;
  SizeCheck best;
  best.violation = std::numeric_limits<float>::infinity();
  for (const auto& view : model.views) {
    const SizeCheck s = checkSizeAgainstView(c, view, truncated, config);
    if (s.violation < best.violation) best = s;
  }
  if (best.violation <= 0.0f) return std::nullopt;
  Verdict v;
  v.gates_passed = 0;
  v.excess = best.violation / best.allowed;
  v.rejection = std::string(best.measured > best.taught ? "too big" : "too small") + ": " +
                best.dimension + " " + metres(best.measured) + ", taught " + metres(best.taught) +
                " (tolerance " + metres(best.allowed) + ")";
  return v;
}

float nearestColour(const TableObject& c, const ObjectModel& model) {
  float best = 1.0f;
  for (const auto& view : model.views) {
    best = std::min(best, colourHistogramDistance(c.colour_histogram, view.colour_histogram));
  }
  return best;
}

float nearestShape(const ObjectShapeDescriptor& d, const ObjectModel& model) {
  float best = 1.0f;
  for (const auto& view : model.views)
    best = std::min(best, shapeDescriptorDistance(d, view.shape));
  return best;
}

// The candidate's shape descriptor, computed on first use; nullopt with the
// reason when its points make no shape.
class CandidateShape {
 public:
  CandidateShape(const OrganizedCloud& cloud, const TableObject& candidate)
      : cloud_(cloud), candidate_(candidate) {}

  const ObjectShapeDescriptor* get() {
    if (!computed_) compute();
    return descriptor_ ? &*descriptor_ : nullptr;
  }
  const std::string& failure() const { return failure_; }
  int pointCount() const { return point_count_; }

 private:
  void compute() {
    computed_ = true;
    std::vector<Eigen::Vector3f> points;
    std::vector<Rgb8> colors;
    objectPointsOf(cloud_, candidate_.pixels, kMaxObjectViewPoints, points, colors);
    point_count_ = static_cast<int>(points.size());
    if (point_count_ < kMinObjectViewPoints) {
      failure_ = "too few points: " + std::to_string(point_count_) + " with depth, need " +
                 std::to_string(kMinObjectViewPoints);
      return;
    }
    try {
      descriptor_ = objectShapeDescriptor(points);
    } catch (const Error& e) {
      failure_ = std::string("wrong shape: ") + e.what();
    }
  }

  const OrganizedCloud& cloud_;
  const TableObject& candidate_;
  bool computed_ = false;
  int point_count_ = 0;
  std::optional<ObjectShapeDescriptor> descriptor_;
  std::string failure_;
};

Verdict judge(const TableObject& c, CandidateShape& shape, const ObjectModel& model,
              const ObjectMatcherConfig& config) {
  if (auto refused = sizeRejection(c, model, config)) return *refused;
  Verdict v;
  const float colour = nearestColour(c, model);
  if (colour > config.max_colour_distance) {
    v.gates_passed = 1;
    v.excess = (colour - config.max_colour_distance) / std::max(config.max_colour_distance, 1e-6f);
    v.rejection =
        "wrong colour: distance " + number(colour) + " > " + number(config.max_colour_distance);
    return v;
  }
  const ObjectShapeDescriptor* d = shape.get();
  if (d == nullptr) {
    v.gates_passed = 2;
    v.excess = std::numeric_limits<float>::infinity();
    v.rejection = shape.failure();
    return v;
  }
  const float distance = nearestShape(*d, model);
  if (distance > config.max_shape_distance) {
    v.gates_passed = 2;
    v.excess = (distance - config.max_shape_distance) / std::max(config.max_shape_distance, 1e-6f);
    v.rejection =
        "wrong shape: distance " + number(distance) + " > " + number(config.max_shape_distance);
    return v;
  }
  v.gates_passed = 3;
  const float colour_part = colour / std::max(config.max_colour_distance, 1e-6f);
  const float shape_part = distance / std::max(config.max_shape_distance, 1e-6f);
  v.score = std::clamp(1.0f - 0.5f * (colour_part + shape_part), 0.0f, 1.0f);
  return v;
}

// Nearer: through more gates, then less beyond the failed gate's limit
// (or, when both matched, a higher score).
bool nearer(const Verdict& a, const Verdict& b) {
  if (a.gates_passed != b.gates_passed) return a.gates_passed > b.gates_passed;
  if (a.gates_passed == 3) return a.score > b.score;
  return a.excess < b.excess;
}

void checkPixels(const OrganizedCloud& cloud, const TableObject& c) {
  for (int p : c.pixels) {
    if (p < 0 || static_cast<std::size_t>(p) >= cloud.size()) {
      throw Error("object matcher: candidate " + std::to_string(c.id) + " has pixel " +
                  std::to_string(p) + " outside the " + std::to_string(cloud.width) + "x" +
                  std::to_string(cloud.height) + " cloud");
    }
  }
}

ObjectMatch matchCandidate(const OrganizedCloud& cloud, const TableObject& c,
                           const std::vector<ObjectModel>& models,
                           const ObjectMatcherConfig& config) {
  checkPixels(cloud, c);
  if (models.empty()) return {"", 0.0f, "no models"};
  CandidateShape shape(cloud, c);
  std::optional<Verdict> best;
  std::size_t best_model = 0;
  for (std::size_t m = 0; m < models.size(); ++m) {
    Verdict v = judge(c, shape, models[m], config);
    if (!best || nearer(v, *best)) {
      best = std::move(v);
      best_model = m;
    }
  }
  ObjectMatch match;
  match.name = models[best_model].name;
  if (best->gates_passed == 3) {
    match.score = best->score;
  } else {
    match.rejection = best->rejection;
  }
  return match;
}

}  // namespace

void validateObjectMatcherConfig(const ObjectMatcherConfig& c) {
  if (!std::isfinite(c.size_tolerance) || c.size_tolerance < 0.0f || c.size_tolerance > 10.0f) {
    badMatcherSetting("size_tolerance", c.size_tolerance, "must be in [0, 10]");
  }
  if (!std::isfinite(c.size_tolerance_m) || c.size_tolerance_m < 0.0f ||
      c.size_tolerance_m > 1.0f) {
    badMatcherSetting("size_tolerance_m", c.size_tolerance_m, "must be in [0, 1] m");
  }
  if (!std::isfinite(c.max_colour_distance) || c.max_colour_distance < 0.0f ||
      c.max_colour_distance > 1.0f) {
    badMatcherSetting("max_colour_distance", c.max_colour_distance, "must be in [0, 1]");
  }
  if (!std::isfinite(c.max_shape_distance) || c.max_shape_distance < 0.0f ||
      c.max_shape_distance > 1.0f) {
    badMatcherSetting("max_shape_distance", c.max_shape_distance, "must be in [0, 1]");
  }
}

const SettingsTable<ObjectMatcherConfig>& objectMatcherSettings() {
  using M = ObjectMatcherConfig;
  static const SettingsTable<M> table = [] {
    SettingsTable<M> t("object_matcher");
    t.add(numberSetting<M, float>(
        "object_matcher.size_tolerance", [](M& m) -> float& { return m.size_tolerance; }, 0, 10,
        "height and footprint length may differ from a taught view's by this fraction ..."));
    t.add(numberSetting<M, float>(
        "object_matcher.size_tolerance_m", [](M& m) -> float& { return m.size_tolerance_m; }, 0, 1,
        "... plus this many metres (depth noise on small objects)"));
    t.add(numberSetting<M, float>(
        "object_matcher.max_colour_distance", [](M& m) -> float& { return m.max_colour_distance; },
        0, 1, "colour histograms at most this far apart (1 - Bhattacharyya coefficient)"));
    t.add(numberSetting<M, float>(
        "object_matcher.max_shape_distance", [](M& m) -> float& { return m.max_shape_distance; }, 0,
        1, "ESF shape descriptors at most this far apart (half the L1 distance)"));
    return t;
  }();
  return table;
}

std::vector<ObjectMatch> matchObjects(const OrganizedCloud& cloud_ground,
                                      const std::vector<TableObject>& candidates,
                                      const std::vector<ObjectModel>& models,
                                      const ObjectMatcherConfig& config) {
  validateObjectMatcherConfig(config);
  std::vector<ObjectMatch> out;
  out.reserve(candidates.size());
  for (const auto& c : candidates) out.push_back(matchCandidate(cloud_ground, c, models, config));
  return out;
}

}  // namespace findmug
