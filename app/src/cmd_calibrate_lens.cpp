// calibrate-lens: a lens calibration from photos of a chessboard, for --lens.
#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "liveprobe/capture/lens_calibrate.h"
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

}  // namespace

const CommandSpec kCalibrateLensSpec{
    "calibrate-lens",
    "PHOTO...",
    "Calibrates a camera's lens from photos of a flat chessboard held in different places and\n"
    "angles, with OpenCV's detector and calibration (cv::fisheye for a fisheye, the Kannala-\n"
    "Brandt model; cv::calibrateCamera for an ordinary lens, Brown-Conrady with 5 coefficients),\n"
    "and writes the calibration for --lens. Says the RMS reprojection error, the photos used and\n"
    "refused, and which parts of the field the boards did not reach.",
    {boardOption(),
     numberOption("--square", "SIZE",
                  "the side of a square, in any unit (required; the calibration is in pixels)",
                  {0, 1e9, true}, "", LP_FIELD(lensCalibration.square), kGroup),
     choiceOption("--lens-model",
                  "the lens model: fisheye (Kannala-Brandt) or pinhole (Brown-Conrady)",
                  {"fisheye", "pinhole"}, "fisheye", LP_FIELD(lensCalibration.model), kGroup),
     opt::out("FILE.yaml", "where the calibration goes (required; OpenCV FileStorage YAML or JSON)",
              {".yaml", ".yml", ".json"}, "Output")},
    1,
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
  const std::vector<std::string> photos = photosOf(a.positional());
  const LensFit fit = calibrateLens(photos, board, model);
  writeLensCalibration(*s.output.out, fit);
  const LensCalibration& l = fit.lens;
  std::printf("%zu of %zu photos show the %dx%d board", fit.used.size(), photos.size(), board.cols,
              board.rows);
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
