// Cameras on the network, against real servers on 127.0.0.1: a motion-JPEG camera over HTTP
// (tests/scripts/mjpeg_camera.py), GStreamer's RTSP server (tests/scripts/rtsp_server.py) and
// FFmpeg's SRT listener, the last two streaming an H.264 file as it is.
// Each gives the coefficients of the same frames read from the file; a camera that drops costs
// no run and no frame count; what nothing answers is one line within the timeout; a password is
// never shown.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "liveprobe/capture/network.h"
#include "server_process.h"
#include "test_util.h"

namespace {

using lpt::runLiveprobe;
using lpt::ServerProcess;
using lpt::shellQuote;

const std::string kJpeg = std::string(LIVEPROBE_SOURCE_DIR) + "/recordings/ball/ball.jpg";
const std::string kCamera = std::string(LIVEPROBE_SOURCE_DIR) + "/tests/scripts/mjpeg_camera.py";

std::vector<nlohmann::json> readJsonl(const std::string& path) {
  std::vector<nlohmann::json> out;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) out.push_back(nlohmann::json::parse(line));
  return out;
}

double l00(const nlohmann::json& j) { return j["coefficients"]["L00"][1].get<double>(); }

/// The camera script with `options`, and the URL it serves at (with `credentials@` where given).
struct Camera {
  ServerProcess server;
  std::string url;
  explicit Camera(std::vector<std::string> options, const std::string& credentials = "")
      : server([&] {
          std::vector<std::string> argv{"python3", kCamera, kJpeg};
          argv.insert(argv.end(), options.begin(), options.end());
          return argv;
        }()) {
    const std::string port = server.firstLine();
    EXPECT_FALSE(port.empty()) << "the motion-JPEG camera did not start";
    url = "http://" + (credentials.empty() ? "" : credentials + "@") + "127.0.0.1:" + port +
          "/stream";
  }
};

/// `liveprobe live URL` headless, taking the frames as equirect, with `options`, its records to
/// `out`.
lpt::RunResult live(const std::string& url, const std::string& options, const std::string& out) {
  return runLiveprobe("live " + shellQuote(url) + " --layout equirect " + options +
                      " --headless --coeffs-out " + out);
}

/// The file's own coefficients, as `coeffs` reads the JPEG.
double fileL00() {
  const auto r = runLiveprobe("coeffs " + shellQuote(kJpeg) + " --layout equirect");
  EXPECT_EQ(r.exitCode, 0) << r.output;
  return l00(nlohmann::json::parse(r.output.substr(r.output.find('{'))));
}

