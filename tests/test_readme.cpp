// Every command example in README.md and the manual (docs/*.md) runs as written, so they cannot
// drift from the program. An example is a line starting with `liveprobe ` inside a ```sh block (a
// trailing backslash continues it). It runs with `liveprobe` on PATH, from a working folder where
// data/ (the test data, wherever LIVEPROBE_DATA_DIR is) and recordings/ resolve as they do from
// the source tree, under Xvfb (so the window path is taken, as on a desktop), and for `live` and
// `calibrate` against the emulated camera (tests/v4l2emu) standing in for the device it names
// (bracketing and calibration with its metadata node, a control delay of two frames, and the
// synthetic sky's HDR frames); `live` of a network camera against a server on 127.0.0.1 standing
// in for the one its URL names (http: the motion-JPEG camera of tests/scripts serving the
// mirror-ball JPEG of recordings/ball; rtsp: GStreamer's RTSP server streaming the 360 video
// data/video/pano.mp4), the URL's host and port made that server's. It must exit 0, or with the
// status a trailing "# exits N" gives; one marked "# runs until Esc or Ctrl-C" must still be
// running after a few seconds, and then stop cleanly on SIGINT (exit 130).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <regex>
#include <set>
#include <sstream>

#include "server_process.h"
#include "sky_frames.h"
#include "test_util.h"

