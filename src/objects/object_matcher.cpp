// Matching table-top candidates against taught objects (object_matcher.hpp):
// size, then colour, then roundness, then ESF shape, cheapest first, so that
// the ESF descriptor (milliseconds) is computed only for a candidate some
// model's size, colour and roundness let through.
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

constexpr int kGates = 4;  // size, colour, roundness, shape

// How far a candidate got with one model: the gates passed (0..kGates) and, for
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

// The least roundness residual of the model's views: the model is round (and
// the roundness gate applies) when it is at most max_roundness_residual.
float modelRoundness(const ObjectModel& model) {
  float best = kNotRound;
  for (const auto& view : model.views) best = std::min(best, view.roundness);
  return best;
}

// The candidate's points, roundness and shape descriptor, each computed on
// first use (only candidates that pass the cheaper gates pay for them).
class CandidateShape {
 public:
  CandidateShape(const OrganizedCloud& cloud, const TableObject& candidate)
      : cloud_(cloud), candidate_(candidate) {}

  // nullptr with failure() when there are too few points for a shape.
  const std::vector<Eigen::Vector3f>* points() {
    if (!have_points_) collectPoints();
    return point_count_ < kMinObjectViewPoints ? nullptr : &points_;
  }
  float roundness() {
    if (!roundness_) roundness_ = objectRoundnessResidual(points_);
    return *roundness_;
  }
  // nullptr with failure() when its points make no shape.
  const ObjectShapeDescriptor* descriptor() {
    if (!computed_) computeDescriptor();
    return descriptor_ ? &*descriptor_ : nullptr;
  }
  const std::string& failure() const { return failure_; }

 private:
  void collectPoints() {
    have_points_ = true;
    std::vector<Rgb8> colors;
    objectPointsOf(cloud_, candidate_.pixels, kMaxObjectViewPoints, points_, colors);
    point_count_ = static_cast<int>(points_.size());
    if (point_count_ < kMinObjectViewPoints) {
      failure_ = "too few points: " + std::to_string(point_count_) + " with depth, need " +
                 std::to_string(kMinObjectViewPoints);
    }
  }
  void computeDescriptor() {
    computed_ = true;
    try {
      descriptor_ = objectShapeDescriptor(points_);
    } catch (const Error& e) {
      failure_ = std::string("wrong shape: ") + e.what();
    }
  }

  const OrganizedCloud& cloud_;
  const TableObject& candidate_;
  bool have_points_ = false;
  bool computed_ = false;
  int point_count_ = 0;
  std::vector<Eigen::Vector3f> points_;
  std::optional<float> roundness_;
  std::optional<ObjectShapeDescriptor> descriptor_;
  std::string failure_;
};

Verdict shapeFailure(int gates_passed, const std::string& why) {
  Verdict v;
  v.gates_passed = gates_passed;
  v.excess = std::numeric_limits<float>::infinity();
  v.rejection = why;
  return v;
}

// A round model (a mug) refuses a candidate whose side is no cylinder.
std::optional<Verdict> roundnessRejection(CandidateShape& shape, const ObjectModel& model,
                                          const ObjectMatcherConfig& config) {
  const float taught = modelRoundness(model);
  if (taught > config.max_roundness_residual) return std::nullopt;
  const float measured = shape.roundness();
  if (measured <= config.max_roundness_residual) return std::nullopt;
  Verdict v;
  v.gates_passed = 2;
  v.excess =
      (measured - config.max_roundness_residual) / std::max(config.max_roundness_residual, 1e-6f);
  v.rejection = "wrong shape: not round: roundness residual " + number(measured) + " > " +
                number(config.max_roundness_residual) + " (taught " + number(taught) + ")";
  return v;
}

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
  if (shape.points() == nullptr) return shapeFailure(2, shape.failure());
  if (auto refused = roundnessRejection(shape, model, config)) return *refused;
  const ObjectShapeDescriptor* d = shape.descriptor();
  if (d == nullptr) return shapeFailure(3, shape.failure());
  const float distance = nearestShape(*d, model);
  if (distance > config.max_shape_distance) {
    v.gates_passed = 3;
    v.excess = (distance - config.max_shape_distance) / std::max(config.max_shape_distance, 1e-6f);
    v.rejection =
        "wrong shape: distance " + number(distance) + " > " + number(config.max_shape_distance);
    return v;
  }
  v.gates_passed = kGates;
  const float colour_part = colour / std::max(config.max_colour_distance, 1e-6f);
  const float shape_part = distance / std::max(config.max_shape_distance, 1e-6f);
  v.score = std::clamp(1.0f - 0.5f * (colour_part + shape_part), 0.0f, 1.0f);
  return v;
}

// Nearer: through more gates, then less beyond the failed gate's limit
// (or, when both matched, a higher score).
bool nearer(const Verdict& a, const Verdict& b) {
  if (a.gates_passed != b.gates_passed) return a.gates_passed > b.gates_passed;
  if (a.gates_passed == kGates) return a.score > b.score;
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
  if (best->gates_passed == kGates) {
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
  if (!std::isfinite(c.max_roundness_residual) || c.max_roundness_residual < 0.0f ||
      c.max_roundness_residual > kNotRound) {
    badMatcherSetting("max_roundness_residual", c.max_roundness_residual, "must be in [0, 1]");
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
    t.add(numberSetting<M, float>(
        "object_matcher.max_roundness_residual",
        [](M& m) -> float& { return m.max_roundness_residual; }, 0, kNotRound,
        "a taught object this round (a mug) refuses candidates less round: side points' residual "
        "off a vertical cylinder, relative to its radius"));
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
