#include "liveprobe/exchange/stream_server.h"

#include <arpa/inet.h>
#include <libwebsockets.h>
#include <linux/sockios.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <list>
#include <map>
#include <mutex>
#include <optional>
#include <thread>
#include <unordered_map>
#include <unordered_set>

#include "liveprobe/sh/error.h"

namespace lp {

namespace {

/// One client. lws allocates per-session memory as plain bytes: it holds a pointer to this.
struct Session {
  CoeffFormat format;
  std::uint64_t sent = 0;  ///< sequence number of the last frame sent (or skipped)
  bool resend = false;     ///< the newest frame again (the client changed its format)
  std::string refusal;     ///< set: closed at its first write, with this reason (1008)
  std::string rx;          ///< a message arriving in fragments
};

/// A client whose socket still holds more than this, unsent, gets no new message until it has
/// read it: the kernel's buffers never fill with stale frames (latest value, low latency).
constexpr int kMaxUnsentBytes = 16 * 1024;
struct SessionSlot {
  Session* s;
};

/// The longest query a client may send (?format=NAME needs a few dozen bytes).
constexpr int kMaxQuery = 256;
// The oldest pending connections looked at for a silent one to close when a limit is reached.
constexpr int kEvictLook = 16;

/// The format a WebSocket client asked for with ?format=NAME; nullopt when it asked for none.
/// Anything else in the query (another key, a repeated or empty format, an over-long query, a
/// broken %-escape) throws lp::Error with the reason, which closes the client with 1008.
std::optional<CoeffFormat> formatFromQuery(lws* wsi) {
  const int total = lws_hdr_total_length(wsi, WSI_TOKEN_HTTP_URI_ARGS);
  if (total <= 0) return std::nullopt;
  if (total > kMaxQuery)
    throw Error("query of " + std::to_string(total) + " bytes (at most " +
                std::to_string(kMaxQuery) + ")");
  std::optional<CoeffFormat> format;
  char buf[kMaxQuery + 1];
  for (int i = 0; lws_hdr_copy_fragment(wsi, buf, sizeof buf, WSI_TOKEN_HTTP_URI_ARGS, i) >= 0;
       ++i) {
    const std::string arg(buf);
    if (arg.find('%') != std::string::npos)
      throw Error("query argument '" + arg + "': a broken %-escape");
    if (arg.rfind("format=", 0) != 0)
      throw Error("query argument '" + arg + "': expected format=NAME");
    if (format) throw Error("format given twice in the query");
    format = parseCoeffFormat(arg.substr(7), "format", true);
  }
  return format;
}

}  // namespace

bool isLoopback(const std::string& host) {
  if (host == "localhost") return true;
  in_addr a{};
  if (inet_pton(AF_INET, host.c_str(), &a) != 1) return false;
  return (ntohl(a.s_addr) >> 24) == 127;
}

namespace {

/// Binds a socket to the address as the server will, and says in one line why it can't: an
/// address this machine does not have (EADDRNOTAVAIL), a port in use, a privileged port.
void checkBindable(const std::string& host, int port, const std::string& where) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw Error(where + ": cannot make a socket (" + std::strerror(errno) + ")");
  const int one = 1;
  ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);  // as lws sets it
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(std::uint16_t(port));
  inet_pton(AF_INET, host.c_str(), &a.sin_addr);
  const int rc = ::bind(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a);
  const int err = errno;
  ::close(fd);
  if (rc == 0) return;
  if (err == EADDRNOTAVAIL) throw Error(where + ": " + host + " is not an address of this machine");
  if (err == EADDRINUSE) throw Error(where + ": the port is in use");
  throw Error(where + ": cannot listen there (" + std::strerror(err) + ")");
}

}  // namespace

