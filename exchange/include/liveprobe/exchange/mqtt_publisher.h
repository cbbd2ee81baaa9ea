#pragma once
// Fan-out through an MQTT broker (a target mqtt[s]://[USER@]HOST:PORT/TOPIC): every
// frame's record (engine_export.h's frameRecord) published retained, QoS 0, with libmosquitto, so a
// late subscriber gets the newest frame at once. A lost broker never stalls capture: libmosquitto
// reconnects on its own thread with exponential backoff, and what could not be handed to the
// broker meanwhile is counted.
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>

#include "liveprobe/exchange/record_sink.h"

struct mosquitto;

namespace lp {

struct MqttTarget {
  std::string host;
  int port = 1883;  ///< 8883 for mqtts://
  std::string topic;
  bool tls = false;      ///< mqtts://: TLS, the broker checked against the CA store or `cafile`
  std::string cafile;    ///< a PEM file of the CAs to trust instead of the system's
  std::string username;  ///< from the URL's user part
  std::string password;  ///< from the URL, or given apart (kept off a command line)
  /// The URL as messages may show it: never the password.
  std::string describe() const;
};

/// Parses mqtt[s]://[USER[:PASSWORD]@]HOST[:PORT]/TOPIC. The topic must be one MQTT can publish
/// to: valid UTF-8 of at most 65535 bytes, without the wildcards + and # or a NUL. Throws
/// lp::Error that quotes the URL, never its password.
MqttTarget parseMqttUrl(const std::string& url);

struct MqttStats {
  std::uint64_t published = 0;   ///< handed to the broker's connection
  std::uint64_t lost = 0;        ///< not sent: no connection at the time
  std::uint64_t reconnects = 0;  ///< connections made after the first
  bool connected = false;
};

class MqttPublisher final : public RecordSink {
 public:
  /// Starts connecting (in the background: a broker that is down is retried, not an error).
  /// Waits up to 3 s for the first connection, not at all where nothing listens at the address
  /// (the connection refused at once), and no longer once `interrupted` (polled every 5 ms; the
  /// app passes its signal flag) says so. A broker that refuses the credentials (or the TLS
  /// handshake) in that time throws lp::Error.
  explicit MqttPublisher(MqttTarget target, const std::function<bool()>& interrupted = {});
  ~MqttPublisher() override;
  MqttPublisher(const MqttPublisher&) = delete;
  MqttPublisher& operator=(const MqttPublisher&) = delete;

  /// Publishes a frame's record, frameRecord() (any thread; never waits for the broker).
  void publish(const std::string& record);
  void publish(FrameRecord& record) override { publish(record.text()); }
  MqttStats stats() const;
  std::string status() const override;
  std::string summary() const override;
  /// Some message reached the broker.
  bool delivered() const override { return published_ > 0; }
  const MqttTarget& target() const { return target_; }
  /// Why the wait for the first connection ended without one ("mqtt://...: no broker answers
  /// yet; ..."), for the caller to say; empty when connected or stopped.
  const std::string& startupWarning() const { return startupWarning_; }

 private:
  MqttTarget target_;
  mosquitto* mosq_ = nullptr;
  std::atomic<std::uint64_t> published_{0}, lost_{0}, connects_{0};
  std::atomic<bool> connected_{false};
  std::atomic<int> refusal_{0};  ///< the broker's CONNACK code when it refused the connection
  std::string startupWarning_;
};

}  // namespace lp
