// scratch.hpp (internal) — per-thread working memory of the per-frame stages.
//
// A stage that runs once per frame keeps its working vectors in a
// thread_local and reuses them, so that a stream of frames of one size
// allocates nothing there once warm (issue 13: near-zero heap allocations in
// the per-frame path). Memory stays bounded: a buffer only grows to the
// largest frame's need, and each thread that ran the stage keeps one set.
//
// Borrowed<T> moves such a buffer into a local object for the scope of a
// call and hands it back at the end, also when the call throws. Used in
// place through the thread_local instead, a buffer's pointers live in memory
// that any store through a char-sized pointer (uint8_t) may alias, and the
// compiler reloads them in the hot loops: measured at 1.4 ms more per VGA
// frame in the oversegmenter than allocating afresh. A moved vector is a
// pointer swap, so borrowing costs nothing.
#pragma once

#include <utility>

namespace findmug::detail {

template <typename T>
class Borrowed {
 public:
  explicit Borrowed(T& home) : home_(home), value_(std::move(home)) {}
  ~Borrowed() { home_ = std::move(value_); }
  Borrowed(const Borrowed&) = delete;
  Borrowed& operator=(const Borrowed&) = delete;
  T& operator*() { return value_; }
  const T& operator*() const { return value_; }
  T* operator->() { return &value_; }
  const T* operator->() const { return &value_; }

 private:
  T& home_;
  T value_;
};

}  // namespace findmug::detail
