// Hostile input: what a user types or feeds never crashes, hangs or leaves debris.
// Each case asserts the three things: exit status 1, one line that names the input and the
// fault, and nothing left behind in the output folder. Commands run under `timeout`, so a hang
// fails the test (exit 124) instead of stalling the suite.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "liveprobe/backends.h"
#include "liveprobe/frame/frame.h"
#if LIVEPROBE_WITH_V4L2
#include <linux/videodev2.h>

#include "liveprobe/capture/v4l2.h"
#endif
#include "test_util.h"

namespace {

namespace fs = std::filesystem;

std::set<std::string> listing(const fs::path& dir) {
  std::set<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) out.insert(e.path().filename().string());
  return out;
}

// Runs `liveprobe ARGS` in `dir` and checks the three promises.
void expectRefused(const lpt::TempDir& dir, const std::string& args, const std::string& names,
                   const std::string& says) {
  const auto before = listing(dir.path);
  const auto r = lpt::runCommand("cd " + lpt::shellQuote(dir.path.string()) + " && timeout 20 " +
                                 LIVEPROBE_BIN + " " + args);
  EXPECT_EQ(r.exitCode, 1) << args << "\n" << r.output;
  EXPECT_EQ(lpt::lineCount(r.output), 1) << args << "\n" << r.output;
  EXPECT_NE(r.output.find(names), std::string::npos) << args << "\n" << r.output;
  EXPECT_NE(r.output.find(says), std::string::npos) << args << "\n" << r.output;
  EXPECT_EQ(listing(dir.path), before) << args << ": left files behind";
}

// A path is never a printf format: %s and %n in it crash nothing, %% does not list one file
// millions of times. Only %d and %0Nd make a sequence, parsed by liveprobe itself.
TEST(Hostile, PathsAreNeverFormatStrings) {
  lpt::TempDir tmp;
  for (const char* name : {"%s.png", "%n%n%n.png", "%%.png", "f_%5$d.png", "f_%d_%d.png"})
    expectRefused(tmp, std::string("coeffs ") + lpt::shellQuote(name), name, "no such file");
  for (const char* name : {"%s.png", "%n.png", "%%d.png"})
    expectRefused(tmp, std::string("replay --headless --frames 1 ") + lpt::shellQuote(name), name,
                  "no such file");
}

// The two patterns that are sequences still are: frames numbered from 0 or 1, zero-padded or not.
TEST(Hostile, FrameNumberPatternsStillWork) {
  lpt::TempDir tmp;
  for (int i = 1; i <= 3; ++i)
    ASSERT_TRUE(cv::imwrite(tmp / ("f_00" + std::to_string(i) + ".png"),
                            cv::Mat(32, 64, CV_8UC3, cv::Scalar(40 * i, 50, 60))));
  const auto r = lpt::runLiveprobe("replay " + lpt::shellQuote(tmp / "f_%03d.png") +
                                   " --headless --quiet --coeffs-out " + (tmp / "c.jsonl"));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  std::ifstream in(tmp / "c.jsonl");
  int lines = 0;
  for (std::string l; std::getline(in, l);) ++lines;
  EXPECT_EQ(lines, 3);
}

// A FIFO given as any input is refused before it is opened (open() would block forever).
TEST(Hostile, FifoInputsAreRefused) {
  lpt::TempDir tmp;
  const std::string fifo = tmp / "pipe.hdr";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string json = tmp / "pipe.json", mp4 = tmp / "pipe.mp4", obj = tmp / "pipe.obj";
  for (const auto& f : {json, mp4, obj}) ASSERT_EQ(::mkfifo(f.c_str(), 0600), 0);
  expectRefused(tmp, "coeffs " + fifo, fifo, "FIFO");
  expectRefused(tmp, "render --headless --out r.png --coeffs " + json, json, "FIFO");
  expectRefused(tmp, "render --headless --out r.png --coeff L00=1 --model " + obj, obj, "FIFO");
  expectRefused(tmp, "replay --headless --frames 1 " + mp4, mp4, "FIFO");
  expectRefused(tmp, "record " + mp4 + " --out out.mkv", mp4, "FIFO");
  expectRefused(tmp, "bench --frames 1 --repeat 1 --baseline " + json, json, "FIFO");
  expectRefused(tmp, "coeffs " + tmp.path.string(), tmp.path.string(), "no image files");
}

