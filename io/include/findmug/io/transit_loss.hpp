// findmug/io/transit_loss.hpp — frames a publisher numbered that never arrived.
//
// A camera driver (or findmug-replay) numbers its frames 0, 1, 2, ... in
// rgbd_frame_t.seq. Over udpm a frame is many datagrams; lose one and LCM
// never delivers the frame, silently. Counting the holes in seq, in arrival
// order, is the only way the daemon can tell "the network lost frames" from
// "the camera sent fewer". Rules:
//   * seq > newest: the frames in between are counted lost (at most
//     kMaxGap of them; a bigger jump is a publisher that restarted with other
//     numbers, not a loss) and remembered (the last kRemembered of them);
//   * a remembered seq that arrives late (reordered) is taken back;
//   * seq == newest, or an older seq that is not remembered: a repeat, or a
//     publisher that started over (a log replay restarted): no count, and
//     an older seq becomes the new reference.
// Not thread-safe: one receive thread owns it.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

namespace findmug::io {

class TransitLossCounter {
 public:
  static constexpr std::int64_t kMaxGap = 1000;   // 33 s at 30 fps
  static constexpr std::size_t kRemembered = 256;

  // One message's seq, in the order messages arrived.
  void observe(std::int64_t seq);
  // Frames counted lost so far (late arrivals already taken back).
  std::uint64_t lost() const { return lost_; }
  // Times the numbering started over or jumped by more than kMaxGap.
  std::uint64_t restarts() const { return restarts_; }

 private:
  std::optional<std::int64_t> newest_;
  std::vector<std::int64_t> missing_;  // ascending, at most kRemembered
  std::uint64_t lost_ = 0;
  std::uint64_t restarts_ = 0;
};

}  // namespace findmug::io
