#include "mqtt_publisher.h"

#include <mosquitto.h>

#include <chrono>
#include <cstdio>
#include <mutex>
#include <string>
#include <thread>

#include "liveprobe/sh/error.h"

namespace lp::cli {

MqttTarget parseMqttUrl(const std::string& url) {
  const std::string scheme = "mqtt://";
  const std::string what = "--publish " + url;
  if (url.rfind(scheme, 0) != 0) throw Error(what + ": expected mqtt://HOST[:PORT]/TOPIC");
  const std::string rest = url.substr(scheme.size());
  const auto slash = rest.find('/');
  if (slash == std::string::npos || slash + 1 >= rest.size())
    throw Error(what + ": no topic (expected mqtt://HOST[:PORT]/TOPIC)");
  MqttTarget t;
  const std::string hostPort = rest.substr(0, slash);
  t.topic = rest.substr(slash + 1);
  if (t.topic.find_first_of("+#") != std::string::npos)
    throw Error(what + ": a topic to publish to has no wildcards (+, #)");
  const auto colon = hostPort.rfind(':');
  t.host = hostPort.substr(0, colon);
  if (colon != std::string::npos) {
    const std::string port = hostPort.substr(colon + 1);
    char* end = nullptr;
    const long p = std::strtol(port.c_str(), &end, 10);
    if (port.empty() || *end != '\0' || p < 1 || p > 65535)
      throw Error(what + ": the port must be 1..65535");
    t.port = int(p);
  }
  if (t.host.empty()) throw Error(what + ": no host");
  return t;
}

namespace {
std::once_flag initOnce;
}

MqttPublisher::MqttPublisher(MqttTarget target) : target_(std::move(target)) {
  std::call_once(initOnce, [] { mosquitto_lib_init(); });
  mosq_ = mosquitto_new(nullptr, true, this);
  if (!mosq_) throw Error("--publish: cannot create an MQTT client (out of memory)");
  mosquitto_connect_callback_set(mosq_, [](mosquitto*, void* obj, int rc) {
    auto* self = static_cast<MqttPublisher*>(obj);
    if (rc == 0) {
      self->connected_ = true;
      ++self->connects_;
    }
  });
  mosquitto_disconnect_callback_set(mosq_, [](mosquitto*, void* obj, int) {
    static_cast<MqttPublisher*>(obj)->connected_ = false;
  });
  // Backoff 1, 2, 4 .. 8 s between tries, on libmosquitto's own thread.
  mosquitto_reconnect_delay_set(mosq_, 1, 8, true);
  // A broker that is down now is not an error: the loop keeps trying.
  mosquitto_connect_async(mosq_, target_.host.c_str(), target_.port, 10);
  if (mosquitto_loop_start(mosq_) != MOSQ_ERR_SUCCESS) {
    mosquitto_destroy(mosq_);
    throw Error("--publish: cannot start the MQTT client's thread");
  }
  // The first frames should reach a broker that is up: wait for the connection up to 3 s.
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(3);
  while (!connected_ && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  if (!connected_)
    std::fprintf(stderr,
                 "liveprobe: --publish: no broker at %s:%d yet; capture goes on, retrying in the "
                 "background\n",
                 target_.host.c_str(), target_.port);
}

MqttPublisher::~MqttPublisher() {
  mosquitto_disconnect(mosq_);
  mosquitto_loop_stop(mosq_, false);
  mosquitto_destroy(mosq_);
}

void MqttPublisher::publish(const std::string& record) {
  if (!connected_) {
    ++lost_;
    return;
  }
  const int rc = mosquitto_publish(mosq_, nullptr, target_.topic.c_str(), int(record.size()),
                                   record.data(), 0, true);
  if (rc == MOSQ_ERR_SUCCESS)
    ++published_;
  else
    ++lost_;
}

MqttStats MqttPublisher::stats() const {
  MqttStats s;
  s.published = published_;
  s.lost = lost_;
  s.reconnects = connects_ > 0 ? connects_ - 1 : 0;
  s.connected = connected_;
  return s;
}

}  // namespace lp::cli