// Sizes in a synthetic source are parsed whole and range-checked: nothing wraps around.
TEST(Hostile, SyntheticSizesDoNotWrap) {
  lpt::TempDir tmp;
  for (const char* spec : {"synthetic:4294967552x128", "synthetic:64x32@-5", "synthetic:64x32x",
                           "synthetic:1e3x64", "synthetic:64x32@30junk"})
    expectRefused(tmp, std::string("replay --headless --frames 1 ") + spec, spec,
                  "expected synthetic");
}

// A recording's rate is validated before anything is written.
TEST(Hostile, RecordRatesOutOfRange) {
  lpt::TempDir tmp;
  for (const char* fps : {"-1", "0", "1e-9", "5000", "nan"})
    expectRefused(tmp, std::string("record synthetic:64x32 --out out.mkv --fps ") + fps, "--fps",
                  fps);
}

// Every write is checked, stdout's included: a full disk is an error, not a silent exit 0, and
// it is named as one whatever the output's size (a glTF with its picture is 85 kB).
TEST(Hostile, FullStdoutIsAnError) {
  for (const char* format : {"text", "gltf"}) {
    const auto r = lpt::runCommand("( " + std::string(LIVEPROBE_BIN) + " coeffs " +
                                   lpt::dataPath("probes/latlong_256x128/grace.hdr") +
                                   " --format " + format + " > /dev/full )");
    EXPECT_EQ(r.exitCode, 1) << format << ": " << r.output;
    EXPECT_EQ(lpt::lineCount(r.output), 1) << format << ": " << r.output;
    EXPECT_NE(r.output.find("standard output: no space left"), std::string::npos)
        << format << ": " << r.output;
  }
}

// A name the file system cannot hold is refused in one line naming the user's file and the
// limit, for a file written whole and for a recording's frames (written in a hidden folder
// first); a name that fits to the byte is written (its temporary's name is cut to fit).
TEST(Hostile, NamesAtTheFileSystemsLimit) {
  lpt::TempDir tmp;
  const std::size_t max = std::size_t(::pathconf(tmp.path.c_str(), _PC_NAME_MAX));
  ASSERT_GT(max, 16u);
  const std::string fits = std::string(max - 4, 'a') + ".png";
  auto r = lpt::runCommand("cd " + lpt::shellQuote(tmp.path.string()) + " && " + LIVEPROBE_BIN +
                           " render --coeff L00=1 --size 16x16 --out " + fits);
  EXPECT_EQ(r.exitCode, 0) << r.output;
  EXPECT_TRUE(fs::exists(tmp.path / fits)) << r.output;
  fs::remove(tmp.path / fits);
  const std::string over = std::string(max - 3, 'a') + ".png";
  expectRefused(tmp, "render --coeff L00=1 --size 16x16 --out " + over, over,
                "the file name is too long (" + std::to_string(max + 1) + " bytes");
  // Frames whose names take the limit exactly, then one byte more.
  r = lpt::runCommand("cd " + lpt::shellQuote(tmp.path.string()) + " && " + LIVEPROBE_BIN +
                      " record synthetic:64x32 --frames 2 --out " + std::string(max - 9, 'c') +
                      "_%04d.exr");
  EXPECT_EQ(r.exitCode, 0) << r.output;
  EXPECT_TRUE(fs::exists(tmp.path / (std::string(max - 9, 'c') + "_0001.exr"))) << r.output;
  fs::remove_all(tmp.path);
  fs::create_directories(tmp.path);
  const std::string stem = std::string(max - 8, 'c');
  expectRefused(tmp, "record synthetic:64x32 --frames 2 --out " + stem + "_%04d.exr",
                stem + "_0000.exr", "the file name is too long");
}

// JSON inputs are read whole: text after the value is an error, not ignored.
TEST(Hostile, TrailingTextAfterJsonIsRefused) {
  lpt::TempDir tmp;
  const auto r = lpt::runLiveprobe("coeffs " + lpt::dataPath("probes/latlong_256x128/grace.hdr") +
                                   " --format json > " + (tmp / "c.json"));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  std::ofstream(tmp / "c.json", std::ios::app) << "junk\n";
  expectRefused(tmp, "render --headless --out r.png --coeffs c.json", "c.json", "not valid JSON");
  std::ofstream(tmp / "b.json") << R"({"calibration_ms": 1, "stages": {}} {"more": 1})";
  expectRefused(tmp, "bench --frames 1 --repeat 1 --baseline b.json", "b.json",
                "not a liveprobe bench JSON");
}

