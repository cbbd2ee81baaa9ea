#include "liveprobe/exchange/mqtt_publisher.h"

#include <mosquitto.h>
#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <mutex>
#include <string>
#include <thread>

#include "liveprobe/sh/error.h"

namespace lp {

std::string MqttTarget::describe() const {
  return std::string(tls ? "mqtts://" : "mqtt://") + (username.empty() ? "" : username + "@") +
         host + ":" + std::to_string(port) + "/" + topic;
}

MqttTarget parseMqttUrl(const std::string& url) {
  MqttTarget t;
  std::string rest;
  if (url.rfind("mqtt://", 0) == 0) {
    rest = url.substr(7);
  } else if (url.rfind("mqtts://", 0) == 0) {
    rest = url.substr(8);
    t.tls = true;
    t.port = 8883;
  }
  const auto slash = rest.find('/');
  std::string authority = rest.substr(0, slash);
  // The password is cut out before anything is quoted back.
  std::string shown = url;
  if (const auto at = authority.rfind('@'); at != std::string::npos) {
    const std::string user = authority.substr(0, at);
    const auto colon = user.find(':');
    t.username = user.substr(0, colon);
    if (colon != std::string::npos) t.password = user.substr(colon + 1);
    authority = authority.substr(at + 1);
    shown = std::string(t.tls ? "mqtts://" : "mqtt://") + t.username + "@" + authority +
            (slash == std::string::npos ? "" : rest.substr(slash));
    if (t.username.empty()) throw Error(shown + ": an empty user name");
  }
  const std::string& what = shown;
  if (rest.empty() && url.rfind("mqtt", 0) != 0)
    throw Error(what + ": expected mqtt://HOST[:PORT]/TOPIC or mqtts://...");
  if (slash == std::string::npos || slash + 1 >= rest.size())
    throw Error(what + ": no topic (expected mqtt://HOST[:PORT]/TOPIC)");
  t.topic = rest.substr(slash + 1);
  if (t.topic.size() > 65535)
    throw Error(what.substr(0, 80) + "...: the topic is " + std::to_string(t.topic.size()) +
                " bytes; MQTT allows 65535");
  if (t.topic.find('\0') != std::string::npos ||
      mosquitto_validate_utf8(t.topic.data(), int(t.topic.size())) != MOSQ_ERR_SUCCESS)
    throw Error(what.substr(0, what.find('/', what.find("//") + 2)) +
                "/...: the topic is not valid UTF-8");
  if (t.topic.find_first_of("+#") != std::string::npos)
    throw Error(what + ": a topic to publish to has no wildcards (+, #)");
  const auto colon = authority.rfind(':');
  t.host = authority.substr(0, colon);
  if (colon != std::string::npos) {
    const std::string port = authority.substr(colon + 1);
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

/// Whether a TCP connection to host:port is refused at once (nothing listens there): a
/// non-blocking connect, answered within `patience`. False for anything else (accepted, no
/// answer yet, a name that does not resolve): the broker may still come up.
bool refusedNow(const std::string& host, int port, std::chrono::milliseconds patience) {
  addrinfo hints{};
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  if (::getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &found) != 0) return false;
  bool refused = false;
  for (addrinfo* a = found; a && !refused; a = a->ai_next) {
    const int fd = ::socket(a->ai_family, a->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd < 0) continue;
    if (::connect(fd, a->ai_addr, a->ai_addrlen) != 0) {
      if (errno == ECONNREFUSED) {
        refused = true;
      } else if (errno == EINPROGRESS) {
        pollfd p{fd, POLLOUT, 0};
        int err = 0;
        socklen_t len = sizeof err;
        if (::poll(&p, 1, int(patience.count())) == 1 &&
            ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len) == 0 && err == ECONNREFUSED)
          refused = true;
      }
    }
    ::close(fd);
  }
  ::freeaddrinfo(found);
  return refused;
}
}  // namespace

