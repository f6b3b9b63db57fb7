// findmug/io/udpm.hpp — LCM's UDP multicast transport, received by findmug itself.
//
// Why not liblcm's receiver: Debian's liblcm 1.3.1 checks a fragment with
// `offset + size > message_size` in 32-bit arithmetic. A fragment whose offset
// is near 2^32 wraps that sum and is copied 4 GB past the message buffer:
// two datagrams from anyone on the multicast group (a first fragment naming a
// subscribed channel, then one with offset 0xFFFFFF00) kill every liblcm
// 1.3.1 subscriber with SIGSEGV (BENCHMARKS.md, Reliability). It also
// reserves up to 256 MB per sender for a message that never completes, and a
// repeated fragment counts as a new one, so a duplicated datagram completes a
// message with a hole in it. So findmug's listeners on udpm:// URLs receive
// with the code here; publishing still goes through liblcm (its sender is not
// exposed to outside bytes), and the wire format is LCM's own, so lcm-spy,
// lcm-logger and other LCM programs interoperate unchanged.
//
//   UdpmUrl          "udpm://GROUP:PORT?ttl=N&recv_buf_size=N&transmit_only=B",
//                    parsed with errors that name the option.
//   UdpmReassembler  datagrams in, whole messages out; no sockets, so tests and
//                    the fuzz target drive it directly. Every header field is
//                    checked before it is used; each rejected datagram is counted
//                    by reason. Bounds: a message at most kMaxMessageBytes, at most
//                    kMaxInFlightBytes held in unfinished messages (the oldest is
//                    evicted), an unfinished message is dropped after kStaleAfter
//                    without a new fragment.
//   UdpmBus          a Bus: its own socket joined to the group (receive side,
//                    owner thread), liblcm for publish().
//
// Wire format (LCM "udpm", all integers big-endian):
//   short message: u32 magic "LC02", u32 seqno, channel NUL, payload
//   fragment:      u32 magic "LC03", u32 seqno, u32 message size, u32 offset,
//                  u16 fragment number, u16 fragment count, then (fragment 0
//                  only) channel NUL, then payload bytes
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "findmug/io/bus.hpp"

namespace findmug::io {

struct UdpmUrl {
  std::string group = "239.255.76.67";
  int port = 7667;
  int ttl = 0;
  int recv_buf_size = 0;  // 0: the kernel's default
  bool transmit_only = false;
};

// True for "udpm://..." and for "" when the default URL (LCM_DEFAULT_URL, else
// LCM's built-in udpm://239.255.76.67:7667?ttl=0) is udpm.
bool isUdpmUrl(const std::string& url);
// The URL that "" stands for (LCM_DEFAULT_URL or LCM's built-in default).
std::string resolveLcmUrl(const std::string& url);
// Throws findmug::Error naming `what`, the URL and the bad part.
UdpmUrl parseUdpmUrl(const std::string& url, const std::string& what);

// Why a datagram was refused (counts in UdpmReassembler::Stats::rejected).
enum class UdpmReject : int {
  TooShort,          // shorter than its header
  BadMagic,          // neither "LC02" nor "LC03"
  BadChannel,        // no NUL within the datagram, empty, or longer than 63 bytes
  MessageTooBig,     // announced size over kMaxMessageBytes
  BadFragmentCount,  // fragment count 0, number >= count, or more fragments than bytes
  FragmentOutside,   // offset + size beyond the announced message (no wrap-around)
  Inconsistent,      // disagrees with earlier fragments of the same message
  Duplicate,         // a fragment already received
  Count_
};
const char* udpmRejectName(UdpmReject why);

class UdpmReassembler {
 public:
  static constexpr std::uint32_t kMaxMessageBytes = 32u << 20;   // a raw 1280x1024 RGB-D frame is 6.5 MB
  static constexpr std::size_t kMaxInFlightBytes = 96u << 20;    // unfinished messages, all senders
  static constexpr std::size_t kMaxInFlightMessages = 64;
  static constexpr std::int64_t kStaleAfterUs = 2'000'000;       // an unfinished message with no fragment for 2 s
  static constexpr std::size_t kMaxChannelBytes = 63;            // LCM_MAX_CHANNEL_NAME_LENGTH

  struct Message {
    std::string channel;
    std::unique_ptr<std::uint8_t[]> bytes;  // every byte written by a datagram
    std::size_t size = 0;
    std::int64_t recv_utime = 0;  // when its first datagram arrived
  };
  struct Stats {
    std::uint64_t datagrams = 0;
    std::uint64_t rejected[static_cast<int>(UdpmReject::Count_)] = {};
    std::uint64_t delivered = 0;
    std::uint64_t ignored = 0;     // whole messages on channels nobody here listens to
    std::uint64_t incomplete = 0;  // unfinished messages dropped (stale, evicted, superseded)
    std::uint64_t rejectedTotal() const;
  };