TEST(Network, AMotionJpegCameraGivesTheJpegsCoefficientsAndNeverItsPassword) {
  const std::string secret = "hunter2-secret";
  Camera camera({"--auth", "user:" + secret}, "user:" + secret);
  lpt::TempDir tmp;
  const auto r = live(camera.url, "--frames 12", tmp / "net.jsonl");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_EQ(r.output.find(secret), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("user:***@127.0.0.1"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("motion JPEG 1280x720"), std::string::npos) << r.output;
  const auto records = readJsonl(tmp / "net.jsonl");
  ASSERT_EQ(records.size(), 12u);
  const double truth = fileL00();
  for (const auto& j : records) {
    EXPECT_NEAR(l00(j), truth, 1e-4 * truth) << j.dump();
    EXPECT_EQ(j.dump().find(secret), std::string::npos);
  }
  // The same camera without the password: refused in one line, which names it unauthorized.
  Camera locked({"--auth", "user:" + secret});
  const auto refused = live(locked.url, "--frames 3", tmp / "none.jsonl");
  EXPECT_EQ(refused.exitCode, 1) << refused.output;
  EXPECT_NE(refused.output.find("unauthorized"), std::string::npos) << refused.output;
  EXPECT_FALSE(std::filesystem::exists(tmp / "none.jsonl"));
}

// The same camera over HTTPS (TLS with a self-signed certificate, as a camera's own is): the
// JPEG's coefficients, and its password shown nowhere.
TEST(Network, AnHttpsCameraIsReadOverTls) {
  lpt::TempDir tmp;
  const std::string cert = tmp / "cert.pem", key = tmp / "key.pem";
  const auto made = lpt::runCommand(
      "openssl req -x509 -newkey rsa:2048 -nodes -days 1 -subj /CN=127.0.0.1 -keyout " + key +
      " -out " + cert + " 2>&1");
  ASSERT_EQ(made.exitCode, 0) << made.output;
  const std::string secret = "tls-secret-3";
  Camera camera({"--tls", cert + "," + key, "--auth", "user:" + secret}, "user:" + secret);
  const std::string https = "https" + camera.url.substr(4);  // http://user:... -> https://
  const auto r = live(https, "--frames 5", tmp / "net.jsonl");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_EQ(r.output.find(secret), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("https://user:***@127.0.0.1"), std::string::npos) << r.output;
  const auto records = readJsonl(tmp / "net.jsonl");
  ASSERT_EQ(records.size(), 5u);
  const double truth = fileL00();
  for (const auto& j : records) EXPECT_NEAR(l00(j), truth, 1e-4 * truth) << j.dump();
  // Plain HTTP to it is no camera: one line, exit 1.
  const auto plain = live(camera.url, "--frames 2 --timeout 2", tmp / "plain.jsonl");
  EXPECT_EQ(plain.exitCode, 1) << plain.output;
  EXPECT_EQ(lpt::lineCount(plain.output), 1) << plain.output;
}

TEST(Network, ACameraThatDropsCostsNoRunAndNoFrameCount) {
  // The camera sends 10 frames, goes away (its port closed) for 1.5 s, and comes back; twice.
  Camera camera({"--fps", "20", "--drop-after", "10", "--down", "1.5"});
  lpt::TempDir tmp;
  const auto r =
      live(camera.url, "--frames 25 --timeout 1 --reconnect 0.5 --record " + tmp / "kept.mkv",
           tmp / "net.jsonl");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("; reconnecting (waiting up to 0.5 s between tries)"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find(": reconnected after "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(" reconnect"), std::string::npos) << r.output;
  const auto records = readJsonl(tmp / "net.jsonl");
  ASSERT_EQ(records.size(), 25u) << r.output;  // --frames N is N frames, across the drops
  std::uint64_t last = 0;
  bool first = true, reconnected = false;
  for (const auto& j : records) {
    const std::uint64_t seq = j["sequence"].get<std::uint64_t>();
    if (!first) EXPECT_GT(seq, last) << "a frame twice across a reconnect";
    first = false;
    last = seq;
    reconnected |= j.value("reconnects", 0) > 0;
  }
  EXPECT_TRUE(reconnected) << "no record says it came after a reconnect";
  // The recording keeps the frames captured, each once, in their order at the source.
  std::ifstream sidecar(tmp / "kept.mkv.json");
  const auto kept = nlohmann::json::parse(sidecar)["sequences"];
  ASSERT_EQ(kept.size(), records.size());
  for (std::size_t i = 0; i < kept.size(); ++i)
    EXPECT_EQ(kept[i].get<std::uint64_t>(), records[i]["sequence"].get<std::uint64_t>());
  // --reconnect 0: the run ends where the stream does, saying why, and fails.
  Camera again({"--fps", "20", "--drop-after", "5", "--down", "30"});
  const auto ended = live(again.url, "--frames 25 --timeout 1 --reconnect 0", tmp / "ended.jsonl");
  EXPECT_NE(ended.output.find(again.url + ": the connection dropped"), std::string::npos)
      << ended.output;
  EXPECT_NE(ended.exitCode, 0) << ended.output;
  EXPECT_EQ(ended.output.find("reconnecting"), std::string::npos) << ended.output;
}

// While the stream is gone, the source says so to whoever asks (the HUD shows it, the lighting
// held), from another thread than the one waiting for its next frame; once back, nothing.
TEST(Network, WhileReconnectingTheSourceSaysWhatItWaits) {
  Camera camera({"--fps", "20", "--drop-after", "5", "--down", "1"});
  lp::NetworkSettings s;
  s.url = camera.url;
  s.timeoutMs = 1000;
  s.reconnectSeconds = 0.25;
  auto source = lp::openNetwork(s);
  std::atomic<bool> done{false};
  std::thread reader([&] {
    lp::Frame f;
    for (int i = 0; i < 9; ++i) EXPECT_TRUE(source->next(f)) << "frame " << i;
    done = true;
  });
  std::string said;
  while (!done) {
    if (const std::string w = source->waitingFor(); !w.empty()) said = w;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  reader.join();
  EXPECT_EQ(said.rfind("reconnecting for ", 0), 0u) << said;
  EXPECT_NE(said.find(": connection refused"), std::string::npos) << said;  // its port is closed
  EXPECT_EQ(source->waitingFor(), "");
  EXPECT_EQ(source->reconnects(), 1u);
}

TEST(Network, AStalledCameraIsReopened) {
  // The camera keeps the connection but sends nothing after 6 frames: a stall, not an end.
  Camera camera({"--fps", "20", "--silent-after", "6"});
  lpt::TempDir tmp;
  const auto r = live(camera.url, "--frames 10 --timeout 0.5 --reconnect 0.5", tmp / "net.jsonl");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find(": no frame for 0.5 s; reconnecting"), std::string::npos) << r.output;
  EXPECT_EQ(readJsonl(tmp / "net.jsonl").size(), 10u);
}

/// Seconds `liveprobe args` took, with its result.
std::pair<double, lpt::RunResult> timed(const std::string& args) {
  const auto t0 = std::chrono::steady_clock::now();
  auto r = runLiveprobe(args);
  return {std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), r};
}

TEST(Network, WhatNothingAnswersIsOneLineWithinTheTimeout) {
  // A port that accepts connections (the kernel completes them) but never answers.
  const int mute = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(mute, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  ASSERT_EQ(::listen(mute, 8), 0);
  socklen_t n = sizeof a;
  ::getsockname(mute, reinterpret_cast<sockaddr*>(&a), &n);
  const std::string port = std::to_string(ntohs(a.sin_port));
  for (const std::string& url :
       {"http://127.0.0.1:" + port + "/", "rtsp://127.0.0.1:" + port + "/x"}) {
    const auto [seconds, r] = timed("live " + url + " --frames 3 --headless --timeout 1");
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find(url + ": timed out (nothing within 1 s)"), std::string::npos)
        << r.output;
    // Connecting, then reading the stream's header: each waits at most the timeout; the rest is
    // the process starting on a loaded machine.
    EXPECT_LT(seconds, 6.0) << r.output;
  }
  ::close(mute);
  // Nothing listening: refused at once.
  const std::string closed = "http://127.0.0.1:" + std::to_string(lpt::freePort()) + "/";
  const auto [seconds, r] = timed("live " + closed + " --frames 3 --headless --timeout 1");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.output.find(closed + ": connection refused"), std::string::npos) << r.output;
  EXPECT_LT(seconds, 6.0);
  // What only a V4L2 camera is asked is refused for a URL, in one line.
  const auto bracket = runLiveprobe("live " + closed + " --bracket -6,0 --headless");
  EXPECT_EQ(bracket.exitCode, 1);
  EXPECT_NE(bracket.output.find("--bracket needs a V4L2 camera's exposure control"),
            std::string::npos)
      << bracket.output;
}

