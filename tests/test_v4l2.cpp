// The V4L2 source's verbs and states, in process, against the emulated camera (tests/v4l2emu):
// main() makes the camera's frames, then runs this binary again with the emulator preloaded.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "liveprobe/capture/v4l2.h"
#include "liveprobe/sh/error.h"
#include "sky_frames.h"

namespace {

using State = lp::V4l2Source::State;

lp::CameraSettings camera() {
  lp::CameraSettings s;
  s.device = "/dev/video7";
  s.format = lp::CameraFormat::Yuyv;
  return s;
}

std::string emuLog() {
  std::ifstream in(std::getenv("LPEMU_LOG"));
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

// A verb in the wrong state is refused in one line that names the state it needs.
void expectRefused(const std::function<void()>& verb, const std::string& needs) {
  try {
    verb();
    ADD_FAILURE() << "accepted; expected a refusal that needs the source " << needs;
  } catch (const lp::Error& e) {
    EXPECT_NE(std::string(e.what()).find("needs the source " + needs), std::string::npos)
        << e.what();
  }
}

TEST(V4l2Verbs, EachVerbMovesOneStateAndNeedsTheOneBefore) {
  lp::V4l2Source src(camera());
  EXPECT_EQ(src.state(), State::Closed);
  expectRefused([&] { src.setFormat(); }, "open");
  expectRefused([&] { src.streamOn(); }, "ready");
  src.open();
  EXPECT_EQ(src.state(), State::Open);
  expectRefused([&] { src.allocateBuffers(); }, "configured");
  src.setFormat();
  EXPECT_EQ(src.state(), State::Configured);
  EXPECT_EQ(src.width(), 128);
  src.allocateBuffers();
  EXPECT_EQ(src.state(), State::Ready);
  expectRefused([&] { src.setFormat(); }, "open");  // the driver would say EBUSY too
  lp::Frame f;
  expectRefused([&] { src.next(f); }, "streaming");
  src.streamOn();
  EXPECT_EQ(src.state(), State::Streaming);
  ASSERT_TRUE(src.next(f));
  EXPECT_EQ(f.width, 128);
  src.streamOff();
  src.streamOff();  // idempotent
  EXPECT_EQ(src.state(), State::Ready);
  src.close();
  src.close();  // idempotent
  EXPECT_EQ(src.state(), State::Closed);
  EXPECT_NE(emuLog().find("close mapped=0 buffers=0 streaming=0"), std::string::npos) << emuLog();
}

// Stop and start again: the same buffers stream again, frames keep coming with rising sequence
// numbers, and the frames the driver did not send while stopped are not counted as dropped.
TEST(V4l2Verbs, AStoppedSourceStreamsAgain) {
  const std::string before = emuLog();
  lp::V4l2Source src(camera());
  src.start();
  lp::Frame f;
  std::uint64_t last = 0;
  for (int round = 0; round < 3; ++round) {
    for (int i = 0; i < 3; ++i) {
      ASSERT_TRUE(src.next(f)) << "round " << round;
      if (round > 0 || i > 0) {
        EXPECT_GT(f.sequence, last);
      }
      last = f.sequence;
    }
    src.streamOff();
    EXPECT_EQ(src.state(), State::Ready);
    usleep(150000);  // the camera would have sent ~4 frames meanwhile
    if (round < 2) src.streamOn();
  }
  EXPECT_EQ(src.skippedFrames(), 0u);
  src.close();
  const std::string log = emuLog().substr(before.size());
  EXPECT_EQ(count(log, "STREAMON"), 3u) << log;
  EXPECT_EQ(count(log, "STREAMOFF"), 3u) << log;
  EXPECT_EQ(count(log, "REQBUFS 0"), 1u) << log;  // buffers kept across the restarts
  // A closed source opens again from the start.
  src.start();
  ASSERT_TRUE(src.next(f));
  src.close();
}

// Per-frame metadata: the driver's absolute CLOCK_MONOTONIC timestamp (so latency can be
// measured against clock_gettime), and the exposure in force for that frame.
TEST(V4l2Verbs, FramesCarryTheirCaptureTimeAndExposure) {
  lp::V4l2Source src(camera());
  src.start();
  lp::Frame f;
  ASSERT_TRUE(src.next(f));
  const double age = lp::monotonicSeconds() - f.captureTime;
  EXPECT_GE(age, 0.0);
  EXPECT_LT(age, 0.5);
  ASSERT_TRUE(f.exposure100us.has_value());
  EXPECT_GT(*f.exposure100us, 0);
  EXPECT_DOUBLE_EQ(f.radianceScale, 1.0 / (*f.exposure100us * 1e-4));
  src.close();
}

}  // namespace

int main(int argc, char** argv) {
  if (!std::getenv("LPEMU_SOURCE")) {
    // First run: make the camera's frames, then run this binary again with the emulator
    // preloaded (it reads its configuration from the environment when it loads).
    const auto dir =
        std::filesystem::temp_directory_path() / ("liveprobe-v4l2-" + std::to_string(::getpid()));
    lpt::makeModes(dir / "modes", {"YUYV_128x64"}, 6);
    ::setenv("LPEMU_SOURCE", (dir / "modes").c_str(), 1);
    ::setenv("LPEMU_DEVICE", "/dev/video7", 1);
    ::setenv("LPEMU_LOG", (dir / "emu.log").c_str(), 1);
    ::setenv("LD_PRELOAD", LIVEPROBE_EMU, 1);
    const pid_t child = ::fork();
    if (child == 0) {
      ::execv("/proc/self/exe", argv);
      std::perror("execv /proc/self/exe");
      ::_exit(127);
    }
    int status = 0;
    ::waitpid(child, &status, 0);
    std::filesystem::remove_all(dir);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 1;
  }
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