void parseServeAddress(const std::string& text, StreamServerOptions& o) {
  const auto colon = text.rfind(':');
  const std::string host = colon == std::string::npos ? "127.0.0.1" : text.substr(0, colon);
  const std::string port = colon == std::string::npos ? text : text.substr(colon + 1);
  char* end = nullptr;
  const long p = std::strtol(port.c_str(), &end, 10);
  if (port.empty() || *end != '\0' || p < 0 || p > 65535)
    throw Error(text + ": expected [ADDR:]PORT with PORT in 0..65535");
  in_addr a{};
  if (host != "localhost" && inet_pton(AF_INET, host.c_str(), &a) != 1)
    throw Error(text + ": " + host + " is not an IPv4 address or localhost");
  o.host = host == "localhost" ? "127.0.0.1" : host;
  o.port = int(p);
}

struct StreamServer::Impl {
  StreamServerOptions opt;
  lws_context* context = nullptr;
  lws_vhost* vhost = nullptr;
  std::thread thread;
  std::atomic<bool> stopping{false};
  std::atomic<int> boundPort{0};

  // The newest frame, handed over by publish() (capture's thread) under the mutex.
  mutable std::mutex mutex;
  ProcessedFrame latest;
  std::uint64_t latestSeq = 0;
  StreamStats stats;  // under the mutex

  // The newest frame's record per format, made once for every client that asks for it (the
  // service thread's own: no lock).
  struct Serialized {
    std::uint64_t seq = 0;
    std::string text;
  };
  std::map<std::string, Serialized> serialized;

  // Connections that have not yet sent a whole HTTP request or WebSocket upgrade, oldest first,
  // each with its peer's address (the service thread's own: no lock). Each has a deadline
  // (kHandshakeSeconds); over the per-address or the overall budget the oldest is closed, so a
  // new client is always heard.
  struct Pending {
    lws* wsi;
    std::string peer;
  };
  std::list<Pending> pending;
  std::unordered_map<lws*, std::list<Pending>::iterator> pendingAt;  // O(1) to forget one
  std::unordered_map<std::string, std::size_t> pendingPerPeer;       // O(1) to count a peer's
  void forget(std::list<Pending>::iterator it) {
    const auto n = pendingPerPeer.find(it->peer);
    if (--n->second == 0) pendingPerPeer.erase(n);
    pendingAt.erase(it->wsi);
    pending.erase(it);
  }
  // Every accepted connection that is not a client (pending, or being sent the page), oldest
  // first, and those of them already told to close. At maxPending of them a new one makes room
  // by closing the oldest whose peer has hung up (a flood's connect, GET, close), or is itself
  // closed as it is accepted, before it costs a round of the service loop: a flood of short
  // connections is turned away as fast as it comes and never fills the kernel's accept queue in
  // front of a real client.
  std::list<lws*> open;
  std::unordered_map<lws*, std::list<lws*>::iterator> openAt;
  std::unordered_set<lws*> dying;
  void opened(lws* wsi) { openAt[wsi] = open.insert(open.end(), wsi); }
  void notOpen(lws* wsi) {
    if (const auto at = openAt.find(wsi); at != openAt.end()) {
      open.erase(at->second);
      openAt.erase(at);
    }
    dying.erase(wsi);
  }
  void kill(lws* wsi) {
    lws_set_timeout(wsi, PENDING_TIMEOUT_USER_OK, LWS_TO_KILL_ASYNC);
    dying.insert(wsi);
    std::lock_guard lock(mutex);
    ++stats.evicted;
  }
  std::size_t pendingFrom(const std::string& peer) const {
    const auto n = pendingPerPeer.find(peer);
    return n == pendingPerPeer.end() ? 0 : n->second;
  }
  void admit(lws* wsi);
  // Whether a new connection (its descriptor, accepted, not yet adopted) is closed at once:
  // its peer has hung up, or full(). Counts the one turned away.
  bool turnAway(int fd);
  bool full();  // at the limit of open connections with none to close
  void handshakeDone(lws* wsi);
  void evictOldest(const std::string* peer);

  lws_protocols protocols[2]{};
  lws_http_mount mounts[2]{};
  lws_retry_bo_t retry{};

