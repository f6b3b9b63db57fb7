// LCM's udpm transport as findmug receives it (io/udpm.hpp): the reassembler
// against hand-made datagrams, then UdpmBus against liblcm's own sender and a
// hostile one, inside a private network namespace this test process makes
// (root only; skipped otherwise, like the other udpm tests).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sched.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "findmug/common/error.hpp"
#include "findmug/io/bus.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/io/lcm_source.hpp"
#include "findmug/io/udpm.hpp"
#include "test_data.hpp"

namespace findmug::io {
namespace {

using Bytes = std::vector<std::uint8_t>;

void put32(Bytes& b, std::uint32_t v) {
  for (int k = 3; k >= 0; --k) b.push_back(static_cast<std::uint8_t>(v >> (8 * k)));
}
void put16(Bytes& b, std::uint16_t v) {
  b.push_back(static_cast<std::uint8_t>(v >> 8));
  b.push_back(static_cast<std::uint8_t>(v));
}

Bytes shortMessage(std::uint32_t seqno, const std::string& channel, const Bytes& payload) {
  Bytes d;
  put32(d, 0x4c433032);
  put32(d, seqno);
  d.insert(d.end(), channel.begin(), channel.end());
  d.push_back(0);
  d.insert(d.end(), payload.begin(), payload.end());
  return d;
}

Bytes fragment(std::uint32_t seqno, std::uint32_t msg_size, std::uint32_t offset,
               std::uint16_t number, std::uint16_t count, const std::string& channel,
               const Bytes& payload) {
  Bytes d;
  put32(d, 0x4c433033);
  put32(d, seqno);
  put32(d, msg_size);
  put32(d, offset);
  put16(d, number);
  put16(d, count);
  if (number == 0) {
    d.insert(d.end(), channel.begin(), channel.end());
    d.push_back(0);
  }
  d.insert(d.end(), payload.begin(), payload.end());
  return d;
}

// A message cut into fragments of `chunk` bytes, as LCM's sender does it.
std::vector<Bytes> fragmentsOf(std::uint32_t seqno, const std::string& channel,
                               const Bytes& message, std::size_t chunk) {
  std::vector<Bytes> out;
  const std::size_t n = (message.size() + chunk - 1) / chunk;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t off = i * chunk, len = std::min(chunk, message.size() - off);
    out.push_back(fragment(seqno, static_cast<std::uint32_t>(message.size()),
                           static_cast<std::uint32_t>(off), static_cast<std::uint16_t>(i),
                           static_cast<std::uint16_t>(n), channel,
                           Bytes(message.begin() + off, message.begin() + off + len)));
  }
  return out;
}

Bytes pattern(std::size_t n, unsigned seed = 1) {
  std::mt19937 rng(seed);
  Bytes b(n);
  for (auto& x : b) x = static_cast<std::uint8_t>(rng());
  return b;
}

struct Fed {
  UdpmReassembler r{[](const std::string& c) { return c == "WANTED"; }};
  std::optional<UdpmReject> why;
  std::optional<UdpmReassembler::Message> feed(const Bytes& d, std::uint64_t sender = 1,
                                               std::int64_t now = 1000) {
    return r.feed(sender, d.data(), d.size(), now, &why);
  }
};

Bytes bytesOf(const UdpmReassembler::Message& m) {
  return Bytes(m.bytes.get(), m.bytes.get() + m.size);
}

TEST(UdpmReassembler, ShortMessageIsDeliveredWithItsChannel) {
  Fed f;
  const auto m = f.feed(shortMessage(3, "WANTED", {1, 2, 3}));
  ASSERT_TRUE(m);
  EXPECT_EQ(m->channel, "WANTED");
  EXPECT_EQ(bytesOf(*m), (Bytes{1, 2, 3}));
  EXPECT_EQ(m->recv_utime, 1000);
  EXPECT_FALSE(f.feed(shortMessage(4, "OTHER", {1})));
  EXPECT_FALSE(f.why) << "another channel on the group is not an error";
  EXPECT_EQ(f.r.stats().ignored, 1u);
}

TEST(UdpmReassembler, FragmentsInAnyOrderGiveTheMessageByteForByte) {
  const Bytes message = pattern(200000);
  for (const bool reversed : {false, true}) {
    Fed f;
    auto frags = fragmentsOf(9, "WANTED", message, 60000);
    if (reversed) std::reverse(frags.begin(), frags.end());  // fragment 0 (the channel) last
    std::optional<UdpmReassembler::Message> m;
    for (std::size_t i = 0; i < frags.size(); ++i) {
      m = f.feed(frags[i], 1, 1000 + static_cast<std::int64_t>(i));
      if (i + 1 < frags.size()) {
        EXPECT_FALSE(m) << "delivered before the last fragment";
      }
    }
    ASSERT_TRUE(m) << (reversed ? "reversed" : "in order");
    EXPECT_EQ(m->channel, "WANTED");
    EXPECT_EQ(bytesOf(*m), message);
    EXPECT_EQ(m->recv_utime, 1000);  // the first datagram's time
    EXPECT_EQ(f.r.inFlightBytes(), 0u);
  }
}

TEST(UdpmReassembler, TwoSendersWithTheSameSeqnoAreKeptApart) {
  Fed f;
  const Bytes a = pattern(100000, 1), b = pattern(100000, 2);
  const auto fa = fragmentsOf(5, "WANTED", a, 60000), fb = fragmentsOf(5, "WANTED", b, 60000);
  EXPECT_FALSE(f.feed(fa[0], 1));
  EXPECT_FALSE(f.feed(fb[0], 2));
  const auto mb = f.feed(fb[1], 2);
  const auto ma = f.feed(fa[1], 1);
  ASSERT_TRUE(ma && mb);
  EXPECT_EQ(bytesOf(*ma), a);
  EXPECT_EQ(bytesOf(*mb), b);
}

// The pair that kills liblcm 1.3.1: its check `offset + size > message size`
// wraps in 32 bits for an offset near 2^32.
TEST(UdpmReassembler, AnOffsetThatWrapsAroundIsRefused) {
  Fed f;
  EXPECT_FALSE(f.feed(fragment(7, 100000, 0, 0, 100, "WANTED", Bytes(100, 'x'))));
  EXPECT_FALSE(f.why);
  EXPECT_FALSE(f.feed(fragment(7, 100000, 0xFFFFFF00u, 1, 100, "", Bytes(0x200, 'y'))));
  ASSERT_TRUE(f.why);
  EXPECT_EQ(*f.why, UdpmReject::FragmentOutside);
  // Past the end without wrapping, too.
  EXPECT_FALSE(f.feed(fragment(7, 100000, 99990, 2, 100, "", Bytes(11, 'z'))));
  EXPECT_EQ(f.why, UdpmReject::FragmentOutside);
}

TEST(UdpmReassembler, EachBadHeaderFieldIsRefusedWithItsReason) {
  struct Case {
    const char* what;
    Bytes datagram;
    UdpmReject why;
  };
  Bytes no_nul = {0x4c, 0x43, 0x30, 0x32, 0, 0, 0, 1, 'W', 'A'};
  const std::string long_channel(64, 'C');
  const std::vector<Case> cases = {
      {"7 bytes", Bytes{0x4c, 0x43, 0x30, 0x32, 0, 0, 0}, UdpmReject::TooShort},
      {"fragment header cut", Bytes{0x4c, 0x43, 0x30, 0x33, 0, 0, 0, 1, 0, 0}, UdpmReject::TooShort},
      {"magic", Bytes{'L', 'C', '0', '9', 0, 0, 0, 1, 'W', 0}, UdpmReject::BadMagic},
      {"channel without NUL", no_nul, UdpmReject::BadChannel},
      {"empty channel", shortMessage(1, "", {1}), UdpmReject::BadChannel},
      {"64-byte channel", shortMessage(1, long_channel, {1}), UdpmReject::BadChannel},
      {"size 2^32-1", fragment(1, 0xFFFFFFFFu, 0, 0, 2, "WANTED", {1}), UdpmReject::MessageTooBig},
      {"size over 32 MB", fragment(1, (32u << 20) + 1, 0, 0, 600, "WANTED", {1}),
       UdpmReject::MessageTooBig},
      {"count 0", fragment(1, 10, 0, 0, 0, "WANTED", {1}), UdpmReject::BadFragmentCount},
      {"number >= count", fragment(1, 10, 0, 3, 3, "", {1}), UdpmReject::BadFragmentCount},
      {"more fragments than bytes", fragment(1, 10, 0, 0, 12, "WANTED", {1}),
       UdpmReject::BadFragmentCount},
      {"fragment 0 without channel NUL",
       [] {
         Bytes d = fragment(1, 10, 0, 1, 2, "", Bytes(4, 'a'));
         d[17] = 0;  // make it fragment 0: its payload must start with the channel
         return d;
       }(),
       UdpmReject::BadChannel},
  };
  for (const Case& c : cases) {
    Fed f;
    EXPECT_FALSE(f.feed(c.datagram)) << c.what;
    ASSERT_TRUE(f.why) << c.what;
    EXPECT_EQ(*f.why, c.why) << c.what << ": " << udpmRejectName(*f.why);
    EXPECT_EQ(f.r.inFlightBytes(), 0u) << c.what;
  }
}

TEST(UdpmReassembler, ARepeatedFragmentDoesNotCompleteAMessageWithAHole) {
  // liblcm counts a repeat as a new fragment: three fragments, the first
  // twice, and it delivers a message whose last third was never sent.
  Fed f;
  const Bytes message = pattern(3000);
  const auto frags = fragmentsOf(2, "WANTED", message, 1000);
  EXPECT_FALSE(f.feed(frags[0]));
  EXPECT_FALSE(f.feed(frags[1]));
  EXPECT_FALSE(f.feed(frags[1]));
  EXPECT_EQ(f.why, UdpmReject::Duplicate);
  const auto m = f.feed(frags[2]);
  ASSERT_TRUE(m);
  EXPECT_EQ(bytesOf(*m), message);
}

TEST(UdpmReassembler, FragmentsThatOverlapAndLeaveAGapAreNotDelivered) {
  Fed f;
  // Two fragments of 500 bytes, both at offset 0 of a 1000-byte message: the
  // byte count adds up, the bytes do not.
  EXPECT_FALSE(f.feed(fragment(4, 1000, 0, 0, 2, "WANTED", Bytes(500, 'a'))));
  EXPECT_FALSE(f.feed(fragment(4, 1000, 0, 1, 2, "", Bytes(500, 'b'))));
  EXPECT_EQ(f.why, UdpmReject::Inconsistent);
  EXPECT_EQ(f.r.stats().delivered, 0u);
  EXPECT_EQ(f.r.inFlightBytes(), 0u);
  // A fragment that changes the message's size or count mid-way.
  EXPECT_FALSE(f.feed(fragment(5, 1000, 0, 0, 2, "WANTED", Bytes(500, 'a'))));
  EXPECT_FALSE(f.feed(fragment(5, 2000, 500, 1, 2, "", Bytes(500, 'b'))));
  EXPECT_EQ(f.why, UdpmReject::Inconsistent);
}

TEST(UdpmReassembler, UnwantedChannelsCostNoBufferAndTheirOtherFragmentsAreSkipped) {
  Fed f;
  const auto frags = fragmentsOf(8, "OTHER", pattern(200000), 60000);
  for (const auto& d : frags) EXPECT_FALSE(f.feed(d));
  EXPECT_FALSE(f.why);
  EXPECT_EQ(f.r.inFlightBytes(), 0u);
  EXPECT_EQ(f.r.stats().rejectedTotal(), 0u);
}

TEST(UdpmReassembler, UnfinishedMessagesAreBoundedInBytesAndTime) {
  Fed f;
  // Hostile first fragments that announce 32 MB messages and never finish,
  // from many senders: what is held stays under the bound.
  for (std::uint64_t s = 0; s < 200; ++s) {
    f.feed(fragment(1, 32u << 20, 0, 0, 600, "WANTED", Bytes(1000, 'h')), s, 1000);
    ASSERT_LE(f.r.inFlightBytes(), UdpmReassembler::kMaxInFlightBytes);
    ASSERT_LE(f.r.inFlightMessages(), UdpmReassembler::kMaxInFlightMessages);
  }
  EXPECT_GT(f.r.stats().incomplete, 190u);
  f.r.expire(1000 + UdpmReassembler::kStaleAfterUs + 1);
  EXPECT_EQ(f.r.inFlightBytes(), 0u);
  // A real message still gets through afterwards.
  const Bytes message = pattern(150000);
  std::optional<UdpmReassembler::Message> m;
  for (const auto& d : fragmentsOf(2, "WANTED", message, 60000)) m = f.feed(d, 999, 5'000'000);
  ASSERT_TRUE(m);
  EXPECT_EQ(bytesOf(*m), message);
}

TEST(UdpmReassembler, RandomAndMutatedDatagramsNeverCrashAndStayBounded) {
  Fed f;
  std::mt19937_64 rng(11);
  const Bytes message = pattern(120000);
  const auto good = fragmentsOf(1, "WANTED", message, 50000);
  for (int i = 0; i < 200000; ++i) {
    Bytes d;
    switch (i % 4) {
      case 0:
        d = pattern(rng() % 1500, static_cast<unsigned>(rng()));
        if (d.size() >= 4 && i % 8 == 0) d[0] = 'L', d[1] = 'C', d[2] = '0', d[3] = '3';
        break;
      case 1: {  // a real fragment with a few bits flipped
        d = good[rng() % good.size()];
        for (int k = 0; k < 3; ++k) d[rng() % std::min<std::size_t>(d.size(), 40)] ^= 1 << (rng() % 8);
        break;
      }
      case 2: {  // a real fragment cut short
        d = good[rng() % good.size()];
        d.resize(rng() % d.size());
        break;
      }
      case 3: {  // header fields at their extremes
        const std::uint32_t sizes[] = {0, 1, 0x7FFFFFFF, 0xFFFFFFFF, 1u << 24, 120000};
        const std::uint32_t offs[] = {0, 1, 0xFFFFFF00u, 0xFFFFFFFFu, 119999, 60000};
        d = fragment(static_cast<std::uint32_t>(rng() % 4), sizes[rng() % 6], offs[rng() % 6],
                     static_cast<std::uint16_t>(rng() % 3), static_cast<std::uint16_t>(rng() % 4),
                     "WANTED", pattern(rng() % 1400, static_cast<unsigned>(i)));
        break;
      }
    }
    const auto m = f.feed(d, rng() % 16, i);
    if (m) {
      ASSERT_LE(m->size, UdpmReassembler::kMaxMessageBytes);
    }
    ASSERT_LE(f.r.inFlightBytes(), UdpmReassembler::kMaxInFlightBytes);
  }
  EXPECT_GT(f.r.stats().rejectedTotal(), 100000u);
}

TEST(UdpmUrl, ParsesLcmOptionsAndNamesWhatIsWrong) {
  const UdpmUrl u = parseUdpmUrl("udpm://239.255.76.68:7668?ttl=1&recv_buf_size=4194304", "k");
  EXPECT_EQ(u.group, "239.255.76.68");
  EXPECT_EQ(u.port, 7668);
  EXPECT_EQ(u.ttl, 1);
  EXPECT_EQ(u.recv_buf_size, 4194304);
  const UdpmUrl d = parseUdpmUrl("udpm://", "k");
  EXPECT_EQ(d.group, "239.255.76.67");
  EXPECT_EQ(d.port, 7667);
  EXPECT_TRUE(isUdpmUrl("udpm://239.255.76.67:7667"));
  EXPECT_FALSE(isUdpmUrl("memq://"));
  const auto error_of = [](const std::string& url) {
    try {
      parseUdpmUrl(url, "daemon.lcm_url");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error_of("udpm://10.0.0.1:7667").find("not a multicast address"), std::string::npos);
  EXPECT_NE(error_of("udpm://239.1.1.1:99999").find("port '99999'"), std::string::npos);
  EXPECT_NE(error_of("udpm://239.1.1.1:7667?ttl=nan").find("ttl 'nan'"), std::string::npos);
  EXPECT_NE(error_of("udpm://239.1.1.1:7667?tll=0").find("unknown option 'tll'"),
            std::string::npos);
  EXPECT_NE(error_of("udpm://239.1.1.1:7667?ttl=0").find("no error"), std::string::npos);
  EXPECT_NE(error_of("udpm://x:1").find("daemon.lcm_url"), std::string::npos);
}

// ---- over the network, in a private namespace ----------------------------------------

const char* kUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";

// As root: enters a private network namespace with multicast routed over
// loopback, or fails the test (a root that cannot is a broken test host).
void enterPrivateNetwork() {
  ASSERT_EQ(::unshare(CLONE_NEWNET), 0) << "unshare(CLONE_NEWNET) failed";
  ASSERT_EQ(std::system("ip link set lo up && ip route add 224.0.0.0/4 dev lo"), 0);
}

// Sends raw datagrams to the group from one source port.
class RawSender {
 public:
  RawSender() {
    fd_ = ::socket(AF_INET, SOCK_DGRAM, 0);
    const unsigned char ttl = 0;
    ::setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof ttl);
    dest_.sin_family = AF_INET;
    dest_.sin_port = htons(7667);
    inet_pton(AF_INET, "239.255.76.67", &dest_.sin_addr);
  }
  ~RawSender() { ::close(fd_); }
  void send(const Bytes& d) {
    ASSERT_EQ(::sendto(fd_, d.data(), d.size(), 0, reinterpret_cast<sockaddr*>(&dest_), sizeof dest_),
              static_cast<ssize_t>(d.size()));
  }

 private:
  int fd_ = -1;
  sockaddr_in dest_{};
};

// Handles until `done()` or 5 s.
template <class Done>
void handleUntil(Bus& bus, Done done) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (!done() && std::chrono::steady_clock::now() < deadline) {
    bus.handle(std::chrono::milliseconds(50));
  }
}

