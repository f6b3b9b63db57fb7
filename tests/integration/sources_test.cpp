// Frame sources: spec parsing, the dataset source on NYU frames, the PCD /
// PCLZF / TIFF sequence sources on PCL's 3-frame grabber sequence (same depth
// in all three formats), bad files skipped and counted, the LCM source over
// memq:// and file://, the OpenNI2 device path (OpenNI2's software "Dummy"
// device), a camera that disappears mid-run and comes back (DeviceSource's
// back-off over a device unplugged on command), and findmug-grab writing a
// log that lcm::LogFile reads back.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <lcm/lcm-cpp.hpp>
#include <thread>

#include "findmug/common/error.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/device_source.hpp"
#include "findmug/io/frame_source.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/lcm_source.hpp"
#include "findmug/io/pcl_frames.hpp"
#include "findmug/io/transit_loss.hpp"
#include "test_data.hpp"
#include "unpluggable_device.hpp"

namespace fs = std::filesystem;

namespace findmug::io {
namespace {

constexpr const char* kSequences = "pcl_test_clouds/grabber_sequences";

std::vector<RgbdFrame> drain(FrameSource& source, std::size_t max = 100) {
  std::vector<RgbdFrame> frames;
  while (frames.size() < max) {
    auto f = source.next();
    if (!f) break;
    frames.push_back(std::move(*f));
  }
  return frames;
}

// Waits (without asserting on time) until `done` holds or a generous limit passes.
template <typename F>
bool eventually(F&& done) {
  for (int i = 0; i < 1000; ++i) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return done();
}

void copyPrefix(const fs::path& from, const fs::path& to, std::size_t bytes) {
  std::ifstream in(from, std::ios::binary);
  std::vector<char> data(bytes);
  in.read(data.data(), static_cast<std::streamsize>(bytes));
  std::ofstream out(to, std::ios::binary);
  out.write(data.data(), in.gcount());
}

// ---- spec parsing ---------------------------------------------------------------------

TEST(SourceSpec, ParsesKindTargetAndOptions) {
  SourceSpec s = parseSourceSpec("dataset:/data/nyu?rate_hz=5&loop=1");
  EXPECT_EQ(s.kind, "dataset");
  EXPECT_EQ(s.target, "/data/nyu");
  EXPECT_EQ(s.options.rate_hz, 5.0);
  EXPECT_TRUE(s.options.loop);

  s = parseSourceSpec("openni2");
  EXPECT_EQ(s.kind, "openni2");
  EXPECT_TRUE(s.target.empty());

  s = parseSourceSpec("openni2:/logs/kitchen.oni?realtime=0&loop=true");
  EXPECT_EQ(s.target, "/logs/kitchen.oni");
  EXPECT_FALSE(s.options.realtime);

  // url takes the rest, with its own '?' and '&'.
  s = parseSourceSpec("lcm:FINDMUG_RGBD_X?queue=4&url=file:///tmp/a.lcm?speed=0&start_timestamp=5");
  EXPECT_EQ(s.target, "FINDMUG_RGBD_X");
  EXPECT_EQ(s.options.lcm_queue_size, 4);
  EXPECT_EQ(s.options.lcm_url, "file:///tmp/a.lcm?speed=0&start_timestamp=5");
}

TEST(SourceSpec, RejectsBadSpecsNamingThePart) {
  auto message = [](const std::string& spec) {
    try {
      parseSourceSpec(spec);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("kinect:/x").find("unknown kind 'kinect'"), std::string::npos);
  EXPECT_NE(message("pcd").find("pcd needs a directory"), std::string::npos);
  EXPECT_NE(message("tiff:/x?rate_hz=fast").find("rate_hz=fast"), std::string::npos);
  EXPECT_NE(message("tiff:/x?rate_hz=-1").find("rate_hz=-1"), std::string::npos);
  EXPECT_NE(message("tiff:/x?loop=maybe").find("loop=maybe"), std::string::npos);
  EXPECT_NE(message("tiff:/x?speed=2").find("unknown option 'speed'"), std::string::npos);
  EXPECT_NE(message("tiff:/x?loop").find("has no value"), std::string::npos);
  EXPECT_NE(message("tiff:/x?url=memq://").find("only applies to lcm"), std::string::npos);
}

TEST(SourceSpec, MissingDirectoriesFailAtStartUp) {
  EXPECT_THROW(makeSource("pcd:/nonexistent/findmug"), Error);
  EXPECT_THROW(makeSource("dataset:/nonexistent/findmug"), Error);
  test::TempDir empty;
  EXPECT_THROW(makeSource("tiff:" + empty.str()), Error);
}

// ---- dataset ---------------------------------------------------------------------------

TEST(DatasetSource, DeliversTheFolderInOrderThenEnds) {
  FINDMUG_REQUIRE_DATA(dir, "nyuv2_labeled");
  const DatasetFolder folder(dir.string());
  auto source = makeSource("dataset:" + dir.string());
  EXPECT_NE(source->describe().find("31 frames"), std::string::npos) << source->describe();
  const std::vector<RgbdFrame> frames = drain(*source);
  ASSERT_EQ(frames.size(), folder.size());
  EXPECT_EQ(source->state(), SourceState::EndOfStream);
  EXPECT_EQ(source->stats().frames_delivered, folder.size());
  EXPECT_EQ(source->stats().frames_rejected, 0u);
  for (std::size_t i : {std::size_t{0}, std::size_t{17}, frames.size() - 1}) {
    const RgbdFrame expected = folder.load(i).frame;
    EXPECT_EQ(frames[i].depth_mm, expected.depth_mm) << i;
    EXPECT_EQ(frames[i].rgb, expected.rgb) << i;
    EXPECT_EQ(frames[i].intrinsics.fx, expected.intrinsics.fx);
  }
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(frames[i].seq, static_cast<std::int64_t>(i));
    if (i > 0) {
      EXPECT_GE(frames[i].utime, frames[i - 1].utime);
    }
  }
  EXPECT_FALSE(source->next().has_value());  // stays ended
}

// ---- PCL sequences -----------------------------------------------------------------------

TEST(PclSequences, SameDepthInAllThreeFormats) {
  FINDMUG_REQUIRE_DATA(dir, kSequences);
  auto pcd = drain(*makeSource("pcd:" + (dir / "pcd").string()));
  auto lzf = drain(*makeSource("pclzf:" + (dir / "pclzf").string()));
  auto tif = drain(*makeSource("tiff:" + (dir / "tiff").string()));
  ASSERT_EQ(pcd.size(), 3u);
  ASSERT_EQ(lzf.size(), 3u);
  ASSERT_EQ(tif.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    ASSERT_EQ(pcd[k].width, 640);
    ASSERT_EQ(pcd[k].height, 480);
    ASSERT_EQ(lzf[k].depth_mm.size(), tif[k].depth_mm.size());
    ASSERT_EQ(pcd[k].depth_mm.size(), tif[k].depth_mm.size());
    std::size_t valid = 0, lzf_diff = 0, pcd_off_by_more_than_1 = 0, pcd_validity_diff = 0;
    for (std::size_t i = 0; i < tif[k].depth_mm.size(); ++i) {
      const int t = tif[k].depth_mm[i];
      valid += t != 0;
      lzf_diff += lzf[k].depth_mm[i] != t;
      pcd_validity_diff += (pcd[k].depth_mm[i] == 0) != (t == 0);
      pcd_off_by_more_than_1 += std::abs(pcd[k].depth_mm[i] - t) > 1;
    }
    // The README: about 88 % valid, 0.67..1.73 m.
    EXPECT_GT(valid, 640u * 480u * 80 / 100) << k;
    EXPECT_LT(valid, 640u * 480u * 95 / 100) << k;
    EXPECT_EQ(lzf_diff, 0u) << "frame " << k;  // both store integer millimetres
    EXPECT_EQ(pcd_validity_diff, 0u) << "frame " << k;
    EXPECT_EQ(pcd_off_by_more_than_1, 0u) << "frame " << k;  // float metres, rounded
    // Colour: identical in the lossless formats (planar PCLZF decoded right).
    EXPECT_EQ(lzf[k].rgb, tif[k].rgb) << k;
    EXPECT_EQ(pcd[k].rgb, tif[k].rgb) << k;
    // The three frames differ from each other (not one frame thrice).
    if (k > 0) {
      EXPECT_NE(tif[k].depth_mm, tif[k - 1].depth_mm);
    }
  }
  // Intrinsics: PCLZF from its xml; PCD fitted to the points (PCL projected
  // them with f = 525 around the image centre).
  EXPECT_EQ(lzf[0].intrinsics.fx, 525.0);
  EXPECT_EQ(lzf[0].intrinsics.cx, 320.0);
  EXPECT_NEAR(pcd[0].intrinsics.fx, 525.0, 1.0);
  EXPECT_NEAR(pcd[0].intrinsics.fy, 525.0, 1.0);
  EXPECT_NEAR(pcd[0].intrinsics.cx, 320.0, 1.0);
  EXPECT_NEAR(pcd[0].intrinsics.cy, 240.0, 1.0);
}

TEST(PclSequences, LoopRepeatsInOrderWithRunningSeq) {
  FINDMUG_REQUIRE_DATA(dir, kSequences);
  auto source = makeSource("tiff:" + (dir / "tiff").string() + "?loop=1");
  const auto frames = drain(*source, 7);
  ASSERT_EQ(frames.size(), 7u);
  for (std::size_t i = 0; i < 7; ++i) {
    EXPECT_EQ(frames[i].seq, static_cast<std::int64_t>(i));
    EXPECT_EQ(frames[i].depth_mm, frames[i % 3].depth_mm) << i;
  }
  EXPECT_NE(frames[0].source, frames[1].source);
  EXPECT_EQ(source->state(), SourceState::Running);
  source->stop();
  EXPECT_FALSE(source->next().has_value());
  EXPECT_EQ(source->state(), SourceState::Stopped);
}

TEST(PclSequences, BadFilesAreSkippedAndCounted) {
  FINDMUG_REQUIRE_DATA(dir, kSequences);
  test::TempDir tmp;
  const auto items = listPclSequence((dir / "tiff").string(), PclFormat::Tiff);
  ASSERT_EQ(items.size(), 3u);
  // Frames 0 and 2 intact (links), frame 1 with its depth cut in half.
  for (std::size_t k : {0, 2}) {
    for (const auto& f : items[k].files) fs::create_symlink(f, tmp.path() / fs::path(f).filename());
  }
  const fs::path bad_depth = tmp.path() / fs::path(items[1].files[0]).filename();
  copyPrefix(items[1].files[0], bad_depth, fs::file_size(items[1].files[0]) / 2);
  fs::create_symlink(items[1].files[1], tmp.path() / fs::path(items[1].files[1]).filename());

  auto source = makeSource("tiff:" + tmp.str());
  const auto frames = drain(*source);
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].seq, 0);
  EXPECT_EQ(frames[1].seq, 1);
  const SourceStats stats = source->stats();
  EXPECT_EQ(stats.frames_rejected, 1u);
  EXPECT_NE(stats.last_error.find(bad_depth.filename().string()), std::string::npos)
      << stats.last_error;
  EXPECT_GT(stats.last_error_utime, 0u);
  EXPECT_EQ(source->state(), SourceState::EndOfStream);
}