  static int callback(lws* wsi, lws_callback_reasons reason, void* user, void* in, size_t len);
  int onWriteable(lws* wsi, Session& s);
  int onReceive(lws* wsi, Session& s, const char* in, size_t len);
  int close(lws* wsi, lws_close_status status, const std::string& why) {
    lws_close_reason(wsi, status, reinterpret_cast<unsigned char*>(const_cast<char*>(why.data())),
                     std::min<std::size_t>(why.size(), 120));
    return -1;
  }
};

void StreamServer::Impl::evictOldest(const std::string* peer) {
  // A connection whose request is already waiting in its socket is read in this round of the
  // service loop: it is a client about to be served, not a silent one. Only the oldest few are
  // looked at: under a flood every one has its request waiting, and a look at all of them for
  // every new connection would slow the loop that serves them.
  const auto waiting = [](lws* wsi) {
    int unread = 0;
    return ioctl(lws_get_socket_fd(wsi), FIONREAD, &unread) == 0 && unread > 0;
  };
  int looked = 0;
  for (auto it = pending.begin(); it != pending.end() && looked < kEvictLook; ++it) {
    if (peer && it->peer != *peer) continue;
    ++looked;
    if (!waiting(it->wsi)) {
      lws* const wsi = it->wsi;
      forget(it);
      kill(wsi);
      return;
    }
  }
}

void StreamServer::Impl::admit(lws* wsi) {
  // The peer's address, read here: lws_get_peer_simple answers a failure with the error's text.
  // A peer already gone has none; it counts against the overall bound only.
  sockaddr_in a{};
  socklen_t size = sizeof a;
  char addr[INET_ADDRSTRLEN] = "";
  if (::getpeername(lws_get_socket_fd(wsi), reinterpret_cast<sockaddr*>(&a), &size) != 0 ||
      a.sin_family != AF_INET || !inet_ntop(AF_INET, &a.sin_addr, addr, sizeof addr))
    addr[0] = '\0';
  const std::string peer = addr;
  opened(wsi);
  if (!peer.empty() && pendingFrom(peer) >= opt.maxPendingPerAddress) evictOldest(&peer);
  if (pending.size() >= opt.maxPending) evictOldest(nullptr);
  pending.push_back({wsi, peer});
  pendingAt[wsi] = std::prev(pending.end());
  ++pendingPerPeer[peer];
}

namespace {
/// Whether the peer has hung up (a FIN, a reset or an error waits on the socket).
bool hungUp(int fd) {
  pollfd p{fd, POLLRDHUP, 0};
  return ::poll(&p, 1, 0) == 1 && (p.revents & (POLLRDHUP | POLLHUP | POLLERR));
}
}  // namespace

bool StreamServer::Impl::turnAway(int fd) {
  // A peer that hung up before it was even accepted (a flood's connect, GET, close) is closed
  // unanswered, at the cost of the accept alone: the server keeps pace with such a flood, and
  // the kernel's accept queue in front of a real client stays short.
  if (!hungUp(fd) && !full()) return false;
  std::lock_guard lock(mutex);
  ++stats.evicted;
  return true;
}

bool StreamServer::Impl::full() {
  if (open.size() - dying.size() < opt.maxPending) return false;
  int looked = 0;
  for (auto it = open.begin(); it != open.end() && looked < kEvictLook; ++it) {
    if (dying.count(*it)) continue;
    ++looked;
    if (hungUp(lws_get_socket_fd(*it))) {
      handshakeDone(*it);
      kill(*it);
      return false;
    }
  }
  return true;
}

void StreamServer::Impl::handshakeDone(lws* wsi) {
  if (const auto at = pendingAt.find(wsi); at != pendingAt.end()) forget(at->second);
}

