// The bus (io/bus.hpp) and the typed subscriber (io/subscriber.hpp): delivery
// semantics of the in-memory bus, the LCM bus over memq:// and file://, the
// fault-injecting decorator, and Subscriber<T>'s counting and end of log.
#include "findmug/io/bus.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/lcm_source.hpp"
#include "findmug/io/subscriber.hpp"
#include "test_data.hpp"

namespace findmug::io {
namespace {

using namespace std::chrono_literals;

template <class Pred>
bool eventually(Pred pred) {
  // Not a timing assertion: a generous bound only so that a broken bus
  // fails the test instead of hanging it.
  for (int i = 0; i < 1000; ++i) {
    if (pred()) return true;
    std::this_thread::sleep_for(10ms);
  }
  return pred();
}

std::vector<std::uint8_t> bytesOf(const std::string& s) { return {s.begin(), s.end()}; }

std::vector<std::uint8_t> poseBytes(std::uint64_t utime, double x) {
  return encodeMessage(encodeRobotPose(RobotPose{utime, {x, 0.0, 0.0}}));
}

Subscriber<RobotPose>::Decode poseDecoder() {
  return [](const std::uint8_t* data, std::size_t size, const std::string& channel) {
    return decodeRobotPose(data, size, channel);
  };
}

TEST(MemoryBus, DeliversToSubscribersOfTheChannelOnTheHandlingThread) {
  MemoryBus bus;
  std::vector<std::string> got_a, got_b;
  std::thread::id handler_thread;
  bus.subscribe("A", [&](const std::string& ch, const std::uint8_t* d, std::size_t n) {
    got_a.push_back(ch + ":" + std::string(d, d + n));
    handler_thread = std::this_thread::get_id();
  });
  bus.subscribe("A", [&](const std::string&, const std::uint8_t* d, std::size_t n) {
    got_b.push_back(std::string(d, d + n));
  });
  const auto one = bytesOf("one"), two = bytesOf("two"), other = bytesOf("x");
  // Published from another thread, handled on this one.
  std::thread publisher([&] {
    EXPECT_TRUE(bus.publish("A", one.data(), one.size()));
    EXPECT_TRUE(bus.publish("B", other.data(), other.size()));  // nobody listens: discarded
    EXPECT_TRUE(bus.publish("A", two.data(), two.size()));
  });
  publisher.join();
  EXPECT_TRUE(got_a.empty());  // nothing is delivered before handle()
  int handled = 0;
  while (bus.handle(0ms) == HandleResult::Handled) ++handled;
  EXPECT_EQ(handled, 3);
  EXPECT_EQ(got_a, (std::vector<std::string>{"A:one", "A:two"}));
  EXPECT_EQ(got_b, (std::vector<std::string>{"one", "two"}));
  EXPECT_EQ(handler_thread, std::this_thread::get_id());
  EXPECT_EQ(bus.handle(10ms), HandleResult::Timeout);
}

TEST(MemoryBus, UnreadMessagesStayBoundedAndEndReportsEndOfLog) {
  MemoryBus bus(4);
  int delivered = 0;
  bus.subscribe("A", [&](const std::string&, const std::uint8_t*, std::size_t) { ++delivered; });
  const auto b = bytesOf("m");
  for (int i = 0; i < 10; ++i) ASSERT_TRUE(bus.publish("A", b.data(), b.size()));
  EXPECT_EQ(bus.queued(), 4u);  // the oldest six were discarded
  EXPECT_EQ(bus.discarded(), 6u);
  bus.end();
  EXPECT_FALSE(bus.publish("A", b.data(), b.size()));  // nothing after the end
  EXPECT_TRUE(bus.replaysLog());
  while (bus.handle(0ms) == HandleResult::Handled) {
  }
  EXPECT_EQ(delivered, 4);
  EXPECT_EQ(bus.handle(0ms), HandleResult::EndOfLog);
}

TEST(FaultyBus, RefusesPublishesOnCommandOnlyOnThatChannel) {
  auto inner = std::make_shared<MemoryBus>();
  FaultyBus bus(inner);
  const auto b = bytesOf("m");
  EXPECT_TRUE(bus.publish("A", b.data(), b.size()));
  bus.failPublish("A", true);
  EXPECT_FALSE(bus.publish("A", b.data(), b.size()));
  EXPECT_TRUE(bus.publish("B", b.data(), b.size()));
  bus.failPublish("A", false);
  EXPECT_TRUE(bus.publish("A", b.data(), b.size()));
  EXPECT_EQ(bus.refused(), 1u);
  EXPECT_EQ(inner->published(), 3u);
}

TEST(LcmBus, MemqDeliversWithinTheHandleAndBadUrlNamesTheSetting) {
  LcmBus bus("memq://");
  std::vector<std::string> got;
  bus.subscribe("FINDMUG_BUS_TEST", [&](const std::string&, const std::uint8_t* d, std::size_t n) {
    got.emplace_back(d, d + n);
  });
  const auto b = bytesOf("hello");
  ASSERT_TRUE(bus.publish("FINDMUG_BUS_TEST", b.data(), b.size()));
  EXPECT_EQ(bus.handle(1000ms), HandleResult::Handled);
  EXPECT_EQ(got, (std::vector<std::string>{"hello"}));
  EXPECT_FALSE(bus.replaysLog());
  try {
    LcmBus bad("nosuchprovider://", "daemon.lcm_url");
    FAIL() << "a bad URL must throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("daemon.lcm_url"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("nosuchprovider://"), std::string::npos);
  }
}

// The channel suffix is the bus's: a program publishes and subscribes by base name, the
// wire carries BASE_SUFFIX (what a raw subscriber of the same LCM provider sees).
TEST(SuffixedBus, PublishesAndSubscribesByBaseNameOnTheSuffixedChannel) {
  auto raw = std::make_shared<LcmBus>("memq://");
  const std::shared_ptr<Bus> bus = withChannelSuffix(raw, "KITCHEN");
  std::vector<std::string> raw_channels, base_got, other_got;
  raw->subscribe(".*", [&](const std::string& c, const std::uint8_t*, std::size_t) {
    raw_channels.push_back(c);
  });
  bus->subscribe("FINDMUG_STATUS", [&](const std::string& c, const std::uint8_t* d, std::size_t n) {
    base_got.push_back(c + "=" + std::string(d, d + n));
  });
  const auto b = bytesOf("s");
  ASSERT_TRUE(bus->publish("FINDMUG_STATUS", b.data(), b.size()));
  // Another daemon's unsuffixed channel is not this bus's.
  ASSERT_TRUE(raw->publish("FINDMUG_STATUS", b.data(), b.size()));
  while (bus->handle(200ms) == HandleResult::Handled) {
  }
  EXPECT_EQ(raw_channels, (std::vector<std::string>{"FINDMUG_STATUS_KITCHEN", "FINDMUG_STATUS"}));
  EXPECT_EQ(base_got, (std::vector<std::string>{"FINDMUG_STATUS_KITCHEN=s"}));
  EXPECT_NE(bus->describe().find("_KITCHEN"), std::string::npos);

  EXPECT_EQ(withChannelSuffix(raw, ""), raw);  // no suffix: the bus itself
  for (const char* bad : {"A B", "_X", "X/Y"}) {
    try {
      withChannelSuffix(raw, bad);
      ADD_FAILURE() << "suffix '" << bad << "' accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
}

TEST(Subscriber, DecodesCountsRejectsAndKeepsTheLatest) {
  MemoryBus bus;
  std::vector<std::uint64_t> seen;
  std::vector<std::string> errors;
  Subscriber<RobotPose> poses(
      bus, "POSE", poseDecoder(),
      [&](const RobotPose& p, const std::string&) { seen.push_back(p.utime); },
      [&](const std::string& what) { errors.push_back(what); });
  const std::vector<std::uint8_t> a = poseBytes(10, 1.0), b = poseBytes(20, 2.0),
                                  junk = bytesOf("not a pose");
  auto truncated = poseBytes(30, 3.0);
  truncated.resize(truncated.size() - 3);
  const std::vector<std::uint8_t>* const in_order[] = {&a, &junk, &b, &truncated};
  for (const std::vector<std::uint8_t>* m : in_order) {
    ASSERT_TRUE(bus.publish("POSE", m->data(), m->size()));
  }
  EXPECT_FALSE(poses.latest().has_value());
  while (bus.handle(0ms) == HandleResult::Handled) {
  }
  EXPECT_EQ(poses.received(), 4u);
  EXPECT_EQ(poses.accepted(), 2u);
  EXPECT_EQ(poses.rejected(), 2u);
  EXPECT_EQ(seen, (std::vector<std::uint64_t>{10, 20}));
  ASSERT_TRUE(poses.latest().has_value());
  EXPECT_DOUBLE_EQ(poses.latest()->pose.x, 2.0);
  ASSERT_EQ(errors.size(), 2u);
  for (const auto& e : errors) EXPECT_NE(e.find("POSE"), std::string::npos) << e;
}

TEST(Subscriber, ReceiveThreadHandlesUntilEndOfLog) {
  MemoryBus bus;
  Subscriber<RobotPose> poses(bus, "POSE", poseDecoder());
  HandleResult end_seen = HandleResult::Handled;
  poses.startReceiving([&](HandleResult how) { end_seen = how; });
  for (std::uint64_t t = 1; t <= 5; ++t) {
    const auto m = poseBytes(t, 0.0);
    ASSERT_TRUE(bus.publish("POSE", m.data(), m.size()));
  }
  bus.end();
  ASSERT_TRUE(eventually([&] { return poses.finished(); }));
  EXPECT_EQ(poses.accepted(), 5u);
  EXPECT_EQ(poses.ended(), HandleResult::EndOfLog);
  EXPECT_EQ(end_seen, HandleResult::EndOfLog);
}

// A message counts as accepted once its handler has run: a caller that waits for the count
// (the search benchmark waits for the pose input's before it submits a frame) must find
// what the handler did. Counted before the handler, the pose could be missing.
TEST(Subscriber, CountsAMessageAcceptedOnlyAfterItsHandlerRan) {
  MemoryBus bus;
  std::atomic<int> handled{0};
  Subscriber<RobotPose> poses(bus, "POSE", poseDecoder(),
                              [&](const RobotPose&, const std::string&) {
                                std::this_thread::sleep_for(30ms);  // a handler that takes a while
                                handled.fetch_add(1);
                              });
  poses.startReceiving();
  for (std::uint64_t t = 1; t <= 5; ++t) {
    const auto m = poseBytes(t, 0.0);
    ASSERT_TRUE(bus.publish("POSE", m.data(), m.size()));
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    while (poses.accepted() < t) {
      ASSERT_LT(std::chrono::steady_clock::now(), deadline) << "message " << t;
      std::this_thread::yield();
    }
    EXPECT_EQ(handled.load(), static_cast<int>(t)) << "accepted() said " << t;
  }
}

TEST(Subscriber, ReadsAnLcmLogFileToItsEnd) {
  test::TempDir dir;
  const std::string log = (dir.path() / "poses.lcm").string();
  {
    LcmBus writer("file://" + log + "?mode=w");
    for (std::uint64_t t = 1; t <= 3; ++t) {
      const auto m = poseBytes(t, static_cast<double>(t));
      ASSERT_TRUE(writer.publish("POSE", m.data(), m.size()));
    }
    const auto junk = bytesOf("junk");
    ASSERT_TRUE(writer.publish("POSE", junk.data(), junk.size()));
  }
  LcmBus reader("file://" + log + "?speed=0");
  EXPECT_TRUE(reader.replaysLog());
  Subscriber<RobotPose> poses(reader, "POSE", poseDecoder());
  poses.startReceiving();
  ASSERT_TRUE(eventually([&] { return poses.finished(); }));
  EXPECT_EQ(poses.ended(), HandleResult::EndOfLog);
  EXPECT_EQ(poses.accepted(), 3u);
  EXPECT_EQ(poses.rejected(), 1u);
  EXPECT_DOUBLE_EQ(poses.latest()->pose.x, 3.0);
}

std::vector<std::uint8_t> frameBytes(std::int64_t seq) {
  RgbdFrame f;
  f.width = 4;
  f.height = 3;
  f.depth_mm.assign(12, static_cast<std::uint16_t>(1000 + seq));
  f.rgb.assign(12, Rgb8{10, 20, static_cast<std::uint8_t>(seq)});
  f.seq = seq;
  f.utime = 1000000 + static_cast<std::uint64_t>(seq);
  return encodeMessage(encodeRgbdFrame(f, {DepthCompression::Zlib, ColorCompression::Png}));
}

TEST(LcmFrameSourceOnMemoryBus, AnEndingBusIsReadLikeALogWithoutDropping) {
  auto bus = std::make_shared<MemoryBus>();
  SourceOptions options;
  options.lcm_queue_size = 1;
  for (int i = 0; i < 4; ++i) {
    const auto b = frameBytes(i);
    ASSERT_TRUE(bus->publish("FINDMUG_RGBD", b.data(), b.size()));
  }
  bus->end();  // a finished "log": the source waits for room, never drops, then ends
  LcmFrameSource source("FINDMUG_RGBD", bus, options);
  for (int i = 0; i < 4; ++i) {
    auto f = source.next();
    ASSERT_TRUE(f.has_value());
    EXPECT_EQ(f->seq, i);
  }
  EXPECT_FALSE(source.next().has_value());
  EXPECT_EQ(source.state(), SourceState::EndOfStream);
  EXPECT_EQ(source.stats().frames_dropped, 0u);
  EXPECT_EQ(source.describe(), "lcm:FINDMUG_RGBD (memory)");
}

}  // namespace
}  // namespace findmug::io