TEST(PclSequences, OnlyBadFilesFailInsteadOfSpinning) {
  FINDMUG_REQUIRE_DATA(dir, kSequences);
  test::TempDir tmp;
  const auto items = listPclSequence((dir / "pclzf").string(), PclFormat::Pclzf);
  const fs::path depth = tmp.path() / fs::path(items[0].files[0]).filename();
  copyPrefix(items[0].files[0], depth, 1000);  // truncated LZF
  fs::create_symlink(items[0].files[1], tmp.path() / fs::path(items[0].files[1]).filename());
  fs::create_symlink(items[0].files[2], tmp.path() / fs::path(items[0].files[2]).filename());
  auto source = makeSource("pclzf:" + tmp.str() + "?loop=1");
  EXPECT_FALSE(source->next().has_value());
  EXPECT_EQ(source->state(), SourceState::Failed);
  EXPECT_EQ(source->stats().frames_rejected, 1u);
}

TEST(PclFrames, CorruptFilesThrowNamingTheFile) {
  FINDMUG_REQUIRE_DATA(dir, kSequences);
  test::TempDir tmp;
  const auto pcd = listPclSequence((dir / "pcd").string(), PclFormat::Pcd)[0].files[0];
  const auto lzf = listPclSequence((dir / "pclzf").string(), PclFormat::Pclzf)[0].files;
  const auto tif = listPclSequence((dir / "tiff").string(), PclFormat::Tiff)[0].files;
  const auto size = [](const std::string& f) { return fs::file_size(f); };
  auto expectNamed = [](auto&& read, const std::string& name) {
    try {
      read();
      ADD_FAILURE() << "no error for " << name;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  };
  // Truncated at several points: inside the header, mid-body, near the end
  // (PCL pads PCD files by a few kB after the data, so not closer than 1 %).
  for (double fraction : {0.0001, 0.3, 0.99}) {
    SCOPED_TRACE(fraction);
    const std::string cut_pcd = tmp.str("cut.pcd");
    copyPrefix(pcd, cut_pcd, static_cast<std::size_t>(size(pcd) * fraction));
    expectNamed([&] { readPcdFrame(cut_pcd); }, "cut.pcd");
    const std::string cut_lzf = tmp.str("cut_depth.pclzf");
    copyPrefix(lzf[0], cut_lzf, static_cast<std::size_t>(size(lzf[0]) * fraction));
    expectNamed([&] { readPclzfFrame(cut_lzf, lzf[1], lzf[2]); }, "cut_depth.pclzf");
    const std::string cut_tif = tmp.str("cut_rgb.tiff");
    copyPrefix(tif[1], cut_tif, static_cast<std::size_t>(size(tif[1]) * fraction));
    expectNamed([&] { readTiffFrame(tif[0], cut_tif, {}); }, "cut_rgb.tiff");
  }
  // Swapped roles: a colour file where depth belongs.
  expectNamed([&] { readPclzfFrame(lzf[1], lzf[1], lzf[2]); }, "rgb24");
  expectNamed([&] { readTiffFrame(tif[1], tif[1], {}); }, tif[1]);
  // Flipped bytes in the LZF body.
  {
    std::ifstream in(lzf[0], std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(in)), {});
    for (std::size_t i = 100; i < bytes.size(); i += 997)
      bytes[i] = static_cast<char>(bytes[i] ^ 0x5a);
    std::ofstream(tmp.str("flip_depth.pclzf"), std::ios::binary)
        .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    expectNamed([&] { readPclzfFrame(tmp.str("flip_depth.pclzf"), lzf[1], lzf[2]); },
                "flip_depth.pclzf");
  }
  // An xml without the depth section.
  std::ofstream(tmp.str("bad.xml")) << "<rgb><focal_length_x>525</focal_length_x></rgb>";
  expectNamed([&] { readPclzfFrame(lzf[0], lzf[1], tmp.str("bad.xml")); }, "bad.xml");
}