int StreamServer::Impl::onWriteable(lws* wsi, Session& s) {
  if (stopping) return close(wsi, LWS_CLOSE_STATUS_GOINGAWAY, "liveprobe stopped");
  if (!s.refusal.empty()) return close(wsi, LWS_CLOSE_STATUS_POLICY_VIOLATION, s.refusal);
  int unsent = 0;
  if (ioctl(lws_get_socket_fd(wsi), SIOCOUTQ, &unsent) == 0 && unsent > kMaxUnsentBytes)
    return 0;  // the next publish() asks again
  std::uint64_t seq;
  std::optional<ProcessedFrame> f;  // copied only when this frame is new in this format
  Serialized& cached = serialized[s.format.name];
  {
    std::lock_guard lock(mutex);
    if (latestSeq == 0 || (s.sent == latestSeq && !s.resend)) return 0;
    seq = latestSeq;
    if (cached.seq != seq) f = latest;
    if (!s.resend && seq > s.sent + 1) stats.dropped += seq - s.sent - 1;
    s.resend = false;
  }
  if (f) cached = {seq, frameRecord(*f, s.format, {})};
  const std::string& msg = cached.text;
  std::vector<unsigned char> buf(LWS_PRE + msg.size());
  std::memcpy(buf.data() + LWS_PRE, msg.data(), msg.size());
  if (lws_write(wsi, buf.data() + LWS_PRE, msg.size(), LWS_WRITE_TEXT) < int(msg.size())) return -1;
  s.sent = seq;
  std::lock_guard lock(mutex);
  ++stats.sent;
  return 0;
}

int StreamServer::Impl::onReceive(lws* wsi, Session& s, const char* in, size_t len) {
  // What a client may send: {"format": "NAME"} to change the format of the messages it gets.
  if (lws_frame_is_binary(wsi)) {
    std::lock_guard lock(mutex);
    ++stats.closed;
    return close(wsi, LWS_CLOSE_STATUS_UNACCEPTABLE_OPCODE, "binary messages are not accepted");
  }
  if (s.rx.size() + len > opt.maxClientMessage) {
    std::lock_guard lock(mutex);
    ++stats.closed;
    return close(wsi, LWS_CLOSE_STATUS_MESSAGE_TOO_LARGE,
                 "message over " + std::to_string(opt.maxClientMessage) + " bytes");
  }
  s.rx.append(in, len);
  if (!lws_is_final_fragment(wsi) || lws_remaining_packet_payload(wsi) > 0) return 0;
  const std::string text = std::move(s.rx);
  s.rx.clear();
  try {
    const auto j = nlohmann::json::parse(text);
    if (!j.is_object() || j.size() != 1 || !j.contains("format") || !j["format"].is_string())
      throw Error("expected {\"format\": NAME}");
    s.format = parseCoeffFormat(j["format"].get<std::string>(), "format", true);
    s.resend = true;  // the newest frame again, in the new format
    lws_callback_on_writable(wsi);
    return 0;
  } catch (const std::exception& e) {
    std::lock_guard lock(mutex);
    ++stats.closed;
    return close(wsi, LWS_CLOSE_STATUS_INVALID_PAYLOAD, e.what());
  }
}

