// findmug/daemon/result_sinks.hpp — where a published frame's result goes.
//
// The pipeline's publish stage hands each labelled frame, in frame order and
// on the publish thread, to the sinks registered on it, in registration order:
//
//   TableMapSink      the persistent table map (findmug/map/table_map.hpp) and the
//                     rule for when it changes: a frame updates the map only
//                     when it has a robot pose (within daemon.pose_max_age_s)
//                     AND it was labelled (a ground plane and at least one
//                     labelled pixel: without them nothing was seen, and "no
//                     table seen" would wrongly count as a miss for every
//                     mapped table in view). After each update the map's
//                     confirmed tables are due on FINDMUG_TABLE_MAP (when
//                     daemon.publish_table_map). It fills FrameResult's
//                     map_info and table_map for the sinks after it.
//   LcmPublisherSink  encodes label_image_t (FINDMUG_LABELS), tables_t
//                     (FINDMUG_TABLES, when daemon.publish_tables; with the
//                     pose and map_info), objects_t (FINDMUG_OBJECTS, with
//                     every tables_t, empty when the frame has no candidates)
//                     and the table map, and publishes them on an io::Bus in
//                     that order; also status_t. A refused
//                     publish of a frame's message throws findmug::Error
//                     naming the channel and the frame (the publish stage
//                     counts the frame as failed and reports it); a refused
//                     status is counted and logged.
//
// A sink that throws stops the frame there (the sinks after it do not see it).
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "findmug/io/bus.hpp"
#include "findmug/io/messages.hpp"
#include "findmug/map/table_map.hpp"
#include "findmug/segmenter/segmenter.hpp"

namespace findmug::daemon {

struct StatusSnapshot;

// One frame's result on its way through the sinks. The segment step's result (`labelled`),
// the latency and the pose are fixed before the first sink; the slots after them are what a
// sink adds for the sinks after it, each declared by the sink (ResultSink::slots) so that the
// order is stated where the sinks are added and checked there (PublishStep::addSink).
// `labelled` is valid only during consume(): afterwards the pipeline hands its buffers back
// to the Segmenter (Segmenter::recycle) for the next frames. Copy what you keep.
struct FrameResult {
  const LabelledFrame& labelled;
  std::int64_t latency_us = 0;        // arrival to publish
  std::optional<io::RobotPose> pose;  // the robot's pose for this frame, if one is close enough
  // Slot MapInfo (TableMapSink): one entry per table of the frame when the map took it,
  std::vector<io::TableMapInfo> map_info;
  // slot TableMapMessage (TableMapSink): the map's confirmed tables when they are due on
  // FINDMUG_TABLE_MAP.
  std::optional<io::TablesMessage> table_map;
  // Slot PublishedLabels (SemanticMapSink, daemon.semantic_map_fused_labels): the label
  // image to publish instead of the frame's own.
  std::optional<LabelImage> published_labels = std::nullopt;
};

// The slots of FrameResult a sink may add to, as bits.
enum ResultSlot : unsigned {
  kMapInfo = 1u << 0,
  kTableMapMessage = 1u << 1,
  kPublishedLabels = 1u << 2,
};
// "map_info", "table_map", "published_labels", joined with ", ".
std::string resultSlotNames(unsigned slots);

// What a sink adds (`writes`) and what it reads of what other sinks add (`reads`). A sink
// that reads a slot must come after every sink that writes it; one slot has one writer.
struct SinkSlots {
  unsigned writes = 0;
  unsigned reads = 0;
};

class ResultSink {
 public:
  virtual ~ResultSink() = default;
  // For messages: the sink's class name.
  virtual std::string name() const = 0;
  // The slots it adds and reads (none by default). PublishStep refuses an order that breaks
  // them, and a frame on which a sink filled a slot it did not declare.
  virtual SinkSlots slots() const { return {}; }
  virtual void consume(FrameResult& result) = 0;
};

// "frame seq N" for messages.
std::string frameName(const RgbdFrame& frame);

class TableMapSink final : public ResultSink {
 public:
  using OnError = std::function<void(const std::string& what)>;

  TableMapSink(const TableMapConfig& map_config, const TableConfig& tables_config, bool publish_map,
               OnError on_error);

  // Whether `labelled` is evidence about tables (see the header comment).
  static bool isEvidence(const LabelledFrame& labelled);

  std::string name() const override { return "TableMapSink"; }
  SinkSlots slots() const override { return {kMapInfo | kTableMapMessage, 0}; }
  void consume(FrameResult& result) override;

  // Tables in the map now, tentative ones included (thread-safe copy).
  std::vector<MappedTable> tables() const;
  // The confirmed tables only (map frame, by id): what FINDMUG_TABLE_MAP carries.
  std::vector<TableCluster> confirmedTables() const;
  std::uint64_t updates() const { return updates_.load(); }  // frames the map took
  // Advances whenever an update may have changed a table (created, seen, confirmed or
  // forgotten); an update that only counted misses leaves it. A reader that copies the
  // tables copies them again only when this moved.
  std::uint64_t revision() const { return revision_.load(); }

 private:
  bool update(const LabelledFrame& labelled, const io::RobotPose& pose,
              std::vector<io::TableMapInfo>* map_info);
  io::TablesMessage mapMessage(const RgbdFrame& frame, const io::RobotPose& pose) const;

  bool publish_map_;
  OnError on_error_;
  mutable std::mutex mutex_;  // guards map_ (updated by the publish thread only)
  TableMap map_;
  std::atomic<std::uint64_t> updates_{0};
  std::atomic<std::uint64_t> revision_{0};
};

class LcmPublisherSink final : public ResultSink {
 public:
  struct Channels {
    std::string labels, tables, objects, table_map, status;
  };

  LcmPublisherSink(std::shared_ptr<io::Bus> bus, Channels channels, bool publish_confidence,
                   bool publish_tables);

  std::string name() const override { return "LcmPublisherSink"; }
  SinkSlots slots() const override { return {0, kMapInfo | kTableMapMessage | kPublishedLabels}; }
  void consume(FrameResult& result) override;
  // Puts each frame's colour image, as a JPEG of `quality` (1..100), into its label
  // image (daemon.publish_color). Call before the first frame.
  void publishColor(int jpeg_quality) { color_jpeg_quality_ = jpeg_quality; }
  // Builds status_t (StatusBuilder) and publishes it; false (counted, logged)
  // when the bus refused it or the sink is closed.
  bool publishStatus(const StatusSnapshot& snapshot);
  // Releases the bus (closing an LcmBus flushes a file:// log and leaves a
  // udpm group); later publishes are refused. Thread-safe, idempotent.
  void close();

  const Channels& channels() const { return channels_; }
  std::uint64_t publishFailures() const { return failures_.load(); }  // all channels

 private:
  // The bus, or nullptr after close().
  std::shared_ptr<io::Bus> bus() const;
  template <class Msg>
  bool send(const std::string& channel, const Msg& message);

  mutable std::mutex bus_mutex_;
  std::shared_ptr<io::Bus> bus_;
  Channels channels_;
  bool publish_confidence_, publish_tables_;
  int color_jpeg_quality_ = 0;  // 0: no colour image in the label images
  std::atomic<std::uint64_t> failures_{0};
};

}  // namespace findmug::daemon