namespace {

namespace fs = std::filesystem;

struct Example {
  std::string file;  ///< relative to the source folder: README.md, docs/NAME.md
  int line = 0;
  std::string command;
  int exitCode = 0;
  bool endless = false;
};

/// README.md, then docs/*.md in name order.
std::vector<std::string> manualFiles() {
  std::vector<std::string> files;
  for (const auto& f : fs::directory_iterator(std::string(LIVEPROBE_SOURCE_DIR) + "/docs"))
    if (f.path().extension() == ".md") files.push_back("docs/" + f.path().filename().string());
  std::sort(files.begin(), files.end());
  files.insert(files.begin(), "README.md");
  return files;
}

std::vector<Example> examplesIn(const std::string& file) {
  std::ifstream in(std::string(LIVEPROBE_SOURCE_DIR) + "/" + file);
  std::vector<Example> out;
  bool sh = false;
  std::string pending;
  int pendingLine = 0, n = 0;
  for (std::string line; std::getline(in, line);) {
    ++n;
    if (line.rfind("```", 0) == 0) {
      sh = line == "```sh";
      continue;
    }
    if (!sh) continue;
    if (pending.empty()) pendingLine = n;
    if (!line.empty() && line.back() == '\\') {
      pending += line.substr(0, line.size() - 1) + " ";
      continue;
    }
    const std::string full = pending + line;
    pending.clear();
    if (full.rfind("liveprobe ", 0) != 0) continue;
    Example e;
    e.file = file;
    e.line = pendingLine;
    e.command = full;
    std::smatch m;
    if (std::regex_search(full, m, std::regex(R"(#\s*exits (\d+))"))) e.exitCode = std::stoi(m[1]);
    e.endless = full.find("# runs until") != std::string::npos;
    e.command =
        std::regex_replace(full, std::regex(R"(\s+#.*$)"), "");  // the comment is for the reader
    out.push_back(e);
  }
  return out;
}

/// Every example of the manual; a command written twice (the front page repeats the reference)
/// runs once, under its first place.
std::vector<Example> readmeExamples() {
  std::vector<Example> all;
  std::set<std::string> seen;
  for (const auto& file : manualFiles())
    for (const auto& e : examplesIn(file))
      if (seen.insert(e.command).second) all.push_back(e);
  return all;
}

void PrintTo(const Example& e, std::ostream* os) {
  *os << e.file << ":" << e.line << ": " << e.command;
}

class ReadmeExample : public ::testing::TestWithParam<Example> {};

// The emulated camera's modes: an MJPEG equirect sky at the sizes the README's live examples ask,
// and the largest also as H.264 (the emulator encodes the PNGs); for a mirror ball, the 1280x720
// frames are the camera JPEG of a chrome ball in recordings/ball.
void makeCameraModes(const fs::path& dir, bool ball) {
  for (const auto& [w, h] : {std::pair{1920, 960}, std::pair{1280, 720}, std::pair{640, 480}})
    for (const std::string format : {"MJPG", "H264"}) {
      if (format == "H264" && w != 1920) continue;
      const fs::path m = dir / (format + "_" + std::to_string(w) + "x" + std::to_string(h));
      fs::create_directories(m);
      if (ball && w == 1280) {
        for (int i = 0; i < 4; ++i)
          fs::copy_file(fs::path(LIVEPROBE_SOURCE_DIR) / "recordings/ball/ball.jpg",
                        m / (std::to_string(i) + ".jpg"));
        continue;
      }
      for (int i = 0; i < 4; ++i)
        ASSERT_TRUE(
            cv::imwrite((m / (std::to_string(i) + (format == "MJPG" ? ".jpg" : ".png"))).string(),
                        lpt::skyFrame8(w, h, i * 0.3)));
    }
}

// For bracketing and calibration: the synthetic sky's HDR frames (the camera renders them as an
// 8-bit sensor would), all of them, or one for a still scene.
void makeHdrModes(const fs::path& dir, bool still) {
  const fs::path m = dir / "MJPG_256x128";
  fs::create_directories(m);
  for (int i = still ? 30 : 0; i < (still ? 31 : 75); ++i) {
    char name[16];
    std::snprintf(name, sizeof name, "%04d.exr", i);
    fs::create_symlink(fs::path(LIVEPROBE_SOURCE_DIR) / "recordings/sky-hdr" / name, m / name);
  }
}

TEST_P(ReadmeExample, RunsAsWritten) {
  const Example& e = GetParam();
  lpt::TempDir tmp;
  // tmp/work/data -> the test data; tmp/work/recordings/* -> the project's recordings (links, so
  // an example that records there replaces the link, never the file, and the test sees it).
  const fs::path work = tmp.path / "work";
  fs::create_directories(work / "recordings");
  fs::create_directory_symlink(fs::absolute(fs::path(LIVEPROBE_DATA_DIR)), work / "data");
  for (const auto& f : fs::directory_iterator(std::string(LIVEPROBE_SOURCE_DIR) + "/recordings"))
    fs::create_symlink(f.path(), work / "recordings" / f.path().filename());
  ASSERT_TRUE(fs::exists(work / "data/equirect")) << "the README's data paths must resolve";

  std::string env = "export PATH=" + fs::path(LIVEPROBE_BIN).parent_path().string() + ":$PATH; ";
  // A bench compared with its baseline times its stages between glFinish calls. On llvmpipe each
  // one waits for the rasterizer's threads to wake: beside the suite's load that wait, not the
  // upload's 0.2 ms, sets the upload stage (single runs' medians 1.8 to 12 ms beside stress-ng),
  // and the example's verdict would be the scheduler's. Rasterizing on the calling thread
  // (LP_NUM_THREADS=0), upload reads 0.17 to 0.21 ms beside the same load.
  // (An example that makes its own baseline; one against the project's keeps the threads the
  // baseline was made with.)
  if (e.command.find("bench --json") != std::string::npos &&
      e.command.find("--baseline") != std::string::npos)
    env += "export LP_NUM_THREADS=0; ";
  std::smatch m;
  if (std::regex_search(e.command, m,
                        std::regex(R"(^liveprobe (live|calibrate) /dev/video(\d+))"))) {
    const bool hdr = m[1] == "calibrate" || e.command.find("--bracket") != std::string::npos;
    if (hdr)
      makeHdrModes(tmp.path / "modes", m[1] == "calibrate");
    else
      makeCameraModes(tmp.path / "modes",
                      e.command.find("--layout mirrorball") != std::string::npos);
    env += "export LD_PRELOAD=" + std::string(LIVEPROBE_EMU) + " LPEMU_DEVICE=/dev/video" +
           m[2].str() + " LPEMU_SOURCE=" + (tmp.path / "modes").string() +
           (hdr ? " LPEMU_META_DEVICE=/dev/video" + std::to_string(std::stoi(m[2]) + 1) +
                      " LPEMU_FAULTS=control_delay=2"
                : std::string()) +
           "; ";
  }
  // A network camera: a server on 127.0.0.1 stands in for the one the URL names.
  std::string command = e.command;
  std::unique_ptr<lpt::ServerProcess> server;
  if (std::regex_search(
          command, m, std::regex(R"(^liveprobe live (http|rtsp)://([^@/ ]*@)?[^/ ]+(/[^ ?]*))"))) {
    const std::string scripts = std::string(LIVEPROBE_SOURCE_DIR) + "/tests/scripts/";
    server = std::make_unique<lpt::ServerProcess>(
        m[1] == "http" ? std::vector<std::string>{"python3", scripts + "mjpeg_camera.py",
                                                  std::string(LIVEPROBE_SOURCE_DIR) +
                                                      "/recordings/ball/ball.jpg"}
                       : std::vector<std::string>{
                             "/usr/bin/python3", scripts + "rtsp_server.py",
                             std::string(LIVEPROBE_DATA_DIR) + "/video/pano.mp4", m[3].str()});
    const std::string port = server->firstLine();
    ASSERT_FALSE(port.empty()) << "no server for " << e.command;
    command = "liveprobe live " + m[1].str() + "://" + m[2].str() + "127.0.0.1:" + port +
              command.substr(std::size_t(m.position(3)));
  }
  const std::string run = e.endless ? env + command +
                                          " & pid=$!; sleep 6; kill -0 $pid 2>/dev/null && echo "
                                          "still-running; kill -INT $pid; wait $pid; echo rc=$?"
                                    : env + command + "\necho rc=$?";
  const std::string cmd = "cd " + lpt::shellQuote(work.string()) + " && timeout -k 10 400 " +
                          lpt::xvfbRun("1600x1000x24") + "bash -c " + lpt::shellQuote(run);
  const std::string out = lpt::runCommand(cmd).output;
  const std::string where = e.file + ":" + std::to_string(e.line) + ": " + e.command + "\n" + out;
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(rc=(\d+))"))) << where;
  if (e.endless) {
    EXPECT_NE(out.find("still-running"), std::string::npos)
        << "ended before it was stopped: " << where;
    EXPECT_EQ(std::stoi(m[1]), 130) << "no clean stop on SIGINT: " << where;
  } else {
    EXPECT_EQ(std::stoi(m[1]), e.exitCode) << where;
  }
  // An example pasted into a checkout writes nothing the project tracks.
  for (const auto& f : fs::directory_iterator(work / "recordings"))
    EXPECT_TRUE(fs::is_symlink(f.symlink_status())) << f.path() << " was written: " << where;
}

std::string exampleName(const ::testing::TestParamInfo<Example>& info) {
  std::string word;  // the subcommand
  std::istringstream(info.param.command) >> word >> word;
  for (char& c : word)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  std::string file = fs::path(info.param.file).stem().string();  // README, commands, live-camera
  for (char& c : file)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return file + "_line" + std::to_string(info.param.line) + "_" + word;
}

INSTANTIATE_TEST_SUITE_P(Readme, ReadmeExample, ::testing::ValuesIn(readmeExamples()), exampleName);

// The manual has examples for every command (so a command cannot lose its example).
TEST(Readme, EveryCommandHasAnExample) {
  std::set<std::string> seen;
  for (const auto& e : readmeExamples()) {
    std::string word;
    std::istringstream(e.command) >> word >> word;
    seen.insert(word);
  }
  for (const char* c : {"coeffs", "irradiance", "compare", "render", "view", "replay", "record",
                        "live", "devices", "calibrate", "bench"})
    EXPECT_TRUE(seen.count(c)) << "neither README.md nor docs/ has an example of liveprobe " << c;
}

}  // namespace