int StreamServer::Impl::callback(lws* wsi, lws_callback_reasons reason, void* user, void* in,
                                 size_t len) {
  lws_context* ctx = lws_get_context(wsi);
  auto* self = ctx ? static_cast<Impl*>(lws_context_user(ctx)) : nullptr;
  auto* slot = static_cast<SessionSlot*>(user);
  if (!self) return lws_callback_http_dummy(wsi, reason, user, in, len);
  switch (reason) {
    // Accepted and given its descriptor: it has handshakeSeconds to say what it wants.
    case LWS_CALLBACK_SERVER_NEW_CLIENT_INSTANTIATED:
      self->admit(wsi);
      return 0;
    case LWS_CALLBACK_FILTER_NETWORK_CONNECTION:  // accepted, not yet adopted: 1 closes it
      return self->turnAway(int(reinterpret_cast<lws_intptr_t>(in))) ? 1 : 0;
    case LWS_CALLBACK_WSI_DESTROY:
      self->handshakeDone(wsi);
      self->notOpen(wsi);
      return 0;
    case LWS_CALLBACK_FILTER_HTTP_CONNECTION:  // a whole request came: no longer pending
      self->handshakeDone(wsi);
      return lws_callback_http_dummy(wsi, reason, user, in, len);
    case LWS_CALLBACK_FILTER_PROTOCOL_CONNECTION: {
      self->handshakeDone(wsi);
      std::lock_guard lock(self->mutex);
      if (self->stopping || self->stats.clients >= std::uint64_t(self->opt.maxClients)) {
        ++self->stats.refused;
        return 1;  // refuses the upgrade
      }
      return 0;
    }
    case LWS_CALLBACK_ESTABLISHED: {
      self->notOpen(wsi);  // a client: counted against --serve-clients, never evicted
      slot->s = new Session;
      slot->s->format = self->opt.defaultFormat;
      try {
        if (auto f = formatFromQuery(wsi)) slot->s->format = *f;
      } catch (const Error& e) {
        slot->s->refusal = e.what();  // closed once the handshake is through, with the reason
      }
      {
        std::lock_guard lock(self->mutex);
        ++self->stats.clients;
        ++self->stats.connected;
        // Frames before it came are not its drops; the newest is sent at once.
        slot->s->sent = self->latestSeq;
        slot->s->resend = self->latestSeq > 0;
      }
      lws_callback_on_writable(wsi);
      return 0;
    }
    case LWS_CALLBACK_CLOSED:
      if (slot && slot->s) {
        std::lock_guard lock(self->mutex);
        // What it never got before it left (a client that stopped reading) was dropped too.
        if (self->latestSeq > slot->s->sent) self->stats.dropped += self->latestSeq - slot->s->sent;
        --self->stats.clients;
        delete slot->s;
        slot->s = nullptr;
      }
      return 0;
    case LWS_CALLBACK_SERVER_WRITEABLE:
      return slot && slot->s ? self->onWriteable(wsi, *slot->s) : 0;
    case LWS_CALLBACK_RECEIVE:
      return slot && slot->s ? self->onReceive(wsi, *slot->s, static_cast<const char*>(in), len)
                             : -1;
    case LWS_CALLBACK_EVENT_WAIT_CANCELLED:  // publish() or stop() woke the service loop
      lws_callback_on_writable_all_protocol(self->context, &self->protocols[0]);
      return 0;
    default:
      return lws_callback_http_dummy(wsi, reason, user, in, len);
  }
}

