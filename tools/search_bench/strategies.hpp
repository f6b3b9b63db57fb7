// strategies.hpp — how the simulated robot searches (findmug-search-bench, issue 51).
//
//   a findmug      look around, then visit the search positions of findmug's table map
//                  (the daemon's FINDMUG_TABLE_MAP), nearest first by planned path and
//                  re-planned after every view, one position per table; when none is left,
//                  explore the nearest
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
//   f tables       (a)'s rules on a perfect table map: the apartment's true tables known from
//                  the start (no look-around there), nearest first, one place in front of
//                  each, a table skipped once its top was seen near enough; then (b)'s
//                  fallbacks. A bound, not a baseline: its time over the oracle's is what
//                  not knowing the mug's table costs, findmug's over its own what findmug's
//                  table perception costs.
// Look-arounds (a, d, and the room exploring (a) and (b) fall back to) turn only through the
// headings whose view would show enough floor plan that none of the robot's frames showed
// (Robot::lookAround, ViewCoverage); coverage's look-arounds turn through every heading (it
// marks its own frontiers by its stop views, and goes only where they showed nothing yet).
// --full-look-arounds: every look-around turns through every heading.
// Every strategy uses the same recogniser at every frame it takes (stop views and frames
// while driving):
//   oracle   the rendered mug's pixels (>= recognise_min_pixels within recognise_range_m);
//   matcher  findmugd's own: every frame goes through the daemon's Pipeline with the taught
//            mug in daemon.objects_dir, then "find mug" is asked on the command bus; "seen"
//            ends the search, checked against the ground truth (claimIsCorrect). The findmug
//            strategy also acts on "look closer" answers (the tables the daemon names first
//            go before the rest of the table map, each at most twice) and at each search
//            position looks 0.5 rad to either side too (the matcher wants the mug whole and
//            twice); the oracle strategy,
//            after its best view, drives to the free pose nearest the mug and looks three
//            times from there (the object map names an object after two matches within its
//            naming range), then does the same. The other baselines act on "seen" only.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "findmug_tables.hpp"
#include "search_sim.hpp"

namespace findmug::search {

// How the mug is recognised, and the daemon behind it.
struct Perception {
  enum class Kind { Oracle, Matcher };
  Kind kind = Kind::Oracle;
  // The daemon's model and settings: the findmug strategy's table map, and with the
  // matcher every strategy's recogniser. Null: no daemon (oracle baselines only).
  const FindmugModel* model = nullptr;
  std::string objects_dir;  // matcher: the folder holding the taught mug.fmo
  std::string object_name = "mug";
};

struct EpisodeResult {
  std::string strategy;
  RunStats stats;
  int tables_mapped = 0;      // (a): confirmed tables in findmug's map at the end; (f): true tables
  int positions_visited = 0;  // (a), (b), (f): search positions / places visited
  int frames_processed = 0;   // frames the daemon's pipeline processed (findmug; matcher: all)
  int look_closer = 0;        // matcher: "look closer" places the strategy went to
  // Matcher: table-top candidates the daemon put to the matcher, those it named "mug", and
  // the refusals by the reason the taught mug gave (size, colour, shape incl. roundness).
  int candidates = 0, matches = 0, refused_size = 0, refused_colour = 0, refused_shape = 0;
  std::vector<std::string> trace;  // Robot::trace() with SimParams::trace
};

// Which rooms a strategy has explored (the findmug and places strategies explore the
// others, nearest first). A room is explored once the robot looked around in it (at the
// start, or at its centre) or once its frames have shown SimParams::room_seen_share of its
// floor plan: its cells that do not block the view, as the robot's ViewCoverage marks them
// (stop views and frames while driving, through doorways too). A drive that ends in a room,
// or a look at one table in it, does not explore it: the rest of its floor may hold the mug.
class RoomExplorer {
 public:
  RoomExplorer(const World& world, const SimParams& params);
  // The robot looked around where it stands: its room is explored.
  void lookedAroundHere(const Robot& robot);
  // The share of the room's floor plan the robot's frames have shown.
  double seenShare(const Robot& robot, int room) const;
  bool explored(const Robot& robot, int room) const;
  // The share of the room's floor plan the robot's frames would have shown after a
  // look-around at `xy`: what they showed, and what a full turn there shows of it within
  // SimParams::coverage_range_m (near enough to count as searched: a mug shows from further
  // only head-on and unhidden).
  double seenShareAfterLookAround(const Robot& robot, int room, const Eigen::Vector2d& xy) const;
  // Explores the nearest room not yet explored (by planned path to the reachable cell
  // nearest its centre); false when every room is explored. The robot drives towards that
  // cell and looks around (only through headings that show something new) at the first
  // frame's spot inside the room from which a look-around would show as much of its floor
  // plan as one from the centre would, or room_seen_share of it: a room seen from its
  // doorway needs no walk to its middle and back (SimParams::explore_to_room_centres: at the
  // centre, always). When `stop_when` stops the drive, the room stays to be explored and
  // there is no look-around (the caller has something new to look at).
  bool exploreNext(Robot& robot, const std::function<bool()>& stop_when = {});

 private:
  // How many of the room's floor_ cells the robot's frames have shown.
  int coveredCells(const Robot& robot, int room) const;

  const World& world_;
  const SimParams& params_;
  std::vector<bool> done_;               // looked around in
  std::vector<std::vector<int>> floor_;  // per room: its grid cells that do not block the view
  std::vector<int> room_of_;             // per grid cell: the room whose floor_ holds it, or -1
};

// "Look closer" (matcher only): the daemon's answer names tables that may hold the mug
// (find_result_t.place_look_closer: matched too few times or from too far). next() drives
// to the first of their places in the answer's order that was visited fewer than twice for
// this reason and has a reachable cell within 0.25 m, faces it and looks; false when there
// is none. `answer` is the caller's latest answer, which the frames of that drive replace:
// the place is copied before the robot moves (a reference into it read a freed heading).
class LookCloser {
 public:
  bool next(Robot& robot, const io::FindResultMessage& answer, const World& world);
  int taken() const { return taken_; }

 private:
  struct Choice {
    PlaceToLook place;
    int cell = -1;  // the reachable grid cell to stand on
  };
  std::optional<Choice> choose(const Robot& robot, const io::FindResultMessage& answer,
                               const World& world);
  int& visitsNear(const Eigen::Vector2d& xy);

  std::vector<std::pair<Eigen::Vector2d, int>> visits_;
  int taken_ = 0;
};

// Known names: "findmug", "places", "coverage", "random", "oracle", "tables" (or a..f).
std::string canonicalStrategy(const std::string& name);

// Runs one strategy on one world. `perception.model` is needed by "findmug" and by every
// strategy under the matcher. Throws findmug::Error when it is missing.
EpisodeResult runStrategy(const std::string& strategy, const World& world, const SimParams& params,
                          const Perception& perception);

}  // namespace findmug::search