/// `record` of `frames` synthetic frames into DIR/rec.mkv; the text of its sidecar (empty, with a
/// test failure, where the recording failed).
std::string recordedSidecar(const lpt::TempDir& dir, int frames) {
  const auto r = lpt::runLiveprobe("record synthetic:64x32 --frames " + std::to_string(frames) +
                                   " --quiet --out " + (dir / "rec.mkv"));
  EXPECT_EQ(r.exitCode, 0) << r.output;
  std::ifstream in(dir / "rec.mkv.json");
  return {std::istreambuf_iterator<char>(in), {}};
}

// A recording's sidecar exposures divide its frames: zero, denormal, negative or non-numbers
// are refused, never turned into infinite or null coefficients.
TEST(Hostile, SidecarExposuresMustBePositiveAndFinite) {
  lpt::TempDir tmp;
  const std::string sidecar = recordedSidecar(tmp, 2);
  const auto at = sidecar.find("\"exposure\":");
  ASSERT_NE(at, std::string::npos) << sidecar;
  const auto end = sidecar.find(',', at);
  for (const char* bad : {"0", "1e-320", "-1", "\"x\""}) {
    std::ofstream(tmp / "rec.mkv.json")
        << sidecar.substr(0, at) << "\"exposure\":" << bad << sidecar.substr(end);
    expectRefused(tmp, "replay --headless --frames 1 rec.mkv", "rec.mkv.json", "exposure");
  }
}

// A bracketed recording's sidecar: a bracket of 1 to 5 frames, every frame's exposure (the merge
// weighs each frame by its own) and frame number (it turns older frames by their distance), and
// a camera response of three rising curves of 256 values.
TEST(Hostile, BracketSidecarsAreChecked) {
  lpt::TempDir tmp;
  const std::string sidecar = recordedSidecar(tmp, 3);
  ASSERT_FALSE(sidecar.empty());
  nlohmann::json good = nlohmann::json::parse(sidecar);
  ASSERT_EQ(good.at("timestamps").size(), 3u) << good.dump();
  good["bracket"] = 3;
  good["exposures"] = {0.001, 0.01, 0.1};
  nlohmann::json curve = nlohmann::json::array();
  for (int c = 0; c < 256; ++c) curve.push_back(c / 255.0);
  good["response"] = {curve, curve, curve};
  std::ofstream(tmp / "rec.mkv.json") << good.dump();
  const auto ok = lpt::runCommand("cd " + lpt::shellQuote(tmp.path.string()) + " && " +
                                  LIVEPROBE_BIN + " replay rec.mkv --headless --frames 3 --quiet");
  ASSERT_EQ(ok.exitCode, 0) << "the well-formed bracket replays: " << ok.output;
  struct Case {
    const char* field;
    nlohmann::json value;
    const char* says;
  };
  nlohmann::json falling = curve;
  falling[200] = 0.1;
  const Case cases[] = {
      {"bracket", 7, "not 1 to 5 frames"},
      {"bracket", 0, "not 1 to 5 frames"},
      {"exposures", {0.001, 0.01}, "one exposure per frame"},
      {"exposures", nullptr, "one exposure per frame"},
      {"response", {curve, curve}, "3 curves"},
      {"response", {curve, curve, {1, 2}}, "256 values"},
      {"response", {curve, curve, falling}, "response"},
      {"sequences", {4, 5}, "2 frame numbers for 3 timestamps"},
      {"sequences", {4, -5, 6}, "frame number -5 is not a whole number"},
      {"sequences", {4, 5.5, 6}, "frame number 5.5 is not a whole number"},
  };
  for (const Case& c : cases) {
    nlohmann::json bad = good;
    if (c.value.is_null())
      bad.erase(c.field);
    else
      bad[c.field] = c.value;
    std::ofstream(tmp / "rec.mkv.json") << bad.dump();
    expectRefused(tmp, "replay --headless --frames 3 rec.mkv", "rec.mkv", c.says);
  }
}

// assimp reads "nan" as a number; the OBJ's coordinates are checked before it sees them.
TEST(Hostile, ModelCoordinatesMustBeFinite) {
  lpt::TempDir tmp;
  for (const char* bad : {"nan", "inf", "1e999", "1.2.3"}) {
    std::ofstream(tmp / "t.obj") << "v 0 0 0\nv 1 0 " << bad << "\nv 0 1 0\nf 1 2 3\n";
    expectRefused(tmp, "render --headless --out r.png --coeff L00=1 --model t.obj", "t.obj",
                  "not a finite number");
  }
}

