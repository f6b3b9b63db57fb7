// object_recognition_eval — how well a taught object is recognised among
// look-alikes, and where the matcher's shipped thresholds come from
// (object_matcher.hpp).
//
// Per seed, a rendered table (tests/support/object_scenes.hpp) holds the
// target mug and five distractors: two mugs of other colours, a mug-sized box,
// a large box and an upright book, the three in the mug's colour. The mug is
// taught from 1, 3 or 10 views around the table; unseen test views (other
// bearings, distances, heights and noise) are rendered twice, with the mug and
// with it taken away. Candidates are the renderer's per-object pixels (ground
// truth), so recognition is measured alone, or with --stage the real stage's
// (detectTables and findTableObjects on the true label image), each taken for
// the object most of its pixels show. Printed:
//   1. the distances the gates compare (colour, shape, the size tolerance a
//      candidate needs), per kind of candidate, as percentiles;
//   2. a sweep of the colour and shape thresholds at each size tolerance:
//      precision, recall and the false "found" rate (share of views without
//      the mug in which some candidate is taken for it);
//   3. matchObjects itself with the shipped defaults (or --size/--colour/
//      --shape): the same figures and why the distractors were refused.
//      These figures are per view: recall is the share of the mug's
//      candidates taken for it, false "found" the share of views without the
//      mug in which some candidate was taken for it.
//   5. Visits: what a robot decides from several views. Each seed's test
//      views, in order, are one visit to the table (with the mug, and the
//      same poses without it). Every view's candidates from the real stage
//      (detectTables and findTableObjects on the true labels, whatever
//      --stage says) are named by matchObjects (3 taught views, shipped
//      settings) and fed to an ObjectMap (map/object_map.hpp) at the camera's
//      pose. After the visit the mug is found when a mapped object within
//      10 cm of it is named "mug"; false "found" is a visit without the mug
//      that ends with an object named "mug". Printed for the evidence rule's
//      settings (object_map.name_after_matches, object_map.max_name_range_m):
//      1 match at any range is the per-view rule applied to a whole visit.
//      Tune these on other seeds (--first-seed 101) than those measured.
//
//   object_recognition_eval [--seeds 30] [--first-seed 1] [--test-views 4] [--stage]
//                           [--size 0.25] [--colour 0.20] [--shape 0.25]
//                           [--roundness 0.10]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "findmug/map/object_map.hpp"
#include "findmug/objects/object_matcher.hpp"
#include "findmug/objects/object_model.hpp"
#include "findmug/objects/table_objects.hpp"
#include "findmug/tables/tables.hpp"
#include "object_scenes.hpp"

