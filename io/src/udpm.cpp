// LCM's udpm transport received by findmug (see udpm.hpp for why).
#include "findmug/io/udpm.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>

#include "findmug/common/error.hpp"
#include "findmug/common/numbers.hpp"
#include "findmug/io/frame_source.hpp"

namespace findmug::io {

namespace {

constexpr std::uint32_t kMagicShort = 0x4c433032;  // "LC02"
constexpr std::uint32_t kMagicLong = 0x4c433033;   // "LC03"
constexpr std::size_t kShortHeader = 8;
constexpr std::size_t kLongHeader = 20;
constexpr const char* kLcmBuiltInUrl = "udpm://239.255.76.67:7667?ttl=0";

std::uint32_t be32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}
std::uint16_t be16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>((p[0] << 8) | p[1]);
}

// The channel name at `p`, NUL-terminated within `n` bytes, 1..63 characters.
std::optional<std::string> channelAt(const std::uint8_t* p, std::size_t n) {
  const auto* end = static_cast<const std::uint8_t*>(std::memchr(p, 0, n));
  if (!end) return std::nullopt;
  const auto len = static_cast<std::size_t>(end - p);
  if (len == 0 || len > UdpmReassembler::kMaxChannelBytes) return std::nullopt;
  return std::string(reinterpret_cast<const char*>(p), len);
}

std::string senderName(std::uint64_t sender) {
  in_addr a{};
  a.s_addr = htonl(static_cast<std::uint32_t>(sender >> 16));
  char text[INET_ADDRSTRLEN] = "?";
  inet_ntop(AF_INET, &a, text, sizeof text);
  return std::string(text) + ":" + std::to_string(sender & 0xFFFF);
}

}  // namespace

// ---- URLs -------------------------------------------------------------------------

std::string resolveLcmUrl(const std::string& url) {
  if (!url.empty()) return url;
  const char* env = std::getenv("LCM_DEFAULT_URL");
  return env && *env ? std::string(env) : std::string(kLcmBuiltInUrl);
}

bool isUdpmUrl(const std::string& url) { return resolveLcmUrl(url).rfind("udpm://", 0) == 0; }

UdpmUrl parseUdpmUrl(const std::string& url_in, const std::string& what) {
  const std::string url = resolveLcmUrl(url_in);
  const auto bad = [&](const std::string& why) {
    return Error(what + ": LCM URL '" + url + "': " + why);
  };
  if (url.rfind("udpm://", 0) != 0) throw bad("not a udpm:// URL");
  UdpmUrl u;
  std::string rest = url.substr(7);
  std::string query;
  if (const auto q = rest.find('?'); q != std::string::npos) {
    query = rest.substr(q + 1);
    rest.resize(q);
  }
  if (!rest.empty()) {
    std::string port_text;
    if (const auto c = rest.find(':'); c != std::string::npos) {
      port_text = rest.substr(c + 1);
      rest.resize(c);
    }
    if (!rest.empty()) u.group = rest;
    if (!port_text.empty()) {
      const auto p = parseInteger(port_text);
      if (!p || *p < 1 || *p > 65535) throw bad("port '" + port_text + "' is not 1..65535");
      u.port = static_cast<int>(*p);
    }
  }
  in_addr group{};
  if (inet_pton(AF_INET, u.group.c_str(), &group) != 1) {
    throw bad("group '" + u.group + "' is not an IPv4 address");
  }
  if (!IN_MULTICAST(ntohl(group.s_addr))) {
    throw bad("group '" + u.group + "' is not a multicast address (224.0.0.0/4)");
  }
  std::size_t start = 0;
  while (start < query.size()) {
    auto amp = query.find('&', start);
    if (amp == std::string::npos) amp = query.size();
    const std::string item = query.substr(start, amp - start);
    start = amp + 1;
    if (item.empty()) continue;
    const auto eq = item.find('=');
    if (eq == std::string::npos) throw bad("option '" + item + "' has no '='");
    const std::string key = item.substr(0, eq), value = item.substr(eq + 1);
    if (key == "ttl") {
      const auto t = parseInteger(value);
      if (!t || *t < 0 || *t > 255) throw bad("ttl '" + value + "' is not 0..255");
      u.ttl = static_cast<int>(*t);
    } else if (key == "recv_buf_size") {
      const auto r = parseInteger(value);
      if (!r || *r < 0 || *r > (1 << 30)) throw bad("recv_buf_size '" + value + "' is not 0..2^30");
      u.recv_buf_size = static_cast<int>(*r);
    } else if (key == "transmit_only") {
      if (value != "true" && value != "false") throw bad("transmit_only '" + value + "' is not true/false");
      u.transmit_only = value == "true";
    } else {
      throw bad("unknown option '" + key + "' (udpm takes ttl, recv_buf_size, transmit_only)");
    }
  }
  return u;
}