// Five of six cube faces is a cube with a face missing, not an image sequence.
TEST(Hostile, MissingCubeFaceIsNamed) {
  lpt::TempDir tmp;
  fs::create_directory(tmp.path / "cube");
  for (const char* f : {"px", "nx", "py", "ny", "pz"})
    fs::copy_file(lpt::dataPath(std::string("cube/pisaHDR/") + f + ".hdr"),
                  tmp.path / "cube" / (std::string(f) + ".hdr"));
  expectRefused(tmp, "coeffs cube", "cube", "missing nz");
}

// One limit on decoded pixels, checked from the header before decoding (a 56-byte Radiance
// file that declares 20000x20000 would otherwise ask for 4.8 GB), raised or lowered with
// LIVEPROBE_MAX_PIXELS.
TEST(Hostile, PixelLimitIsCheckedFromTheHeader) {
  lpt::TempDir tmp;
  std::ofstream(tmp / "big.hdr") << "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 20000 +X 20000\n";
  expectRefused(tmp, "coeffs big.hdr", "big.hdr", "above the limit of 268 M");
  ASSERT_TRUE(cv::imwrite(tmp / "small.png", cv::Mat(32, 64, CV_8UC3, cv::Scalar(9, 9, 9))));
  const auto r =
      lpt::runCommand("cd " + lpt::shellQuote(tmp.path.string()) +
                      " && LIVEPROBE_MAX_PIXELS=1000 " + LIVEPROBE_BIN + " coeffs small.png");
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_EQ(lpt::lineCount(r.output), 1) << r.output;
  EXPECT_NE(r.output.find("small.png: 64x32"), std::string::npos) << r.output;
  // A JPEG's SOF segment and an OpenEXR header's dataWindow, patched to declare 20000x20000 in a
  // file of a few hundred bytes: refused from the header, before OpenCV decodes anything.
  auto patched = [&](const std::string& name, const cv::Mat& image, const std::string& marker,
                     std::size_t offset, const std::vector<std::uint8_t>& bytes) {
    std::vector<std::uint8_t> file;
    EXPECT_TRUE(cv::imencode(fs::path(name).extension().string(), image, file));
    const std::string text(file.begin(), file.end());
    const std::size_t at = text.find(marker);
    EXPECT_NE(at, std::string::npos) << name;
    if (at == std::string::npos) return;
    std::copy(bytes.begin(), bytes.end(), file.begin() + std::ptrdiff_t(at + offset));
    std::ofstream(tmp / name, std::ios::binary)
        .write(reinterpret_cast<const char*>(file.data()), std::streamsize(file.size()));
  };
  // SOF0: FF C0, length (2), precision (1), height (2), width (2).
  patched("big.jpg", cv::Mat(32, 64, CV_8UC3, cv::Scalar(9, 9, 9)), "\xFF\xC0", 5,
          {0x4E, 0x20, 0x4E, 0x20});
  expectRefused(tmp, "coeffs big.jpg", "big.jpg", "20000x20000 is 400 M pixels, above the limit");
  // A stray byte before the SOF: libjpeg skips it and would decode the 20000x20000; the strict
  // reading of the markers finds no frame header, and says the file is corrupt.
  {
    std::ifstream in(tmp / "big.jpg", std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    bytes.insert(bytes.find("\xFF\xC0"), 1, '\x7E');
    std::ofstream(tmp / "stray.jpg", std::ios::binary) << bytes;
  }
  expectRefused(tmp, "coeffs stray.jpg", "stray.jpg", "corrupt JPEG: no frame header (SOF)");
  // dataWindow box2i: size (4), xMin, yMin, xMax, yMax (little-endian int32).
  patched("big.exr", cv::Mat(32, 64, CV_32FC3, cv::Scalar(1, 1, 1)),
          std::string("dataWindow\0box2i\0", 17), 17 + 4 + 8, {0x1F, 0x4E, 0, 0, 0x1F, 0x4E, 0, 0});
  expectRefused(tmp, "coeffs big.exr", "big.exr", "20000x20000 is 400 M pixels, above the limit");
}

// Pixels near float's maximum sum to infinity: an error, never a null in the JSON.
TEST(Hostile, OverflowingPixelsAreAnError) {
  lpt::TempDir tmp;
  ASSERT_TRUE(
      cv::imwrite(tmp / "huge.exr", cv::Mat(32, 64, CV_32FC3, cv::Scalar(3e38, 3e38, 3e38))));
  expectRefused(tmp, "coeffs huge.exr", "huge.exr", "not finite");
}

// A recording of a run that fails (a sequence whose second frame has another size) is discarded:
// no video, sidecar or temporary is left (not a video finalised with one frame).
TEST(Hostile, FailedRecordingIsDiscarded) {
  lpt::TempDir tmp;
  fs::create_directory(tmp.path / "seq");
  ASSERT_TRUE(cv::imwrite(tmp / "seq/a.png", cv::Mat(32, 64, CV_8UC3, cv::Scalar(9, 9, 9))));
  ASSERT_TRUE(cv::imwrite(tmp / "seq/b.png", cv::Mat(64, 128, CV_8UC3, cv::Scalar(9, 9, 9))));
  expectRefused(tmp, "record seq --quiet --out o.mkv", "b.png", "128x64 differs");
  expectRefused(tmp, "replay seq --headless --quiet --out-video v.mkv", "b.png", "128x64 differs");
}

}  // namespace

