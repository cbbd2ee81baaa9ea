#include "commands.h"

namespace lp::cli {

const std::vector<Command>& commands() {
  static const std::vector<Command> all = {
      {kCoeffsSpec, runCoeffs},
      {kIrradianceSpec, runIrradiance},
      {kCompareSpec, runCompare},
      {kRenderSpec, runRender},
      {kViewSpec, runView},
      {kReplaySpec, runReplay},
      {kRecordSpec, runRecord},
      {kLiveSpec, runLive},
      {kDevicesSpec, runDevices},
      {kBenchSpec, runBench},
  };
  return all;
}

}  // namespace lp::cli
