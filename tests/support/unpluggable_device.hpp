// A camera that can be unplugged and plugged back in by a test (issue 11):
// an io::Device whose frames come from a real frame source (a dataset folder,
// a PCD sequence, ...) opened afresh by every open(), as a real camera's
// streams are. Put inside an io::DeviceSource it exercises the reconnect path
// every camera goes through (back-off, states, counters), not a copy of it.
//
//   unplug(): reads fail at once ("device disconnected", like a driver's
//             error when the USB link goes) and open() fails until plug();
//   silence(true): the device stays "open" but delivers nothing and reports
//             no error (a stalled driver); DeviceSource's frame timeout must
//             notice.
// Only for tests that link findmug_io.
#pragma once

#include <atomic>
#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include "findmug/io/device_source.hpp"
#include "findmug/io/frame_source.hpp"

namespace findmug::test {

class UnpluggableDevice : public io::Device {
 public:
  // `spec` is the frame source behind the "camera", e.g. "dataset:/dir?loop=1&rate_hz=10".
  explicit UnpluggableDevice(std::string spec) : spec_(std::move(spec)) {}

  // Thread-safe: called by the test while the source thread reads.
  void unplug() { plugged_.store(false); }
  void plug() { plugged_.store(true); }
  void silence(bool on) { silent_.store(on); }
  // How often open() was called and succeeded (thread-safe).
  int opens() const { return opens_.load(); }

  std::string describe() const override { return "unpluggable test camera (" + spec_ + ")"; }

  std::string open() override {
    close();
    if (!plugged_.load()) return "no device at usb:2-1 (test camera unplugged)";
    inner_ = io::makeSource(spec_);  // throws on a bad spec: a test error
    opens_.fetch_add(1);
    return {};
  }

  void close() override { inner_.reset(); }

  io::DeviceRead read(std::chrono::milliseconds limit) override {
    using Kind = io::DeviceRead::Kind;
    if (!plugged_.load()) return io::DeviceRead::with(Kind::Lost, "device disconnected (test)");
    if (silent_.load() || !inner_) {
      std::this_thread::sleep_for(limit);
      return io::DeviceRead::with(Kind::Idle);
    }
    auto frame = inner_->next();
    if (!frame) return io::DeviceRead::with(Kind::Ended);
    frame->seq = 0;  // numbering is the DeviceSource's job
    return io::DeviceRead::of(std::move(*frame));
  }

 private:
  std::string spec_;
  std::unique_ptr<io::FrameSource> inner_;
  std::atomic<bool> plugged_{true};
  std::atomic<bool> silent_{false};
  std::atomic<int> opens_{0};
};

}  // namespace findmug::test
