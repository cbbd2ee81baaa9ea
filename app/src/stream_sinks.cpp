// The stream's record sinks: --serve, --publish and --coeffs-out.
#include "stream_sinks.h"

#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>

#include "commands.h"
#include "liveprobe/backends.h"
#include "liveprobe/frame/input_file.h"
#include "liveprobe/sh/error.h"
#include "progress.h"
#if LIVEPROBE_WITH_MQTT
#include "liveprobe/exchange/mqtt_publisher.h"
#endif
#if LIVEPROBE_WITH_STREAM
#include "liveprobe/exchange/stream_server.h"
#endif

namespace lp::cli {

namespace fs = std::filesystem;

namespace {

class CoeffsFileSink final : public RecordSink {
 public:
  CoeffsFileSink(AtomicTextFile& file, const CoeffFormat& format, CoeffsLines when, bool keepSent)
      : file_(file), format_(format), when_(when), keepSent_(keepSent) {}

  void publish(FrameRecord& record) override {
    if (when_ == CoeffsLines::AtCapture) return file_.line(record.text());
    if (!keepSent_) return;
    std::lock_guard lock(mutex_);
    sent_.emplace(record.frame().index, record.text());
  }
  void shown(const ProcessedFrame& f, RecordTimes t) override {
    if (when_ != CoeffsLines::AtDraw) return;
    file_.line(frameRecord(f, format_, t));
    std::lock_guard lock(mutex_);
    sent_.erase(sent_.begin(), sent_.upper_bound(f.index));
  }
  void stop() override {  // the records sent and never drawn, in frame order
    std::lock_guard lock(mutex_);
    for (const auto& [index, text] : sent_) file_.line(text);
    sent_.clear();
  }

 private:
  AtomicTextFile& file_;
  CoeffFormat format_;
  CoeffsLines when_;
  bool keepSent_;
  std::mutex mutex_;
  std::map<std::uint64_t, std::string> sent_;  ///< AtDraw: sent at capture, not yet drawn
};

std::unique_ptr<RecordSink> openStream([[maybe_unused]] const StreamSettings& st,
                                       [[maybe_unused]] std::vector<std::string>& opening) {
  requireBackend(OptionalBackend::Stream, "--serve");
#if LIVEPROBE_WITH_STREAM
  StreamServerOptions o;
  try {
    parseServeAddress(*st.serve, o);
  } catch (const Error& e) {
    throw Error("--serve " + std::string(e.what()));
  }
  if (!isLoopback(o.host) && !st.serveRemote)
    throw Error("--serve " + *st.serve + ": " + o.host +
                " is reachable from other machines; add --serve-remote to listen there");
  o.maxClients = st.serveClients.value_or(32);
  o.idleSeconds = st.serveIdle.value_or(30);
  o.defaultFormat = parseCoeffFormat("three", "--serve", true);
  const char* web = std::getenv("LIVEPROBE_WEB_DIR");
  o.webDir = web ? web : shareDir() + "/web";
  o.threeDir = o.webDir + "/three";
  if (!fs::exists(o.threeDir + "/three.module.js"))
    warn("--serve: three.js is not in " + o.threeDir +
         " (the build stages it there from app/web/vendor/three; LIVEPROBE_WEB_DIR names another "
         "folder); the page will not draw");
  std::unique_ptr<StreamServer> server;
  try {
    server = std::make_unique<StreamServer>(o);
  } catch (const Error& e) {
    throw Error("--serve " + std::string(e.what()));
  }
  const std::string url = o.host + ":" + std::to_string(server->port());
  opening.push_back("liveprobe: serving http://" + url + "/ (WebSocket ws://" + url +
                    "/?format=three)");
  return server;
#else
  return nullptr;  // (requireBackend threw)
#endif
}

std::unique_ptr<RecordSink> openBroker([[maybe_unused]] const StreamSettings& st,
                                       [[maybe_unused]] std::vector<std::string>& opening) {
  requireBackend(OptionalBackend::Mqtt, "--publish");
#if LIVEPROBE_WITH_MQTT
  MqttTarget t;
  try {
    t = parseMqttUrl(*st.publish);
  } catch (const Error& e) {
    throw Error("--publish " + std::string(e.what()));
  }
  if (st.mqttCafile) {
    if (!t.tls) throw Error("--mqtt-cafile goes with an mqtts:// broker");
    t.cafile = *st.mqttCafile;
    readInputFile(t.cafile);  // a missing or unreadable file is one line, now
  }
  if (t.password.empty() && !t.username.empty()) {
    if (st.mqttPasswordFile) {
      const std::string text = readInputFile(*st.mqttPasswordFile);
      t.password = text.substr(0, text.find_first_of("\r\n"));  // its first line
    } else if (const char* pw = std::getenv("LIVEPROBE_MQTT_PASSWORD")) {
      t.password = pw;
    }
  }
  std::unique_ptr<MqttPublisher> publisher;
  try {
    publisher = std::make_unique<MqttPublisher>(std::move(t), stopRequested);
  } catch (const Error& e) {
    throw Error("--publish " + std::string(e.what()));
  }
  if (!publisher->startupWarning().empty())
    opening.push_back("liveprobe: warning: " + publisher->startupWarning());
  return publisher;
#else
  return nullptr;  // (requireBackend threw)
#endif
}

}  // namespace

void RecordSinks::fill(HudCounters& c) const {
  for (const auto& s : all)
    if (std::string line = s->status(); !line.empty()) c.sinks.push_back(std::move(line));
}

void RecordSinks::shown(const ProcessedFrame& f, RecordTimes t) const {
  for (const auto& s : all) s->shown(f, t);
}

RecordSinks openSinks(const StreamSettings& st) {
  RecordSinks s;
  if (st.serve) s.all.push_back(openStream(st, s.opening));
  if (st.publish) s.all.push_back(openBroker(st, s.opening));
  return s;
}

void addCoeffsSink(RecordSinks& sinks, AtomicTextFile& file, const CoeffFormat& format,
                   CoeffsLines when) {
  const bool network = !sinks.all.empty();
  sinks.all.push_back(std::make_unique<CoeffsFileSink>(file, format, when, network));
}

}  // namespace lp::cli