TEST(UdpmBus, ReceivesWhatLiblcmSendsShortAndFragmentedAndSurvivesTheLiblcmKiller) {
  FINDMUG_REQUIRE_ROOT();
  ASSERT_NO_FATAL_FAILURE(enterPrivateNetwork());
  const auto bus = openBus(kUrl, "test");
  ASSERT_NE(dynamic_cast<UdpmBus*>(bus.get()), nullptr) << "a udpm URL opens findmug's receiver";
  std::vector<Bytes> got;
  bus->subscribe("WANTED", [&](const std::string&, const std::uint8_t* d, std::size_t n) {
    got.emplace_back(d, d + n);
  });
  LcmBus publisher(kUrl, "publisher");
  const Bytes small = pattern(300, 3), big = pattern(1'500'000, 4);  // big: about 23 fragments
  ASSERT_TRUE(publisher.publish("WANTED", small.data(), small.size()));
  ASSERT_TRUE(publisher.publish("OTHER", big.data(), big.size()));
  ASSERT_TRUE(publisher.publish("WANTED", big.data(), big.size()));
  handleUntil(*bus, [&] { return got.size() >= 2; });
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0], small);
  EXPECT_EQ(got[1], big);

  // The two datagrams that crash a liblcm 1.3.1 subscriber, then a real message.
  RawSender hostile;
  hostile.send(fragment(7, 100000, 0, 0, 100, "WANTED", Bytes(100, 'x')));
  hostile.send(fragment(7, 100000, 0xFFFFFF00u, 1, 100, "", Bytes(0x200, 'y')));
  ASSERT_TRUE(publisher.publish("WANTED", small.data(), small.size()));
  handleUntil(*bus, [&] { return got.size() >= 3; });
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[2], small);
  const auto& stats = static_cast<UdpmBus&>(*bus).stats();
  EXPECT_EQ(stats.rejected[static_cast<int>(UdpmReject::FragmentOutside)], 1u);
}