#if LIVEPROBE_WITH_V4L2
namespace {

lp::Frame decodeMjpeg(const std::vector<std::uint8_t>& jpeg, int width, int height) {
  lp::Frame f;
  lp::decodeCameraFrame({V4L2_PIX_FMT_MJPEG, width, height, 0, jpeg.data(), jpeg.size()}, 1, f);
  return f;
}

}  // namespace

// A camera frame is decoded only when its JPEG header declares the negotiated size: a corrupt
// header that declares 65535x65535 would make the decoder allocate gigabytes (an input of the
// camera_frame fuzz target, kept in tests/fuzz/corpus/camera_frame/).
TEST(Hostile, CameraFrameOfAnotherSizeIsDropped) {
  cv::Mat img(16, 32, CV_8UC3, cv::Scalar(40, 80, 120));
  std::vector<std::uint8_t> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", img, jpeg));
  const lp::Frame ok = decodeMjpeg(jpeg, 32, 16);
  EXPECT_EQ(ok.width, 32);
  EXPECT_EQ(ok.height, 16);
  EXPECT_EQ(decodeMjpeg(jpeg, 64, 32).width, 0) << "a frame of another size was accepted";
  // The same frame with its SOF height patched to 65535: dropped before any decoding.
  std::vector<std::uint8_t> huge = jpeg;
  for (std::size_t i = 2; i + 8 < huge.size(); ++i)
    if (huge[i] == 0xFF && huge[i + 1] == 0xC0) {
      huge[i + 5] = huge[i + 6] = 0xFF;
      break;
    }
  EXPECT_EQ(decodeMjpeg(huge, 32, 16).width, 0);
  // Not a JPEG at all (no SOI marker), and a buffer shorter than its rows, in YUYV.
  std::vector<std::uint8_t> png;
  ASSERT_TRUE(cv::imencode(".png", img, png));
  EXPECT_EQ(decodeMjpeg(png, 32, 16).width, 0);
  lp::Frame yuyv;
  lp::decodeCameraFrame({V4L2_PIX_FMT_YUYV, 32, 16, 64, png.data(), 64 * 15}, 1, yuyv);
  EXPECT_EQ(yuyv.width, 0);
}
#endif  // LIVEPROBE_WITH_V4L2

// OpenCV's video writer does not report FFmpeg's write errors: a video cut short by a full disk
// (here, a file size limit; SIGXFSZ ignored, so writes fail as on a full disk) is found when it
// is read back, reported, and removed with its sidecar.
TEST(Hostile, VideoCutShortByTheDiskIsAnError) {
  lpt::TempDir tmp;
  const auto before = listing(tmp.path);
  const auto r =
      lpt::runCommand("cd " + lpt::shellQuote(tmp.path.string()) +
                      " && trap '' XFSZ && ulimit -f 300 && " + "timeout 60 " + LIVEPROBE_BIN +
                      " replay synthetic:256x128@30 --frames 60 --headless --size 320x180 --quiet "
                      "--out-video v.mkv");
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find("v.mkv: the video was not written whole"), std::string::npos) << r.output;
  EXPECT_EQ(listing(tmp.path), before) << "left files behind";
}

// A video with no frames is refused, never "replayed".
TEST(Hostile, VideoWithoutFramesIsRefused) {
  lpt::TempDir tmp;
  {
    cv::VideoWriter w((tmp / "zero.mkv"), cv::CAP_FFMPEG,
                      cv::VideoWriter::fourcc('F', 'F', 'V', '1'), 30, {64, 32}, true);
    ASSERT_TRUE(w.isOpened());
  }
  expectRefused(tmp, "replay zero.mkv --headless --frames 5 --size 64x36", "zero.mkv",
                "cannot open as video");
  expectRefused(tmp, "coeffs zero.mkv", "zero.mkv", "cannot open as video");
}

