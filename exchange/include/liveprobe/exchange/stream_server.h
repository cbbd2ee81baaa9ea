#pragma once
// The live coefficient stream: a WebSocket server (libwebsockets) that sends
// every client the newest frame's record (engine_export.h's frameRecord, in the format the client
// asked for) and answers HTTP at / with the web page of app/web (a three.js scene lit by the
// stream). Latest-value semantics: a slow client gets the newest frame when it can take one,
// never a queue; what it missed is counted as dropped. Capture never waits for a client.
#include <cstdint>
#include <memory>
#include <string>

#include "liveprobe/exchange/engine_export.h"
#include "liveprobe/exchange/record_sink.h"

namespace lp {

struct StreamServerOptions {
  std::string host = "127.0.0.1";  ///< an IPv4 address, or "localhost"
  int port = 8080;                 ///< 0: any free port (port() tells which)
  int maxClients = 32;
  int idleSeconds = 30;                 ///< a client that answers no ping for this long is closed
  std::size_t maxClientMessage = 4096;  ///< the largest message a client may send, bytes
  /// A connection must send a whole HTTP request or WebSocket upgrade within this long.
  int handshakeSeconds = 3;
  /// Connections still in their handshake, in all and from one address: over either limit the
  /// oldest silent one (of that address) is closed, so a new client is always heard. maxPending
  /// also bounds every connection that is not a client (pending, or being sent the page): at it a
  /// new one closes the oldest whose peer has hung up, or is closed as it is accepted. A peer
  /// that has hung up before its connection is accepted is closed unanswered.
  std::size_t maxPending = 256, maxPendingPerAddress = 64;
  CoeffFormat defaultFormat;  ///< for clients that ask for none (?format=)
  std::string webDir;         ///< the page (index.html, main.js)
  std::string threeDir;       ///< three.js's build folder, served at /three/
};

/// "[ADDR:]PORT": ADDR (an IPv4 address or localhost) defaults to 127.0.0.1. Throws lp::Error
/// quoting the text.
void parseServeAddress(const std::string& text, StreamServerOptions& o);
/// Whether `host` (an IPv4 address or localhost) is on the loopback, out of other machines' reach.
bool isLoopback(const std::string& host);

struct StreamStats {
  std::uint64_t connected = 0;  ///< clients served, in all
  std::uint64_t clients = 0;    ///< connected now
  std::uint64_t sent = 0;       ///< messages sent
  std::uint64_t dropped = 0;    ///< frames a slow client missed (it got a newer one instead)
  std::uint64_t refused = 0;    ///< connections over the client limit
  std::uint64_t closed = 0;     ///< clients closed for a bad message, or idle
  std::uint64_t evicted = 0;    ///< connections closed before their handshake (deadline, limits)
};

class StreamServer final : public RecordSink {
 public:
  /// Binds and starts serving on its own thread. Throws lp::Error if the address can't be bound.
  explicit StreamServer(StreamServerOptions options);
  ~StreamServer() override;  ///< stop()
  StreamServer(const StreamServer&) = delete;
  StreamServer& operator=(const StreamServer&) = delete;

  int port() const;
  /// Hands the server a frame (any thread; never waits for a client). Each client gets it in
  /// the format it asked for, serialized once per format.
  void publish(const ProcessedFrame& frame);
  void publish(FrameRecord& record) override { publish(record.frame()); }
  StreamStats stats() const;
  std::string status() const override;
  std::string summary() const override;
  /// Closes every connection (status 1001, going away) and stops serving. Idempotent.
  void stop() override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lp