// ---- LCM ----------------------------------------------------------------------------------------

RgbdFrame smallFrame(std::int64_t seq) {
  RgbdFrame f;
  f.width = 8;
  f.height = 6;
  f.depth_mm.assign(48, static_cast<std::uint16_t>(1000 + seq));
  f.rgb.assign(48, Rgb8{10, 20, static_cast<std::uint8_t>(seq)});
  f.seq = seq;
  f.utime = 1000000 + static_cast<std::uint64_t>(seq);
  f.source = "test";
  return f;
}

std::vector<std::uint8_t> frameBytes(std::int64_t seq) {
  return encodeMessage(
      encodeRgbdFrame(smallFrame(seq), {DepthCompression::Zlib, ColorCompression::Png}));
}

TEST(LcmSource, MemqFramesArriveInOrderAndBadMessagesAreCounted) {
  SourceOptions options;
  options.lcm_queue_size = 32;
  LcmFrameSource source("FINDMUG_RGBD_T", "memq://", options);
  const std::vector<std::uint8_t> garbage(100, 0xab);
  std::vector<std::uint8_t> truncated = frameBytes(99);
  truncated.resize(truncated.size() / 2);
  const auto other_type = encodeMessage(encodeRobotPose(RobotPose{1, {0, 0, 0}}));
  for (int i = 0; i < 5; ++i) {
    const auto b = frameBytes(i);
    ASSERT_TRUE(source.bus().publish("FINDMUG_RGBD_T", b.data(), b.size()));
    if (i == 1) source.bus().publish("FINDMUG_RGBD_T", garbage.data(), garbage.size());
    if (i == 2) source.bus().publish("FINDMUG_RGBD_T", truncated.data(), truncated.size());
    if (i == 3) source.bus().publish("FINDMUG_RGBD_T", other_type.data(), other_type.size());
    // Another channel is not ours.
    source.bus().publish("FINDMUG_RGBD_OTHER", b.data(), b.size());
  }
  for (int i = 0; i < 5; ++i) {
    auto f = source.next();
    ASSERT_TRUE(f.has_value());
    EXPECT_EQ(f->seq, i);
    EXPECT_EQ(f->utime, 1000000u + static_cast<std::uint64_t>(i));  // capture time kept
    EXPECT_EQ(f->depth_mm[0], 1000 + i);
    EXPECT_EQ(f->rgb[0].b, i);
    EXPECT_EQ(f->source, "FINDMUG_RGBD_T: test");
  }
  ASSERT_TRUE(eventually([&] { return source.stats().frames_rejected == 3; }));
  EXPECT_EQ(source.stats().frames_delivered, 5u);
  EXPECT_EQ(source.stats().frames_dropped, 0u);
  EXPECT_EQ(source.state(), SourceState::Running);
  EXPECT_NE(source.stats().last_error.find("FINDMUG_RGBD_T"), std::string::npos);
}

