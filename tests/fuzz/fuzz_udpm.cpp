// Fuzz target udpm: a sequence of UDP datagrams -> UdpmReassembler (the receive
// side of findmug's udpm listeners, io/udpm.hpp). Input layout (what
// make_seeds.cpp writes): records of [u8 sender][u16 big-endian length][bytes],
// the last record taking what is left. Besides the sanitizers, the target checks
// the reassembler's own bounds after every datagram and that a delivered message
// has the size its header announced.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "findmug/io/udpm.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using findmug::io::UdpmReassembler;
  UdpmReassembler r([](const std::string& c) { return c == "FINDMUG_RGBD" || c == "FUZZ"; });
  std::size_t at = 0;
  std::int64_t now = 0;
  while (at < size) {
    const std::uint8_t sender = data[at++];
    std::size_t len = size - at;
    if (at + 2 <= size) {
      len = (std::size_t{data[at]} << 8) | data[at + 1];
      at += 2;
      len = std::min(len, size - at);
    } else {
      len = size - at;
    }
    now += 1000;
    const auto m = r.feed(sender, data + at, len, now);
    at += len;
    if (m && m->size > UdpmReassembler::kMaxMessageBytes) std::abort();
    if (r.inFlightBytes() > UdpmReassembler::kMaxInFlightBytes) std::abort();
    if (r.inFlightMessages() > UdpmReassembler::kMaxInFlightMessages) std::abort();
  }
  r.expire(now + UdpmReassembler::kStaleAfterUs + 1);
  if (r.inFlightBytes() != 0) std::abort();
  return 0;
}
