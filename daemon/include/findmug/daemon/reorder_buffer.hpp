// findmug/daemon/reorder_buffer.hpp — puts results of parallel workers back in order.
//
// Workers take items with consecutive tickets (BoundedQueue hands them out)
// but finish in any order. The buffer holds early finishers until every
// smaller ticket has been delivered, then releases a run in ticket order. A
// worker whose item failed delivers an empty result (a tombstone) for its
// ticket so the sequence never stalls on a hole.
//
// Not thread-safe by itself: the owner serialises insert/release so that the
// released run is also handed downstream by one thread at a time, in order.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace findmug::daemon {

template <typename T>
class ReorderBuffer {
 public:
  // `result` empty = the item with this ticket produced nothing (skipped).
  void insert(std::uint64_t ticket, std::optional<T> result) {
    if (ticket < next_ || pending_.count(ticket)) {
      throw std::logic_error("ReorderBuffer: ticket " + std::to_string(ticket) +
                             " delivered twice");
    }
    pending_.emplace(ticket, std::move(result));
  }

  // Removes and returns, in ticket order, every result whose predecessors
  // have all been delivered. Tombstones advance the sequence but are not returned.
  std::vector<T> release() {
    std::vector<T> ready;
    for (auto it = pending_.begin(); it != pending_.end() && it->first == next_;
         it = pending_.erase(it)) {
      if (it->second) ready.push_back(std::move(*it->second));
      ++next_;
    }
    return ready;
  }

  std::uint64_t nextTicket() const { return next_; }
  std::size_t waiting() const { return pending_.size(); }  // finished early, held back

 private:
  std::uint64_t next_ = 0;
  std::map<std::uint64_t, std::optional<T>> pending_;
};

}  // namespace findmug::daemon
