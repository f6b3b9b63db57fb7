// findmug-lossy-relay — a lossy, reordering network link for LCM udpm traffic,
// in user space (this kernel has no netem qdisc).
//
//   findmug-lossy-relay --in 239.255.76.67:7667 --out 239.255.76.68:7668
//       [--loss 0.001] [--reorder 0.01] [--reorder-depth 3] [--duplicate 0]
//       [--seed 1] [--stats FILE]
//
// Every datagram sent to the --in multicast group (whole LCM messages and the
// fragments of big ones alike) is forwarded to the --out group, except that
// each is, independently: lost with probability --loss; held back and sent
// after the next --reorder-depth datagrams with probability --reorder; sent
// twice with probability --duplicate. A publisher on the --in group and a
// subscriber on the --out group then talk over a link that loses, reorders
// and duplicates packets. Runs until SIGTERM/SIGINT; then sends what it holds
// and writes its counts to --stats (key=value lines) and stdout.
//
// Network rule: run it only inside a private network namespace (soak.sh
// makes one); it sends with TTL 0 on the loopback interface.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <deque>
#include <fstream>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace {

volatile std::sig_atomic_t g_stop = 0;
void onSignal(int) { g_stop = 1; }

struct Endpoint {
  in_addr group{};
  std::uint16_t port = 0;
};

Endpoint parseEndpoint(const std::string& text, const std::string& flag) {
  const auto colon = text.rfind(':');
  Endpoint e;
  if (colon == std::string::npos || inet_pton(AF_INET, text.substr(0, colon).c_str(), &e.group) != 1) {
    throw CLI::ValidationError(flag, "'" + text + "' is not GROUP:PORT (e.g. 239.255.76.67:7667)");
  }
  const std::string port = text.substr(colon + 1);
  char* end = nullptr;
  const long p = std::strtol(port.c_str(), &end, 10);
  if (port.empty() || *end != '\0' || p < 1 || p > 65535) {
    throw CLI::ValidationError(flag, "port '" + port + "' is not 1..65535");
  }
  if ((ntohl(e.group.s_addr) >> 28) != 0xE) {
    throw CLI::ValidationError(flag, text.substr(0, colon) + " is not a multicast group");
  }
  e.port = static_cast<std::uint16_t>(p);
  return e;
}

[[noreturn]] void fail(const std::string& what) {
  std::cerr << "findmug-lossy-relay: " << what << ": " << std::strerror(errno) << "\n";
  std::exit(2);
}

int openReceiver(const Endpoint& in) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) fail("socket");
  const int one = 1;
  ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  const int rcvbuf = 8 << 20;  // a whole burst of frame fragments
  ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(in.port);
  addr.sin_addr.s_addr = htonl(INADDR_ANY);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) fail("bind");
  ip_mreq mreq{};
  mreq.imr_multiaddr = in.group;
  mreq.imr_interface.s_addr = htonl(INADDR_ANY);
  if (::setsockopt(fd, IPPROTO_IP, IP_ADD_MEMBERSHIP, &mreq, sizeof mreq) != 0) {
    fail("joining the --in group");
  }
  return fd;
}

