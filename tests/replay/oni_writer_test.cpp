// .oni files written without a camera (OpenNI 1.5 mock nodes + recorder) must
// play back through OpenNI2 — via findmug's own openni2:FILE.oni source —
// with depth bit-exact, colour exact (raw codec) or close (JPEG), the
// focal length preserved through the field of view, and nothing more.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <optional>
#include <thread>

#include "findmug/common/error.hpp"
#include "findmug/io/device_source.hpp"
#include "findmug/io/frame_source.hpp"
#include "oni_writer.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

std::vector<RgbdFrame> nyuFrames(const std::filesystem::path& dir, int count) {
  auto source = io::makeSource("dataset:" + dir.string());
  std::vector<RgbdFrame> frames;
  while (static_cast<int>(frames.size()) < count) {
    auto f = source->next();
    if (!f) break;
    frames.push_back(std::move(*f));
  }
  return frames;
}

std::vector<RgbdFrame> playBack(const std::string& oni) {
  auto source = io::makeSource("openni2:" + oni + "?realtime=0");
  std::vector<RgbdFrame> frames;
  while (auto f = source->next()) frames.push_back(std::move(*f));
  EXPECT_EQ(source->state(), io::SourceState::EndOfStream) << source->stats().last_error;
  return frames;
}

class OniWriterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    FINDMUG_REQUIRE_DATA(nyu_dir, "nyuv2_labeled");
    frames = nyuFrames(nyu_dir, 3);
    ASSERT_EQ(frames.size(), 3u);
  }
  std::vector<RgbdFrame> frames;
  test::TempDir tmp;
};

