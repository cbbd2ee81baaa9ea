#include "commands.h"

namespace lp::cli {

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
      {kBenchSpec, runBench, "frame-time regression run against a baseline"},
  };
  return all;
}

}  // namespace lp::cli
