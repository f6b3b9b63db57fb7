// ObjectSearchSink (findmug/daemon/object_search_sink.hpp): taught objects named
// among the table-top candidates, kept in the object map, and "find" answered.
#include "findmug/daemon/object_search_sink.hpp"

#include <spdlog/spdlog.h>

#include <sstream>
#include <utility>

#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/map/table_map.hpp"

namespace findmug::daemon {
namespace {

// What tells one answer from the next: a client is told again only when it changed.
std::string answerKey(const io::FindResultMessage& m) {
  std::ostringstream key;
  key << static_cast<int>(m.result) << '|' << m.seen_object_id << '|' << m.seen_table_id << '|'
      << m.stand_here.has_value() << '|' << m.places.size();
  for (const PlaceToLook& p : m.places) {
    key << '|' << p.table_id << ',' << p.searched << ',' << p.seen_here_before;
  }
  for (const std::string& n : m.taught_names) key << '|' << n;
  return key.str();
}

std::uint64_t nowUtime() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                        std::chrono::system_clock::now().time_since_epoch())
                                        .count());
}

}  // namespace

ObjectSearchSink::ObjectSearchSink(ObjectSearchSettings settings, std::shared_ptr<io::Bus> bus,
                                   std::string find_channel, MapTables map_tables,
                                   OnError on_error)
    : settings_(std::move(settings)),
      bus_(std::move(bus)),
      find_channel_(std::move(find_channel)),
      map_tables_source_(std::move(map_tables)),
      on_error_(std::move(on_error)),
      library_(settings_.objects_dir),
      map_(settings_.object_map),
      search_(settings_.object_search) {
  validateObjectMatcherConfig(settings_.matcher);
  refreshLibrary();
}

void ObjectSearchSink::refreshLibrary() {
  if (settings_.objects_dir.empty()) return;
  const ObjectLibraryChange change = library_.refresh();
  next_refresh_ = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                     std::chrono::duration<double>(settings_.refresh_period_s));
  if (!change.changed()) return;
  for (const std::string& file : change.loaded) spdlog::info("taught object loaded: {}", file);
  for (const std::string& file : change.dropped) spdlog::info("taught object dropped: {}", file);
  std::vector<std::string> names;
  for (const ObjectModel& model : *library_.models()) names.push_back(model.name);
  std::lock_guard lock(mutex_);
  taught_ = std::move(names);
  for (const ObjectFileRefusal& refusal : change.refused) {
    ++counters_.object_files_refused;
    on_error_("taught object refused: " + refusal.file + ": " + refusal.reason);
  }
}

std::vector<ObjectIdentity> ObjectSearchSink::nameCandidates(const LabelledFrame& labelled) {
  const std::vector<TableObject>& candidates = labelled.table_objects.objects;
  const ObjectLibrary::Models models = library_.models();
  if (candidates.empty() || !models || models->empty()) return {};
  const std::vector<ObjectMatch> matches = matchObjects(labelled.segmented.prepared.cloud_ground,
                                                        candidates, *models, settings_.matcher);
  std::vector<ObjectIdentity> identities(matches.size());
  std::uint64_t named = 0;
  const bool log_rejections = Clock::now() >= next_rejection_log_;
  for (std::size_t i = 0; i < matches.size(); ++i) {
    if (matches[i].matched()) {
      identities[i] = {matches[i].name, matches[i].score};
      ++named;
    } else if (log_rejections) {
      spdlog::debug("{}: candidate {} is not {}: {}", frameName(labelled.segmented.prepared.frame),
                    candidates[i].id, matches[i].name, matches[i].rejection);
    }
  }
  if (log_rejections) next_rejection_log_ = Clock::now() + std::chrono::seconds(1);
  std::lock_guard lock(mutex_);
  ++counters_.frames_matched;
  counters_.matches += named;
  return identities;
}

void ObjectSearchSink::rememberTableMap() {
  // mutex_ held. The confirmed tables, map frame, stable ids: what FINDMUG_TABLE_MAP
  // publishes, so that the places to look are tables a client has been told of.
  if (!map_tables_source_) return;
  map_tables_.clear();
  for (MappedTable& mapped : map_tables_source_()) {
    if (mapped.confirmed) map_tables_.push_back(std::move(mapped.table));
  }
}

