// Commands to the daemon over LCM; see command_input.hpp.
#include "findmug/daemon/command_input.hpp"

#include <spdlog/spdlog.h>

#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/udpm.hpp"

namespace findmug::daemon {

CommandInput::CommandInput(const std::string& url, std::string channel,
                           std::map<std::string, Handler> handlers, OnError on_error)
    : CommandInput(std::shared_ptr<io::Bus>(
                       io::openBus(url, "daemon.command_url (commands on " + channel + ")")),
                   channel, std::move(handlers), std::move(on_error)) {
  url_ = url.empty() ? std::string("the default LCM provider") : url;
}

CommandInput::CommandInput(std::shared_ptr<io::Bus> bus, std::string channel,
                           std::map<std::string, Handler> handlers, OnError on_error)
    : url_(bus->describe()),
      channel_(std::move(channel)),
      handlers_(std::move(handlers)),
      on_error_(std::move(on_error)),
      bus_(std::move(bus)) {
  subscriber_ = std::make_unique<io::Subscriber<io::CommandMessage>>(
      *bus_, channel_,
      [](const std::uint8_t* data, std::size_t size, const std::string& ch) {
        return io::decodeCommand(data, size, ch);
      },
      [this](const io::CommandMessage& command, const std::string&) { dispatch(command); },
      [this](const std::string& what) {
        if (on_error_) on_error_("refusing command: " + what);
      });
  subscriber_->startReceiving([this](io::HandleResult how) {
    if (how == io::HandleResult::Failed && on_error_) {
      on_error_(channel_ + ": LCM handle for commands failed (" + url_ +
                "); no more commands are received");
    }
  });
}

CommandInput::~CommandInput() { stop(); }

void CommandInput::stop() {
  subscriber_->stop();
  bus_.reset();
}

std::uint64_t CommandInput::accepted() const { return subscriber_->accepted() - refused_.load(); }

std::uint64_t CommandInput::rejected() const { return subscriber_->rejected() + refused_.load(); }

void CommandInput::dispatch(const io::CommandMessage& command) {
  const auto handler = handlers_.find(command.command);
  try {
    if (handler == handlers_.end()) {
      std::string known;
      for (const auto& [name, h] : handlers_) known += (known.empty() ? "" : ", ") + name;
      throw Error("command_t.command: unknown command '" + command.command + "' (known: " +
                  known + ")");
    }
    handler->second(command);
    spdlog::info("{}: command {} (request {}) taken", channel_, command.command,
                 command.request_id);
  } catch (const std::exception& e) {
    // Counted before the subscriber's accepted count could be read as including it.
    refused_.fetch_add(1);
    if (on_error_) {
      on_error_("refusing command: " + channel_ + ": request " +
                std::to_string(command.request_id) + ": " + e.what());
    }
  }
  dispatched_.fetch_add(1);
}

}  // namespace findmug::daemon
