// liveprobe bench against a baseline taken in the same run. Its own executable, run serially by
// ctest: timings taken while other tests load both cores would say nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

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
  const auto compare = [&] {
    return lpt::runLiveprobe("bench --frames 100 --repeat 1 --baseline " + baseline +
                             " --threshold 150 --json " + json + " --plot " + plot);
  };
  auto r = compare();
  // Beside the suite's load a stage of a tenth of a millisecond can be held up a millisecond by
  // the scheduler for a whole run (seen once: project 0.14 -> 1.28 ms at a contention of only
  // 1.38): what the same build does not repeat is not a regression, so a verdict of one is
  // asked again.
  if (r.exitCode == 1) r = compare();
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
    // Judged whatever the load beside the suite (--max-contention): 8 ms of busy work in a stage
    // of a tenth of a millisecond is beyond what any contention explains.
    r = lpt::runLiveprobe("bench --frames 30 --repeat 1 --baseline " + against +
                          " --threshold 150 --max-contention 1000 --inject-delay project=8");
    EXPECT_EQ(r.exitCode, 1) << against << "\n" << r.output;
    EXPECT_NE(r.output.find("REGRESSION: project"), std::string::npos) << r.output;
  }
}

// A busy machine is no regression: beside 3N stress-ng workers on N CPUs (at the program's own
// priority) the scheduler gives each runnable thread at most a quarter of a CPU, so the run's
// threads wait for one several times as long as the baseline's did. bench measures that wait
// (the kernel's scheduler statistics), and a stage the load made slower is inconclusive (exit 2),
// never a regression.
TEST(BenchCli, ABusyMachineIsInconclusiveNotARegression) {
  lpt::TempDir tmp;
  const std::string base = tmp / "base.json", busy = tmp / "busy.json";
  const auto b = lpt::runLiveprobe("bench --frames 30 --repeat 1 --quiet --json " + base);
  ASSERT_EQ(b.exitCode, 0) << b.output;
  const unsigned workers = 3 * std::max(1u, std::thread::hardware_concurrency());
  const auto r = lpt::runCommand("stress-ng --cpu " + std::to_string(workers) +
                                 " --timeout 300 --quiet & s=$!; sleep 1; " LIVEPROBE_BIN
                                 " bench --frames 30 --repeat 1 --quiet --baseline " +
                                 base + " --json " + busy + "; rc=$?; kill $s; wait $s; exit $rc");
  std::ifstream bin(base), nin(busy);
  const auto before = nlohmann::json::parse(bin), now = nlohmann::json::parse(nin);
  const double load = now["contention"].get<double>() / before["contention"].get<double>();
  EXPECT_GT(load, 1.5) << r.output;
  EXPECT_TRUE(now["regressions"].empty()) << r.output;
  EXPECT_NE(r.exitCode, 1) << r.output;
  if (r.exitCode == 2) {
    EXPECT_FALSE(now["inconclusive"].empty());
    EXPECT_NE(r.output.find("verdict: inconclusive: "), std::string::npos) << r.output;
  } else {
    EXPECT_EQ(r.exitCode, 0) << r.output;
  }
}

}  // namespace
