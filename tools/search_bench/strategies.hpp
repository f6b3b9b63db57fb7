// strategies.hpp — how the simulated robot searches (findmug-search-bench, issue 51).
//
//   a findmug      look around, then visit the search positions of findmug's table map
//                  (the daemon's FINDMUG_TABLE_MAP), nearest first by planned path and
//                  re-planned after every view; when none is left, explore the nearest
//                  room not yet looked around in, and go on; with every room done, the
//                  coverage of (c) from there on.
//   b places       hand-placed search places from the furniture ground truth (one in front
//                  of each table, desk, cabinet and shelf), nearest first, as Hobbit had
//                  before semantic places; then the same fallbacks as (a).
//   c coverage     frontier-style coverage of the known floor plan: look around, drive to
//                  the nearest reachable floor not yet seen (within coverage_range_m of a
//                  view), look around again.
//   d random       random reachable poses, a look-around at each.
//   e oracle       straight to the nearest pose that recognises the mug (upper bound).
// Every strategy uses the same oracle recogniser at every view it takes.
#pragma once

#include <string>
#include <vector>

#include "findmug_tables.hpp"
#include "search_sim.hpp"

namespace findmug::search {

struct EpisodeResult {
  std::string strategy;
  RunStats stats;
  int tables_mapped = 0;      // (a): confirmed tables in findmug's map at the end
  int positions_visited = 0;  // (a), (b): search positions / places visited
  int frames_processed = 0;   // (a): frames the daemon's pipeline processed
};

// Known names: "findmug", "places", "coverage", "random", "oracle" (or a..e).
std::string canonicalStrategy(const std::string& name);

// Runs one strategy on one world. `model` is needed by "findmug" only.
EpisodeResult runStrategy(const std::string& strategy, const World& world, const SimParams& params,
                          const FindmugModel* model);

}  // namespace findmug::search