// Seq holes are frames the network lost; late (reordered) frames are taken
// back; repeats and a publisher starting over are not losses.
TEST(TransitLoss, CountsHolesTakesBackLateFramesAndIgnoresRestarts) {
  TransitLossCounter c;
  for (std::int64_t s : {10, 11, 12}) c.observe(s);
  EXPECT_EQ(c.lost(), 0u);
  c.observe(15);  // 13 and 14 missing
  EXPECT_EQ(c.lost(), 2u);
  c.observe(13);  // late, not lost
  EXPECT_EQ(c.lost(), 1u);
  c.observe(13);  // a repeat of a late frame is not taken back twice: a restart at 13
  EXPECT_EQ(c.lost(), 1u);
  EXPECT_EQ(c.restarts(), 1u);
  c.observe(14);
  c.observe(14);  // repeat of the newest
  EXPECT_EQ(c.lost(), 1u);
  c.observe(0);  // log replay restarted from the beginning
  c.observe(1);
  c.observe(3);
  EXPECT_EQ(c.lost(), 2u);
  EXPECT_EQ(c.restarts(), 2u);
  c.observe(3 + TransitLossCounter::kMaxGap + 2);  // another publisher's numbering: no loss
  EXPECT_EQ(c.lost(), 2u);
  EXPECT_EQ(c.restarts(), 3u);
  c.observe(std::numeric_limits<std::int64_t>::min());  // extreme values: no overflow
  c.observe(std::numeric_limits<std::int64_t>::max());
  EXPECT_EQ(c.lost(), 2u);
}

TEST(TransitLoss, OnlyTheLastRememberedHolesCanBeTakenBack) {
  TransitLossCounter c;
  c.observe(0);
  c.observe(901);  // 900 lost, the last 256 remembered
  EXPECT_EQ(c.lost(), 900u);
  c.observe(900);
  c.observe(901 - static_cast<std::int64_t>(TransitLossCounter::kRemembered));
  EXPECT_EQ(c.lost(), 898u);
}

TEST(LcmSource, PeekReadsTheSeqOfAFrameAndNothingElse) {
  const auto b = frameBytes(123456789012);
  ASSERT_EQ(peekRgbdFrameSeq(b.data(), b.size()), std::optional<std::int64_t>(123456789012));
  EXPECT_FALSE(peekRgbdFrameSeq(b.data(), 23).has_value());
  const auto pose = encodeMessage(encodeRobotPose(RobotPose{1, {0, 0, 0}}));
  EXPECT_FALSE(peekRgbdFrameSeq(pose.data(), pose.size()).has_value());
}