/// Each record's L00 is that of some frame of the file (within 1e-3), and those frames come in
/// the file's order (the video has B-frames: decoding order is not showing order); returns the
/// worst.
double worstAgainstTheFile(const std::vector<nlohmann::json>& records,
                           const std::vector<nlohmann::json>& truth) {
  double worst = 0;
  long last = -1;
  for (const auto& j : records) {
    double best = 1e9;
    long at = -1;
    for (std::size_t i = 0; i < truth.size(); ++i)
      if (const double d = std::abs(l00(j) - l00(truth[i])) / l00(truth[i]); d < best)
        best = d, at = long(i);
    EXPECT_LT(best, 1e-3) << "no frame of the file has this record's L00: " << j.dump();
    EXPECT_GT(at, last) << "frame " << at << " of the file after frame " << last;
    last = at;
    worst = std::max(worst, best);
  }
  return worst;
}

/// `live URL` until it gives `frames` records (a server a moment from listening is tried again).
std::vector<nlohmann::json> liveRecords(const std::string& url, const std::string& options,
                                        const std::string& out, std::size_t frames) {
  lpt::RunResult r{-1, {}};
  for (int tries = 0; tries < 5 && r.exitCode != 0; ++tries)
    r = live(url, options + " --frames " + std::to_string(frames) + " --timeout 3 --reconnect 0",
             out);
  EXPECT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("h264 1920x1080"), std::string::npos) << r.output;
  auto records = readJsonl(out);
  EXPECT_EQ(records.size(), frames) << r.output;
  return records;
}