StreamServer::StreamServer(StreamServerOptions options) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.opt = std::move(options);
  lws_set_log_level(LLL_ERR, [](int, const char*) {});  // errors reach the user as lp::Error
  m.protocols[0].name = "liveprobe";
  m.protocols[0].callback = &Impl::callback;
  m.protocols[0].per_session_data_size = sizeof(SessionSlot);
  m.protocols[0].rx_buffer_size = m.opt.maxClientMessage;
  // / serves the page; /three/ three.js's build (both plain files).
  m.mounts[0].mountpoint = "/";
  m.mounts[0].mountpoint_len = 1;
  m.mounts[0].origin = m.opt.webDir.c_str();
  m.mounts[0].def = "index.html";
  m.mounts[0].origin_protocol = LWSMPRO_FILE;
  m.mounts[0].mount_next = &m.mounts[1];
  m.mounts[1].mountpoint = "/three";
  m.mounts[1].mountpoint_len = 6;
  m.mounts[1].origin = m.opt.threeDir.c_str();
  m.mounts[1].origin_protocol = LWSMPRO_FILE;
  // Idle: a client that has not answered a ping for idleSeconds is hung up.
  m.retry.secs_since_valid_ping = std::uint16_t(std::max(1, m.opt.idleSeconds / 2));
  m.retry.secs_since_valid_hangup = std::uint16_t(std::max(2, m.opt.idleSeconds));

  lws_context_creation_info info{};
  info.port = m.opt.port;  // 0: the kernel picks a free one
  info.iface = m.opt.host.c_str();
  info.protocols = m.protocols;
  info.mounts = m.mounts;
  info.user = &m;
  info.retry_and_idle_policy = &m.retry;
  info.options = LWS_SERVER_OPTION_DISABLE_IPV6 | LWS_SERVER_OPTION_VALIDATE_UTF8 |
                 LWS_SERVER_OPTION_FAIL_UPON_UNABLE_TO_BIND;
  // Every client and every pending connection has a descriptor and a header buffer. lws accepts
  // while the listening socket has connections and its descriptors are under this limit: the
  // limit is what bounds a flood's descriptors (the rest wait in the kernel's accept queue).
  info.fd_limit_per_thread = unsigned(m.opt.maxClients) + unsigned(m.opt.maxPending) + 16;
  info.max_http_header_pool = std::uint16_t(m.opt.maxPending + 8);
  // Room for a request with a long query, so that it reaches formatFromQuery and is refused
  // there with its reason (1008) instead of being cut off by lws.
  info.max_http_header_data = 8192;
  // The handshake deadline: lws closes a connection that has not sent its whole request (or
  // upgrade) within timeout_secs, and frees a header buffer held idle as long.
  info.timeout_secs = unsigned(m.opt.handshakeSeconds);
  info.timeout_secs_ah_idle = unsigned(m.opt.handshakeSeconds);
  const std::string where = m.opt.host + ":" + std::to_string(m.opt.port);
  checkBindable(m.opt.host, m.opt.port, where);
  m.context = lws_create_context(&info);
  if (!m.context) throw Error(where + ": cannot listen there");
  m.vhost = lws_get_vhost_by_name(m.context, "default");
  m.boundPort = m.vhost ? lws_get_vhost_listen_port(m.vhost) : 0;
  if (m.boundPort <= 0) {
    lws_context_destroy(m.context);
    throw Error(where + ": cannot listen there");
  }
  m.thread = std::thread([&m] {
    auto stopAt = std::chrono::steady_clock::time_point::max();
    while (true) {
      lws_service(m.context, 0);
      if (m.stopping) {
        const auto now = std::chrono::steady_clock::now();
        if (stopAt == std::chrono::steady_clock::time_point::max())
          stopAt = now + std::chrono::seconds(2);
        std::uint64_t clients;
        {
          std::lock_guard lock(m.mutex);
          clients = m.stats.clients;
        }
        if (clients == 0 || now > stopAt) break;
        lws_callback_on_writable_all_protocol(m.context, &m.protocols[0]);
      }
    }
    lws_context_destroy(m.context);  // (publish() no longer touches it: `stopping` is set)
  });
}

StreamServer::~StreamServer() { stop(); }

int StreamServer::port() const { return impl_->boundPort; }

void StreamServer::publish(const ProcessedFrame& frame) {
  {
    std::lock_guard lock(impl_->mutex);
    impl_->latest = frame;
    impl_->latest.background = {};  // the record needs the numbers, not the pixels
    ++impl_->latestSeq;
  }
  if (impl_->context && !impl_->stopping) lws_cancel_service(impl_->context);
}

StreamStats StreamServer::stats() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->stats;
}

std::string StreamServer::status() const {
  const StreamStats s = stats();
  return "stream: " + std::to_string(s.clients) + " clients, " + std::to_string(s.dropped) +
         " dropped";
}

std::string StreamServer::summary() const {
  const StreamStats s = stats();
  return "stream: " + std::to_string(s.connected) + " clients served, " + std::to_string(s.sent) +
         " messages sent, " + std::to_string(s.dropped) + " dropped for slow clients, " +
         std::to_string(s.refused) + " refused (client limit), " + std::to_string(s.closed) +
         " closed (bad message or idle), " + std::to_string(s.evicted) +
         " connections closed before their handshake";
}

void StreamServer::stop() {
  if (!impl_->thread.joinable()) return;
  impl_->stopping = true;
  lws_cancel_service(impl_->context);
  impl_->thread.join();
}

}  // namespace lp