namespace {

using namespace findmug;
using findmug::test::TableScene;

// splitmix64: the scene draws, reproducible everywhere.
struct Rng {
  std::uint64_t s;
  double uniform(double lo = 0.0, double hi = 1.0) {
    std::uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return lo + (hi - lo) * static_cast<double>(z >> 11) * 0x1.0p-53;
  }
  int integer(int n) { return std::min(n - 1, static_cast<int>(uniform() * n)); }
};

const Rgb8 kPalette[] = {{200, 40, 40},   {40, 90, 200}, {60, 150, 70},  {230, 190, 40},
                         {240, 240, 235}, {30, 30, 35},  {220, 110, 30}, {120, 60, 150}};
constexpr int kPaletteSize = sizeof(kPalette) / sizeof(kPalette[0]);

const char* const kKinds[] = {"target mug", "mug, other colour", "mug-sized box, same colour",
                              "large box, same colour", "upright book, same colour"};
constexpr int kKindCount = 5;

struct Layout {
  TableScene with_target, without_target;
  std::vector<int> objects_with;     // scene object index per kind slot (with the mug)
  std::vector<int> kinds_with;       // kind per entry of objects_with
  std::vector<int> objects_without;  // the same scene without the mug
  std::vector<int> kinds_without;
};

// One object of the layout, drawn once and placed in both scenes.
struct Placed {
  int kind;
  bool mug;
  Eigen::Vector2d xy;
  double yaw, radius, height;
  Eigen::Vector3d half;
  Rgb8 colour;
};

std::vector<Placed> drawObjects(Rng& rng, const TableScene& t) {
  const int target_colour = rng.integer(kPaletteSize);
  int other1 = (target_colour + 1 + rng.integer(kPaletteSize - 1)) % kPaletteSize;
  int other2 = other1;
  while (other2 == other1 || other2 == target_colour) other2 = rng.integer(kPaletteSize);
  std::vector<Eigen::Vector2d> slots;
  for (double sx : {-0.42, 0.0, 0.42})
    for (double sy : {-0.2, 0.2})
      slots.push_back(t.table_center + Eigen::Vector2d(sx + rng.uniform(-0.04, 0.04),
                                                       sy + rng.uniform(-0.04, 0.04)));
  for (int i = static_cast<int>(slots.size()) - 1; i > 0; --i) {
    std::swap(slots[i], slots[rng.integer(i + 1)]);
  }
  auto mug = [&](int kind, int colour, const Eigen::Vector2d& xy) {
    return Placed{kind,
                  true,
                  xy,
                  rng.uniform(0.0, 2 * M_PI),
                  rng.uniform(0.037, 0.045),
                  rng.uniform(0.085, 0.11),
                  Eigen::Vector3d::Zero(),
                  kPalette[colour]};
  };
  auto box = [&](int kind, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                 const Eigen::Vector2d& xy) {
    const Eigen::Vector3d half(rng.uniform(lo.x(), hi.x()), rng.uniform(lo.y(), hi.y()),
                               rng.uniform(lo.z(), hi.z()));
    return Placed{kind, false, xy, rng.uniform(0.0, M_PI), 0, 0, half, kPalette[target_colour]};
  };
  return {mug(0, target_colour, slots[0]),
          mug(1, other1, slots[1]),
          mug(1, other2, slots[2]),
          box(2, {0.035, 0.035, 0.04}, {0.05, 0.05, 0.055}, slots[3]),
          box(3, {0.08, 0.06, 0.04}, {0.12, 0.10, 0.10}, slots[4]),
          box(4, {0.012, 0.07, 0.08}, {0.025, 0.11, 0.13}, slots[5])};
}

int place(TableScene& t, const Placed& p) {
  if (p.mug) return test::addMug(t, p.xy, p.radius, p.height, p.yaw, p.colour);
  return test::addBox(t, p.kind == 4 ? "book" : "box", p.xy, p.yaw, p.half, p.colour);
}

Layout makeLayout(Rng& rng) {
  Layout l;
  l.with_target = test::makeTableScene();
  l.without_target = test::makeTableScene();
  for (const Placed& p : drawObjects(rng, l.with_target)) {
    l.objects_with.push_back(place(l.with_target, p));
    l.kinds_with.push_back(p.kind);
    if (p.kind == 0) continue;
    l.objects_without.push_back(place(l.without_target, p));
    l.kinds_without.push_back(p.kind);
  }
  return l;
}

synth::CameraPose randomPose(Rng& rng, const TableScene& t, double bearing) {
  return test::cameraAround(t, bearing, rng.uniform(1.0, 1.9), rng.uniform(1.0, 1.4));
}

constexpr int kMinCandidatePoints = 30;  // table_objects.min_points' default

// --stage: candidates from the real stage instead of ground-truth pixels.
bool g_use_stage = false;
struct StageCounts {
  // Over the teaching and the test views.
  int objects = 0;    // scene objects with at least kMinCandidatePoints pixels with depth
  int dropped = 0;    // ... of which no stage candidate is mostly
  int fragments = 0;  // further candidates of an object that has a larger one (left out)
  int mixed = 0;      // candidates no object has half of (left out)
};
StageCounts g_stage;

// The scene object index that at least half of `c`'s pixels show, or -1.
int majorityObject(const test::RenderedTable& r, const TableObject& c) {
  std::map<int, int> count;
  for (int p : c.pixels) count[r.frame.object[static_cast<std::size_t>(p)]]++;
  for (const auto& [object, n] : count)
    if (2 * n >= static_cast<int>(c.pixels.size())) return object;
  return -1;
}

int validPixelsOf(const test::RenderedTable& r, int object) {
  int n = 0;
  for (std::size_t i = 0; i < r.frame.object.size(); ++i)
    n += r.frame.object[i] == object && r.cloud_ground.valid(static_cast<int>(i));
  return n;
}

// The real stage on the renderer's true label image: detectTables, then
// findTableObjects; per object of `objects`, its largest candidate.
std::vector<TableObject> stageCandidatesFor(const test::RenderedTable& r,
                                            const std::vector<int>& objects) {
  LabelImage labels;
  labels.width = r.cloud_ground.width;
  labels.height = r.cloud_ground.height;
  labels.labels = r.frame.labeled.labels;
  labels.confidence.assign(labels.labels.size(), 1.0f);
  const TableDetection tables = detectTables(r.cloud_ground, labels, TableConfig{});
  const TableObjectDetection d =
      findTableObjects(r.cloud_ground, labels, tables.tables, TableObjectConfig{});
  std::vector<TableObject> out(objects.size());
  for (const TableObject& c : d.objects) {
    const int majority = majorityObject(r, c);
    g_stage.mixed += majority < 0;
    const auto at = std::find(objects.begin(), objects.end(), majority);
    if (at == objects.end()) continue;  // mixed, or an object not asked for
    TableObject& slot = out[static_cast<std::size_t>(at - objects.begin())];
    if (slot.point_count > 0) g_stage.fragments++;
    if (c.point_count > slot.point_count) slot = c;
  }
  for (std::size_t o = 0; o < objects.size(); ++o) {
    if (validPixelsOf(r, objects[o]) < kMinCandidatePoints) continue;
    g_stage.objects++;
    g_stage.dropped += out[o].point_count == 0;
  }
  return out;
}

// One candidate per object of `objects` (point_count 0 when it has none),
// from ground-truth pixels or (--stage) the real stage.
std::vector<TableObject> candidatesFor(const test::RenderedTable& r,
                                       const std::vector<int>& objects, float top) {
  if (g_use_stage) return stageCandidatesFor(r, objects);
  std::vector<TableObject> out;
  for (std::size_t o = 0; o < objects.size(); ++o)
    out.push_back(test::candidateOf(r, objects[o], top, static_cast<int>(o)));
  return out;
}

// A candidate of a test view and the numbers the gates compare, per teaching.
struct Record {
  int kind = 0;
  bool view_has_target = false;
  int view = 0;  // test view index over the run (absent views separately numbered)
  TableObject candidate;
  // Per teaching (1, 3, 10 views): what the gates compare.
  float size_need[3] = {0, 0, 0};  // smallest relative tolerance that lets it through
  float colour[3] = {1, 1, 1};
  float shape[3] = {1, 1, 1};       // ESF on kObjectShapePoints points (as matchObjects)
  float shape_full[3] = {1, 1, 1};  // ESF on all (up to 2000) points, as before
  float model_roundness[3] = {kNotRound, kNotRound, kNotRound};
  float roundness = kNotRound;  // the candidate's objectRoundnessResidual
};

// Per-candidate cost of the shape cues (milliseconds, summed over candidates).
struct Costs {
  double roundness_ms = 0, esf_ms = 0, esf_full_ms = 0;
  int n = 0;
};
Costs g_costs;

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// The candidate's ESF on `max_points` of its points, timed into `ms`; false
// when its points make no shape.
bool timedShape(const std::vector<Eigen::Vector3f>& points, int max_points,
                ObjectShapeDescriptor& out, double& ms) {
  const auto t0 = std::chrono::steady_clock::now();
  try {
    out = objectShapeDescriptor(points, max_points);
  } catch (const Error&) {
    return false;
  }
  ms += msSince(t0);
  return true;
}

float sizeNeed(const TableObject& c, const ObjectModel& m, float tolerance_m) {
  const bool truncated = (c.truncation & (kTruncatedBorder | kTruncatedDepthHole)) != 0;
  float best = 1e9f;
  for (const auto& v : m.views) {
    const float measured[2] = {c.height_above_top, 2 * std::max(c.extents.x(), c.extents.y())};
    const float taught[2] = {v.height_above_top, 2 * v.extents.x()};
    float need = 0.0f;
    for (int d = 0; d < 2; ++d) {
      const float diff = measured[d] - taught[d];
      if (diff < 0 && truncated) continue;
      need = std::max(need, (std::abs(diff) - tolerance_m) / taught[d]);
    }
    best = std::min(best, need);
  }
  return best;
}

// One view of a visit: the stage's candidates on its tables, the camera's
// pose on the floor, and what the matcher (3 taught views) named them.
struct VisitView {
  std::vector<TableObject> candidates;
  std::vector<TableCluster> tables;
  Pose2D base_in_map;
  std::vector<ObjectIdentity> identities;
};
struct Visit {
  bool has_target = false;
  Eigen::Vector2f target_xy = Eigen::Vector2f::Zero();  // world frame (the map)
  std::vector<VisitView> views;
};

// The real stage's candidates of a view (true labels), named by the matcher.
VisitView visitView(const test::RenderedTable& r, const synth::CameraPose& pose,
                    const ObjectModel& model) {
  LabelImage labels;
  labels.width = r.cloud_ground.width;
  labels.height = r.cloud_ground.height;
  labels.labels = r.frame.labeled.labels;
  labels.confidence.assign(labels.labels.size(), 1.0f);
  VisitView v;
  v.tables = detectTables(r.cloud_ground, labels, TableConfig{}).tables;
  v.candidates = findTableObjects(r.cloud_ground, labels, v.tables, TableObjectConfig{}).objects;
  v.base_in_map = Pose2D{pose.xy.x(), pose.xy.y(), pose.yaw};
  for (const ObjectMatch& m :
       matchObjects(r.cloud_ground, v.candidates, {model}, ObjectMatcherConfig{})) {
    v.identities.push_back({m.matched() ? m.name : std::string(), m.score});
  }
  return v;
}

struct Run {
  std::vector<Visit> visits;
  std::vector<Record> records;
  std::vector<ObjectModel> models;  // per seed x teaching, for the matchObjects pass
  std::vector<OrganizedCloud> clouds;
  int absent_views = 0, present_views = 0;
};

const int kTeachCounts[3] = {1, 3, 10};

void evaluateSeed(std::uint64_t seed, int test_views, Run& run,
                  std::vector<std::vector<ObjectModel>>& per_seed_models) {
  Rng rng{seed * 0x2545F4914F6CDD1Dull + 7};
  Layout layout = makeLayout(rng);
  const float top = static_cast<float>(layout.with_target.top_z);
  // Teaching: ten views evenly around the table, from a random start.
  const double start = rng.uniform(0.0, 2 * M_PI);
  std::vector<ObjectView> taught;
  std::vector<int> taught_index;  // which of the 10 poses each taught view is
  for (int i = 0; i < 10; ++i) {
    const auto pose = randomPose(rng, layout.with_target, start + i * 2 * M_PI / 10);
    const auto r = test::renderTable(layout.with_target, pose, seed * 100 + i);
    const TableObject c = candidatesFor(r, {layout.objects_with[0]}, top)[0];
    if (c.point_count < kMinCandidatePoints) continue;
    taught.push_back(makeObjectView(r.cloud_ground, c));
    taught_index.push_back(i);
  }
  std::vector<ObjectModel> models(3);
  std::vector<std::vector<ObjectShapeDescriptor>> full_shapes(3);  // 2000-point ESF per view
  for (int k = 0; k < 3; ++k) {
    models[k].name = "mug";
    // 1 view: the first; 3: spread around (every third); 10: all.
    const int step = std::max(1, static_cast<int>(taught.size()) / kTeachCounts[k]);
    for (std::size_t i = 0;
         i < taught.size() && static_cast<int>(models[k].views.size()) < kTeachCounts[k];
         i += step) {
      models[k].views.push_back(taught[i]);
      full_shapes[k].push_back(objectShapeDescriptor(taught[i].points, kMaxObjectViewPoints));
    }
  }
  if (taught.empty()) return;
  per_seed_models.push_back(models);
  const int model_set = static_cast<int>(per_seed_models.size()) - 1;
  Visit visits[2];  // without, with the mug
  visits[1].has_target = true;
  {
    const auto& prims = layout.with_target.scene.primitives;
    for (const synth::Primitive& part : prims) {
      if (part.object != layout.objects_with[0]) continue;
      visits[1].target_xy = part.center.head<2>().cast<float>();
      break;
    }
  }
  for (int v = 0; v < test_views; ++v) {
    const auto pose = randomPose(rng, layout.with_target, rng.uniform(0.0, 2 * M_PI));
    for (int with = 1; with >= 0; --with) {
      const TableScene& scene = with ? layout.with_target : layout.without_target;
      const auto& objects = with ? layout.objects_with : layout.objects_without;
      const auto& kinds = with ? layout.kinds_with : layout.kinds_without;
      const auto r = test::renderTable(scene, pose, seed * 100 + 50 + v);
      visits[with].views.push_back(visitView(r, pose, models[1]));
      const int view = with ? run.present_views++ : run.absent_views++;
      run.clouds.push_back(r.cloud_ground);
      const std::vector<TableObject> candidates = candidatesFor(r, objects, top);
      for (std::size_t o = 0; o < objects.size(); ++o) {
        Record rec;
        rec.kind = kinds[o];
        rec.view_has_target = with;
        rec.view = view;
        rec.candidate = candidates[o];
        if (rec.candidate.point_count < kMinCandidatePoints) continue;
        std::vector<Eigen::Vector3f> points;
        std::vector<Rgb8> colors;
        objectPointsOf(r.cloud_ground, rec.candidate.pixels, kMaxObjectViewPoints, points, colors);
        ObjectShapeDescriptor shape{}, shape_full{};
        const bool has_shape =
            timedShape(points, kObjectShapePoints, shape, g_costs.esf_ms) &&
            timedShape(points, kMaxObjectViewPoints, shape_full, g_costs.esf_full_ms);
        const auto t0 = std::chrono::steady_clock::now();
        rec.roundness = objectRoundnessResidual(points);
        g_costs.roundness_ms += msSince(t0);
        g_costs.n++;
        for (int k = 0; k < 3; ++k) {
          rec.model_roundness[k] = kNotRound;
          for (const auto& tv : models[k].views)
            rec.model_roundness[k] = std::min(rec.model_roundness[k], tv.roundness);
          rec.size_need[k] =
              sizeNeed(rec.candidate, models[k], ObjectMatcherConfig{}.size_tolerance_m);
          rec.colour[k] = 1.0f;
          rec.shape[k] = 1.0f;
          rec.shape_full[k] = 1.0f;
          for (std::size_t t = 0; t < full_shapes[k].size() && has_shape; ++t) {
            rec.shape_full[k] =
                std::min(rec.shape_full[k], shapeDescriptorDistance(shape_full, full_shapes[k][t]));
          }
          for (const auto& tv : models[k].views) {
            rec.colour[k] = std::min(
                rec.colour[k],
                colourHistogramDistance(rec.candidate.colour_histogram, tv.colour_histogram));
            if (has_shape)
              rec.shape[k] = std::min(rec.shape[k], shapeDescriptorDistance(shape, tv.shape));
          }
        }
        // Which cloud and model set the matchObjects pass uses.
        rec.candidate.table = static_cast<int>(run.clouds.size()) - 1;
        rec.candidate.id = model_set;
        run.records.push_back(std::move(rec));
      }
    }
  }
  run.visits.push_back(std::move(visits[1]));
  run.visits.push_back(std::move(visits[0]));
}

struct Figures {
  int tp = 0, fn = 0, fp = 0, false_found_views = 0;
  double precision() const { return tp + fp ? static_cast<double>(tp) / (tp + fp) : 1.0; }
  double recall() const { return tp + fn ? static_cast<double>(tp) / (tp + fn) : 0.0; }
};

template <typename Accept>
Figures figuresOf(const Run& run, Accept accept) {
  Figures f;
  std::vector<int> found(static_cast<std::size_t>(std::max(0, run.absent_views)), 0);
  for (std::size_t i = 0; i < run.records.size(); ++i) {
    const Record& r = run.records[i];
    const bool a = accept(i, r);
    if (r.kind == 0) {
      (a ? f.tp : f.fn)++;
    } else if (a) {
      f.fp++;
      if (!r.view_has_target) found[static_cast<std::size_t>(r.view)] = 1;
    }
  }
  for (const int c : found) f.false_found_views += c;
  return f;
}

float percentile(std::vector<float> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * (v.size() - 1) + 0.5))];
}

