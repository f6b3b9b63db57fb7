// The taught mug of findmug-search-bench's matcher perception (see teach_mug.hpp).
#include "teach_mug.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "findmug/common/error.hpp"
#include "findmug/objects/object_model.hpp"
#include "findmug/segmenter/segmenter.hpp"

namespace findmug::search {

namespace {

// The free pose 1.0-1.6 m from the mug (on the floor) facing it that shows the most of it,
// on a 0.15 m lattice; false when none shows recognise_min_pixels. The mug's pixels are
// counted without rendering whole frames (countObjectPixels: the count a frame would show).
bool teachingPose(const World& w, const SimParams& params, Eigen::Vector2d& xy, double& yaw) {
  const Eigen::Vector2d mug = w.mug.position.head<2>();
  synth::RenderOptions options;
  options.noise.enabled = false;
  int best = params.recognise_min_pixels - 1;
  for (double dy = -1.6; dy <= 1.6; dy += 0.15)
    for (double dx = -1.6; dx <= 1.6; dx += 0.15) {
      const Eigen::Vector2d p = mug + Eigen::Vector2d(dx, dy);
      const double d = (p - mug).norm();
      if (d < 1.0 || d > 1.6) continue;
      const int c = w.grid.cellAt(p);
      if (c < 0 || !w.grid.free(c)) continue;
      const double a = std::atan2(mug.y() - p.y(), mug.x() - p.x());
      const int pixels = synth::countObjectPixels(w.apartment.scene, cameraAt(params, p, a),
                                                  options, w.mug.object);
      if (pixels > best) best = pixels, xy = p, yaw = a;
    }
  return best >= params.recognise_min_pixels;
}

}  // namespace

TaughtObject teachTargetMug(const FindmugModel& model, const SimParams& params,
                            const std::string& objects_dir, const std::string& name, int views,
                            std::uint64_t first_seed,
                            const std::vector<std::uint64_t>& episode_seeds) {
  validateObjectModelName(name);
  TaughtObject taught;
  taught.path = (std::filesystem::path(objects_dir) / (name + ".fmo")).string();
  std::filesystem::remove(taught.path);
  const Segmenter segmenter(model.loaded.config.segmenter, model.forest);
  SimParams table_only = params;
  table_only.prior = {1.0, 0.0, 0.0};
  std::ostringstream skipped;  // seeds passed over and why
  for (std::uint64_t seed = first_seed;
       seed < first_seed + 40 && static_cast<int>(taught.views.size()) < views; ++seed) {
    if (std::find(episode_seeds.begin(), episode_seeds.end(), seed) != episode_seeds.end())
      throw Error("search: teaching apartment seed " + std::to_string(seed) +
                  " is also an episode's apartment");
    World w;
    w.apartment = synth::makeMultiRoomApartment(seed, table_only.apartment);
    w.mug = synth::placeTargetMug(w.apartment, mix(seed ^ 0x7eac4ULL), table_only.prior,
                                  params.look_alikes);
    w.grid = Grid(w.apartment.scene, params.robot_radius_m, params.cell_m);
    Eigen::Vector2d xy;
    double yaw = 0.0;
    if (!teachingPose(w, params, xy, yaw)) {
      skipped << " " << seed << " (no pose shows the mug)";
      continue;
    }
    synth::RenderedFrame frame =
        synth::render(w.apartment.scene, cameraAt(params, xy, yaw), synth::RenderOptions{},
                      mix(seed * 31 + 7));
    const std::vector<std::int32_t> object = frame.object;
    const LabelledFrame labelled = segmenter.process(std::move(frame.labeled.frame));
    // The candidate a person would click: the one holding most of the mug's pixels, and
    // mostly made of them.
    const TableObject* pick = nullptr;
    int pick_on_mug = 0;
    for (const TableObject& c : labelled.table_objects.objects) {
      int on_mug = 0;
      for (const int i : c.pixels) on_mug += object[i] == w.mug.object;
      if (on_mug > pick_on_mug && 2 * on_mug >= static_cast<int>(c.pixels.size()))
        pick = &c, pick_on_mug = on_mug;
    }
    if (pick == nullptr) {
      skipped << " " << seed << " (no candidate on the mug)";
      continue;
    }
    try {
      addObjectViewToFile(taught.path, name,
                          makeObjectView(labelled.segmented.prepared.cloud_ground, *pick));
    } catch (const Error& e) {
      skipped << " " << seed << " (" << e.what() << ")";
      continue;
    }
    taught.views.push_back({seed, (xy - w.mug.position.head<2>()).norm(), pick->point_count});
  }
  if (static_cast<int>(taught.views.size()) < views)
    throw Error("search: taught " + std::to_string(taught.views.size()) + " of " +
                std::to_string(views) + " views of the " + name + " from apartment seeds " +
                std::to_string(first_seed) + "-" + std::to_string(first_seed + 39) +
                "; skipped:" + skipped.str());
  return taught;
}

}  // namespace findmug::search