// ---- UdpmReassembler ----------------------------------------------------------------

const char* udpmRejectName(UdpmReject why) {
  switch (why) {
    case UdpmReject::TooShort: return "shorter than its header";
    case UdpmReject::BadMagic: return "not an LCM datagram (magic)";
    case UdpmReject::BadChannel: return "bad channel name (no NUL, empty or over 63 bytes)";
    case UdpmReject::MessageTooBig: return "announced message size over the limit";
    case UdpmReject::BadFragmentCount: return "bad fragment number or count";
    case UdpmReject::FragmentOutside: return "fragment lies outside its message";
    case UdpmReject::Inconsistent: return "fragment disagrees with earlier fragments of its message";
    case UdpmReject::Duplicate: return "fragment received twice";
    case UdpmReject::Count_: break;
  }
  return "?";
}

std::uint64_t UdpmReassembler::Stats::rejectedTotal() const {
  std::uint64_t n = 0;
  for (const auto r : rejected) n += r;
  return n;
}

UdpmReassembler::UdpmReassembler(std::function<bool(const std::string&)> wanted)
    : wanted_(std::move(wanted)) {}

std::optional<UdpmReassembler::Message> UdpmReassembler::reject(UdpmReject why,
                                                               std::optional<UdpmReject>* reason) {
  ++stats_.rejected[static_cast<int>(why)];
  if (reason) *reason = why;
  return std::nullopt;
}

std::optional<UdpmReassembler::Message> UdpmReassembler::feed(std::uint64_t sender,
                                                             const std::uint8_t* data,
                                                             std::size_t size,
                                                             std::int64_t now_utime,
                                                             std::optional<UdpmReject>* reason) {
  ++stats_.datagrams;
  if (reason) reason->reset();
  if (size < kShortHeader) return reject(UdpmReject::TooShort, reason);
  const std::uint32_t magic = be32(data);
  if (magic == kMagicLong) return feedFragment(sender, data, size, now_utime, reason);
  if (magic != kMagicShort) return reject(UdpmReject::BadMagic, reason);
  auto channel = channelAt(data + kShortHeader, size - kShortHeader);
  if (!channel) return reject(UdpmReject::BadChannel, reason);
  if (!wanted_(*channel)) {
    ++stats_.ignored;
    return std::nullopt;
  }
  const std::size_t start = kShortHeader + channel->size() + 1;
  Message m;
  m.channel = std::move(*channel);
  m.size = size - start;
  m.bytes.reset(new std::uint8_t[std::max<std::size_t>(m.size, 1)]);
  if (m.size > 0) std::memcpy(m.bytes.get(), data + start, m.size);
  m.recv_utime = now_utime;
  ++stats_.delivered;
  return m;
}

