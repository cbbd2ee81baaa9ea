#pragma once
// The subcommands of the liveprobe program. Each returns the process exit code; errors are
// thrown as lp::Error and printed by main() as one line.
#include <string>
#include <vector>

#include "args.h"

namespace lp::cli {

struct Command {
  CommandSpec spec;
  int (*run)(const Args&);
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
std::vector<OptionSpec> streamOptions();

extern const CommandSpec kCoeffsSpec, kIrradianceSpec, kCompareSpec, kRenderSpec, kViewSpec, kReplaySpec, kRecordSpec, kBenchSpec;

}  // namespace lp::cli
