// findmug-lcm-flood — hostile datagrams for findmugd's LCM input (udpm).
//
//   findmug-lcm-flood --group 239.255.76.67 --port 7667 --count 1000000 [--seed 1]
//                     [--channel FINDMUG_RGBD] [--sockets 8] [--rate 0]
//
// Sends --count UDP datagrams to the LCM multicast group, from --sockets
// source ports (liblcm keeps one fragment buffer per sender), cycling through
// kinds of damage: random bytes; LCM short messages ("LC02") on the frame
// channel with random, truncated or bit-flipped rgbd_frame_t payloads; and
// fragments ("LC03") with random message sizes (0 .. 2^32-1), offsets,
// fragment numbers and counts, including a first fragment that announces a
// large message and never completes; and the pair that kills a liblcm 1.3.1
// subscriber (a first fragment naming the channel, then one whose offset
// wraps liblcm's 32-bit bounds check). Only for private network namespaces
// (scripts/soak.sh --flood): it refuses groups outside 239.0.0.0/8 and ttl is 0.
// Prints how many datagrams of each kind went out.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <climits>
#include <cstdint>
#include <cstring>
#include <iostream>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "findmug/common/numbers.hpp"
#include "findmug/io/lcm_codec.hpp"

namespace {

void put32(std::vector<std::uint8_t>& b, std::uint32_t v) {
  for (int k = 3; k >= 0; --k) b.push_back(static_cast<std::uint8_t>(v >> (8 * k)));
}
void put16(std::vector<std::uint8_t>& b, std::uint16_t v) {
  b.push_back(static_cast<std::uint8_t>(v >> 8));
  b.push_back(static_cast<std::uint8_t>(v));
}

[[noreturn]] void usage(const std::string& why) {
  std::cerr << "findmug-lcm-flood: " << why << " (see tests/soak/lcm_flood.cpp)\n";
  std::exit(2);
}

}  // namespace