  // `wanted(channel)`: is anybody listening? Messages on other channels are
  // skipped as early as possible (ignored, not rejected: a group carries
  // everybody's channels).
  explicit UdpmReassembler(std::function<bool(const std::string&)> wanted);

  // One datagram from `sender` (address and port; one numbering per sender).
  // Returns the message it completes, if any. `reason` (optional) gets the
  // reject reason when the datagram was refused.
  std::optional<Message> feed(std::uint64_t sender, const std::uint8_t* data, std::size_t size,
                              std::int64_t now_utime, std::optional<UdpmReject>* reason = nullptr);
  // Drops unfinished messages older than kStaleAfterUs.
  void expire(std::int64_t now_utime);

  const Stats& stats() const { return stats_; }
  std::size_t inFlightBytes() const { return in_flight_bytes_; }
  std::size_t inFlightMessages() const { return partial_.size(); }

 private:
  struct Partial {
    std::string channel;  // empty until fragment 0 arrives
    std::uint32_t size = 0;
    std::uint16_t count = 0;
    std::uint16_t received = 0;
    std::uint64_t bytes_received = 0;
    std::vector<bool> have;                                  // by fragment number
    std::vector<std::pair<std::uint32_t, std::uint32_t>> ranges;  // offset, size received
    // Not zero-filled (a hostile first fragment must not cost a 32 MB memset):
    // delivered only when the received ranges tile it exactly.
    std::unique_ptr<std::uint8_t[]> bytes;
    std::int64_t first_utime = 0, last_utime = 0;
  };
  using Key = std::pair<std::uint64_t, std::uint32_t>;  // sender, seqno

  std::optional<Message> feedFragment(std::uint64_t sender, const std::uint8_t* data,
                                      std::size_t size, std::int64_t now_utime,
                                      std::optional<UdpmReject>* reason);
  std::optional<Message> reject(UdpmReject why, std::optional<UdpmReject>* reason);
  void drop(std::map<Key, Partial>::iterator it, bool count_incomplete);
  void makeRoom(std::size_t bytes);

  std::function<bool(const std::string&)> wanted_;
  std::map<Key, Partial> partial_;
  std::set<Key> ignored_;  // messages whose fragment 0 named an unwanted channel (bounded)
  std::size_t in_flight_bytes_ = 0;
  Stats stats_;
};

// A Bus on a udpm:// URL whose receive side is UdpmReassembler over findmug's
// own socket. Channel names match exactly (see bus.hpp). Rejected datagrams are
// logged (the first ten, then every thousandth) with the sender and the reason.
class UdpmBus final : public Bus {
 public:
  // Throws findmug::Error naming `what` when the URL is bad or the socket
  // cannot join the group.
  UdpmBus(const std::string& url, const std::string& what);
  ~UdpmBus() override;
  UdpmBus(const UdpmBus&) = delete;
  UdpmBus& operator=(const UdpmBus&) = delete;

  bool publish(const std::string& channel, const void* data, std::size_t size) override;
  void subscribeTimed(const std::string& channel, TimedHandler handler) override;
  HandleResult handle(std::chrono::milliseconds timeout) override;
  std::string describe() const override { return url_; }
  bool replaysLog() const override { return false; }

  // Owner thread only (the reassembler is not locked).
  const UdpmReassembler::Stats& stats() const { return reassembler_.stats(); }

 private:
  void openSocket(const UdpmUrl& u, const std::string& what);
  std::string url_;
  std::string what_;  // who listens (the setting the URL came from), for log lines
  int fd_ = -1;
  std::unique_ptr<LcmBus> sender_;  // publishes; created on first publish()
  std::mutex sender_mutex_;
  std::multimap<std::string, TimedHandler> handlers_;
  UdpmReassembler reassembler_;
  std::vector<std::uint8_t> datagram_;
  std::int64_t last_expire_utime_ = 0;
};

// The bus a listener should use for `url`: a UdpmBus for udpm (the default
// URL included), an LcmBus for anything else (memq://, file://, ...).
std::unique_ptr<Bus> openBus(const std::string& url, const std::string& what);
// The same with the program's channel suffix applied by the bus (withChannelSuffix):
// the program publishes and subscribes by base name.
std::shared_ptr<Bus> openBus(const std::string& url, const std::string& what,
                             const std::string& channel_suffix);

}  // namespace findmug::io
