// findmug/daemon/object_teacher.hpp — teaching an object from the live view:
// the command "teach NAME SEQ INDEX" (command_t) makes the candidate INDEX of
// the objects_t of frame SEQ one more view of the taught object NAME.
//
// A sink after the LcmPublisherSink (result_sinks.hpp), on the publish thread:
// for each of the last `frames_kept` published frames it keeps the frame's
// table-top candidates as objects_t described them (same order, so INDEX is
// the candidate's index in that message) with their points taken out of the
// frame's cloud (objectPointsOf, at most kMaxObjectViewPoints each): a client
// that saw a candidate on FINDMUG_OBJECTS (findmug-web's live page) names it
// by the frame's seq and its index, and the daemon, which held the points,
// builds the view.
//
// teach() runs on the command thread: the view is made by makeObjectView
// (objects/object_model.hpp, the function findmug-teach uses) and added to
// daemon.objects_dir/NAME.fmo by addObjectViewToFile (a new model, or one
// more view of the model there, at most kMaxObjectViews; written through a
// temporary file renamed over it), so that the ObjectSearchSink's library
// reads it on its next refresh, without a restart. Refused, with the reason
// and the request id in the outcome (status_t.last_teach_*), and counted: no
// daemon.objects_dir, a bad argument, a frame no longer held, no such
// candidate, a candidate cut by the image border (only part of the object is
// in view: a view of it would teach a smaller object), too few points with
// depth, the model full, a file that cannot be read or written.
//
// Thread safety: consume() on the publish thread, teach() and the readers
// from any thread.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <vector>

#include "findmug/daemon/result_sinks.hpp"
#include "findmug/objects/table_objects.hpp"

namespace findmug::daemon {

// The outcome of the last teach request, for status_t.
struct TeachStatus {
  std::uint64_t taught = 0;   // views added
  std::uint64_t refused = 0;  // requests refused
  bool last_ok = false;
  // "taught mug (3 views) from frame seq 41, candidate 2", or the refusal; "" before any.
  std::string last_result;
  std::int64_t last_request_id = -1;  // -1 before any
};

class ObjectTeacher final : public ResultSink {
 public:
  static constexpr std::size_t kDefaultFramesKept = 30;

  // `objects_dir`: where the models are written ("" = teaching refused).
  explicit ObjectTeacher(std::string objects_dir, std::size_t frames_kept = kDefaultFramesKept);

  std::string name() const override { return "ObjectTeacher"; }
  void consume(FrameResult& result) override;

  // `argument`: "NAME SEQ INDEX" (io::parseTeachArgument). Returns the outcome's
  // line; throws findmug::Error with it when refused (after recording it), so
  // that the command input counts and logs the refusal.
  std::string teach(std::int64_t request_id, const std::string& argument);

  TeachStatus status() const;
  // The seqs held now, oldest first (for the tests).
  std::vector<std::int64_t> heldSeqs() const;

 private:
  struct Candidate {
    TableObject object;  // pixels dropped: the points below are what is kept
    std::vector<Eigen::Vector3f> points;
    std::vector<Rgb8> colors;
  };
  struct HeldFrame {
    std::int64_t seq = 0;
    std::vector<Candidate> candidates;
  };

  // Records the refusal and throws it.
  [[noreturn]] void refuse(std::int64_t request_id, const std::string& why);

  const std::string objects_dir_;
  const std::size_t frames_kept_;
  mutable std::mutex mutex_;  // guards frames_ and status_
  std::deque<HeldFrame> frames_;
  TeachStatus status_;
  std::mutex write_mutex_;  // one teach at a time writes the folder
};

}  // namespace findmug::daemon