void printDistances(const Run& run) {
  std::printf("\n## 1. What the gates compare (percentiles 5/50/95 over test candidates)\n\n");
  std::printf(
      "| taught views | candidate | n | size tolerance needed | colour distance | shape distance "
      "(ESF, %d points) | shape distance (ESF, %d points) | roundness residual |\n",
      kObjectShapePoints, kMaxObjectViewPoints);
  std::printf("|---|---|---|---|---|---|---|---|\n");
  auto triple = [](const std::vector<float>& v) {
    std::printf(" %.2f / %.2f / %.2f |", percentile(v, 0.05), percentile(v, 0.5),
                percentile(v, 0.95));
  };
  for (int k = 0; k < 3; ++k) {
    for (int kind = 0; kind < kKindCount; ++kind) {
      std::vector<float> s, c, h, hf, rd;
      for (const auto& r : run.records) {
        if (r.kind != kind) continue;
        s.push_back(r.size_need[k]);
        c.push_back(r.colour[k]);
        h.push_back(r.shape[k]);
        hf.push_back(r.shape_full[k]);
        rd.push_back(r.roundness);
      }
      std::printf("| %d | %s | %zu |", kTeachCounts[k], kKinds[kind], s.size());
      for (const auto* v : {&s, &c, &h, &hf, &rd}) triple(*v);
      std::printf("\n");
    }
  }
}