int openSender() {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) fail("socket");
  const unsigned char ttl = 0;  // never beyond this host
  ::setsockopt(fd, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof ttl);
  const unsigned char loop = 1;
  ::setsockopt(fd, IPPROTO_IP, IP_MULTICAST_LOOP, &loop, sizeof loop);
  const int sndbuf = 8 << 20;
  ::setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &sndbuf, sizeof sndbuf);
  return fd;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"A lossy, reordering link between two udpm multicast groups (user-space netem)."};
  std::string in_text, out_text, stats_path;
  double loss = 0.0, reorder = 0.0, duplicate = 0.0;
  int reorder_depth = 3;
  unsigned seed = 1;
  app.add_option("--in", in_text, "multicast GROUP:PORT the publisher sends to")->required();
  app.add_option("--out", out_text, "multicast GROUP:PORT the subscribers listen on")->required();
  app.add_option("--loss", loss, "probability that a datagram is lost")->check(CLI::Range(0.0, 1.0));
  app.add_option("--reorder", reorder, "probability that a datagram is held back")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--reorder-depth", reorder_depth, "datagrams that overtake a held-back one")
      ->check(CLI::Range(1, 1000));
  app.add_option("--duplicate", duplicate, "probability that a datagram is sent twice")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--seed", seed, "random seed (same seed, same decisions)");
  app.add_option("--stats", stats_path, "write the counts here at exit");
  Endpoint in, out;
  try {
    app.parse(argc, argv);
    in = parseEndpoint(in_text, "--in");
    out = parseEndpoint(out_text, "--out");
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  if (in.group.s_addr == out.group.s_addr && in.port == out.port) {
    std::cerr << "findmug-lossy-relay: --in and --out are the same group: it would relay to itself\n";
    return 2;
  }

  std::signal(SIGTERM, onSignal);
  std::signal(SIGINT, onSignal);
  const int rx = openReceiver(in);
  const int tx = openSender();
  sockaddr_in dest{};
  dest.sin_family = AF_INET;
  dest.sin_port = htons(out.port);
  dest.sin_addr = out.group;

  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  struct Held {
    std::vector<std::uint8_t> bytes;
    int overtakers_left = 0;
  };
  std::deque<Held> held;
  std::uint64_t received = 0, forwarded = 0, lost = 0, reordered = 0, duplicated = 0,
                send_errors = 0, bytes_in = 0;
  std::size_t largest = 0;
  auto send = [&](const std::uint8_t* data, std::size_t size) {
    if (::sendto(tx, data, size, 0, reinterpret_cast<sockaddr*>(&dest), sizeof dest) < 0) {
      ++send_errors;
    } else {
      ++forwarded;
    }
  };

  std::vector<std::uint8_t> buffer(65536);
  while (!g_stop) {
    pollfd pfd{rx, POLLIN, 0};
    const int ready = ::poll(&pfd, 1, 100);
    if (ready < 0) {
      if (errno == EINTR) continue;
      fail("poll");
    }
    if (ready == 0) continue;
    const ssize_t n = ::recv(rx, buffer.data(), buffer.size(), 0);
    if (n < 0) {
      if (errno == EINTR || errno == EAGAIN) continue;
      fail("recv");
    }
    ++received;
    bytes_in += static_cast<std::uint64_t>(n);
    largest = std::max(largest, static_cast<std::size_t>(n));
    const auto size = static_cast<std::size_t>(n);
    // The decisions are drawn in a fixed order, so that a seed replays a run.
    const bool drop = u(rng) < loss;
    const bool hold = u(rng) < reorder;
    const bool twice = u(rng) < duplicate;
    if (drop) {
      ++lost;
    } else if (hold) {
      ++reordered;
      held.push_back({std::vector<std::uint8_t>(buffer.begin(), buffer.begin() + n), reorder_depth});
      if (twice) {
        ++duplicated;
        send(buffer.data(), size);
      }
      continue;  // a held datagram is not an overtaker of the others
    } else {
      send(buffer.data(), size);
      if (twice) {
        ++duplicated;
        send(buffer.data(), size);
      }
    }
    for (auto& h : held) --h.overtakers_left;
    while (!held.empty() && held.front().overtakers_left <= 0) {
      send(held.front().bytes.data(), held.front().bytes.size());
      held.pop_front();
    }
  }
  for (const auto& h : held) send(h.bytes.data(), h.bytes.size());

  const std::string counts =
      "received=" + std::to_string(received) + "\nforwarded=" + std::to_string(forwarded) +
      "\nlost=" + std::to_string(lost) + "\nreordered=" + std::to_string(reordered) +
      "\nduplicated=" + std::to_string(duplicated) + "\nsend_errors=" + std::to_string(send_errors) +
      "\nbytes_in=" + std::to_string(bytes_in) + "\nlargest_datagram=" + std::to_string(largest) +
      "\n";
  std::cout << counts;
  if (!stats_path.empty()) std::ofstream(stats_path) << counts;
  ::close(rx);
  ::close(tx);
  return send_errors == 0 ? 0 : 1;
}