int main(int argc, char** argv) {
  std::string group = "239.255.76.67", channel = "FINDMUG_RGBD";
  int port = 7667, sockets_n = 8;
  long long count = 1000000;
  double rate = 0;
  unsigned seed = 1;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string f = argv[i], v = argv[i + 1];
    const auto integer = [&f, &v](long long lo, long long hi) {
      const auto x = findmug::parseInteger(v);
      if (!x || *x < lo || *x > hi) usage(f + ": bad value '" + v + "'");
      return *x;
    };
    if (f == "--group") group = v;
    else if (f == "--port") port = static_cast<int>(integer(1, 65535));
    else if (f == "--count") count = integer(0, LLONG_MAX);
    else if (f == "--seed") seed = static_cast<unsigned>(integer(0, UINT_MAX));
    else if (f == "--channel") channel = v;
    else if (f == "--sockets") sockets_n = static_cast<int>(integer(1, 1024));
    else if (f == "--rate") {
      const auto x = findmug::parseNumber(v);
      if (!x || *x < 0) usage(f + ": bad value '" + v + "'");
      rate = *x;
    }
    else usage("unknown flag " + f);
  }
  if (argc % 2 == 0) usage("flags come in pairs");
  in_addr addr{};
  if (inet_pton(AF_INET, group.c_str(), &addr) != 1 || (ntohl(addr.s_addr) >> 24) != 239) {
    usage("--group must be an administratively scoped multicast address (239.x.x.x)");
  }
  sockaddr_in dest{};
  dest.sin_family = AF_INET;
  dest.sin_port = htons(static_cast<std::uint16_t>(port));
  dest.sin_addr = addr;
  std::vector<int> socks;
  for (int s = 0; s < sockets_n; ++s) {
    const int fd = socket(AF_INET, SOCK_DGRAM, 0);
    if (fd < 0) usage("socket() failed");
    unsigned char ttl = 0;
    setsockopt(fd, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof ttl);
    socks.push_back(fd);
  }

  // A small valid frame to truncate and flip.
  findmug::RgbdFrame frame;
  frame.width = 16;
  frame.height = 12;
  frame.depth_mm.assign(16 * 12, 1500);
  frame.rgb.assign(16 * 12, findmug::Rgb8{10, 20, 30});
  frame.utime = 1;
  const auto valid = findmug::io::encodeMessage(findmug::io::encodeRgbdFrame(frame));

  std::mt19937_64 rng(seed);
  auto u32 = [&rng] { return static_cast<std::uint32_t>(rng()); };
  std::array<long long, 6> sent{};
  const char* names[] = {"random", "short-truncated", "short-flipped", "fragment-random",
                         "fragment-huge-never-completes", "liblcm-offset-wrap-pairs"};
  const auto start = std::chrono::steady_clock::now();
  std::uint32_t seqno = 0;
  for (long long n = 0; n < count; ++n) {
    std::vector<std::uint8_t> d;
    const int kind = static_cast<int>(n % 6);
    switch (kind) {
      case 0: {
        const std::size_t len = u32() % 1500;
        for (std::size_t i = 0; i < len; ++i) d.push_back(static_cast<std::uint8_t>(rng()));
        if (len >= 4 && (n / 5) % 2 == 0) {  // half of them with a real magic
          const std::uint32_t magic = (n / 10) % 2 ? 0x4c433032 : 0x4c433033;
          for (int k = 0; k < 4; ++k) d[k] = static_cast<std::uint8_t>(magic >> (24 - 8 * k));
        }
        break;
      }
      case 1:
      case 2: {
        put32(d, 0x4c433032);
        put32(d, seqno++);
        d.insert(d.end(), channel.begin(), channel.end());
        d.push_back(0);
        std::vector<std::uint8_t> payload = valid;
        if (kind == 1) {
          payload.resize(u32() % payload.size());
        } else {
          for (int f = 0; f < 1 + static_cast<int>(u32() % 8); ++f) {
            payload[u32() % payload.size()] ^= static_cast<std::uint8_t>(1u << (u32() % 8));
          }
        }
        d.insert(d.end(), payload.begin(), payload.end());
        break;
      }
      case 3:
      case 4: {
        put32(d, 0x4c433033);
        put32(d, kind == 4 ? seqno++ : u32());
        const std::uint32_t sizes[] = {0u, 1u, u32(), 0xFFFFFFFFu, 0x7FFFFFFFu, (1u << 28) - 1,
                                       1u << 28};
        put32(d, kind == 4 ? (1u << 28) - 1 : sizes[u32() % 7]);  // message size
        put32(d, kind == 4 ? 0 : u32() % 70000);                   // fragment offset
        put16(d, kind == 4 ? 0 : static_cast<std::uint16_t>(u32()));  // fragment number
        put16(d, kind == 4 ? 4096 : static_cast<std::uint16_t>(u32()));  // fragments in message
        if (kind == 4 || u32() % 2) {
          d.insert(d.end(), channel.begin(), channel.end());
          d.push_back(0);
        }
        const std::size_t len = u32() % 1400;
        for (std::size_t i = 0; i < len; ++i) d.push_back(static_cast<std::uint8_t>(rng()));
        break;
      }
    }
    const int fd = socks[static_cast<std::size_t>(n) % socks.size()];
    if (kind == 5) {
      // Two datagrams from one port: a first fragment of a 100 kB message on
      // the channel (sent here), then fragment 1 at offset 0xFFFFFF00 (0x200
      // bytes, sent below with the other kinds).
      const std::uint32_t seq = seqno++;
      for (int part = 0; part < 2; ++part) {
        d.clear();
        put32(d, 0x4c433033);
        put32(d, seq);
        put32(d, 100000);
        put32(d, part == 0 ? 0 : 0xFFFFFF00u);
        put16(d, static_cast<std::uint16_t>(part));
        put16(d, 100);
        if (part == 0) {
          d.insert(d.end(), channel.begin(), channel.end());
          d.push_back(0);
        }
        d.insert(d.end(), part == 0 ? 100 : 0x200, static_cast<std::uint8_t>('x'));
        if (part == 0) {
          (void)sendto(fd, d.data(), d.size(), 0, reinterpret_cast<sockaddr*>(&dest), sizeof dest);
        }
      }
    }
    // ENOBUFS etc. just means the kernel dropped it: that is fine for a flood.
    (void)sendto(fd, d.data(), d.size(), 0, reinterpret_cast<sockaddr*>(&dest), sizeof dest);
    ++sent[static_cast<std::size_t>(kind)];
    if (rate > 0) {
      std::this_thread::sleep_until(start + std::chrono::duration<double>((n + 1) / rate));
    }
  }
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (std::size_t k = 0; k < sent.size(); ++k) std::cout << names[k] << " " << sent[k] << "\n";
  std::cout << "total " << count << " datagrams in " << s << " s\n";
  for (int fd : socks) close(fd);
  return 0;
}