std::optional<UdpmReassembler::Message> UdpmReassembler::feedFragment(
    std::uint64_t sender, const std::uint8_t* data, std::size_t size, std::int64_t now_utime,
    std::optional<UdpmReject>* reason) {
  if (size < kLongHeader) return reject(UdpmReject::TooShort, reason);
  const std::uint32_t seqno = be32(data + 4);
  const std::uint32_t msg_size = be32(data + 8);
  const std::uint32_t offset = be32(data + 12);
  const std::uint16_t number = be16(data + 16);
  const std::uint16_t count = be16(data + 18);
  if (msg_size > kMaxMessageBytes) return reject(UdpmReject::MessageTooBig, reason);
  // Every fragment but the channel-only first one carries at least one byte.
  if (count == 0 || number >= count || count > std::uint64_t{msg_size} + 1) {
    return reject(UdpmReject::BadFragmentCount, reason);
  }
  const std::uint8_t* payload = data + kLongHeader;
  std::size_t payload_size = size - kLongHeader;
  std::string channel;
  if (number == 0) {
    auto c = channelAt(payload, payload_size);
    if (!c) return reject(UdpmReject::BadChannel, reason);
    channel = std::move(*c);
    payload += channel.size() + 1;
    payload_size -= channel.size() + 1;
  }
  // In 64 bits: offset + size cannot wrap (liblcm 1.3.1's check can).
  if (std::uint64_t{offset} + payload_size > msg_size) {
    return reject(UdpmReject::FragmentOutside, reason);
  }
  const Key key{sender, seqno};
  if (ignored_.count(key)) {
    return std::nullopt;  // the rest of a message on a channel nobody here wants
  }
  if (number == 0 && !wanted_(channel)) {
    if (auto it = partial_.find(key); it != partial_.end()) drop(it, false);
    if (ignored_.size() >= 256) ignored_.erase(ignored_.begin());
    ignored_.insert(key);
    ++stats_.ignored;
    return std::nullopt;
  }
  auto it = partial_.find(key);
  if (it == partial_.end()) {
    // A new message from this sender: its older unfinished ones will not
    // complete any more in the common case (one publisher, in order); they
    // are left to expire so that a reordered link still completes them.
    makeRoom(msg_size);
    Partial p;
    p.size = msg_size;
    p.count = count;
    p.have.assign(count, false);
    p.bytes.reset(new std::uint8_t[std::max<std::uint32_t>(msg_size, 1)]);
    p.first_utime = now_utime;
    it = partial_.emplace(key, std::move(p)).first;
    in_flight_bytes_ += msg_size;
  } else if (it->second.size != msg_size || it->second.count != count) {
    return reject(UdpmReject::Inconsistent, reason);
  }
  Partial& p = it->second;
  if (p.have[number]) return reject(UdpmReject::Duplicate, reason);
  p.have[number] = true;
  ++p.received;
  p.bytes_received += payload_size;
  p.last_utime = now_utime;
  if (number == 0) p.channel = std::move(channel);
  if (payload_size > 0) {
    std::memcpy(p.bytes.get() + offset, payload, payload_size);
    p.ranges.emplace_back(offset, static_cast<std::uint32_t>(payload_size));
  }
  if (p.received < p.count) return std::nullopt;
  // All fragments are in: they must tile the message, no gap and no overlap
  // (else a forgery or a mix of two messages; nothing of it is delivered).
  std::sort(p.ranges.begin(), p.ranges.end());
  std::uint64_t covered = 0;
  for (const auto& [o, n] : p.ranges) {
    if (o != covered) break;
    covered += n;
  }
  if (covered != p.size || p.bytes_received != p.size) {
    drop(it, true);
    return reject(UdpmReject::Inconsistent, reason);
  }
  Message m;
  m.channel = std::move(p.channel);
  m.bytes = std::move(p.bytes);
  m.size = p.size;
  m.recv_utime = p.first_utime;
  drop(it, false);
  ++stats_.delivered;
  return m;
}

void UdpmReassembler::drop(std::map<Key, Partial>::iterator it, bool count_incomplete) {
  in_flight_bytes_ -= it->second.size;
  if (count_incomplete) ++stats_.incomplete;
  partial_.erase(it);
}

void UdpmReassembler::makeRoom(std::size_t bytes) {
  // Evict the unfinished messages that have waited longest until the new one fits.
  while (!partial_.empty() && (in_flight_bytes_ + bytes > kMaxInFlightBytes ||
                               partial_.size() >= kMaxInFlightMessages)) {
    auto oldest = partial_.begin();
    for (auto it = partial_.begin(); it != partial_.end(); ++it) {
      if (it->second.last_utime < oldest->second.last_utime) oldest = it;
    }
    drop(oldest, true);
  }
}

void UdpmReassembler::expire(std::int64_t now_utime) {
  for (auto it = partial_.begin(); it != partial_.end();) {
    auto next = std::next(it);
    if (now_utime - it->second.last_utime > kStaleAfterUs) drop(it, true);
    it = next;
  }
}

// ---- UdpmBus ------------------------------------------------------------------------

UdpmBus::UdpmBus(const std::string& url, const std::string& what)
    : url_(resolveLcmUrl(url)),
      what_(what),
      reassembler_([this](const std::string& channel) { return handlers_.count(channel) > 0; }),
      datagram_(65536) {
  const UdpmUrl u = parseUdpmUrl(url_, what);
  if (!u.transmit_only) openSocket(u, what);
}

UdpmBus::~UdpmBus() {
  if (fd_ >= 0) ::close(fd_);
}

void UdpmBus::openSocket(const UdpmUrl& u, const std::string& what) {
  const auto fail = [&](const std::string& step) {
    const int e = errno;
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    return Error(what + ": cannot listen on '" + url_ + "': " + step + ": " + std::strerror(e));
  };
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw fail("socket");
  const int one = 1;
  // Several programs on one host listen to the same group and port, as with liblcm.
  if (::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) < 0) throw fail("SO_REUSEADDR");
  if (u.recv_buf_size > 0 &&
      ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &u.recv_buf_size, sizeof u.recv_buf_size) < 0) {
    throw fail("SO_RCVBUF");
  }
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_ANY);
  addr.sin_port = htons(static_cast<std::uint16_t>(u.port));
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) < 0) throw fail("bind");
  ip_mreq mreq{};
  inet_pton(AF_INET, u.group.c_str(), &mreq.imr_multiaddr);
  mreq.imr_interface.s_addr = htonl(INADDR_ANY);
  if (::setsockopt(fd_, IPPROTO_IP, IP_ADD_MEMBERSHIP, &mreq, sizeof mreq) < 0) {
    throw fail("joining group " + u.group + " (is there a multicast route? see README)");
  }
}