// An image write that fails (a file size limit here, with SIGXFSZ ignored, as a full disk fails
// with ENOSPC) is one line that says why, and nothing is left behind.
TEST(Hostile, ImageWriteFailureSaysWhy) {
  lpt::TempDir tmp;
  const auto before = listing(tmp.path);
  const auto r = lpt::runCommand("cd " + lpt::shellQuote(tmp.path.string()) +
                                 " && trap '' XFSZ && ulimit -f 2 && timeout 60 " + LIVEPROBE_BIN +
                                 " render --headless --coeff L00=1 --size 512x512 --out r.png");
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_EQ(lpt::lineCount(r.output), 1) << r.output;
  EXPECT_NE(r.output.find("r.png: cannot write (file too large"), std::string::npos) << r.output;
  EXPECT_EQ(listing(tmp.path), before) << "left files behind";
}

namespace {

// `liveprobe ARGS` in `dir` under a file-size limit of `kb` KiB, with SIGXFSZ at its default
// action (a shell's `ulimit -f` leaves it so), and OpenCV's temporary folder pointed into `dir`.
lpt::RunResult runUnderSizeLimit(const lpt::TempDir& dir, int kb, const std::string& args) {
  return lpt::runCommand("cd " + lpt::shellQuote(dir.path.string()) +
                         " && mkdir -p cvtmp && export OPENCV_TEMP_PATH=$PWD/cvtmp && trap - XFSZ "
                         "&& ulimit -f " +
                         std::to_string(kb) + " && timeout 60 " + LIVEPROBE_BIN + " " + args);
}

void writeTruncatedCopy(const std::string& from, const std::string& to, std::size_t bytes) {
  std::ifstream in(from, std::ios::binary);
  std::string data(bytes, '\0');
  in.read(data.data(), std::streamsize(bytes));
  std::ofstream(to, std::ios::binary).write(data.data(), in.gcount());
}

}  // namespace

// Every writer stopped by a file-size limit says so in one line, naming the limit, and leaves
// nothing behind: not its own temporary, and not OpenCV's (the process is never killed by
// SIGXFSZ, which would leave both).
TEST(Hostile, WritesPastTheFileSizeLimitAreOneLineAndClean) {
  lpt::TempDir tmp;
  const std::string map = lpt::dataPath("probes/latlong_256x128/grace.hdr");
  const std::vector<std::string> writers = {
      "irradiance " + map + " --size 256x128 --out e.exr",
      "irradiance " + map + " --size 256x128 --out e.hdr",
      "irradiance " + map + " --size 256x128 --out e.png",
      "replay synthetic:256x128@30 --frames 400 --headless --size 64x36 --quiet --coeffs-out "
      "c.jsonl",
      "record synthetic:256x128@30 --frames 300 --quiet --out r.mkv"};
  for (const std::string& args : writers) {
    fs::create_directories(tmp.path / "cvtmp");
    const auto before = listing(tmp.path);
    const auto r = runUnderSizeLimit(tmp, 20, args);
    EXPECT_EQ(r.exitCode, 1) << args << "\n" << r.output;
    EXPECT_EQ(lpt::lineCount(r.output), 1) << args << "\n" << r.output;
    EXPECT_TRUE(std::regex_search(r.output,
                                  std::regex(R"(file-size limit \(ulimit -f\) (is|of) \d+ bytes)")))
        << args << "\n"
        << r.output;
    EXPECT_EQ(listing(tmp.path), before) << args << ": left files behind";
    EXPECT_TRUE(fs::is_empty(tmp.path / "cvtmp")) << args << ": OpenCV's temporary was left";
  }
}

