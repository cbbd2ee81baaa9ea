// calibrate-lens: a lens calibration from photos of a chessboard, for --lens.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <tuple>

#include "commands.h"
#include "liveprobe/backends.h"
#include "liveprobe/capture/lens_calibrate.h"
#include "liveprobe/capture/v4l2.h"
#include "liveprobe/sh/error.h"
#include "progress.h"

namespace lp::cli {

namespace {

const std::string kGroup = "Calibration";

OptionSpec boardOption() {
  OptionSpec o = declared("--board", "COLSxROWS",
                          "the chessboard's inner corners, as OpenCV counts them (a board of 10x7 "
                          "squares has 9x6; required)",
                          kGroup);
  o.set = [](Settings& s, const std::string& v) {
    s.lensCalibration.board = parseSize(v, "--board", 200);
    if (s.lensCalibration.board->first < 2 || s.lensCalibration.board->second < 2)
      throw Error("--board " + v + ": a board has at least 2x2 inner corners");
  };
  return o;
}

/// The photos: the arguments, or the images of the one folder given.
std::vector<std::string> photosOf(const std::vector<std::string>& args) {
  namespace fs = std::filesystem;
  if (args.size() != 1 || !fs::is_directory(args[0])) return args;
  std::vector<std::string> photos;
  for (const auto& e : fs::directory_iterator(args[0])) {
    std::string ext = e.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    if (e.is_regular_file() && (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" ||
                                ext == ".tif" || ext == ".tiff"))
      photos.push_back(e.path().string());
  }
  std::sort(photos.begin(), photos.end());
  if (photos.empty()) throw Error(args[0] + ": a folder with no photos (png, jpg, bmp, tif)");
  return photos;
}

/// Boards from a live camera: each kept when held still in a new place, until --boards are kept
/// or a signal stops it.
LensFit calibrateFromCamera(const Settings& s, const Chessboard& board,
                            LensCalibration::Model model) {
#if LIVEPROBE_WITH_V4L2
  const auto& c = s.lensCalibration;
  CameraSettings cs = s.camera;
  cs.device = *c.device;
  if (s.output.size) std::tie(cs.width, cs.height) = *s.output.size;
  auto camera = startCamera(cs, false);
  std::fprintf(stderr,
               "liveprobe calibrate-lens: %s; hold the %dx%d board still in %d places, across the "
               "whole field and tilted (Ctrl-C to calibrate from those kept so far)\n",
               camera->describe().c_str(), board.cols, board.rows, c.boards);
  BoardCollector boards(board);
  Frame frame;
  while (int(boards.views().size()) < c.boards && !stopRequested()) {
    if (!camera->next(frame))
      throw Error(cs.device + ": the camera stopped sending frames" +
                  (camera->endReason().empty() ? "" : " (" + camera->endReason() + ")"));
    if (boards.offer(frame) == BoardCollector::Seen::Kept)
      std::fprintf(stderr, "liveprobe calibrate-lens: board %zu of %d kept (frame %llu)\n",
                   boards.views().size(), c.boards,
                   static_cast<unsigned long long>(frame.sequence));
  }
  if (int(boards.views().size()) < kMinCalibrationBoards)
    throw Error(cs.device + ": " + std::to_string(boards.views().size()) +
                " boards held still in different places; a calibration needs at least " +
                std::to_string(kMinCalibrationBoards));
  return fitLens(boards.views(), boards.width(), boards.height(), board, model);
#else
  (void)s, (void)board, (void)model;
  requireBackend(OptionalBackend::V4l2, "--device");
  return {};
#endif
}

}  // namespace

const CommandSpec kCalibrateLensSpec{
    "calibrate-lens",
    "[PHOTO...]",
    "Calibrates a camera's lens from photos of a flat chessboard held in different places and\n"
    "angles, with OpenCV's detector and calibration (cv::fisheye for a fisheye, the Kannala-\n"
    "Brandt model; cv::calibrateCamera for an ordinary lens, Brown-Conrady with 5 coefficients),\n"
    "and writes the calibration for --lens. Says the RMS reprojection error, the photos used and\n"
    "refused, and which parts of the field the boards did not reach. With --device, from a live\n"
    "camera: a frame is kept each time the board is held still in a new place.",
    {boardOption(),
     numberOption("--square", "SIZE",
                  "the side of a square, in any unit (required; the calibration is in pixels)",
                  {0, 1e9, true}, "", LP_FIELD(lensCalibration.square), kGroup),
     choiceOption("--lens-model",
                  "the lens model: fisheye (Kannala-Brandt) or pinhole (Brown-Conrady)",
                  {"fisheye", "pinhole"}, "fisheye", LP_FIELD(lensCalibration.model), kGroup),
     textOption("--device", "DEVICE",
                "a V4L2 camera to take the boards from instead of photos (e.g. /dev/video0)",
                LP_FIELD(lensCalibration.device), kGroup),
     integerOption("--boards", "N", "with --device: how many boards to keep", kMinCalibrationBoards,
                   200, "20", LP_FIELD(lensCalibration.boards), kGroup),
     opt::size("with --device: the capture size asked of the camera", 16384, "its largest", kGroup),
     opt::out("FILE.yaml", "where the calibration goes (required; OpenCV FileStorage YAML or JSON)",
              {".yaml", ".yml", ".json"}, "Output")},
    0,
    1024,
    "the photos, or one folder holding them"};

int runCalibrateLens(const Args& a) {
  const Settings& s = a.settings();
  const auto& c = s.lensCalibration;
  if (!c.board) throw Error("--board COLSxROWS is required");
  if (!c.square) throw Error("--square SIZE is required");
  if (!s.output.out) throw Error("--out FILE.yaml is required");
  const Chessboard board{c.board->first, c.board->second, *c.square};
  const auto model =
      c.model == "fisheye" ? LensCalibration::Model::Fisheye : LensCalibration::Model::Pinhole;
  if (c.device && !a.positional().empty())
    throw Error("photos or --device " + *c.device + ", not both");
  if (!c.device && a.positional().empty())
    throw Error("the photos (or a folder of them), or --device DEVICE");
  const std::vector<std::string> photos =
      c.device ? std::vector<std::string>{} : photosOf(a.positional());
  const LensFit fit =
      c.device ? calibrateFromCamera(s, board, model) : calibrateLens(photos, board, model);
  writeLensCalibration(*s.output.out, fit);
  const LensCalibration& l = fit.lens;
  if (c.device)
    std::printf("%zu frames of %s keep the %dx%d board still in different places", fit.used.size(),
                c.device->c_str(), board.cols, board.rows);
  else
    std::printf("%zu of %zu photos show the %dx%d board", fit.used.size(), photos.size(),
                board.cols, board.rows);
  for (std::size_t i = 0; i < fit.refused.size(); ++i)
    std::printf("%s%s: %s", i ? "; " : " (refused: ", fit.refused[i].first.c_str(),
                fit.refused[i].second.c_str());
  std::printf("%s\n", fit.refused.empty() ? "" : ")");
  std::printf("%s lens %dx%d: focal %.2f %.2f px, centre %.2f %.2f px, distortion", c.model.c_str(),
              l.width, l.height, l.K[0], l.K[4], l.K[2], l.K[5]);
  for (const double d : l.distortion) std::printf(" %.6g", d);
  std::printf("\nRMS reprojection error %.3f px\n", fit.rms);
  std::printf("the boards reached %d of 9 parts of the field", fit.partsCovered);
  for (std::size_t i = 0; i < fit.partsMissed.size(); ++i)
    std::printf("%s%s", i ? ", " : " (not the ", fit.partsMissed[i].c_str());
  std::printf("%s\n", fit.partsMissed.empty() ? "" : ")");
  std::printf("wrote %s\n", s.output.out->c_str());
  if (fit.rms > 1.0)
    warn(
        "an RMS above 1 px: blurred photos, a board that is not flat, a wrong --board or "
        "--square, or the wrong --lens-model");
  if (!fit.partsMissed.empty())
    warn("hold the board where it has not been: the distortion there is extrapolated");
  return 0;
}

}  // namespace lp::cli
