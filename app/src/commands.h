#pragma once
// The subcommands of the liveprobe program. Each returns the process exit code; errors are
// thrown as lp::Error and printed by main() as one line.
#include <memory>
#include <string>
#include <vector>

#include "args.h"
#include "liveprobe/capture/frame.h"

namespace lp::cli {

struct Command {
  CommandSpec spec;
  int (*run)(const Args&);
  const char* brief;  ///< one line for `liveprobe --help`
};

const std::vector<Command>& commands();

int runCoeffs(const Args&);
int runIrradiance(const Args&);
int runCompare(const Args&);
int runRender(const Args&);
int runView(const Args&);
int runReplay(const Args&);
int runRecord(const Args&);
int runBench(const Args&);
int runLive(const Args&);
int runDevices(const Args&);
/// The replay pipeline with an opened camera as its source (cmd_replay.cpp).
int runStreamForLive(const Args& a, std::unique_ptr<FrameSource> camera);
std::vector<OptionSpec> streamOptions();
/// recordings/sky.mkv in the source tree, or $LIVEPROBE_DEFAULT_RECORDING.
std::string defaultRecording();

extern const CommandSpec kCoeffsSpec, kIrradianceSpec, kCompareSpec, kRenderSpec, kViewSpec,
    kReplaySpec, kRecordSpec, kBenchSpec, kLiveSpec, kDevicesSpec;

}  // namespace lp::cli
