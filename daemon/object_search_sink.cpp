// ObjectSearchSink (findmug/daemon/object_search_sink.hpp): taught objects named
// among the table-top candidates, kept in the object map, and "find" answered.
#include "findmug/daemon/object_search_sink.hpp"

#include <spdlog/spdlog.h>

#include <sstream>
#include <string_view>
#include <thread>
#include <utility>

#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/lcm_codec_objects.hpp"
#include "findmug/map/semantic_map.hpp"
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
                                   Channels channels, TableMapSource table_map, OnError on_error)
    : settings_(std::move(settings)),
      bus_(std::move(bus)),
      channels_(std::move(channels)),
      table_map_(std::move(table_map)),
      on_error_(std::move(on_error)),
      library_(settings_.objects_dir),
      map_(settings_.object_map),
      search_(settings_.object_search),
      map_tables_(std::make_shared<const std::vector<TableCluster>>()) {
  validateObjectMatcherConfig(settings_.matcher);
  if (settings_.queue_capacity < 1) throw Error("object search: the queue needs room for a frame");
  refreshLibrary();
  StageOptions options;
  options.name = "object_search";
  options.mode = settings_.mode;
  options.queue_capacity = static_cast<std::size_t>(settings_.queue_capacity);
  options.policy = DropPolicy::DropOldest;
  options.latency_window = std::chrono::seconds(3600);
  options.thread_name = "findmug-objects";
  stage_ = std::make_unique<Stage<Job, Done>>(
      options, StageCallbacks<Job, Done>{
                   .work = [this](Job& job) -> std::optional<Done> {
                     work(job);
                     recycle(job);
                     return Done{};
                   },
                   .emit = [](Done&&) {},
                   .on_drop =
                       [this](Job& dropped) {
                         spdlog::debug("object search behind: skipped frame seq {}", dropped.seq);
                         recycle(dropped);
                       },
                   .on_error = [this](const std::string& what) { on_error_(what); },
               });
  // A worker only where there can be work: taught objects to look for, or a map to keep.
  if (active()) stage_->start();
}

ObjectSearchSink::~ObjectSearchSink() { stop(false); }

void ObjectSearchSink::refreshLibrary() {
  if (settings_.objects_dir.empty()) return;
  const ObjectLibraryChange change = library_.refresh();
  next_refresh_ = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                     std::chrono::duration<double>(settings_.refresh_period_s));
  has_models_.store(!library_.models()->empty());
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

void ObjectSearchSink::countRefusal(const std::string& rejection) {
  // mutex_ held. The matcher's refusals begin with their reason (object_matcher.hpp).
  const auto starts = [&](std::string_view prefix) { return rejection.rfind(prefix, 0) == 0; };
  if (starts("too big")) {
    ++counters_.refused_too_big;
  } else if (starts("too small")) {
    ++counters_.refused_too_small;
  } else if (starts("wrong colour")) {
    ++counters_.refused_colour;
  } else if (starts("wrong shape: not round")) {
    ++counters_.refused_not_round;
  } else if (starts("wrong shape")) {
    ++counters_.refused_shape;
  } else if (starts("too few points")) {
    ++counters_.refused_few_points;
  }
}

std::vector<ObjectIdentity> ObjectSearchSink::nameCandidates(const Job& job) {
  const ObjectLibrary::Models models = library_.models();
  if (job.candidates.empty() || !models || models->empty()) return {};
  const std::vector<ObjectMatch> matches =
      matchObjects(job.points, job.candidates, *models, settings_.matcher);
  std::vector<ObjectIdentity> identities(matches.size());
  const bool log_rejections = Clock::now() >= next_rejection_log_;
  std::lock_guard lock(mutex_);
  ++counters_.frames_matched;
  counters_.candidates += matches.size();
  for (std::size_t i = 0; i < matches.size(); ++i) {
    if (matches[i].matched()) {
      identities[i] = {matches[i].name, matches[i].score};
      ++counters_.matches;
      continue;
    }
    countRefusal(matches[i].rejection);
    if (log_rejections) {
      spdlog::debug("{}: candidate {} is not {}: {}", job.frame_name, job.candidates[i].id,
                    matches[i].name, matches[i].rejection);
    }
  }
  if (log_rejections) next_rejection_log_ = Clock::now() + std::chrono::seconds(1);
  return identities;
}

namespace {

// The table without its pixel list (the object map needs its top and hull only).
TableCluster withoutPixels(const TableCluster& t) {
  TableCluster out;
  out.id = t.id;
  out.centroid = t.centroid;
  out.top_height = t.top_height;
  out.major_axis = t.major_axis;
  out.minor_axis = t.minor_axis;
  out.extents = t.extents;
  out.center = t.center;
  out.hull = t.hull;
  out.top_area_m2 = t.top_area_m2;
  out.horizontal_share = t.horizontal_share;
  out.point_count = t.point_count;
  out.mean_confidence = t.mean_confidence;
  out.search_positions = t.search_positions;
  return out;
}

}  // namespace

