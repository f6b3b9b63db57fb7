// The replay verdicts must catch each way a daemon can get replay wrong:
// foreign, reordered, duplicated or resized label images, frames lost without
// being counted, rejected frames, label images lost on the way, a missing
// final status — and must pass a clean run.
#include <gtest/gtest.h>

#include <sstream>

#include "replay_check.hpp"

namespace findmug::replay {
namespace {

constexpr int kW = 640, kH = 480;

// A clean run: frames 10..14 replayed and seen, labels for 10, 11, 13, 14 (12
// dropped by the daemon), and a final status that says so.
class ReplayCheckTest : public ::testing::Test {
 protected:
  void SetUp() override {
    for (int i = 0; i < 5; ++i) {
      const FrameInfo f{10 + i, utime(10 + i), kW, kH};
      check.addReplayedFrame(f);
      check.frameSeen(f, seenAt(10 + i), false);
    }
  }
  static std::uint64_t utime(std::int64_t seq) { return 1'000'000 + 200'000 * static_cast<std::uint64_t>(seq); }
  static std::int64_t seenAt(std::int64_t seq) { return 5'000'000 + 200'000 * seq; }
  void label(std::int64_t seq, std::int64_t latency_us = 300'000, int w = kW, int h = kH,
             bool all_void = false) {
    check.labelReceived(
        LabelInfo{seq, utime(seq), w, h, seenAt(seq) + latency_us, 250'000, all_void});
  }
  void finalStatus(std::int64_t processed, std::int64_t dropped, std::int64_t rejected = 0,
                   int state = kSourceStopped) {
    StatusInfo s;
    s.frames_received = processed + dropped + rejected;
    s.frames_processed = processed;
    s.frames_dropped = dropped;
    s.frames_rejected = rejected;
    s.source_state = state;
    check.statusReceived(s);
  }
  static bool mentions(const Report& r, const std::string& text) {
    for (const auto& v : r.violations) {
      if (v.find(text) != std::string::npos) return true;
    }
    return false;
  }
  ReplayCheck check;
};

TEST_F(ReplayCheckTest, CleanRunHoldsAndIsMeasured) {
  for (int seq : {10, 11, 13}) label(seq, 100'000 * (seq - 9));
  label(14, 500'000, kW, kH, /*all_void=*/true);
  finalStatus(4, 1);
  const Report r = check.evaluate(5, {});
  EXPECT_TRUE(r.ok()) << r.violations.front();
  EXPECT_EQ(r.labels_received, 4);
  EXPECT_EQ(r.dropped_by_seq_gap, 1);
  EXPECT_EQ(r.labels_all_void, 1);
  EXPECT_EQ(r.frames_seen, 5);
  ASSERT_EQ(r.latency_ms.count, 4u);
  EXPECT_DOUBLE_EQ(r.latency_ms.p50, 200.0);  // latencies 100, 200, 400, 500 ms
  EXPECT_DOUBLE_EQ(r.latency_ms.max, 500.0);
  EXPECT_DOUBLE_EQ(r.daemon_latency_ms.p50, 250.0);
  EXPECT_NEAR(r.input_fps, 5.0, 1e-9);  // one frame every 200 ms
  EXPECT_TRUE(check.drained(5));
  EXPECT_FALSE(check.drained(6));
}

TEST_F(ReplayCheckTest, LabelForAFrameNeverReplayed) {
  label(10);
  check.labelReceived(LabelInfo{99, utime(99), kW, kH, seenAt(12), 0});
  finalStatus(2, 3);
  const Report r = check.evaluate(5, {});
  EXPECT_TRUE(mentions(r, "seq 99")) << r.violations.size();
  EXPECT_TRUE(mentions(r, "no replayed frame"));
}

TEST_F(ReplayCheckTest, LabelWithTheWrongUtimeIsForeign) {
  check.labelReceived(LabelInfo{11, utime(11) + 1, kW, kH, seenAt(11), 0});
  finalStatus(1, 4);
  EXPECT_TRUE(mentions(check.evaluate(5, {}), "has utime"));
}

TEST_F(ReplayCheckTest, OutOfOrderAndDuplicateLabels) {
  label(10);
  label(12);
  label(11);  // after 12: out of order
  label(12);  // again
  finalStatus(4, 1);
  const Report r = check.evaluate(5, {});
  EXPECT_TRUE(mentions(r, "out of order"));
  EXPECT_TRUE(mentions(r, "published twice"));
}

TEST_F(ReplayCheckTest, ResizedLabelImage) {
  label(10, 1000, 320, 240);
  finalStatus(1, 4);
  EXPECT_TRUE(mentions(check.evaluate(5, {}), "320x240 but the frame is 640x480"));
}

TEST_F(ReplayCheckTest, FramesLostWithoutBeingCounted) {
  label(10);
  label(11);
  finalStatus(2, 1);  // 5 replayed, 3 accounted for
  const Report r = check.evaluate(5, {});
  EXPECT_TRUE(mentions(r, "accounting: 5 frames replayed but 2 published + 1 dropped"));
}

TEST_F(ReplayCheckTest, RejectedValidFrames) {
  label(10);
  finalStatus(1, 3, 1);
  const Report r = check.evaluate(5, {});
  EXPECT_TRUE(mentions(r, "1 valid frames were rejected"));
  CheckOptions lenient;
  lenient.expect_no_rejects = false;
  EXPECT_TRUE(check.evaluate(5, lenient).ok());
}

TEST_F(ReplayCheckTest, LabelImagesLostOnTheWay) {
  label(10);
  finalStatus(2, 3);  // the daemon published two
  EXPECT_TRUE(mentions(check.evaluate(5, {}), "published 2 label images but 1 were received"));
}

TEST_F(ReplayCheckTest, NoFinalStatusOrNotTheFinalOne) {
  label(10);
  EXPECT_TRUE(mentions(check.evaluate(5, {}), "no status message"));
  finalStatus(1, 4, 0, /*running*/ 1);
  EXPECT_TRUE(mentions(check.evaluate(5, {}), "not the daemon's final one"));
}

TEST_F(ReplayCheckTest, NothingPublishedIsNotAPass) {
  finalStatus(0, 5);
  EXPECT_TRUE(mentions(check.evaluate(5, {}), "only 0 label images"));
}

TEST(ReplayCheck, DuplicateFrameInTheRecordingAndLiveFrames) {
  ReplayCheck check;
  check.addReplayedFrame({1, 100, kW, kH});
  check.addReplayedFrame({1, 100, kW, kH});
  // Live: frames seen on the bus become the replayed set.
  check.frameSeen({2, 200, kW, kH}, 1000, true);
  check.frameSeen({3, 300, kW, kH}, 2000, false);  // not added
  EXPECT_EQ(check.framesReplayed(), 2);
  bool duplicate = false;
  for (const auto& v : check.evaluate(2, {}).violations) {
    duplicate |= v.find("appears twice") != std::string::npos;
  }
  EXPECT_TRUE(duplicate);
}

TEST(ReplayCheck, PercentilesAndHistogram) {
  const Percentiles p = percentiles({5, 1, 4, 2, 3, 6, 7, 8, 9, 10});
  EXPECT_DOUBLE_EQ(p.p50, 5);
  EXPECT_DOUBLE_EQ(p.p90, 9);
  EXPECT_DOUBLE_EQ(p.p99, 10);
  EXPECT_DOUBLE_EQ(p.max, 10);
  EXPECT_DOUBLE_EQ(p.mean, 5.5);
  EXPECT_EQ(percentiles({}).count, 0u);

  const auto h = histogram({0, 49.9, 50, 120, 5000, -3}, 50, 3);
  ASSERT_EQ(h.size(), 3u);
  EXPECT_EQ(h[0].count, 3u);  // 0, 49.9, and -3 (clamped)
  EXPECT_EQ(h[1].count, 1u);  // 50
  EXPECT_EQ(h[2].count, 2u);  // 120 and 5000 in the open last bin
}

TEST_F(ReplayCheckTest, ReportsAreWritten) {
  for (int seq : {10, 11, 12, 13, 14}) label(seq);
  finalStatus(5, 0);
  const Report r = check.evaluate(5, {});
  std::ostringstream json, csv, chart, text;
  writeJson(json, "run \"a\"", r);
  writeHistogram(csv, chart, "run", r, 100, 5);
  printReport(text, "run", r);
  EXPECT_NE(json.str().find("\"name\": \"run \\\"a\\\"\""), std::string::npos);
  EXPECT_NE(json.str().find("\"ok\": true"), std::string::npos);
  EXPECT_NE(csv.str().find("300,400,5"), std::string::npos) << csv.str();
  EXPECT_NE(chart.str().find("#"), std::string::npos);
  EXPECT_NE(text.str().find("OK"), std::string::npos);
}

}  // namespace
}  // namespace findmug::replay