void printSweep(const Run& run) {
  const float sizes[] = {0.15f, 0.25f, 0.40f};
  const float colours[] = {0.2f, 0.35f, 0.5f};
  const float shapes[] = {0.15f, 0.2f, 0.25f, 0.3f, 0.35f, 0.45f};
  std::printf(
      "\n## 2. Threshold sweep (P = precision, R = recall, FF = false found: views "
      "without the mug, %d, in which a candidate was taken for it)\n\n",
      run.absent_views);
  std::printf(
      "| size tol | colour | shape | 1 view P / R / FF | 3 views P / R / FF | 10 views P / R / FF "
      "|\n");
  std::printf("|---|---|---|---|---|---|\n");
  for (float st : sizes)
    for (float ct : colours)
      for (float ht : shapes) {
        std::printf("| %.2f | %.2f | %.2f |", st, ct, ht);
        for (int k = 0; k < 3; ++k) {
          const Figures f = figuresOf(run, [&](std::size_t, const Record& r) {
            return r.size_need[k] <= st && r.colour[k] <= ct && r.shape[k] <= ht;
          });
          std::printf(
              " %.3f / %.3f / %.3f |", f.precision(), f.recall(),
              run.absent_views ? static_cast<double>(f.false_found_views) / run.absent_views : 0.0);
        }
        std::printf("\n");
      }
}

