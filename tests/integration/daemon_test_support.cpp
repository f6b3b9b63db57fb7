#include "daemon_test_support.hpp"

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstring>
#include <lcm/lcm-cpp.hpp>
#include <stdexcept>

#include "findmug/offline/training.hpp"
#include "findmug/segmenter/segmenter.hpp"

namespace findmug::daemon::test {

SegmenterConfig fastSegmenterConfig() {
  SegmenterConfig config;
  config.oversegmentation.kind = OversegmenterKind::Organized;
  return config;
}

SegmenterConfig fastSegmenterConfig(int step) {
  SegmenterConfig config = fastSegmenterConfig();
  config.ground.min_floor_points /= step * step;
  return config;
}

RgbdFrame subsampled(const RgbdFrame& in, int step) {
  RgbdFrame out = in;
  out.width = in.width / step;
  out.height = in.height / step;
  out.depth_mm.assign(static_cast<std::size_t>(out.width) * out.height, 0);
  out.rgb.assign(out.depth_mm.size(), Rgb8{});
  for (int y = 0; y < out.height; ++y) {
    for (int x = 0; x < out.width; ++x) {
      const std::size_t from = static_cast<std::size_t>(step * y) * in.width + step * x;
      out.depth_mm[static_cast<std::size_t>(y) * out.width + x] = in.depth_mm[from];
      out.rgb[static_cast<std::size_t>(y) * out.width + x] = in.rgb[from];
    }
  }
  out.intrinsics = {in.intrinsics.fx / step, in.intrinsics.fy / step, in.intrinsics.cx / step,
                    in.intrinsics.cy / step};
  return out;
}

LabeledFrame subsampled(const LabeledFrame& in, int step) {
  LabeledFrame out;
  out.name = in.name;
  out.frame = subsampled(in.frame, step);
  out.labels.resize(static_cast<std::size_t>(out.frame.width) * out.frame.height);
  for (int y = 0; y < out.frame.height; ++y) {
    for (int x = 0; x < out.frame.width; ++x) {
      out.labels[static_cast<std::size_t>(y) * out.frame.width + x] =
          in.labels[static_cast<std::size_t>(step * y) * in.frame.width + step * x];
    }
  }
  return out;
}

std::vector<LabeledFrame> framesWithGround(const std::string& dataset_dir, std::size_t count) {
  DatasetFolder ds(dataset_dir);
  const Segmenter probe(fastSegmenterConfig(), nullptr);
  std::vector<LabeledFrame> frames;
  for (std::size_t i = 0; i < ds.size() && frames.size() < count; ++i) {
    LabeledFrame f = ds.load(i);
    if (probe.prepare(f.frame).ground) frames.push_back(std::move(f));
  }
  return frames;
}

std::shared_ptr<const RandomForest> trainTinyModel(const SegmenterConfig& config,
                                                   const std::vector<LabeledFrame>& frames,
                                                   const std::string& path) {
  const Segmenter extractor(config, nullptr);
  TrainingSet data;
  std::string summary;
  for (const LabeledFrame& f : frames) {
    const SegmentedFrame segmented = extractor.oversegment(extractor.prepare(f.frame));
    summary += " [" + f.name + ": ground " + (segmented.prepared.ground ? "yes" : "no") + ", " +
               std::to_string(segmented.segmentation.segments.size()) + " segments]";
    const SegmentFeatures features = extractor.features(segmented);
    const std::vector<std::uint8_t> labels =
        segmentMajorityLabels(segmented.segmentation, f.labels);
    for (std::size_t s = 0; s < features.features.size(); ++s) {
      if (labels[s] == kVoidLabel) continue;
      data.features.push_back(features.features[s]);
      data.labels.push_back(labels[s]);
    }
  }
  if (data.features.empty()) {
    throw std::runtime_error("trainTinyModel: no labelled segments:" + summary);
  }
  ForestParams params;
  params.num_trees = 3;
  params.max_depth = 8;
  params.min_samples_leaf = 2;
  params.num_threads = 2;
  RandomForest forest = RandomForest::train(data, params);
  forest.save(path);
  return std::make_shared<const RandomForest>(RandomForest::load(path));
}

void linkDatasetSubset(const std::filesystem::path& src, const std::vector<std::string>& names,
                       const std::filesystem::path& dst) {
  for (const char* sub : {"rgb", "depth", "label8"}) {
    std::filesystem::create_directories(dst / sub);
    for (const std::string& name : names) {
      std::filesystem::create_symlink(src / sub / (name + ".png"), dst / sub / (name + ".png"));
    }
  }
}

std::vector<LogMessage> readLcmLog(const std::string& path) {
  lcm::LogFile log(path, "r");
  if (!log.good()) throw std::runtime_error("cannot read LCM log " + path);
  std::vector<LogMessage> out;
  while (const lcm::LogEvent* event = log.readNextEvent()) {
    const auto* bytes = static_cast<const std::uint8_t*>(event->data);
    out.push_back({event->channel, std::vector<std::uint8_t>(bytes, bytes + event->datalen)});
  }
  return out;
}

void writeLcmLog(const std::string& path, const std::vector<LogMessage>& messages) {
  lcm::LogFile log(path, "w");
  if (!log.good()) throw std::runtime_error("cannot write LCM log " + path);
  std::int64_t n = 0;
  for (const LogMessage& m : messages) {
    lcm::LogEvent event;
    event.eventnum = n;
    event.timestamp = 1'000'000 + n * 1000;
    event.channel = m.channel;
    event.datalen = static_cast<std::int32_t>(m.data.size());
    event.data = const_cast<std::uint8_t*>(m.data.data());
    if (log.writeEvent(&event) != 0) throw std::runtime_error("cannot write to " + path);
    ++n;
  }
}

NotifySocket::NotifySocket(std::string path) : path_(std::move(path)) {
  fd_ = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::runtime_error("socket: " + std::string(std::strerror(errno)));
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  if (path_.size() >= sizeof(addr.sun_path)) throw std::runtime_error("socket path too long");
  std::strcpy(addr.sun_path, path_.c_str());
  if (bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0) {
    throw std::runtime_error("bind " + path_ + ": " + std::strerror(errno));
  }
}

NotifySocket::~NotifySocket() {
  if (fd_ >= 0) close(fd_);
  unlink(path_.c_str());
}

std::optional<std::string> NotifySocket::receive(std::chrono::milliseconds timeout) {
  pollfd p{fd_, POLLIN, 0};
  if (poll(&p, 1, static_cast<int>(timeout.count())) <= 0) return std::nullopt;
  char buffer[4096];
  const ssize_t n = recv(fd_, buffer, sizeof(buffer), 0);
  if (n < 0) return std::nullopt;
  return std::string(buffer, static_cast<std::size_t>(n));
}

}  // namespace findmug::daemon::test