TEST_F(OniWriterTest, RawColourRoundTripsExactly) {
  const std::string path = tmp.str("nyu.oni");
  {
    oni::OniWriter writer(path, 640, 480, frames[0].intrinsics,
                          {oni::DepthCodec::Z16, oni::ColorCodec::Raw, 5});
    for (std::size_t i = 0; i < frames.size(); ++i) writer.write(frames[i], i * 200'000);
    writer.close();
    EXPECT_EQ(writer.framesWritten(), 3);
  }
  const auto played = playBack(path);
  ASSERT_EQ(played.size(), frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) {
    SCOPED_TRACE("frame " + std::to_string(i));
    ASSERT_EQ(played[i].width, 640);
    ASSERT_EQ(played[i].height, 480);
    EXPECT_TRUE(played[i].depth_mm == frames[i].depth_mm);  // 16z is lossless
    ASSERT_EQ(played[i].rgb.size(), frames[i].rgb.size());
    EXPECT_EQ(0, std::memcmp(played[i].rgb.data(), frames[i].rgb.data(), frames[i].rgb.size() * 3));
    // The focal length survives as a field of view (float in OpenNI2).
    EXPECT_NEAR(played[i].intrinsics.fx, frames[0].intrinsics.fx, 0.01);
    EXPECT_NEAR(played[i].intrinsics.fy, frames[0].intrinsics.fy, 0.01);
    EXPECT_EQ(played[i].seq, static_cast<std::int64_t>(i));
  }
}

TEST_F(OniWriterTest, JpegColourIsCloseAndRawDepthExact) {
  const std::string path = tmp.str("nyu-jpeg.oni");
  {
    oni::OniWriter writer(path, 640, 480, frames[0].intrinsics,
                          {oni::DepthCodec::Raw, oni::ColorCodec::Jpeg, 30});
    for (std::size_t i = 0; i < frames.size(); ++i) writer.write(frames[i], 1 + i * 33'333);
  }  // the destructor finalises the file
  const auto played = playBack(path);
  ASSERT_EQ(played.size(), frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_TRUE(played[i].depth_mm == frames[i].depth_mm);
    double diff = 0;
    const auto* a = reinterpret_cast<const std::uint8_t*>(played[i].rgb.data());
    const auto* b = reinterpret_cast<const std::uint8_t*>(frames[i].rgb.data());
    for (std::size_t k = 0; k < frames[i].rgb.size() * 3; ++k) diff += std::abs(a[k] - b[k]);
    const double mean = diff / static_cast<double>(frames[i].rgb.size() * 3);
    EXPECT_LT(mean, 4.0) << "JPEG mean absolute colour error, frame " << i;
    EXPECT_GT(mean, 0.0) << "JPEG is lossy: identical colour means the codec was not applied";
  }
}

// The OpenNI2 source's own reconnect path, without a camera: a device URI
// that names no file yet is a live device that is absent (Reconnecting, the
// OpenNI2 open failing on each back-off attempt); once a recording appears
// under that URI, OpenNI2 opens it as a device and frames flow. Then the
// "device" breaks under the driver (the file cut to nothing): no frame
// within frame_timeout_ms, so the source closes it, retries (the open fails
// on the broken file), and comes back when the recording is whole again.
TEST_F(OniWriterTest, Openni2DeviceThatAppearsVanishesAndComesBackIsReopened) {
  const std::string uri = tmp.str("camera.oni");
  auto write = [&](const std::string& path) {
    oni::OniWriter writer(path, 640, 480, frames[0].intrinsics,
                          {oni::DepthCodec::Z16, oni::ColorCodec::Raw, 5});
    for (std::size_t i = 0; i < frames.size(); ++i) writer.write(frames[i], i * 200'000);
    writer.close();
  };
  auto owned = io::makeSource("openni2:" + uri +
                              "?reconnect_ms=20&reconnect_max_ms=80&frame_timeout_ms=500");
  auto* source = dynamic_cast<io::DeviceSource*>(owned.get());
  ASSERT_NE(source, nullptr);
  EXPECT_EQ(source->state(), io::SourceState::Reconnecting);
  std::optional<RgbdFrame> got;
  std::thread consumer, consumer2;
  // A failed ASSERT returns early: stop the source and join, not terminate.
  struct Cleanup {
    io::FrameSource& source;
    std::thread &a, &b;
    ~Cleanup() {
      source.stop();
      if (a.joinable()) a.join();
      if (b.joinable()) b.join();
    }
  } cleanup{*source, consumer, consumer2};
  consumer = std::thread([&] { got = source->next(); });
  auto wait_for = [](auto done) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (!done() && std::chrono::steady_clock::now() < end) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return done();
  };
  ASSERT_TRUE(wait_for([&] { return source->reconnectAttempts().size() >= 4; }));
  EXPECT_NE(source->stats().last_error.find("camera.oni"), std::string::npos)
      << source->stats().last_error;
  // The camera is plugged in: written aside, then moved in whole.
  write(tmp.str("aside.oni"));
  std::filesystem::rename(tmp.str("aside.oni"), uri);
  consumer.join();
  ASSERT_TRUE(got);
  EXPECT_EQ(got->width, 640);
  EXPECT_EQ(source->stats().reconnects, 1u);
  EXPECT_EQ(source->state(), io::SourceState::Running);
  const std::size_t before = source->reconnectAttempts().size();

  // The device breaks mid-run.
  std::filesystem::resize_file(uri, 0);
  got.reset();
  consumer2 = std::thread([&] {  // frames already queued in the driver may still come first
    while (auto f = source->next()) {
      if (source->stats().reconnects >= 2) {
        got = std::move(f);
        break;
      }
    }
  });
  ASSERT_TRUE(wait_for([&] { return source->reconnectAttempts().size() >= before + 3; }))
      << source->stats().last_error;
  EXPECT_EQ(source->state(), io::SourceState::Reconnecting) << source->stats().last_error;
  write(tmp.str("aside.oni"));
  std::filesystem::rename(tmp.str("aside.oni"), uri);
  ASSERT_TRUE(wait_for([&] { return source->stats().reconnects >= 2; }))
      << source->stats().last_error;
  consumer2.join();
  ASSERT_TRUE(got);
  EXPECT_EQ(got->width, 640);
  EXPECT_EQ(source->state(), io::SourceState::Running);
}

TEST_F(OniWriterTest, BadInputIsAnErrorNamingTheFile) {
  const std::string path = tmp.str("bad.oni");
  oni::OniWriter writer(path, 640, 480, frames[0].intrinsics);
  writer.write(frames[0], 100);
  RgbdFrame small = frames[1];
  small.width = 320;
  try {
    writer.write(small, 200);
    FAIL() << "a frame of another size must be rejected";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.oni"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("320x480"), std::string::npos) << e.what();
  }
  EXPECT_THROW(writer.write(frames[1], 100), Error);  // timestamp does not increase
  writer.close();
  EXPECT_THROW(writer.write(frames[1], 300), Error);  // closed

  CameraIntrinsics bad;
  bad.fx = 0;
  EXPECT_THROW(oni::OniWriter(tmp.str("k.oni"), 640, 480, bad), Error);
  EXPECT_THROW(oni::OniWriter(tmp.str("s.oni"), 0, 480, frames[0].intrinsics), Error);
  EXPECT_THROW(oni::OniWriter("/nonexistent-dir/x.oni", 640, 480, frames[0].intrinsics), Error);
  EXPECT_THROW(oni::parseDepthCodec("zip"), Error);
  EXPECT_THROW(oni::parseColorCodec("png"), Error);
}

}  // namespace
}  // namespace findmug