// The roundness gate's threshold and ESF's point count, the other gates at
// the shipped defaults (a model that is not round skips the roundness gate).
void printRoundnessSweep(const Run& run, const ObjectMatcherConfig& config) {
  const float thresholds[] = {kNotRound, 0.04f, 0.06f, 0.08f, 0.10f, 0.12f, 0.15f, 0.20f};
  std::printf(
      "\n## 2b. Roundness threshold sweep (size %.2f, colour %.2f, shape %.2f; P / R / FF as "
      "above; roundness 1 = gate off)\n\n",
      config.size_tolerance, config.max_colour_distance, config.max_shape_distance);
  std::printf(
      "| roundness | ESF points | 1 view P / R / FF | 3 views P / R / FF | 10 views P / R / FF "
      "|\n|---|---|---|---|---|\n");
  for (float rt : thresholds)
    for (bool full : {false, true}) {
      std::printf("| %.2f | %d |", rt, full ? kMaxObjectViewPoints : kObjectShapePoints);
      for (int k = 0; k < 3; ++k) {
        const Figures f = figuresOf(run, [&](std::size_t, const Record& r) {
          const bool round = r.model_roundness[k] > rt || r.roundness <= rt;
          return r.size_need[k] <= config.size_tolerance &&
                 r.colour[k] <= config.max_colour_distance && round &&
                 (full ? r.shape_full[k] : r.shape[k]) <= config.max_shape_distance;
        });
        std::printf(
            " %.3f / %.3f / %.3f |", f.precision(), f.recall(),
            run.absent_views ? static_cast<double>(f.false_found_views) / run.absent_views : 0.0);
      }
      std::printf("\n");
    }
}