// The case of an extension never changes what is written: .HDR and .Exr hold irradiance as .hdr
// and .exr do (not the 8-bit formats' irradiance / pi).
TEST(Hostile, ExtensionCaseDoesNotChangeWhatIsWritten) {
  lpt::TempDir tmp;
  const std::string map = lpt::dataPath("probes/latlong_256x128/grace.hdr");
  auto l00 = [&](const std::string& name) {
    const auto w = lpt::runLiveprobe("irradiance " + map + " --size 64x32 --out " + (tmp / name));
    EXPECT_EQ(w.exitCode, 0) << w.output;
    const auto r = lpt::runLiveprobe("coeffs " + (tmp / name));
    EXPECT_EQ(r.exitCode, 0) << r.output;
    const auto at = r.output.find("\"L00\":[");
    return at == std::string::npos ? -1.0 : std::stod(r.output.substr(at + 7));
  };
  const double hdr = l00("e.hdr"), exr = l00("e.exr");
  EXPECT_GT(hdr, 2.5);  // E, not E / pi (about 0.95)
  EXPECT_DOUBLE_EQ(l00("E.HDR"), hdr);
  EXPECT_DOUBLE_EQ(l00("e.Exr"), exr);
}

// A sequence recording checks every frame's place before it moves any frame there, refuses a
// pattern in the folder part, and never removes what is not a frame file.
TEST(Hostile, RecordingPatternIsCheckedBeforeAnythingMoves) {
  lpt::TempDir tmp;
  fs::create_directory(tmp.path / "d0");
  expectRefused(tmp, "record synthetic:64x32@30 --frames 3 --quiet --out 'd%d/x.exr'", "d%d/x.exr",
                "pattern goes in the file name");
  EXPECT_TRUE(fs::is_empty(tmp.path / "d0"));
  fs::create_directories(tmp.path / "r/0002.exr");
  const auto r = lpt::runCommand(
      "cd " + lpt::shellQuote(tmp.path.string()) + " && timeout 60 " + LIVEPROBE_BIN +
      " record synthetic:64x32@30 --frames 5 --quiet --out 'r/%04d.exr'");
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_EQ(lpt::lineCount(r.output), 1) << r.output;
  EXPECT_NE(r.output.find("r/0002.exr: cannot put the recorded frame in place"), std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("(Success)"), std::string::npos) << r.output;
  EXPECT_EQ(listing(tmp.path / "r"), std::set<std::string>{"0002.exr"}) << "frames were moved";
  // An empty folder named like a later frame is not liveprobe's to remove.
  fs::remove(tmp.path / "r/0002.exr");
  fs::create_directories(tmp.path / "r/0004.exr");
  const auto ok = lpt::runCommand(
      "cd " + lpt::shellQuote(tmp.path.string()) + " && timeout 60 " + LIVEPROBE_BIN +
      " record synthetic:64x32@30 --frames 3 --quiet --out 'r/%04d.exr'");
  EXPECT_EQ(ok.exitCode, 0) << ok.output;
  EXPECT_EQ(listing(tmp.path / "r"),
            (std::set<std::string>{"0000.exr", "0001.exr", "0002.exr", "0004.exr"}));
}

// A replay that fails part-way keeps no frames in --out-dir (and removes the folder it made, but
// nothing that was there before); two missing frames inside a sequence are an error, never a
// silent early end.
TEST(Hostile, FailedReplayKeepsNoFramesAndGapsAreErrors) {
  lpt::TempDir tmp;
  const std::string map = lpt::dataPath("probes/latlong_256x128/grace.hdr");
  fs::create_directory(tmp.path / "s");
  for (int i = 0; i < 8; ++i) fs::copy_file(map, tmp / ("s/f" + std::to_string(i) + ".hdr"));
  writeTruncatedCopy(map, tmp / "s/f6.hdr", 3000);
  const std::string replay = "replay 's/f%d.hdr' --headless --size 64x36 --quiet ";
  expectRefused(tmp, replay + "--out-dir od", "s/f6.hdr", "truncated");
  fs::create_directory(tmp.path / "mine");
  std::ofstream(tmp / "mine/notes.txt") << "mine\n";
  expectRefused(tmp, replay + "--out-dir mine --coeffs-out c.jsonl", "s/f6.hdr", "truncated");
  EXPECT_EQ(listing(tmp.path / "mine"), std::set<std::string>{"notes.txt"});
  fs::copy_file(map, tmp / "s/f6.hdr", fs::copy_options::overwrite_existing);
  fs::remove(tmp.path / "s/f3.hdr");
  fs::remove(tmp.path / "s/f4.hdr");
  expectRefused(tmp, replay, "s/f3.hdr and s/f4.hdr are missing", "s/f5.hdr");
}

