// findmug/daemon/check.hpp — `findmugd --check`: the first-run self-test a person runs
// on the robot before enabling the service.
//
// It goes through what the daemon needs, in the order it needs it, and prints one verdict
// line per item: config, model, source, frames (resolution, frame rate, depth validity),
// ground plane, one labelled frame. A failing line says what to do. Items after a failure
// that they depend on are reported as skipped. Settings: the `check:` section
// (check.frames, check.timeout_s, check.min_valid_depth).
#pragma once

#include <ostream>
#include <string>

#include "findmug/daemon/daemon_config.hpp"
#include "findmug/settings/config.hpp"

namespace findmug::daemon {

enum class Verdict { Ok, Warn, Fail, Skipped };

// "[ OK ]", "[WARN]", "[FAIL]", "[SKIP]" followed by the item name, padded, and `what`;
// for Warn/Fail a second line "       do: ..." with `todo`.
std::string verdictLine(Verdict verdict, const std::string& item, const std::string& what,
                        const std::string& todo = "");

// Runs the self-test with a loaded, valid configuration; writes the lines to `out`.
// Returns the number of Fail lines (the exit code is 0 only without failures).
int runSelfCheck(const LoadedConfig& loaded, std::ostream& out);

}  // namespace findmug::daemon
