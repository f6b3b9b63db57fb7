// ObjectTeacher (findmug/daemon/object_teacher.hpp): a live candidate becomes a view
// of a taught object.
#include "findmug/daemon/object_teacher.hpp"

#include <spdlog/spdlog.h>

#include <filesystem>
#include <optional>
#include <utility>

#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/objects/object_model.hpp"

namespace findmug::daemon {

ObjectTeacher::ObjectTeacher(std::string objects_dir, std::size_t frames_kept)
    : objects_dir_(std::move(objects_dir)), frames_kept_(frames_kept) {
  if (frames_kept_ == 0) throw Error("ObjectTeacher: frames_kept must be at least 1");
}

void ObjectTeacher::consume(FrameResult& result) {
  if (objects_dir_.empty()) return;  // teaching is refused anyway: keep nothing
  const LabelledFrame& labelled = result.labelled;
  const OrganizedCloud& cloud = labelled.segmented.prepared.cloud_ground;
  HeldFrame held;
  held.seq = labelled.segmented.prepared.frame.seq;
  held.candidates.reserve(labelled.table_objects.objects.size());
  for (const TableObject& o : labelled.table_objects.objects) {
    Candidate c;
    objectPointsOf(cloud, o.pixels, kMaxObjectViewPoints, c.points, c.colors);
    c.object = o;
    c.object.pixels.clear();
    c.object.pixels.shrink_to_fit();
    held.candidates.push_back(std::move(c));
  }
  std::lock_guard lock(mutex_);
  // A replayed log or a restarted camera starts its seqs again: what was held is stale.
  if (!frames_.empty() && held.seq <= frames_.back().seq) frames_.clear();
  frames_.push_back(std::move(held));
  while (frames_.size() > frames_kept_) frames_.pop_front();
}

void ObjectTeacher::refuse(std::int64_t request_id, const std::string& why) {
  const std::string line = "teach refused: " + why;
  {
    std::lock_guard lock(mutex_);
    ++status_.refused;
    status_.last_ok = false;
    status_.last_result = line;
    status_.last_request_id = request_id;
  }
  throw Error(line);
}

std::string ObjectTeacher::teach(std::int64_t request_id, const std::string& argument) {
  io::TeachRequest request;
  try {
    request = io::parseTeachArgument(argument);
  } catch (const Error& e) {
    refuse(request_id, e.what());
  }
  if (objects_dir_.empty()) {
    refuse(request_id, "daemon.objects_dir is not set: there is no folder to write " +
                                  request.name + ".fmo to");
  }
  std::optional<Candidate> chosen;
  std::string why;
  {
    std::lock_guard lock(mutex_);
    const HeldFrame* frame = nullptr;
    for (const HeldFrame& f : frames_) {
      if (f.seq == request.seq) frame = &f;
    }
    if (!frame) {
      why = "frame seq " + std::to_string(request.seq) + " is not held (the last " +
            std::to_string(frames_kept_) + " frames are kept; " +
            (frames_.empty() ? std::string("none held yet")
                             : "holding seqs " + std::to_string(frames_.front().seq) + ".." +
                                   std::to_string(frames_.back().seq)) +
            ")";
    } else if (static_cast<std::size_t>(request.index) >= frame->candidates.size()) {
      why = "frame seq " + std::to_string(request.seq) + " has " +
            std::to_string(frame->candidates.size()) + " candidate(s), no index " +
            std::to_string(request.index);
    } else {
      chosen = frame->candidates[static_cast<std::size_t>(request.index)];
    }
  }
  if (!chosen) refuse(request_id, why);
  const std::string which = "frame seq " + std::to_string(request.seq) + ", candidate " +
                            std::to_string(request.index);
  if ((chosen->object.truncation & kTruncatedBorder) != 0) {
    refuse(request_id, which + " is cut by the image border (only part of it is in "
                                      "view); teach it from a frame that shows all of it");
  }
  const std::string path = (std::filesystem::path(objects_dir_) / (request.name + ".fmo")).string();
  int views = 0;
  try {
    ObjectView view =
        makeObjectView(chosen->object, std::move(chosen->points), std::move(chosen->colors));
    std::lock_guard write(write_mutex_);
    views = addObjectViewToFile(path, request.name, std::move(view));
  } catch (const Error& e) {
    refuse(request_id, which + ": " + e.what());
  }
  const std::string line = "taught " + request.name + " (" + std::to_string(views) +
                           (views == 1 ? " view" : " views") + ") from " + which;
  spdlog::info("teach request {}: {} -> {}", request_id, line, path);
  std::lock_guard lock(mutex_);
  ++status_.taught;
  status_.last_ok = true;
  status_.last_result = line;
  status_.last_request_id = request_id;
  return line;
}

TeachStatus ObjectTeacher::status() const {
  std::lock_guard lock(mutex_);
  return status_;
}

std::vector<std::int64_t> ObjectTeacher::heldSeqs() const {
  std::lock_guard lock(mutex_);
  std::vector<std::int64_t> out;
  for (const HeldFrame& f : frames_) out.push_back(f.seq);
  return out;
}

}  // namespace findmug::daemon
