// Helpers shared by the daemon integration tests: a tiny model trained in
// process, LCM log files in and out, a dataset subset made of symlinks, and
// a NOTIFY_SOCKET the test owns.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "findmug/frame/dataset.hpp"
#include "findmug/learner/forest.hpp"
#include "findmug/settings/config.hpp"

namespace findmug::daemon::test {

// Settings that keep the tests quick on a 2-core machine while exercising
// every stage (the organized oversegmenter; the MRF stays on).
SegmenterConfig fastSegmenterConfig();

// Every `step`-th pixel of every `step`-th row, the intrinsics scaled with it (and the
// labels likewise): smaller frames for tests that need many of them quickly. Pair with
// fastSegmenterConfig(step), whose floor support is scaled to the smaller frames.
RgbdFrame subsampled(const RgbdFrame& frame, int step);
LabeledFrame subsampled(const LabeledFrame& frame, int step);
SegmenterConfig fastSegmenterConfig(int step);

// The first `count` frames of a labelled dataset whose ground plane the
// segmenter finds (only those have features to train on).
std::vector<LabeledFrame> framesWithGround(const std::string& dataset_dir, std::size_t count);

// Trains a small forest on the frames' patch features and ground-truth
// labels, saves it to `path` and returns it.
std::shared_ptr<const RandomForest> trainTinyModel(const SegmenterConfig& config,
                                                   const std::vector<LabeledFrame>& frames,
                                                   const std::string& path);

// A folder `dst` in the NYU layout holding symlinks to `names` of `src`
// (rgb/, depth/, label8/): a short sequence without copying the data.
void linkDatasetSubset(const std::filesystem::path& src, const std::vector<std::string>& names,
                       const std::filesystem::path& dst);

struct LogMessage {
  std::string channel;
  std::vector<std::uint8_t> data;
};
std::vector<LogMessage> readLcmLog(const std::string& path);
void writeLcmLog(const std::string& path, const std::vector<LogMessage>& messages);

// An AF_UNIX datagram socket bound at `path`, as systemd's NOTIFY_SOCKET.
class NotifySocket {
 public:
  explicit NotifySocket(std::string path);
  ~NotifySocket();
  NotifySocket(const NotifySocket&) = delete;
  NotifySocket& operator=(const NotifySocket&) = delete;
  const std::string& path() const { return path_; }
  // One datagram, or nullopt after `timeout`.
  std::optional<std::string> receive(std::chrono::milliseconds timeout);

 private:
  std::string path_;
  int fd_ = -1;
};

}  // namespace findmug::daemon::test