// Frames the publisher numbered but the channel never delivered are counted
// apart from drops (never received) and from rejects (arrived broken).
TEST(LcmSource, SeqHolesAreCountedAsLostInTransit) {
  SourceOptions options;
  options.lcm_queue_size = 32;
  LcmFrameSource source("FINDMUG_RGBD", "memq://", options);
  const std::vector<std::uint8_t> garbage(100, 0xab);
  for (std::int64_t seq : {0, 1, 4, 3, 5, 9}) {  // 2, 6, 7, 8 never sent; 3 late
    const auto b = frameBytes(seq);
    ASSERT_TRUE(source.bus().publish("FINDMUG_RGBD", b.data(), b.size()));
    // A broken message among them (rejected when next() reaches it): no seq, no hole.
    if (seq == 4) source.bus().publish("FINDMUG_RGBD", garbage.data(), garbage.size());
  }
  for (int i = 0; i < 6; ++i) ASSERT_TRUE(source.next().has_value());
  ASSERT_TRUE(eventually([&] { return source.stats().frames_rejected == 1; }));
  EXPECT_EQ(source.stats().frames_lost_in_transit, 4u);
  EXPECT_EQ(source.stats().frames_delivered, 6u);
  EXPECT_EQ(source.stats().frames_dropped, 0u);
}

TEST(LcmSource, SlowConsumerGetsTheNewestFrame) {
  SourceOptions options;
  options.lcm_queue_size = 1;
  LcmFrameSource source("FINDMUG_RGBD", "memq://", options);
  for (int i = 0; i < 6; ++i) {
    const auto b = frameBytes(i);
    source.bus().publish("FINDMUG_RGBD", b.data(), b.size());
  }
  ASSERT_TRUE(eventually([&] { return source.stats().frames_dropped == 5; }));
  auto f = source.next();
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->seq, 5);
}

TEST(LcmSource, FramesQueuedAtStopAreCountedAsDropped) {
  SourceOptions options;
  options.lcm_queue_size = 1;
  LcmFrameSource source("FINDMUG_RGBD", "memq://", options);
  for (int i = 0; i < 3; ++i) {
    const auto b = frameBytes(i);
    source.bus().publish("FINDMUG_RGBD", b.data(), b.size());
  }
  // All three handled: two pushed out by newer ones, the newest still queued.
  ASSERT_TRUE(eventually([&] { return source.stats().frames_dropped == 2; }));
  source.stop();
  // Never processed, never lost silently: frames in = delivered + dropped.
  EXPECT_EQ(source.stats().frames_dropped, 3u);
  EXPECT_EQ(source.stats().frames_delivered, 0u);
  EXPECT_FALSE(source.next().has_value());
}

TEST(LcmSource, SilentPublisherShowsAsReconnectingUntilFramesReturn) {
  LcmFrameSource source("FINDMUG_RGBD", "memq://", SourceOptions{});
  EXPECT_EQ(source.state(), SourceState::Starting);
  auto b = frameBytes(0);
  source.bus().publish("FINDMUG_RGBD", b.data(), b.size());
  ASSERT_TRUE(source.next().has_value());
  EXPECT_EQ(source.state(), SourceState::Running);
  // Nothing for longer than the silence timeout.
  ASSERT_TRUE(eventually([&] { return source.state() == SourceState::Reconnecting; }));
  b = frameBytes(1);
  source.bus().publish("FINDMUG_RGBD", b.data(), b.size());
  auto f = source.next();
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->seq, 1);
  EXPECT_EQ(source.state(), SourceState::Running);
}

TEST(LcmSource, StopUnblocksNext) {
  auto source = makeSource("lcm:FINDMUG_RGBD?url=memq://");
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    source->stop();
  });
  EXPECT_FALSE(source->next().has_value());
  stopper.join();
  EXPECT_EQ(source->state(), SourceState::Stopped);
}

TEST(LcmSource, ReplaysALogFileToTheEndWithoutDropping) {
  test::TempDir tmp;
  const std::string log_path = tmp.str("frames.lcm");
  {
    lcm::LogFile log(log_path, "w");
    ASSERT_TRUE(log.good());
    for (int i = 0; i < 6; ++i) {
      auto b = i == 3 ? std::vector<std::uint8_t>(50, 0x01) : frameBytes(i);
      lcm::LogEvent event;
      event.eventnum = i;
      event.timestamp = 1000 + i;
      event.channel = "FINDMUG_RGBD";
      event.datalen = static_cast<int32_t>(b.size());
      event.data = b.data();
      ASSERT_EQ(log.writeEvent(&event), 0);
    }
  }
  // Queue of 1 on a log: the reader waits instead of dropping.
  auto source = makeSource("lcm:FINDMUG_RGBD?queue=1&url=file://" + log_path + "?speed=0");
  const auto frames = drain(*source);
  ASSERT_EQ(frames.size(), 5u);
  const std::int64_t expected_seq[] = {0, 1, 2, 4, 5};
  for (std::size_t i = 0; i < frames.size(); ++i) EXPECT_EQ(frames[i].seq, expected_seq[i]);
  EXPECT_EQ(source->state(), SourceState::EndOfStream);
  EXPECT_EQ(source->stats().frames_rejected, 1u);
  EXPECT_EQ(source->stats().frames_dropped, 0u);
}

