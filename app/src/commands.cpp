#include "commands.h"

namespace lp::cli {

std::vector<OptionSpec> lightOptionSpecs() {
  return {{"--sun", "",
           "take the dominant compact source (sun, lamp, window) out of the coefficients and keep "
           "it as a disc light"},
          {"--lights", "K", "up to K such lights (implies --sun; 1..8, default 1)"}};
}

LightOptions chooseLights(const Args& a) {
  LightOptions o;
  o.maxLights =
      a.has("--lights") ? a.integerIn("--lights", 1, 1, kMaxLights) : (a.has("--sun") ? 1 : 0);
  return o;
}

const std::vector<Command>& commands() {
  static const std::vector<Command> all = {
      {kCoeffsSpec, runCoeffs,
       "the nine SH coefficients of an environment map (JSON, table, GLSL)"},
      {kIrradianceSpec, runIrradiance, "the irradiance map E(n), from SH or by brute force"},
      {kCompareSpec, runCompare,
       "SH irradiance against the brute-force integral (the paper's errors)"},
      {kRenderSpec, runRender, "one image of a model lit by the coefficients"},
      {kViewSpec, runView, "an interactive window (orbit, zoom)"},
      {kReplaySpec, runReplay, "a stream re-projected every frame, lighting a model"},
      {kRecordSpec, runRecord, "save a source for replay (FFV1 or MJPEG, with timestamps)"},
      {kLiveSpec, runLive, "a live light probe from a V4L2 camera"},
      {kDevicesSpec, runDevices, "list cameras: formats, sizes, frame rates, controls"},
      {kCalibrateSpec, runCalibrate, "a camera's response curve, for --response"},
      {kBenchSpec, runBench, "frame-time regression run against a baseline"},
  };
  return all;
}

}  // namespace lp::cli
