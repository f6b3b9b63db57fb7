// findmug/daemon/frame_steps.hpp — the pipeline's three steps, one named class each.
//
//   PrepareStep   the frame checked (validateFrame), then Segmenter::prepare: cloud,
//                 normals, ground plane
//   SegmentStep   Segmenter::oversegment + classify: oversegmentation, features, forest, MRF,
//                 labels, tables
//   PublishStep   the robot's pose for the frame (PoseInput, if any), then every
//                 ResultSink in the order they were added (result_sinks.hpp)
//
// Each step does one frame's work and knows nothing of threads, queues or drop policies:
// Pipeline (pipeline.hpp) runs each inside a Stage, which owns those. So a test can run a
// step on one frame, and a step can be reused in another arrangement. A failing step throws
// findmug::Error naming the frame; the Stage counts it as rejected.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "findmug/daemon/frame_trace.hpp"
#include "findmug/daemon/pose_input.hpp"
#include "findmug/daemon/result_sinks.hpp"
#include "findmug/frame/frame.hpp"
#include "findmug/segmenter/segmenter.hpp"

namespace findmug::daemon {

using StepClock = std::chrono::steady_clock;

// The Segmenter a step runs one frame with, asked for once per frame (the daemon's
// ModelSlot, whose model may be swapped between frames: model_reload.hpp).
using CurrentSegmenter = std::function<std::shared_ptr<const Segmenter>()>;
// Always `segmenter` (not owned: it must outlive the step).
CurrentSegmenter fixedSegmenter(const Segmenter& segmenter);

// What travels between the steps: the frame's data, when it arrived (for latency) and when
// it entered and left each stage so far (the Stage callbacks stamp it; the steps carry it on).
struct FrameJob {
  RgbdFrame frame;
  StepClock::time_point arrival;
  FrameTrace trace;
};
struct PreparedJob {
  PreparedFrame prepared;
  StepClock::time_point arrival;
  // The Segmenter that prepared the frame: the frame's other steps run on it too, so that
  // a model swapped in meanwhile, whose recorded settings (cloud, normals) may differ,
  // never classifies a frame another model's settings prepared.
  std::shared_ptr<const Segmenter> segmenter;
  FrameTrace trace;
};
struct ResultJob {
  LabelledFrame labelled;
  StepClock::time_point arrival;
  FrameTrace trace;
};

// Owns the stream's ground tracker (ground.reestimate_every_frames): the floor found in one
// frame is kept for the next ones, whichever model the current Segmenter has, so a model
// reload does not reset it. Not thread-safe: one thread at a time runs a PrepareStep (the
// pipeline's prepare stage has one worker; sequential mode runs it on the caller's thread).
class PrepareStep {
 public:
  explicit PrepareStep(const Segmenter& segmenter) : segmenter_(fixedSegmenter(segmenter)) {}
  explicit PrepareStep(CurrentSegmenter segmenter) : segmenter_(std::move(segmenter)) {}
  PreparedJob operator()(FrameJob& job);
  // The floor the stream follows (tests).
  const GroundTracker& ground() const { return ground_; }

 private:
  CurrentSegmenter segmenter_;
  GroundTracker ground_;
};

class SegmentStep {
 public:
  // `before_segment` (tests: hold a worker) runs first on every frame, if set.
  explicit SegmentStep(const Segmenter& segmenter,
                       std::function<void(const RgbdFrame&)> before_segment = {})
      : segmenter_(fixedSegmenter(segmenter)), before_segment_(std::move(before_segment)) {}
  explicit SegmentStep(CurrentSegmenter segmenter,
                       std::function<void(const RgbdFrame&)> before_segment = {})
      : segmenter_(std::move(segmenter)), before_segment_(std::move(before_segment)) {}
  // Oversegments and classifies with one Segmenter (one model) for the whole frame: the
  // one that prepared it (PreparedJob::segmenter), else the current one.
  ResultJob operator()(PreparedJob& job) const;

 private:
  CurrentSegmenter segmenter_;
  std::function<void(const RgbdFrame&)> before_segment_;
};

class PublishStep {
 public:
  explicit PublishStep(std::uint64_t pose_max_age_us) : pose_max_age_us_(pose_max_age_us) {}
  // Both before the first frame (not thread-safe against operator()).
  void addSink(std::shared_ptr<ResultSink> sink);
  void setPoseInput(const PoseInput* poses) { poses_ = poses; }  // nullptr: no poses
  // Hands the result, with the pose closest in time (within pose_max_age_us), to every
  // sink; returns the frame's latency from arrival to `now`, in microseconds.
  std::int64_t operator()(const ResultJob& job, StepClock::time_point now) const;

 private:
  std::uint64_t pose_max_age_us_;
  const PoseInput* poses_ = nullptr;
  std::vector<std::shared_ptr<ResultSink>> sinks_;  // in the order they see a result
};

}  // namespace findmug::daemon