void printCosts() {
  const double n = std::max(1, g_costs.n);
  std::printf(
      "\n## 4. Cost per candidate (ms, mean over %d candidates, one thread)\n\n"
      "| roundness | ESF, %d points | ESF, %d points |\n|---|---|---|\n| %.3f | %.2f | %.2f |\n",
      g_costs.n, kObjectShapePoints, kMaxObjectViewPoints, g_costs.roundness_ms / n,
      g_costs.esf_ms / n, g_costs.esf_full_ms / n);
}

void printMatcher(const Run& run, const std::vector<std::vector<ObjectModel>>& per_seed_models,
                  const ObjectMatcherConfig& config) {
  std::printf(
      "\n## 3. matchObjects (size_tolerance %.2f + %.3f m, max_colour_distance %.2f, "
      "max_shape_distance %.2f, max_roundness_residual %.2f)\n\n",
      config.size_tolerance, config.size_tolerance_m, config.max_colour_distance,
      config.max_shape_distance, config.max_roundness_residual);
  std::printf(
      "| taught views | precision | recall | false found | targets | distractors | "
      "distractors refused: too big / too small / wrong colour / not round / wrong shape / other "
      "|\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  std::vector<std::string> accepted_lines;
  for (int k = 0; k < 3; ++k) {
    std::vector<ObjectMatch> matches(run.records.size());
    for (std::size_t i = 0; i < run.records.size(); ++i) {
      const Record& r = run.records[i];
      const auto& model = per_seed_models[r.candidate.id][k];
      matches[i] = matchObjects(run.clouds[r.candidate.table], {r.candidate}, {model}, config)[0];
    }
    const Figures f =
        figuresOf(run, [&](std::size_t i, const Record&) { return matches[i].matched(); });
    std::map<std::string, int> why;
    int accepted_by_kind[kKindCount] = {0, 0, 0, 0, 0};
    int seen_by_kind[kKindCount] = {0, 0, 0, 0, 0};
    for (std::size_t i = 0; i < run.records.size(); ++i) {
      seen_by_kind[run.records[i].kind]++;
      if (matches[i].matched()) accepted_by_kind[run.records[i].kind]++;
    }
    std::string accepted;
    for (int kind = 1; kind < kKindCount; ++kind) {
      accepted += std::string(kind > 1 ? ", " : "") + kKinds[kind] + " " +
                  std::to_string(accepted_by_kind[kind]) + "/" + std::to_string(seen_by_kind[kind]);
    }
    accepted_lines.push_back(std::to_string(kTeachCounts[k]) + " views: " + accepted);
    int distractors = 0;
    for (std::size_t i = 0; i < run.records.size(); ++i) {
      if (run.records[i].kind == 0) continue;
      ++distractors;
      const std::string& rej = matches[i].rejection;
      std::string key = "other";
      // The last that fits: "wrong shape: not round" is also "wrong shape".
      for (const char* w :
           {"too big", "too small", "wrong colour", "wrong shape", "wrong shape: not round"})
        if (rej.rfind(w, 0) == 0) key = w;
      if (!rej.empty()) why[key]++;
    }
    std::printf(
        "| %d | %.3f | %.3f | %.3f (%d of %d) | %d | %d | %d / %d / %d / %d / %d / %d |\n",
        kTeachCounts[k], f.precision(), f.recall(),
        run.absent_views ? static_cast<double>(f.false_found_views) / run.absent_views : 0.0,
        f.false_found_views, run.absent_views, f.tp + f.fn, distractors, why["too big"],
        why["too small"], why["wrong colour"], why["wrong shape: not round"], why["wrong shape"],
        why["other"]);
  }
  std::printf("\nDistractors taken for the mug, by kind:\n");
  for (const auto& line : accepted_lines) std::printf("- %s\n", line.c_str());
}

// Section 5: the visits through an ObjectMap under each evidence rule.
void printVisits(const Run& run) {
  int with = 0, without = 0;
  for (const Visit& v : run.visits) (v.has_target ? with : without)++;
  std::printf(
      "\n## 5. Visits (each seed's test views in order, the stage's candidates named by "
      "matchObjects, 3 taught views, into an ObjectMap): %d visits with the mug, %d without\n\n",
      with, without);
  std::printf(
      "| name_after_matches | max_name_range_m | recall (visits) | false found (visits) | "
      "mug pending at the end (visits with it) |\n|---|---|---|---|---|\n");
  for (const int k : {1, 2, 3}) {
    for (const float range : {100.0f, 2.0f, 1.9f, 1.8f, 1.7f, 1.5f, 1.3f}) {
      ObjectMapConfig config;
      config.name_after_matches = k;
      config.max_name_range_m = range;
      int found = 0, false_found = 0, pending = 0;
      for (const Visit& visit : run.visits) {
        ObjectMap map(config);
        std::uint64_t t = 0;
        for (const VisitView& v : visit.views) {
          map.update(v.candidates, v.tables, {}, v.base_in_map, ++t, v.identities);
        }
        bool target_named = false, other_named = false, target_pending = false;
        for (const MappedObject& o : map.objects()) {
          const bool is_target =
              visit.has_target && (o.centroid.head<2>() - visit.target_xy).norm() <= 0.10f;
          if (o.name == "mug") (is_target ? target_named : other_named) = true;
          if (is_target && o.pending_name == "mug") target_pending = true;
        }
        if (visit.has_target) {
          found += target_named;
          pending += target_pending;
        } else {
          false_found += other_named;
        }
      }
      char range_text[16] = "any";
      if (range < 50) {
        std::snprintf(range_text, sizeof range_text, "%.1f", static_cast<double>(range));
      }
      std::printf("| %d | %s | %.3f (%d of %d) | %.3f (%d of %d) | %d |\n", k, range_text,
                  with ? static_cast<double>(found) / with : 0.0, found, with,
                  without ? static_cast<double>(false_found) / without : 0.0, false_found,
                  without, pending);
    }
  }
}

double flagValue(int argc, char** argv, const char* name, double fallback) {
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], name) == 0) return std::atof(argv[i + 1]);
  return fallback;
}

}  // namespace

