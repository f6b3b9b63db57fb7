// sources_internal.hpp (internal to findmug_io) — constructors behind makeSource()
// and the file-sequence machinery the dataset and PCL sources share.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "findmug/io/frame_source.hpp"

namespace findmug::io::detail {

std::unique_ptr<FrameSource> makeOpenni2Source(const SourceSpec& spec);
std::unique_ptr<FrameSource> makeLcmSource(const SourceSpec& spec);
std::unique_ptr<FrameSource> makeDatasetSource(const SourceSpec& spec);
std::unique_ptr<FrameSource> makePclSequenceSource(const SourceSpec& spec);

// A finite list of frames on disk, delivered in order at options.rate_hz,
// optionally looping. A frame that fails to load is logged, counted and
// skipped; a whole pass without one good frame ends the source as Failed
// (looping over nothing but bad files would spin forever).
class FileSequenceSource : public FrameSourceBase {
 public:
  using Loader = std::function<RgbdFrame(std::size_t index)>;

  FileSequenceSource(std::string description, std::size_t count, Loader loader,
                     SourceOptions options);
  std::optional<RgbdFrame> next() override;
  std::string describe() const override { return description_; }

 private:
  std::string description_;
  std::size_t count_;
  Loader loader_;
  SourceOptions options_;
  std::size_t index_ = 0;
  std::int64_t seq_ = 0;
  std::size_t good_in_pass_ = 0;
};

}  // namespace findmug::io::detail
