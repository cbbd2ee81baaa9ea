// liveprobe bench against a baseline taken in the same run. Its own executable, run serially by
// ctest: timings taken while other tests load both cores would say nothing.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "test_util.h"

namespace {

// The frame-time regression run: against a baseline taken in the same run (so on the same
// machine under the same load) with a loose threshold it passes; an injected delay in one stage
// is caught and named, against that baseline and against the committed one of this machine class.
TEST(BenchCli, PassesAgainstTheBaselineAndCatchesAnInjectedDelay) {
  lpt::TempDir tmp;
  const std::string baseline = tmp / "base.json";
  const std::string committed =
      std::string(LIVEPROBE_SOURCE_DIR) + "/recordings/bench-baseline.json";
  const std::string json = tmp / "bench.json", plot = tmp / "bench.png";
  auto base = lpt::runLiveprobe("bench --frames 100 --repeat 1 --quiet --json " + baseline);
  ASSERT_EQ(base.exitCode, 0) << base.output;
  auto r = lpt::runLiveprobe("bench --frames 100 --repeat 1 --baseline " + baseline +
                             " --threshold 150 --json " + json + " --plot " + plot);
  EXPECT_EQ(r.exitCode, 0) << r.output;
  std::ifstream in(json);
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["frames"], 100);
  for (const char* s : {"grab", "convert", "project", "resample", "upload", "render", "readback"})
    for (const char* k : {"median_ms", "p95_ms", "p99_ms", "max_ms"})
      EXPECT_TRUE(j["stages"][s][k].is_number()) << s << k;
  EXPECT_GT(j["calibration_ms"].get<double>(), 0);
  EXPECT_TRUE(j["regressions"].empty());
  EXPECT_TRUE(std::filesystem::exists(plot));
  for (const std::string& against : {baseline, committed}) {
    r = lpt::runLiveprobe("bench --frames 30 --repeat 1 --baseline " + against +
                          " --threshold 150 --inject-delay project=8");
    EXPECT_EQ(r.exitCode, 1) << against << "\n" << r.output;
    EXPECT_NE(r.output.find("REGRESSION: project"), std::string::npos) << r.output;
  }
}

}  // namespace