bool UdpmBus::publish(const std::string& channel, const void* data, std::size_t size) {
  std::lock_guard lock(sender_mutex_);
  if (!sender_) {
    // liblcm only sends here: with no subscription it opens no receive socket.
    try {
      sender_ = std::make_unique<LcmBus>(url_, "udpm publisher");
    } catch (const Error& e) {
      spdlog::warn("{}: {}", url_, e.what());
      return false;
    }
  }
  return sender_->publish(channel, data, size);
}

void UdpmBus::subscribeTimed(const std::string& channel, TimedHandler handler) {
  handlers_.emplace(channel, std::move(handler));
}

HandleResult UdpmBus::handle(std::chrono::milliseconds timeout) {
  if (fd_ < 0) {
    // transmit_only: nothing will ever arrive.
    if (timeout.count() > 0) ::poll(nullptr, 0, static_cast<int>(timeout.count()));
    return HandleResult::Timeout;
  }
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    pollfd p{fd_, POLLIN, 0};
    const int ready = ::poll(&p, 1, static_cast<int>(std::max<std::int64_t>(0, left.count())));
    if (ready < 0) {
      if (errno == EINTR) return HandleResult::Timeout;
      spdlog::error("{}: poll failed: {}", url_, std::strerror(errno));
      return HandleResult::Failed;
    }
    const auto now = static_cast<std::int64_t>(hostUtimeNow());
    if (now - last_expire_utime_ > 100'000) {
      reassembler_.expire(now);
      last_expire_utime_ = now;
    }
    if (ready == 0) return HandleResult::Timeout;
    // Drain what is queued; dispatch the first message completed (as LCM
    // does, one message per handle()), the rest waits in the socket buffer.
    for (int budget = 0; budget < 4096; ++budget) {
      sockaddr_in from{};
      socklen_t from_len = sizeof from;
      const ssize_t n = ::recvfrom(fd_, datagram_.data(), datagram_.size(), MSG_TRUNC,
                                   reinterpret_cast<sockaddr*>(&from), &from_len);
      if (n < 0) {
        if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) break;
        spdlog::error("{}: receive failed: {}", url_, std::strerror(errno));
        return HandleResult::Failed;
      }
      const std::uint64_t sender =
          (std::uint64_t{ntohl(from.sin_addr.s_addr)} << 16) | ntohs(from.sin_port);
      std::optional<UdpmReject> why;
      // MSG_TRUNC: n is the datagram's real length; over 64 KiB cannot happen
      // on UDP, but a cut datagram is refused rather than half read.
      const auto size = static_cast<std::size_t>(n);
      std::optional<UdpmReassembler::Message> message;
      if (size > datagram_.size()) {
        why = UdpmReject::TooShort;
      } else {
        message = reassembler_.feed(sender, datagram_.data(), size, now, &why);
      }
      if (why) {
        const std::uint64_t total = reassembler_.stats().rejectedTotal();
        if (total <= 10 || total % 1000 == 0) {
          spdlog::warn("{} on {}: refused a datagram of {} bytes from {}: {} ({} refused so far)",
                       what_, url_, size, senderName(sender), udpmRejectName(*why), total);
        }
      }
      if (message) {
        const auto range = handlers_.equal_range(message->channel);
        for (auto h = range.first; h != range.second; ++h) {
          h->second(message->channel, message->bytes.get(), message->size,
                    message->recv_utime);
        }
        return HandleResult::Handled;
      }
    }
    if (std::chrono::steady_clock::now() >= deadline) return HandleResult::Timeout;
  }
}

std::unique_ptr<Bus> openBus(const std::string& url, const std::string& what) {
  if (isUdpmUrl(url)) return std::make_unique<UdpmBus>(url, what);
  return std::make_unique<LcmBus>(url, what);
}

std::shared_ptr<Bus> openBus(const std::string& url, const std::string& what,
                             const std::string& channel_suffix) {
  return withChannelSuffix(openBus(url, what), channel_suffix);
}

}  // namespace findmug::io