std::vector<std::uint16_t> ObjectSearchSink::takeDepthBuffer() {
  std::lock_guard lock(spare_depth_mutex_);
  if (spare_depth_.empty()) return {};
  std::vector<std::uint16_t> buffer = std::move(spare_depth_.back());
  spare_depth_.pop_back();
  return buffer;
}

void ObjectSearchSink::recycle(Job& job) {
  if (!job.view_depth) return;
  std::lock_guard lock(spare_depth_mutex_);
  // As many as can be in flight: the queue, the job at work and the one being made.
  if (spare_depth_.size() < static_cast<std::size_t>(settings_.queue_capacity) + 2)
    spare_depth_.push_back(std::move(job.view_depth->depth_mm));
  job.view_depth.reset();
}

ObjectSearchSink::Job ObjectSearchSink::makeJob(const FrameResult& result) {
  const LabelledFrame& labelled = result.labelled;
  const PreparedFrame& prepared = labelled.segmented.prepared;
  Job job;
  job.utime = prepared.frame.utime;
  job.seq = prepared.frame.seq;
  job.frame_name = frameName(prepared.frame);
  job.pose = result.pose;
  job.evidence = result.pose && TableMapSink::isEvidence(labelled);
  bool searching = false;
  {
    std::lock_guard lock(mutex_);
    searching = request_name_.has_value();
  }
  const RgbdFrame& frame = prepared.frame;
  const bool has_depth = frame.width > 0 && frame.height > 0 &&
                         frame.depth_mm.size() == static_cast<std::size_t>(frame.width) * frame.height;
  if (searching && has_depth && result.pose && prepared.ground) {
    RgbdFrame depth;
    depth.width = frame.width;
    depth.height = frame.height;
    depth.depth_mm = takeDepthBuffer();
    depth.depth_mm.assign(frame.depth_mm.begin(), frame.depth_mm.end());
    depth.intrinsics = frame.intrinsics;
    depth.source = job.frame_name;
    job.view_depth = std::move(depth);
    job.camera_in_map = cameraInMap(result.pose->pose, prepared.ground->camera_to_ground);
  }
  const std::vector<TableObject>& candidates = labelled.table_objects.objects;
  // The matcher reads each candidate's points from the cloud by pixel: copy those points
  // alone, in the same order (the same points go to the matcher, so the same results),
  // rather than the frame's whole cloud.
  const bool matching = has_models_.load() && !candidates.empty();
  std::size_t pixels = 0;
  if (matching) {
    for (const TableObject& c : candidates) pixels += c.pixels.size();
    job.points.points.reserve(pixels);
  }
  job.candidates.reserve(candidates.size());
  const OrganizedCloud& cloud = prepared.cloud_ground;
  for (const TableObject& c : candidates) {
    TableObject copy;
    copy.id = c.id;
    copy.table = c.table;
    copy.centroid = c.centroid;
    copy.height_above_top = c.height_above_top;
    copy.major_axis = c.major_axis;
    copy.extents = c.extents;
    copy.center = c.center;
    copy.point_count = c.point_count;
    copy.mean_rgb = c.mean_rgb;
    copy.colour_histogram = c.colour_histogram;
    copy.truncation = c.truncation;
    if (matching) {
      copy.pixels.reserve(c.pixels.size());
      for (int p : c.pixels) {
        if (p < 0 || static_cast<std::size_t>(p) >= cloud.size()) {
          throw Error(job.frame_name + ": object candidate " + std::to_string(c.id) +
                      " has pixel " + std::to_string(p) + " outside the cloud");
        }
        copy.pixels.push_back(static_cast<int>(job.points.points.size()));
        job.points.points.push_back(cloud.points[static_cast<std::size_t>(p)]);
      }
    }
    job.candidates.push_back(std::move(copy));
  }
  job.points.width = static_cast<int>(job.points.points.size());
  job.points.height = job.points.width > 0 ? 1 : 0;
  if (job.evidence) {
    job.tables.reserve(labelled.tables.size());
    for (const TableCluster& t : labelled.tables) job.tables.push_back(withoutPixels(t));
    if (result.map_info.size() == labelled.tables.size()) {
      for (const io::TableMapInfo& info : result.map_info) job.table_ids.push_back(info.map_id);
    }
  }
  // The table map's tables: copied only when the map changed since the last copy; every
  // job holds the copy current at its frame (a dropped job loses nothing).
  if (settings_.map_objects && result.pose && table_map_.revision && table_map_.confirmed_tables) {
    const std::uint64_t revision = table_map_.revision();
    if (!table_map_revision_ || *table_map_revision_ != revision || !table_map_copy_) {
      table_map_copy_ =
          std::make_shared<const std::vector<TableCluster>>(table_map_.confirmed_tables());
      table_map_revision_ = revision;
      std::lock_guard lock(mutex_);
      ++counters_.table_map_copies;
    }
  }
  job.map_tables = table_map_copy_;
  return job;
}