MqttPublisher::MqttPublisher(MqttTarget target, const std::function<bool()>& interrupted)
    : target_(std::move(target)) {
  std::call_once(initOnce, [] { mosquitto_lib_init(); });
  const std::string what = target_.describe();
  mosq_ = mosquitto_new(nullptr, true, this);
  if (!mosq_) throw Error(what + ": cannot create an MQTT client (out of memory)");
  const auto fail = [&](const std::string& why) {
    mosquitto_disconnect(mosq_);
    mosquitto_loop_stop(mosq_, true);
    mosquitto_destroy(mosq_);
    throw Error(what + ": " + why);
  };
  if (!target_.username.empty() &&
      mosquitto_username_pw_set(mosq_, target_.username.c_str(),
                                target_.password.empty() ? nullptr : target_.password.c_str()) !=
          MOSQ_ERR_SUCCESS)
    fail("the user name or password is not valid UTF-8");
  if (target_.tls) {
    const int rc =
        target_.cafile.empty()
            ? mosquitto_int_option(mosq_, MOSQ_OPT_TLS_USE_OS_CERTS, 1)
            : mosquitto_tls_set(mosq_, target_.cafile.c_str(), nullptr, nullptr, nullptr, nullptr);
    if (rc != MOSQ_ERR_SUCCESS)
      fail("cannot set up TLS" +
           (target_.cafile.empty() ? std::string() : " with the CA file " + target_.cafile) + " (" +
           mosquitto_strerror(rc) + ")");
  }
  mosquitto_connect_callback_set(mosq_, [](mosquitto*, void* obj, int rc) {
    auto* self = static_cast<MqttPublisher*>(obj);
    if (rc == 0) {
      self->connected_ = true;
      ++self->connects_;
    } else {
      self->refusal_ = rc;
    }
  });
  mosquitto_disconnect_callback_set(mosq_, [](mosquitto*, void* obj, int) {
    static_cast<MqttPublisher*>(obj)->connected_ = false;
  });
  // Backoff 1, 2, 4 .. 8 s between tries, on libmosquitto's own thread.
  mosquitto_reconnect_delay_set(mosq_, 1, 8, true);
  // A broker that is down now is not an error: the loop keeps trying.
  mosquitto_connect_async(mosq_, target_.host.c_str(), target_.port, 10);
  if (mosquitto_loop_start(mosq_) != MOSQ_ERR_SUCCESS)
    fail("cannot start the MQTT client's thread");
  // The first frames should reach a broker that is up: wait for the connection up to 3 s,
  // unless nothing listens there (the connection refused at once) or a stop is asked for.
  const bool nothingListens =
      refusedNow(target_.host, target_.port, std::chrono::milliseconds(200));
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(3);
  bool stopped = false;
  while (!nothingListens && !connected_ && !refusal_ && std::chrono::steady_clock::now() < until &&
         !(stopped = interrupted && interrupted()))
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  if (const int rc = refusal_)
    fail(std::string("the broker refused the connection: ") + mosquitto_connack_string(rc));
  if (!connected_ && !stopped)
    startupWarning_ = what + ": " +
                      (nothingListens ? "no broker listens there (connection refused)"
                                      : "no broker answers yet") +
                      "; frames are counted as lost until one does (retrying in the background)";
}

MqttPublisher::~MqttPublisher() {
  mosquitto_disconnect(mosq_);
  // Connected: the loop sends the disconnect and ends. Not connected, it may be asleep in a
  // reconnect's backoff (up to 8 s) or a TLS handshake with nothing to deliver: cancelled.
  mosquitto_loop_stop(mosq_, !connected_);
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

std::string MqttPublisher::status() const { return "mqtt: " + std::to_string(lost_) + " lost"; }

std::string MqttPublisher::summary() const {
  const MqttStats m = stats();
  return target_.describe() + ": " + std::to_string(m.published) + " published, " +
         std::to_string(m.lost) + " lost (no broker connection), " + std::to_string(m.reconnects) +
         " reconnects" + (m.published == 0 && m.lost > 0 ? "; no message reached the broker" : "");
}

}  // namespace lp