TEST(LcmSource, BadUrlFailsAtStartUp) {
  EXPECT_THROW(makeSource("lcm:X?url=nosuchprovider://"), Error);
}

// ---- OpenNI2 ---------------------------------------------------------------------------------
// OpenNI2 ships a software "Dummy" device (320x240 depth + RGB888 streams):
// the same open / configure / pair / convert code a Kinect goes through.

TEST(Openni2Source, DummyDeviceDeliversPairedFrames) {
  auto source = makeSource("openni2:Dummy");
  const auto frames = drain(*source, 4);
  ASSERT_EQ(frames.size(), 4u);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(frames[i].width, 320);
    EXPECT_EQ(frames[i].height, 240);
    EXPECT_EQ(frames[i].seq, static_cast<std::int64_t>(i));
    EXPECT_GT(frames[i].utime, 1600000000000000u);  // host clock, not the device's
    EXPECT_NO_THROW(validateFrame(frames[i]));
    if (i > 0) {
      EXPECT_GT(frames[i].utime, frames[i - 1].utime);
    }
  }
  EXPECT_EQ(source->state(), SourceState::Running);
  EXPECT_EQ(source->stats().frames_delivered, 4u);
  EXPECT_NE(source->describe().find("Dummy"), std::string::npos);
  // The opened device names itself (findmugd --check shows it).
  EXPECT_NE(source->describe().find(", uri Dummy)"), std::string::npos) << source->describe();
  // A configured camera mount is attached to device frames.
  SourceSpec spec = parseSourceSpec("openni2:Dummy");
  spec.options.extrinsics = CameraExtrinsics{1.2, 0.4, 0.0};
  auto mounted = makeSource(spec);
  auto f = mounted->next();
  ASSERT_TRUE(f && f->extrinsics);
  EXPECT_EQ(f->extrinsics->height_m, 1.2);
}

TEST(Openni2Source, AbsentDeviceReportsReconnectingAndStops) {
  SourceSpec spec = parseSourceSpec("openni2:NoSuchDevice/1");
  spec.options.reconnect_initial = std::chrono::milliseconds(20);
  spec.options.reconnect_max = std::chrono::milliseconds(40);
  auto source = makeSource(spec);  // not an error: the camera may come later
  EXPECT_EQ(source->state(), SourceState::Reconnecting);
  std::thread stopper([&] {
    eventually([&] { return source->stats().last_error.find("retrying in") != std::string::npos; });
    EXPECT_EQ(source->state(), SourceState::Reconnecting);  // still, after failed retries
    source->stop();
  });
  EXPECT_FALSE(source->next().has_value());
  stopper.join();
  EXPECT_EQ(source->state(), SourceState::Stopped);
  EXPECT_NE(source->stats().last_error.find("NoSuchDevice"), std::string::npos)
      << source->stats().last_error;
}

TEST(Openni2Source, CorruptOniFileFailsAtStartUp) {
  test::TempDir tmp;
  std::ofstream(tmp.str("broken.oni"), std::ios::binary) << std::string(4096, 'x');
  try {
    makeSource("openni2:" + tmp.str("broken.oni"));
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("broken.oni"), std::string::npos) << e.what();
  }
}