// A truncated EXR is one line from liveprobe: OpenCV's own "imread_" line is not printed.
TEST(Hostile, TruncatedExrIsOneLine) {
  lpt::TempDir tmp;
  writeTruncatedCopy(lpt::dataPath("probes/latlong_full/grace_latlong.exr"), tmp / "t.exr", 5000);
  for (const char* args : {"coeffs t.exr", "irradiance t.exr --out i.png",
                           "record t.exr --out "
                           "r.mkv --frames 2",
                           "replay t.exr --headless --frames 2", "bench t.exr --frames 2"})
    expectRefused(tmp, args, "t.exr", "not a readable image");
}

// A source that fails at its first frame is one line with --serve and --publish too: where the
// stream is served and a broker that does not answer are said once the source has given a frame.
TEST(Hostile, AFailingSourceIsOneLineWithTheStreamAndTheBroker) {
  lpt::TempDir tmp;
  fs::create_directory(tmp.path / "seq");
  for (const char* f : {"seq/0000.exr", "seq/0001.exr"})
    writeTruncatedCopy(lpt::dataPath("probes/latlong_full/grace_latlong.exr"), tmp / f, 5000);
#if LIVEPROBE_WITH_STREAM
  expectRefused(tmp, "replay 'seq/%04d.exr' --headless --serve 0 --frames 2", "0000.exr",
                "not a readable image");
#endif
#if LIVEPROBE_WITH_MQTT
  expectRefused(tmp, "replay 'seq/%04d.exr' --headless --publish mqtt://127.0.0.1:1/t --frames 2",
                "0000.exr", "not a readable image");
#endif
  if (!LIVEPROBE_WITH_STREAM && !LIVEPROBE_WITH_MQTT)
    expectRefused(tmp, "replay 'seq/%04d.exr' --headless --frames 2", "0000.exr",
                  "not a readable image");
}

// Links that loop or lead nowhere, as the input or among a folder's frames: one line, exit 1.
TEST(Hostile, LoopingLinksAreOneLine) {
  lpt::TempDir tmp;
  fs::create_directory_symlink("loop", tmp.path / "loop");
  expectRefused(tmp, "coeffs loop", "loop", "Too many levels of symbolic links");
  fs::create_symlink("nothing.hdr", tmp.path / "dangling.hdr");
  expectRefused(tmp, "coeffs dangling.hdr", "dangling.hdr", "a symbolic link to nothing");
  fs::create_directory(tmp.path / "frames");
  fs::copy_file(lpt::dataPath("probes/latlong_256x128/grace.hdr"), tmp / "frames/a.hdr");
  fs::create_symlink("b.hdr", tmp.path / "frames/b.hdr");
  expectRefused(tmp, "coeffs frames", "frames/b.hdr", "Too many levels of symbolic links");
}

// Lighting liveprobe cannot draw is refused in one line: more lights than the shaders draw, and
// values whose products overflow float (which would render an all-black image with exit 0).
TEST(Hostile, LightingBeyondWhatIsDrawnIsRefused) {
  lpt::TempDir tmp;
  auto file = [&](const std::string& name, int lights, double l00, double power) {
    std::ofstream f(tmp / name);
    f << "{\"coefficients\":{\"L00\":[" << l00 << ",0.1,0.1]";
    for (const char* k : {"L1-1", "L10", "L11", "L2-2", "L2-1", "L20", "L21", "L22"})
      f << ",\"" << k << "\":[0,0,0]";
    f << "},\"lights\":[";
    for (int i = 0; i < lights; ++i)
      f << (i ? "," : "") << "{\"direction\":[" << i << ",1,1],\"power\":[" << power << ",1,1]}";
    f << "]}";
  };
  file("nine.json", 9, 0.1, 1);
  file("eight.json", 8, 0.1, 1);
  file("l00.json", 1, 3e38, 1);
  file("power.json", 1, 0.1, 3e38);
  const std::string render = "render --headless --size 32x32 --out r.png --coeffs ";
  expectRefused(tmp, render + "nine.json", "nine.json", "9 lights; liveprobe draws at most 8");
  expectRefused(tmp, render + "l00.json", "coefficient L00 is 3e+38", "the most liveprobe takes");
  expectRefused(tmp, render + "power.json", "light 1 power is 3e+38", "the most liveprobe takes");
  expectRefused(tmp, "render --headless --size 32x32 --out r.png --coeff L00=3e38", "L00=3e38",
                "the most liveprobe takes");
  const auto ok = lpt::runCommand("cd " + lpt::shellQuote(tmp.path.string()) + " && " +
                                  LIVEPROBE_BIN + " " + render + "eight.json");
  EXPECT_EQ(ok.exitCode, 0) << ok.output;
}
