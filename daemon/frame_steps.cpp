// The pipeline's three steps (frame_steps.hpp).
#include "findmug/daemon/frame_steps.hpp"

#include <spdlog/spdlog.h>

#include <exception>
#include <stdexcept>
#include <string>

#include "findmug/common/error.hpp"

namespace findmug::daemon {

namespace {

// The slots of `r` that hold something.
unsigned filledSlots(const FrameResult& r) {
  return (r.map_info.empty() ? 0u : unsigned{kMapInfo}) |
         (r.table_map ? unsigned{kTableMapMessage} : 0u) |
         (r.published_labels ? unsigned{kPublishedLabels} : 0u);
}

}  // namespace

CurrentSegmenter fixedSegmenter(const Segmenter& segmenter) {
  // Aliasing constructor: points at `segmenter`, owns nothing.
  return [p = &segmenter] { return std::shared_ptr<const Segmenter>(std::shared_ptr<void>(), p); };
}

PreparedJob PrepareStep::operator()(FrameJob& job) {
  const std::string name = frameName(job.frame);
  try {
    validateFrame(job.frame);
    std::shared_ptr<const Segmenter> segmenter = segmenter_();
    PreparedFrame prepared = segmenter->prepare(std::move(job.frame), ground_);
    return PreparedJob{std::move(prepared), job.arrival, std::move(segmenter), job.trace};
  } catch (const std::exception& e) {
    throw Error(name + ": " + e.what());
  }
}

ResultJob SegmentStep::operator()(PreparedJob& job) const {
  if (before_segment_) before_segment_(job.prepared.frame);
  const std::string name = frameName(job.prepared.frame);
  try {
    const std::shared_ptr<const Segmenter> segmenter = job.segmenter ? job.segmenter : segmenter_();
    return ResultJob{segmenter->classify(segmenter->oversegment(std::move(job.prepared))),
                     job.arrival, job.trace};
  } catch (const std::exception& e) {
    throw Error(name + ": " + e.what());
  }
}

void PublishStep::addSink(std::shared_ptr<ResultSink> sink) {
  if (!sink) return;
  const SinkSlots added = sink->slots();
  for (const auto& earlier : sinks_) {
    const SinkSlots e = earlier->slots();
    if (const unsigned both = e.writes & added.writes) {
      throw std::logic_error(sink->name() + " and " + earlier->name() + " both write " +
                             resultSlotNames(both) + " of the frame result");
    }
    if (const unsigned too_late = e.reads & added.writes) {
      throw std::logic_error(sink->name() + " writes " + resultSlotNames(too_late) + ", which " +
                             earlier->name() + ", added before it, reads: add it earlier");
    }
  }
  sinks_.push_back(std::move(sink));
}

std::int64_t PublishStep::operator()(const ResultJob& job, StepClock::time_point now) const {
  const LabelledFrame& labelled = job.labelled;
  const RgbdFrame& frame = labelled.segmented.prepared.frame;
  const auto latency_us =
      std::chrono::duration_cast<std::chrono::microseconds>(now - job.arrival).count();
  if (spdlog::should_log(spdlog::level::debug)) {
    for (const std::string& line : labelled.table_diagnostics) {
      spdlog::debug("{}: tables: {}", frameName(frame), line);
    }
  }
  FrameResult result{labelled, latency_us, std::nullopt, {}, std::nullopt, std::nullopt};
  // The robot's pose for this frame, if one close enough in time has arrived.
  if (poses_) result.pose = poses_->history().closest(frame.utime, pose_max_age_us_);
  for (const auto& sink : sinks_) {
    const unsigned before = filledSlots(result);
    sink->consume(result);
    if (const unsigned undeclared = filledSlots(result) & ~before & ~sink->slots().writes) {
      throw std::logic_error(sink->name() + " filled " + resultSlotNames(undeclared) +
                             " of " + frameName(frame) + " without declaring it (slots())");
    }
  }
  return latency_us;
}

}  // namespace findmug::daemon
