// teach_mug.hpp — the mug findmug-search-bench's matcher perception looks for, taught the
// way a person teaches findmugd: a few views of the mug standing on a table, each segmented
// by the daemon's Segmenter (the benchmark's model and settings), the table-top candidate on
// the mug picked (the person's click: the candidate holding most of the mug's rendered
// pixels), and makeObjectView + addObjectViewToFile (objects/object_model.hpp, what
// findmug-teach and the daemon's teach command use) into NAME.fmo.
//
// Why other apartments: the episodes must not be searched with views of their own rooms.
// The teaching apartments' seeds are refused when an episode uses one of them.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "findmug_tables.hpp"
#include "search_sim.hpp"

namespace findmug::search {

struct TaughtView {
  std::uint64_t apartment_seed = 0;
  double distance_m = 0.0;  // camera to the mug, on the floor
  int candidate_points = 0;
};

struct TaughtObject {
  std::string path;  // objects_dir/NAME.fmo
  std::vector<TaughtView> views;
};

// Teaches `name` from `views` rendered views into `objects_dir`/NAME.fmo (a new file).
// Apartment seeds are tried from `first_seed` upwards (the mug on a table of each, placed by
// placeTargetMug, looked at from the free pose 1.0-1.6 m away with the most mug pixels); a
// seed whose view gives no candidate on the mug is skipped. Seeds in `episode_seeds` are
// refused. Throws findmug::Error naming why when fewer views could be taught from 40 seeds.
TaughtObject teachTargetMug(const FindmugModel& model, const SimParams& params,
                            const std::string& objects_dir, const std::string& name, int views,
                            std::uint64_t first_seed,
                            const std::vector<std::uint64_t>& episode_seeds);

}  // namespace findmug::search