TEST(UdpmBus, TheDaemonsFrameSourceKeepsReceivingFramesThroughHostileDatagrams) {
  FINDMUG_REQUIRE_ROOT();
  ASSERT_NO_FATAL_FAILURE(enterPrivateNetwork());
  SourceOptions options;
  LcmFrameSource source("FINDMUG_RGBD", kUrl, options);
  EXPECT_NE(source.describe().find("udpm://"), std::string::npos);
  LcmBus publisher(kUrl, "publisher");
  RgbdFrame frame;
  frame.width = 64;
  frame.height = 48;
  frame.intrinsics = {57.0, 57.0, 32.0, 24.0};
  frame.depth_mm.assign(64 * 48, 1500);
  frame.rgb.assign(64 * 48, Rgb8{100, 110, 120});
  frame.utime = 42;
  const Bytes encoded = encodeMessage(encodeRgbdFrame(frame));
  RawSender hostile;
  for (int i = 0; i < 3; ++i) {
    hostile.send(fragment(static_cast<std::uint32_t>(i), 100000, 0, 0, 100, "FINDMUG_RGBD",
                          Bytes(100, 'x')));
    hostile.send(fragment(static_cast<std::uint32_t>(i), 100000, 0xFFFFFF00u, 1, 100, "",
                          Bytes(0x200, 'y')));
    ASSERT_TRUE(publisher.publish("FINDMUG_RGBD", encoded.data(), encoded.size()));
    const auto got = source.next();
    ASSERT_TRUE(got) << "frame " << i;
    EXPECT_EQ(got->width, 64);
    EXPECT_EQ(got->utime, 42u);
  }
  source.stop();
}

}  // namespace
}  // namespace findmug::io
