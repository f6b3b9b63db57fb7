// FileSequenceSource (shared by dataset / pcd / pclzf / tiff) and the dataset source.
#include <spdlog/spdlog.h>

#include "findmug/common/error.hpp"
#include "findmug/frame/dataset.hpp"
#include "sources_internal.hpp"

namespace findmug::io::detail {

FileSequenceSource::FileSequenceSource(std::string description, std::size_t count, Loader loader,
                                       SourceOptions options)
    : description_(std::move(description)),
      count_(count),
      loader_(std::move(loader)),
      options_(std::move(options)) {
  if (count_ == 0) throw Error(description_ + ": no frames");
}

std::optional<RgbdFrame> FileSequenceSource::next() {
  while (!stopRequested()) {
    if (index_ == count_) {
      if (good_in_pass_ == 0) {
        setState(SourceState::Failed);
        recordError("no frame of the sequence could be read; giving up");
        return std::nullopt;
      }
      if (!options_.loop) {
        setState(SourceState::EndOfStream);
        return std::nullopt;
      }
      index_ = 0;
      good_in_pass_ = 0;
    }
    const std::size_t i = index_++;
    RgbdFrame frame;
    try {
      frame = loader_(i);
      frame.utime = 0;  // set at delivery below: the replay's "capture" time
      finishFrame(frame, options_);
    } catch (const Error& e) {
      recordRejected(e.what());
      continue;
    }
    ++good_in_pass_;
    if (!pace(options_.rate_hz)) break;
    frame.utime = hostUtimeNow();
    frame.seq = seq_++;
    recordDelivered();
    return frame;
  }
  setState(SourceState::Stopped);
  return std::nullopt;
}

std::unique_ptr<FrameSource> makeDatasetSource(const SourceSpec& spec) {
  // Replay needs no ground truth: a folder of one's own recordings has none.
  DatasetOptions dataset_options;
  dataset_options.require_labels = false;
  auto folder = std::make_shared<DatasetFolder>(spec.target, dataset_options);
  std::string description =
      "dataset:" + spec.target + " (" + std::to_string(folder->size()) + " frames";
  if (!folder->hasLabels()) description += ", unlabelled";
  if (spec.options.rate_hz > 0)
    description += ", " + fmt::format("{:g}", spec.options.rate_hz) + " Hz";
  if (spec.options.loop) description += ", loop";
  description += ")";
  auto loader = [folder](std::size_t i) {
    LabeledFrame labeled = folder->load(i);
    RgbdFrame frame = std::move(labeled.frame);
    if (frame.source.empty()) frame.source = folder->dir() + "/" + labeled.name;
    return frame;
  };
  return std::make_unique<FileSequenceSource>(std::move(description), folder->size(),
                                              std::move(loader), spec.options);
}

}  // namespace findmug::io::detail