// An RTSP camera that asks for a password (RTSP Basic authentication, GStreamer's RTSPAuth): the
// URL's credentials play it, none or wrong ones are one line naming it unauthorized, and the
// password is shown nowhere.
TEST(Network, AnRtspCameraWithAPasswordTakesItAndNeverShowsIt) {
  const std::string secret = "rtsp-secret-7";
  ServerProcess rtsp({"/usr/bin/python3",
                      std::string(LIVEPROBE_SOURCE_DIR) + "/tests/scripts/rtsp_server.py",
                      lpt::dataPath("video/pano.mp4"), "/cam", "--auth", "viewer:" + secret});
  const std::string port = rtsp.firstLine();
  ASSERT_FALSE(port.empty()) << "the RTSP server did not start";
  lpt::TempDir tmp;
  const std::string at = "127.0.0.1:" + port + "/cam";
  const auto r = live("rtsp://viewer:" + secret + "@" + at,
                      "--frames 3 --timeout 3 --reconnect 0 --view-size 64x32", tmp / "ok.jsonl");
  EXPECT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("rtsp://viewer:***@" + at), std::string::npos) << r.output;
  EXPECT_EQ(readJsonl(tmp / "ok.jsonl").size(), 3u);
  for (const std::string credentials : {"", "viewer:wrong@"}) {
    const auto refused =
        live("rtsp://" + credentials + at, "--frames 3 --timeout 3", tmp / "refused.jsonl");
    EXPECT_EQ(refused.exitCode, 1) << refused.output;
    EXPECT_EQ(lpt::lineCount(refused.output), 1) << refused.output;
    EXPECT_NE(refused.output.find("unauthorized"), std::string::npos) << refused.output;
    EXPECT_FALSE(std::filesystem::exists(tmp / "refused.jsonl"));
  }
  std::ifstream records(tmp / "ok.jsonl");
  const std::string written((std::istreambuf_iterator<char>(records)), {});
  for (const std::string* out : {&r.output, &written})
    EXPECT_EQ(out->find(secret), std::string::npos) << *out;
}

TEST(Network, HttpRtspAndSrtGiveTheFilesFramesCoefficients) {
  // The H.264 file as it is (no re-encoding), at its own rate: GStreamer's RTSP server (Debian's
  // python3-gi, hence /usr/bin/python3), and FFmpeg's SRT listener.
  const std::string video = lpt::dataPath("video/pano.mp4");
  lpt::TempDir tmp;
  // Every frame of the file, as replay reads it (OpenCV's FFmpeg); drawn small, as only the
  // coefficients are compared.
  const auto file =
      runLiveprobe("replay " + shellQuote(video) +
                   " --layout equirect --headless --size 64x32 --coeffs-out " + tmp / "file.jsonl");
  ASSERT_EQ(file.exitCode, 0) << file.output;
  const auto truth = readJsonl(tmp / "file.jsonl");
  ASSERT_GE(truth.size(), 180u);

  // The file itself on a web server: replay reads it frame by frame, as from the disk.
  ServerProcess web({"python3", std::string(LIVEPROBE_SOURCE_DIR) + "/tests/scripts/web_server.py",
                     std::filesystem::path(video).parent_path().string()});
  const std::string webPort = web.firstLine();
  ASSERT_FALSE(webPort.empty()) << "the web server did not start";
  const std::string webUrl = "http://127.0.0.1:" + webPort + "/pano.mp4";
  const auto replayed =
      runLiveprobe("replay " + webUrl + " --layout equirect --headless --size 64x32 --coeffs-out " +
                   tmp / "web.jsonl");
  ASSERT_EQ(replayed.exitCode, 0) << replayed.output;
  const auto fromWeb = readJsonl(tmp / "web.jsonl");
  ASSERT_EQ(fromWeb.size(), truth.size()) << replayed.output;
  for (std::size_t i = 0; i < truth.size(); ++i)
    EXPECT_NEAR(l00(fromWeb[i]), l00(truth[i]), 1e-6 * l00(truth[i])) << "frame " << i;

  ServerProcess rtsp({"/usr/bin/python3",
                      std::string(LIVEPROBE_SOURCE_DIR) + "/tests/scripts/rtsp_server.py", video});
  const std::string port = rtsp.firstLine();
  ASSERT_FALSE(port.empty()) << "the RTSP server did not start";
  const std::string rtspUrl = "rtsp://127.0.0.1:" + port + "/stream";
  for (const std::string transport : {"tcp", "udp"}) {
    const auto records =
        liveRecords(rtspUrl, "--rtsp-transport " + transport, tmp / (transport + ".jsonl"), 15);
    std::printf("RTSP over %s: the worst record is %.2g of L00 from its nearest frame\n",
                transport.c_str(), worstAgainstTheFile(records, truth));
  }

  const std::string srtUrl = "srt://127.0.0.1:" + std::to_string(lpt::freePort(SOCK_DGRAM));
  ServerProcess ffmpeg({"sh", "-c",
                        "echo ready; exec ffmpeg -loglevel fatal -re -i " + shellQuote(video) +
                            " -c copy -f mpegts '" + srtUrl + "?mode=listener' </dev/null"});
  ASSERT_EQ(ffmpeg.firstLine(), "ready");
  const auto records = liveRecords(srtUrl, "", tmp / "srt.jsonl", 15);
  std::printf("SRT: the worst record is %.2g of L00 from its nearest frame\n",
              worstAgainstTheFile(records, truth));
}

}  // namespace