int main(int argc, char** argv) {
  const int seeds = static_cast<int>(flagValue(argc, argv, "--seeds", 30));
  const int first = static_cast<int>(flagValue(argc, argv, "--first-seed", 1));
  const int test_views = static_cast<int>(flagValue(argc, argv, "--test-views", 4));
  for (int i = 1; i < argc; ++i) g_use_stage = g_use_stage || std::strcmp(argv[i], "--stage") == 0;
  ObjectMatcherConfig config;
  config.size_tolerance =
      static_cast<float>(flagValue(argc, argv, "--size", config.size_tolerance));
  config.max_colour_distance =
      static_cast<float>(flagValue(argc, argv, "--colour", config.max_colour_distance));
  config.max_shape_distance =
      static_cast<float>(flagValue(argc, argv, "--shape", config.max_shape_distance));
  config.max_roundness_residual =
      static_cast<float>(flagValue(argc, argv, "--roundness", config.max_roundness_residual));
  const auto t0 = std::chrono::steady_clock::now();
  Run run;
  std::vector<std::vector<ObjectModel>> per_seed_models;
  for (int s = first; s < first + seeds; ++s)
    evaluateSeed(static_cast<std::uint64_t>(s), test_views, run, per_seed_models);
  std::printf(
      "# object_recognition_eval: seeds %d..%d, %d test views each (with and without the "
      "mug), %zu candidates, %.0f s\n",
      first, first + seeds - 1, test_views, run.records.size(),
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  if (g_use_stage) {
    std::printf(
        "\nCandidates: findTableObjects on the true label image (detectTables). Of %d objects "
        "in view, %d had no candidate; %d smaller fragments and %d mixed candidates left out.\n",
        g_stage.objects, g_stage.dropped, g_stage.fragments, g_stage.mixed);
  } else {
    std::printf("\nCandidates: the renderer's per-object pixels (ground truth).\n");
  }
  printDistances(run);
  printSweep(run);
  printRoundnessSweep(run, config);
  printMatcher(run, per_seed_models, config);
  printCosts();
  printVisits(run);
  return 0;
}