TEST(SourceSpec, OpenniBackoffAndTimeoutKeys) {
  const SourceSpec spec =
      parseSourceSpec("openni2?reconnect_ms=50&reconnect_max_ms=800&frame_timeout_ms=300");
  EXPECT_EQ(spec.options.reconnect_initial, std::chrono::milliseconds(50));
  EXPECT_EQ(spec.options.reconnect_max, std::chrono::milliseconds(800));
  EXPECT_EQ(spec.options.frame_timeout, std::chrono::milliseconds(300));
  const SourceSpec defaults = parseSourceSpec("openni2");
  EXPECT_EQ(defaults.options.reconnect_initial, std::chrono::milliseconds(500));
  EXPECT_EQ(defaults.options.reconnect_max, std::chrono::milliseconds(5000));
  EXPECT_EQ(defaults.options.frame_timeout, std::chrono::milliseconds(2000));
  auto message = [](const std::string& text) {
    try {
      parseSourceSpec(text);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("openni2?reconnect_ms=0").find("reconnect_ms=0 not in"), std::string::npos);
  EXPECT_NE(message("openni2?frame_timeout_ms=1.5").find("frame_timeout_ms=1.5"),
            std::string::npos);
  EXPECT_NE(message("openni2?reconnect_ms=6000").find("reconnect_max_ms is below reconnect_ms"),
            std::string::npos);
  EXPECT_NE(message("dataset:/x?reconnect_ms=5").find("only applies to openni2"),
            std::string::npos);
}

// ---- a camera that disappears mid-run ------------------------------------------------------
// DeviceSource is the reconnect loop of every device source (the OpenNI2
// one included). Here its device is a "camera" streaming real NYU frames
// that the test unplugs and plugs back in.

TEST(Backoff, DoublesFromTheInitialDelayUpToTheCapAndResets) {
  using std::chrono::milliseconds;
  Backoff b(milliseconds(500), milliseconds(5000));
  std::vector<long> got;
  for (int i = 0; i < 7; ++i) got.push_back(static_cast<long>(b.next().count()));
  EXPECT_EQ(got, (std::vector<long>{500, 1000, 2000, 4000, 5000, 5000, 5000}));
  b.reset();
  EXPECT_EQ(b.next(), milliseconds(500));
  Backoff huge(milliseconds(1), milliseconds::max());  // doubling must not overflow
  for (int i = 0; i < 80; ++i) EXPECT_GT(huge.next().count(), 0) << i;
  EXPECT_THROW(Backoff(milliseconds(0), milliseconds(10)), Error);
  EXPECT_THROW(Backoff(milliseconds(20), milliseconds(10)), Error);
}

// Waits (without asserting on time) until `done` holds, at most a minute
// (the machine may be loaded).
template <typename F>
bool waitFor(F&& done) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (std::chrono::steady_clock::now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return done();
}

// The attempts' back-off delays must be the schedule (initial, x2, ...,
// capped), and each attempt must come at least its delay after the one
// before (a lower bound only: a loaded machine may be late, never early).
void expectBackoffSchedule(const std::vector<ReconnectAttempt>& attempts,
                           std::chrono::milliseconds initial, std::chrono::milliseconds cap) {
  auto expected = initial;
  for (std::size_t i = 0; i < attempts.size(); ++i) {
    EXPECT_EQ(attempts[i].waited, expected) << "attempt " << i;
    expected = std::min(expected * 2, cap);
    if (i > 0) {
      EXPECT_GE(attempts[i].at - attempts[i - 1].at, attempts[i].waited) << "attempt " << i;
    }
  }
}

TEST(DeviceSource, CameraThatDisappearsMidRunComesBackWithBackoff) {
  FINDMUG_REQUIRE_DATA(dir, "nyuv2_labeled");
  using std::chrono::milliseconds;
  const DatasetFolder folder(dir.string());
  auto owned = std::make_unique<test::UnpluggableDevice>("dataset:" + dir.string() + "?loop=1");
  test::UnpluggableDevice& camera = *owned;
  DeviceSourceSettings settings;
  settings.reconnect_initial = milliseconds(20);
  settings.reconnect_max = milliseconds(80);
  settings.poll = milliseconds(20);
  DeviceSource source(std::move(owned), settings);
  EXPECT_EQ(source.state(), SourceState::Starting);
  EXPECT_NE(source.describe().find("unpluggable"), std::string::npos);

  // Running: three frames.
  for (std::int64_t i = 0; i < 3; ++i) {
    auto f = source.next();
    ASSERT_TRUE(f);
    EXPECT_EQ(f->seq, i);
  }
  EXPECT_EQ(source.state(), SourceState::Running);

  // Unplugged: the next read fails; the source reconnects with back-off
  // while the consumer is blocked in next().
  camera.unplug();
  std::optional<RgbdFrame> after;
  std::thread consumer, consumer2;
  // A failed ASSERT returns early: stop the source and join, not terminate.
  struct Cleanup {
    FrameSource& source;
    std::thread &a, &b;
    ~Cleanup() {
      source.stop();
      if (a.joinable()) a.join();
      if (b.joinable()) b.join();
    }
  } cleanup{source, consumer, consumer2};
  consumer = std::thread([&] { after = source.next(); });
  ASSERT_TRUE(waitFor([&] { return source.reconnectAttempts().size() >= 6; }));
  EXPECT_EQ(source.state(), SourceState::Reconnecting);
  const SourceStats lost = source.stats();
  EXPECT_EQ(lost.reconnects, 0u);
  EXPECT_NE(lost.last_error.find("test camera unplugged"), std::string::npos) << lost.last_error;
  EXPECT_NE(lost.last_error.find("retrying in 80 ms"), std::string::npos) << lost.last_error;

  // Plugged back in: frames flow again, numbered on from before the loss.
  camera.plug();
  consumer.join();
  ASSERT_TRUE(after);
  EXPECT_EQ(after->seq, 3);
  // The camera was opened afresh: its stream starts at its first frame again.
  EXPECT_EQ(after->depth_mm, folder.load(0).frame.depth_mm);
  EXPECT_EQ(source.state(), SourceState::Running);
  EXPECT_EQ(source.stats().reconnects, 1u);
  EXPECT_EQ(camera.opens(), 2);
  const auto attempts = source.reconnectAttempts();
  ASSERT_GE(attempts.size(), 7u);
  for (std::size_t i = 0; i + 1 < attempts.size(); ++i) {
    EXPECT_FALSE(attempts[i].succeeded) << i;
    EXPECT_NE(attempts[i].error.find("unplugged"), std::string::npos) << i;
  }
  EXPECT_TRUE(attempts.back().succeeded);
  expectBackoffSchedule(attempts, settings.reconnect_initial, settings.reconnect_max);

  // A second loss, this time a stalled driver (no frames, no error): the
  // frame timeout notices it, and the back-off starts from the initial delay.
  camera.silence(true);
  consumer2 = std::thread([&] { after = source.next(); });
  ASSERT_TRUE(waitFor([&] { return source.state() == SourceState::Reconnecting; }));
  EXPECT_NE(source.stats().last_error.find("no frame for 2000 ms; device lost"),  // the default
            std::string::npos)
      << source.stats().last_error;
  camera.silence(false);
  consumer2.join();
  ASSERT_TRUE(after);
  EXPECT_EQ(after->seq, 4);
  EXPECT_EQ(source.stats().reconnects, 2u);
  const auto again = source.reconnectAttempts();
  ASSERT_EQ(again.size(), attempts.size() + 1);  // plugged: the first attempt succeeds
  EXPECT_TRUE(again.back().succeeded);
  EXPECT_EQ(again.back().waited, settings.reconnect_initial);
  EXPECT_EQ(source.stats().frames_delivered, 5u);
}

TEST(DeviceSource, StopEndsTheBackoffAndAnUnopenablePlaybackFailsAtStartUp) {
  using std::chrono::milliseconds;
  auto owned = std::make_unique<test::UnpluggableDevice>("dataset:/nonexistent");
  owned->unplug();
  DeviceSourceSettings settings;
  settings.reconnect_initial = milliseconds(10000);  // stop() must not wait for it
  settings.reconnect_max = milliseconds(10000);
  DeviceSource source(std::move(owned), settings);
  EXPECT_EQ(source.state(), SourceState::Reconnecting);
  EXPECT_NE(source.stats().last_error.find("unplugged); retrying"), std::string::npos);
  std::thread stopper([&] {
    std::this_thread::sleep_for(milliseconds(50));
    source.stop();
  });
  EXPECT_FALSE(source.next());
  stopper.join();
  EXPECT_EQ(source.state(), SourceState::Stopped);
  EXPECT_TRUE(source.reconnectAttempts().empty());

  auto file = std::make_unique<test::UnpluggableDevice>("dataset:/nonexistent");
  file->unplug();
  settings.reconnect = false;
  try {
    DeviceSource playback(std::move(file), settings);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("unpluggable test camera"), std::string::npos) << e.what();
  }
}

