// command_routes.hpp — findmug-web's requests to findmugd: command_t messages on
// FINDMUG_COMMAND[_suffix] (lcmtypes/command_t.lcm), published on the LCM URL findmug-web
// listens on.
//
//   POST /api/command  {"command": "save_frame" | "reload_model" | "teach" | "find",
//                       "argument": "..."}
//                      -> {"request_id": N}: the daemon's answer is in its status
//                      (last_collected_frame, last_reload_* or last_teach_* with request
//                      N) or, for find, on FINDMUG_FIND_RESULT (GET /api/live's "find").
// Refused with 400 (and logged, as every 4xx of findmug-web): a body that is not a JSON
// object, a command other than those four, an argument that is not a string or that the
// daemon would refuse (io::encodeCommand's rules; save_frame's note also without comma or
// quote, reload_model without any, teach's "NAME SEQ INDEX" (io::parseTeachArgument),
// find's a taught-object name). 503 when findmug-web has no bus to publish on.
#pragma once

#include <cstdint>
#include <functional>

#include "findmug/io/messages.hpp"

namespace httplib {
class Server;
}

namespace findmug::web {

// Publishes one command; throws findmug::Error when the bus refuses it.
using SendCommand = std::function<void(const io::CommandMessage&)>;

void addCommandRoutes(httplib::Server& server, SendCommand send);

// The next command_t.request_id of this process: counts up from the clock in
// milliseconds at the first call, so that a restarted findmug-web's ids are new.
std::int64_t nextRequestId();

}  // namespace findmug::web