void ObjectSearchSink::consume(FrameResult& result) {
  if (stopped_.load()) return;
  // Nothing to name and nothing to map: no job (the folder is still looked at when taught
  // objects may appear in it).
  const bool mapping = settings_.map_objects && result.pose.has_value();
  if (settings_.objects_dir.empty() && !mapping) return;
  Job job = makeJob(result);
  {
    std::lock_guard lock(mutex_);
    ++counters_.frames_queued;
  }
  stage_->push(std::move(job));
}

void ObjectSearchSink::work(Job& job) {
  if (settings_.before_job) settings_.before_job();
  if (!settings_.objects_dir.empty() && Clock::now() >= next_refresh_) refreshLibrary();
  const std::vector<ObjectIdentity> identities = nameCandidates(job);
  if (!settings_.map_objects || !job.pose) return;
  std::optional<io::FindResultMessage> changed;
  std::vector<std::uint8_t> map_bytes;
  {
    std::lock_guard lock(mutex_);
    if (job.map_tables) map_tables_ = job.map_tables;
    if (job.evidence) {
      map_.update(job.candidates, job.tables, job.table_ids, job.pose->pose, job.utime,
                  identities);
      counters_.mapped_objects = map_.objects().size();
      if (settings_.publish_map) {
        map_bytes = io::encodeMessage(io::encodeObjectMap(job.utime, job.seq, map_.objects(),
                                                          *map_tables_, *job.pose));
      }
    }
    robot_ = job.pose->pose;
    search_.observeRobot(*robot_, *map_tables_);
    if (job.view_depth) search_.observeView(*map_tables_, *job.view_depth, job.camera_in_map);
    if (request_name_) {
      io::FindResultMessage answer = answerLocked(nowUtime());
      if (answerKey(answer) != last_answer_) {
        last_answer_ = answerKey(answer);
        changed = std::move(answer);
      }
    }
  }
  if (!map_bytes.empty()) publishMap(map_bytes, job.seq);
  if (changed) publish(*changed);
}

io::FindResultMessage ObjectSearchSink::answerLocked(std::uint64_t utime) {
  const FindAnswer answer = search_.answer(search_.requestId(), *request_name_, taught_, map_,
                                           *map_tables_, robot_, utime);
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
          search_.answer(request_id, name, taught_, map_, *map_tables_, robot_, utime);
      message = io::findResultMessage(answer, request_id, utime, taught_);
      last_answer_ = answerKey(message);
    }
  }
  spdlog::info("find request {}: {}", request_id, message.summary);
  publish(message);
}

void ObjectSearchSink::stop(bool drain) {
  if (stopped_.exchange(true)) return;
  stage_->stop(drain ? StopMode::Drain : StopMode::Discard);
}

void ObjectSearchSink::close() {
  std::lock_guard lock(bus_mutex_);
  bus_.reset();
}

bool ObjectSearchSink::waitIdle(Clock::duration timeout) const {
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    const StageStats s = stage_->stats();
    if (s.queue_depth == 0 && s.in_flight == 0) return true;
    if (Clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

void ObjectSearchSink::publish(const io::FindResultMessage& message) {
  std::shared_ptr<io::Bus> bus;
  {
    std::lock_guard lock(bus_mutex_);
    bus = bus_;
  }
  if (!bus) return;
  if (!io::publishMessage(*bus, channels_.find_result, io::encodeFindResult(message))) {
    on_error_("publish refused on " + channels_.find_result + " (find request " +
              std::to_string(message.request_id) + ")");
    return;
  }
  std::lock_guard lock(mutex_);
  ++counters_.find_answers;
}

void ObjectSearchSink::publishMap(const std::vector<std::uint8_t>& bytes, std::int64_t seq) {
  std::shared_ptr<io::Bus> bus;
  {
    std::lock_guard lock(bus_mutex_);
    bus = bus_;
  }
  if (!bus) return;
  if (!bus->publish(channels_.object_map, bytes.data(), bytes.size())) {
    on_error_("publish refused on " + channels_.object_map + " (object map at frame seq " +
              std::to_string(seq) + ")");
    return;
  }
  std::lock_guard lock(mutex_);
  ++counters_.map_publishes;
}

ObjectSearchSink::Counters ObjectSearchSink::counters() const {
  const StageStats stats = stage_->stats();
  std::lock_guard lock(mutex_);
  Counters c = counters_;
  c.frames_skipped = stats.evicted;
  c.frames_failed = stats.failed;
  c.queue_depth = stats.queue_depth;
  c.queue_capacity = stats.queue_capacity;
  c.latency = stats.latency;
  return c;
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