// ---- findmug-grab ----------------------------------------------------------------------------

int run(const std::string& command) {
  const int rc = std::system((command + " >/dev/null 2>&1").c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

TEST(FindmugGrab, WritesALogThatLcmLogFileReadsBack) {
  FINDMUG_REQUIRE_DATA(dir, "nyuv2_labeled");
  test::TempDir tmp;
  const std::string log_path = tmp.str("grab.lcm");
  ASSERT_EQ(run(std::string(FINDMUG_GRAB_EXE) + " --source 'dataset:" + dir.string() +
                "' --count 4 --channel-suffix TEST --color-compression png --url 'file://" +
                log_path + "?mode=w'"),
            0);
  lcm::LogFile log(log_path, "r");
  ASSERT_TRUE(log.good());
  const DatasetFolder folder(dir.string());
  int count = 0;
  while (const lcm::LogEvent* event = log.readNextEvent()) {
    EXPECT_EQ(event->channel, "FINDMUG_RGBD_TEST");
    const RgbdFrame f =
        decodeRgbdFrame(event->data, static_cast<std::size_t>(event->datalen), event->channel);
    EXPECT_EQ(f.seq, count);
    const RgbdFrame expected = folder.load(static_cast<std::size_t>(count)).frame;
    EXPECT_EQ(f.depth_mm, expected.depth_mm);  // zlib + PNG: lossless
    EXPECT_EQ(f.rgb, expected.rgb);
    ++count;
  }
  EXPECT_EQ(count, 4);
}

TEST(FindmugGrab, PublishesAWholeSequenceAndRejectsBadFlags) {
  FINDMUG_REQUIRE_DATA(dir, kSequences);
  test::TempDir tmp;
  const std::string log_path = tmp.str("pcd.lcm");
  ASSERT_EQ(run(std::string(FINDMUG_GRAB_EXE) + " --source 'pcd:" + (dir / "pcd").string() +
                "' --url 'file://" + log_path + "?mode=w'"),
            0);
  lcm::LogFile log(log_path, "r");
  int count = 0;
  while (const lcm::LogEvent* event = log.readNextEvent()) {
    EXPECT_EQ(event->channel, "FINDMUG_RGBD");
    ++count;
  }
  EXPECT_EQ(count, 3);
  EXPECT_EQ(run(std::string(FINDMUG_GRAB_EXE) + " --color-compression webp"), 2);
  EXPECT_EQ(run(std::string(FINDMUG_GRAB_EXE) + " --bogus"), 2);
  EXPECT_EQ(run(std::string(FINDMUG_GRAB_EXE) + " --source 'pcd:/nonexistent' --url 'file://" +
                tmp.str("x.lcm") + "?mode=w'"),
            1);
}

}  // namespace
}  // namespace findmug::io
