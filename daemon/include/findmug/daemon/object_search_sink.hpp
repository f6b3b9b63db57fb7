// findmug/daemon/object_search_sink.hpp — the objects on the tables, named, mapped and found.
//
// A sink after the TableMapSink (result_sinks.hpp), on the publish thread, in
// frame order. For each published frame:
//   1. every daemon.objects_refresh_s it re-reads daemon.objects_dir (the
//      taught objects, ObjectLibrary): a new or changed file is picked up, a
//      corrupt one refused with its reason (logged, last_error, counted);
//   2. it names the frame's table-top candidates with the taught-object
//      matcher (objects/object_matcher.hpp); why the nearest taught object was
//      refused for a candidate is logged at debug level, at most once a second;
//   3. with a robot pose for a frame that was labelled (the table map's rule),
//      it updates the object map (map/object_map.hpp) with the candidates, the
//      table map ids the TableMapSink gave the frame's tables, and the names;
//   4. it notes the tables at whose search positions the robot stands as
//      searched for the latest find request, and when that request's answer
//      changed (seen now, another place first, a table searched) it publishes
//      it again on FINDMUG_FIND_RESULT.
// A "find" command (command_t, from the command thread) is answered at once
// from what the sink holds (requestFind): where the object was seen, or the
// places to look (map/object_search.hpp), or a refusal with the reason (no
// pose input, so no map; a name not taught, listing the taught ones).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "findmug/daemon/object_library.hpp"
#include "findmug/daemon/result_sinks.hpp"
#include "findmug/io/bus.hpp"
#include "findmug/io/lcm_codec_find.hpp"
#include "findmug/map/object_map.hpp"
#include "findmug/map/object_search.hpp"
#include "findmug/objects/object_matcher.hpp"

namespace findmug::daemon {

struct ObjectSearchSettings {
  std::string objects_dir;         // daemon.objects_dir ("" = no taught objects)
  double refresh_period_s = 1.0;   // how often the folder is looked at again
  bool map_objects = true;         // false without a pose input: no map, no places
  ObjectMapConfig object_map;
  ObjectSearchConfig object_search;
  ObjectMatcherConfig matcher;
};

class ObjectSearchSink final : public ResultSink {
 public:
  using OnError = std::function<void(const std::string& what)>;
  using Clock = std::chrono::steady_clock;

  struct Counters {
    std::uint64_t frames_matched = 0;  // frames whose candidates went through the matcher
    std::uint64_t matches = 0;         // candidates named
    std::uint64_t object_files_refused = 0;
    std::uint64_t find_requests = 0;
    std::uint64_t find_answers = 0;    // find_result_t published (first answers and updates)
    std::uint64_t mapped_objects = 0;  // now
  };

  // The table map's tables now (map frame, stable ids; TableMapSink::tables).
  using MapTables = std::function<std::vector<MappedTable>()>;

  // `bus` (may be null: nothing is published) and `channel` for find_result_t;
  // `map_tables` (may be empty: no tables) where the places to look come from.
  ObjectSearchSink(ObjectSearchSettings settings, std::shared_ptr<io::Bus> bus,
                   std::string find_channel, MapTables map_tables, OnError on_error);

  void consume(FrameResult& result) override;

  // The command "find NAME" with its request id; answers on the find channel
  // (thread-safe, returns quickly). Throws findmug::Error for a name that is
  // not a taught-object name (the command input counts it as refused).
  void requestFind(std::int64_t request_id, const std::string& name, std::uint64_t utime);

  // Lets go of the bus (the pipeline's stop: the last holder closes it, which
  // flushes a file:// log); later answers are not sent. Thread-safe, idempotent.
  void close();

  Counters counters() const;
  std::vector<MappedObject> mappedObjects() const;  // thread-safe copy
  std::vector<std::string> taughtNames() const;

 private:
  void refreshLibrary();
  std::vector<ObjectIdentity> nameCandidates(const LabelledFrame& labelled);
  void updateMap(const FrameResult& result, const std::vector<ObjectIdentity>& identities);
  void rememberTableMap();
  io::FindResultMessage answerLocked(std::uint64_t utime);
  void publish(const io::FindResultMessage& message);

  ObjectSearchSettings settings_;
  mutable std::mutex bus_mutex_;  // guards bus_ (publish thread, command thread, stop)
  std::shared_ptr<io::Bus> bus_;
  std::string find_channel_;
  MapTables map_tables_source_;
  OnError on_error_;
  ObjectLibrary library_;
  Clock::time_point next_refresh_{};
  Clock::time_point next_rejection_log_{};

  mutable std::mutex mutex_;  // guards everything below (publish thread and command thread)
  ObjectMap map_;
  ObjectSearch search_;
  std::vector<TableCluster> map_tables_;  // the table map's confirmed tables, map frame
  std::optional<Pose2D> robot_;           // the newest frame pose
  std::vector<std::string> taught_;       // names in the library, sorted
  std::optional<std::string> request_name_;
  std::string last_answer_;  // summary + places of the last answer published, to spot changes
  Counters counters_;
};

}  // namespace findmug::daemon
