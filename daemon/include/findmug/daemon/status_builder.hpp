// findmug/daemon/status_builder.hpp — the pipeline's figures as a plain snapshot,
// and the status_t message built from it.
//
//   StatusSnapshot  (status_snapshot.hpp) what the pipeline knows at one
//                   instant: plain types, taken by Pipeline::statusSnapshot().
//   StatusBuilder   turns a snapshot into findmug_lcm::status_t (the field
//                   order of the latency and queue arrays, the source fields,
//                   which last error wins). The only place that fills status_t,
//                   so pipeline.hpp needs no generated type.
#pragma once

#include "findmug/daemon/status_snapshot.hpp"
#include "findmug_lcm/status_t.hpp"

namespace findmug::daemon {

class StatusBuilder {
 public:
  // The source's last error replaces the pipeline's when it is more recent.
  // Without a source, the source is "(in-process)", running.
  static findmug_lcm::status_t build(const StatusSnapshot& snapshot);
};

class Pipeline;
// StatusBuilder::build(pipeline.statusSnapshot()): the status findmugd publishes now.
findmug_lcm::status_t makeStatus(const Pipeline& pipeline);

}  // namespace findmug::daemon