void ObjectSearchSink::updateMap(const FrameResult& result,
                                 const std::vector<ObjectIdentity>& identities) {
  // mutex_ held.
  const LabelledFrame& labelled = result.labelled;
  robot_ = result.pose->pose;
  std::vector<int> table_ids;
  if (result.map_info.size() == labelled.tables.size()) {
    for (const io::TableMapInfo& info : result.map_info) table_ids.push_back(info.map_id);
  }
  map_.update(labelled.table_objects.objects, labelled.tables, table_ids, result.pose->pose,
              labelled.segmented.prepared.frame.utime, identities);
  counters_.mapped_objects = map_.objects().size();
}

void ObjectSearchSink::consume(FrameResult& result) {
  if (!settings_.objects_dir.empty() && Clock::now() >= next_refresh_) refreshLibrary();
  const std::vector<ObjectIdentity> identities = nameCandidates(result.labelled);
  if (!settings_.map_objects || !result.pose) return;
  std::optional<io::FindResultMessage> changed;
  {
    std::lock_guard lock(mutex_);
    rememberTableMap();
    if (TableMapSink::isEvidence(result.labelled)) updateMap(result, identities);
    robot_ = result.pose->pose;
    search_.observeRobot(*robot_, map_tables_);
    if (request_name_) {
      io::FindResultMessage answer = answerLocked(nowUtime());
      if (answerKey(answer) != last_answer_) {
        last_answer_ = answerKey(answer);
        changed = std::move(answer);
      }
    }
  }
  if (changed) publish(*changed);
}

io::FindResultMessage ObjectSearchSink::answerLocked(std::uint64_t utime) {
  const FindAnswer answer = search_.answer(search_.requestId(), *request_name_, taught_, map_,
                                           map_tables_, robot_, utime);
  return io::findResultMessage(answer, search_.requestId(), utime, taught_);
}

void ObjectSearchSink::requestFind(std::int64_t request_id, const std::string& name,
                                   std::uint64_t utime) {
  validateObjectModelName(name);  // throws: the command input counts the refusal
  io::FindResultMessage message;
  {
    std::lock_guard lock(mutex_);
    ++counters_.find_requests;
    if (!settings_.map_objects) {
      message = io::findRefusal(name, request_id, utime,
                                "find " + name +
                                    ": no robot pose input, so no object or table map "
                                    "(daemon.pose_input)",
                                taught_);
    } else {
      request_name_ = name;
      // A new request id starts with no table searched (ObjectSearch::answer).
      const FindAnswer answer =
          search_.answer(request_id, name, taught_, map_, map_tables_, robot_, utime);
      message = io::findResultMessage(answer, request_id, utime, taught_);
      last_answer_ = answerKey(message);
    }
  }
  spdlog::info("find request {}: {}", request_id, message.summary);
  publish(message);
}

void ObjectSearchSink::close() {
  std::lock_guard lock(bus_mutex_);
  bus_.reset();
}

void ObjectSearchSink::publish(const io::FindResultMessage& message) {
  std::shared_ptr<io::Bus> bus;
  {
    std::lock_guard lock(bus_mutex_);
    bus = bus_;
  }
  if (!bus) return;
  if (!io::publishMessage(*bus, find_channel_, io::encodeFindResult(message))) {
    on_error_("publish refused on " + find_channel_ + " (find request " +
              std::to_string(message.request_id) + ")");
    return;
  }
  std::lock_guard lock(mutex_);
  ++counters_.find_answers;
}

ObjectSearchSink::Counters ObjectSearchSink::counters() const {
  std::lock_guard lock(mutex_);
  return counters_;
}

std::vector<MappedObject> ObjectSearchSink::mappedObjects() const {
  std::lock_guard lock(mutex_);
  return map_.objects();
}

std::vector<std::string> ObjectSearchSink::taughtNames() const {
  std::lock_guard lock(mutex_);
  return taught_;
}

}  // namespace findmug::daemon
