// findmug/daemon/command_input.hpp — requests to the daemon over LCM (command_t).
//
// CommandInput listens on FINDMUG_COMMAND[_suffix] with an io::Subscriber on a
// bus of its own (an LcmBus on the command URL, see effectiveCommandUrl, or one
// handed in by a test), whose receive thread owns that bus and runs the
// handlers. Each message goes through the hardened decoder (io::decodeCommand:
// wire layout, then every field); the command must be one registered with a
// handler, and the handler may refuse its argument by throwing findmug::Error.
// Anything refused is counted in rejected(), reported through `on_error`
// (the channel and what was wrong) and skipped; nothing leaves the thread.
// Handlers must return quickly (a model reload only asks the reloader).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>

#include "findmug/io/bus.hpp"
#include "findmug/io/messages.hpp"
#include "findmug/io/subscriber.hpp"

namespace findmug::daemon {

class CommandInput {
 public:
  using Handler = std::function<void(const io::CommandMessage&)>;
  using OnError = std::function<void(const std::string& what)>;

  // Opens `url` and starts the receive thread; throws findmug::Error naming
  // daemon.command_url when the provider cannot be opened.
  CommandInput(const std::string& url, std::string channel,
               std::map<std::string, Handler> handlers, OnError on_error);
  // Listens on `bus` instead (tests: an io::MemoryBus); the command thread owns it.
  CommandInput(std::shared_ptr<io::Bus> bus, std::string channel,
               std::map<std::string, Handler> handlers, OnError on_error);
  ~CommandInput();
  CommandInput(const CommandInput&) = delete;
  CommandInput& operator=(const CommandInput&) = delete;

  // Stops the thread and closes the handle. Idempotent; the counters stay readable.
  void stop();

  // Messages dealt with: refused by the decoder, or decoded and their handler run (or
  // refused). A test waits for this before looking at a command's effect.
  std::uint64_t handled() const { return subscriber_->rejected() + dispatched_.load(); }
  std::uint64_t accepted() const;  // commands handed to their handler and taken
  std::uint64_t rejected() const;  // undecodable, unknown command, argument refused
  const std::string& channel() const { return channel_; }
  std::string describe() const { return url_; }

 private:
  void dispatch(const io::CommandMessage& command);

  std::string url_, channel_;
  std::map<std::string, Handler> handlers_;
  OnError on_error_;
  std::atomic<std::uint64_t> refused_{0};     // decoded but refused by the dispatch
  std::atomic<std::uint64_t> dispatched_{0};  // decoded and dispatched (taken or refused)
  std::shared_ptr<io::Bus> bus_;
  std::unique_ptr<io::Subscriber<io::CommandMessage>> subscriber_;
};

}  // namespace findmug::daemon
