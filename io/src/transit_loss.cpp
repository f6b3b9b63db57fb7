#include "findmug/io/transit_loss.hpp"

#include <algorithm>

namespace findmug::io {

void TransitLossCounter::observe(std::int64_t seq) {
  if (!newest_) {
    newest_ = seq;
    return;
  }
  if (seq > *newest_) {
    // Difference in unsigned arithmetic: seq - newest may not fit in int64.
    const auto step = static_cast<std::uint64_t>(seq) - static_cast<std::uint64_t>(*newest_);
    if (step - 1 <= static_cast<std::uint64_t>(kMaxGap)) {
      lost_ += step - 1;
      for (std::int64_t s = std::max(*newest_ + 1, seq - static_cast<std::int64_t>(kRemembered));
           s < seq; ++s) {
        missing_.push_back(s);
      }
      if (missing_.size() > kRemembered) {
        missing_.erase(missing_.begin(),
                       missing_.begin() + static_cast<std::ptrdiff_t>(missing_.size() - kRemembered));
      }
    } else {
      ++restarts_;
      missing_.clear();
    }
    newest_ = seq;
    return;
  }
  if (seq == *newest_) return;  // a repeat
  const auto it = std::lower_bound(missing_.begin(), missing_.end(), seq);
  if (it != missing_.end() && *it == seq) {  // late, not lost
    missing_.erase(it);
    --lost_;
    return;
  }
  ++restarts_;  // the publisher started over
  missing_.clear();
  newest_ = seq;
}

}  // namespace findmug::io
