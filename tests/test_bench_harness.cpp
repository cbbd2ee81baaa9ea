// liveprobe::bench on its own: the comparison and its verdict against hand-worked numbers, the
// baseline reader's refusals, the contention measure against two threads made to share one CPU,
// the calibration kernel's contract, the runs' bookkeeping and report against the same figures
// computed here, and the plot through the real gnuplot.
#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "liveprobe/bench/calibration.h"
#include "liveprobe/bench/contention.h"
#include "liveprobe/bench/plot.h"
#include "liveprobe/bench/runs.h"
#include "liveprobe/bench/verdict.h"
#include "liveprobe/capture/stages.h"
#include "liveprobe/sh/error.h"
#include "liveprobe/sh/simd.h"
#include "test_util.h"

namespace {

namespace fs = std::filesystem;
using lp::bench::Verdict;

// A baseline taken at calibration 2 ms: render 10 ms, project 0.3 ms, readback 0.01 ms.
const nlohmann::json kBaseline = lp::bench::parseBaseline(
    R"({"calibration_ms": 2, "contention": 1.05, "stages": {"render": {"median_ms": 10},
        "project": {"median_ms": 0.3}, "readback": {"median_ms": 0.01}}})",
    "base.json");

lp::bench::Comparison compare(double calibration, double render, double load = 1.0,
                              double project = 0.3, double readback = 0.01) {
  return lp::bench::compareWithBaseline(
      {{"render", render}, {"project", project}, {"readback", readback}, {"upload", 1.0}},
      calibration, kBaseline, 25, load, 1.5);
}

TEST(BenchHarness, ASlowerMachineIsNotARegression) {
  // Half the speed (the kernel takes 4 ms, not 2): render 20 ms is 10 ms at the baseline's speed.
  const auto c = compare(4, 20);
  EXPECT_TRUE(c.regressions.empty()) << c.regressions.dump();
  EXPECT_EQ(c.compared, 3);  // upload is not in the baseline
  EXPECT_EQ(lp::bench::verdict(c, 25, 1.0).second,
            "verdict: no regression (3 stages within 25% of the baseline)");
  // 30 ms there is 15 at the baseline's speed: +50%, +5 ms.
  const auto slow = compare(4, 30);
  ASSERT_EQ(slow.regressions.size(), 1u);
  EXPECT_EQ(slow.regressions[0]["stage"], "render");
  EXPECT_NEAR(slow.regressions[0]["change_pct"].get<double>(), 50.0, 1e-9);
  EXPECT_NEAR(slow.regressions[0]["change_ms"].get<double>(), 5.0, 1e-9);
  const auto [v, line] = lp::bench::verdict(slow, 25, 1.0);
  EXPECT_EQ(v, Verdict::Regression);
  EXPECT_EQ(line, "verdict: REGRESSION: render +5.00 ms (+50.0%) (threshold 25% and 0.5 ms)");
}

TEST(BenchHarness, TheLoadExplainsOnlyWhatItCan) {
  // +50% at a contention 1.3 times the baseline's: 15 ms <= 10 x 1.3 x 1.25 = 16.25: explained.
  auto c = compare(2, 15, 1.3);
  EXPECT_TRUE(c.regressions.empty());
  ASSERT_EQ(c.inconclusive.size(), 1u);
  EXPECT_EQ(lp::bench::verdict(c, 25, 1.3).first, Verdict::Inconclusive);
  // At 1.1: 15 > 13.75, slower than the load explains.
  c = compare(2, 15, 1.1);
  EXPECT_EQ(c.regressions.size(), 1u);
  // Over --max-contention (1.5) nothing is judged: 30 ms is inconclusive.
  c = compare(2, 30, 2.0);
  EXPECT_TRUE(c.regressions.empty());
  EXPECT_EQ(c.inconclusive.size(), 1u);
}

TEST(BenchHarness, SmallStagesAreJudgedByMillisecondsNotPercent) {
  // project 0.3 -> 0.7 ms is +133% but 0.4 ms: noise. readback 0.01 -> 0.02: too small.
  const auto c = compare(2, 10, 1.0, 0.7, 0.02);
  EXPECT_TRUE(c.regressions.empty()) << c.regressions.dump();
  bool tooSmall = false;
  for (const auto& l : c.lines)
    tooSmall |= l.find("readback") == 0 && l.find("too small to measure") != std::string::npos;
  EXPECT_TRUE(tooSmall);
  // 0.3 -> 0.9 ms is over 0.5 ms: a regression.
  EXPECT_EQ(compare(2, 10, 1.0, 0.9).regressions.size(), 1u);
}

TEST(BenchHarness, GpuStagesCompareAsMeasured) {
  lp::bench::Comparison c;
  nlohmann::json base = kBaseline;
  base["gpu"] = {{"timer", true}, {"render", {{"median_ms", 4.0}}}};
  // The CPU's kernel does not scale a GPU's time: 6 ms against 4 is +50%.
  lp::bench::compareGpu({{"render", 6.0}}, base, 25, c);
  ASSERT_EQ(c.regressions.size(), 1u);
  EXPECT_NEAR(c.regressions[0]["change_pct"].get<double>(), 50.0, 1e-9);
  // A baseline without a GPU timer compares nothing.
  lp::bench::Comparison none;
  base["gpu"]["timer"] = false;
  lp::bench::compareGpu({{"render", 6.0}}, base, 25, none);
  EXPECT_EQ(none.compared, 0);
}

TEST(BenchHarness, ABaselineIsReadWholeOrRefusedByName) {
  for (const char* bad : {"", "{}", R"({"calibration_ms": 0, "stages": {}})",
                          R"({"calibration_ms": 1, "stages": []})",
                          R"({"calibration_ms": 1, "stages": {"render": {"median_ms": -1}}})",
                          R"({"calibration_ms": 1, "stages": {}} trailing)"}) {
    try {
      lp::bench::parseBaseline(bad, "b.json");
      ADD_FAILURE() << "accepted: " << bad;
    } catch (const lp::Error& e) {
      EXPECT_EQ(std::string(e.what()).rfind("b.json: ", 0), 0u) << e.what();
    }
  }
}

// Two threads spinning on one CPU each wait about as long as they run: the factor reads about 2
// (more on a loaded machine, never less than the sharing explains).
TEST(BenchHarness, ContentionSeesThreadsSharingACpu) {
  cpu_set_t mine;
  ASSERT_EQ(pthread_getaffinity_np(pthread_self(), sizeof mine, &mine), 0);
  int cpu = 0;
  while (!CPU_ISSET(cpu, &mine)) ++cpu;
  const lp::bench::Contention contention;
  std::atomic<bool> go{true};
  const auto spin = [&] {
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(cpu, &one);
    pthread_setaffinity_np(pthread_self(), sizeof one, &one);
    volatile double x = 0;
    while (go.load()) x = x + 1;
  };
  std::thread a(spin), b(spin);
  std::this_thread::sleep_for(std::chrono::milliseconds(600));
  const double shared = contention.factor();  // (the threads alive: their counts)
  go = false;
  a.join();
  b.join();
  EXPECT_GE(shared, 1.6);
}

TEST(BenchHarness, TheCalibrationKernelKeepsTheFastestOnTheScalarPath) {
  lp::bench::CalibrationKernel k;
  EXPECT_TRUE(std::isinf(k.speed()));
  const std::string path = lp::simd::current();
  double last = k.speed();
  for (int i = 0; i < 5; ++i) {
    k.time();
    EXPECT_LE(k.speed(), last);  // the fastest so far
    last = k.speed();
    EXPECT_EQ(lp::simd::current(), path) << "the SIMD path in use is given back";
  }
  EXPECT_GT(k.speed(), 0.0);
  EXPECT_LT(k.speed(), 10000.0);
  EXPECT_EQ(k.repetitions(), 5u);
}

TEST(BenchHarness, RunsKeepEveryFrameAndEachRunsMedian) {
  int started = 0;
  // Stage a: the frame's number in its run; stage b: 10 x the run; stage c: 1.
  const auto runs =
      lp::bench::measure({"a", "b", "c"}, 3, 5,
                         {.startRun = [&](int run) { EXPECT_EQ(run, started++); },
                          .frame =
                              [](int run, int i) {
                                return std::vector<double>{double(i), 10.0 * run, 1.0};
                              }});
  EXPECT_EQ(started, 3);
  ASSERT_EQ(runs.frames.size(), 15u);
  EXPECT_FALSE(runs.stopped);
  EXPECT_EQ(runs.runMedians[0], (std::vector<double>{2, 2, 2}));
  EXPECT_EQ(runs.runMedians[1], (std::vector<double>{0, 10, 20}));
  EXPECT_GT(runs.calibrationMs, 0.0);
  EXPECT_GE(runs.contention, 1.0);
  const auto s = lp::bench::summarize(runs, "test frames");
  EXPECT_DOUBLE_EQ(s.json["stages"]["a"]["median_ms"].get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(s.json["stages"]["b"]["median_ms"].get<double>(), 10.0);
  EXPECT_DOUBLE_EQ(s.json["stages"]["b"]["max_ms"].get<double>(), 20.0);
  // Latency: the stages after the first, b + c: 1, 11, 21 five times each.
  EXPECT_DOUBLE_EQ(s.json["latency_ms"]["p50"].get<double>(), 11.0);
  EXPECT_DOUBLE_EQ(
      s.json["latency_ms"]["p95"].get<double>(),
      lp::percentile(std::vector<double>{1, 1, 1, 1, 1, 11, 11, 11, 11, 11, 21, 21, 21, 21, 21},
                     0.95));
  EXPECT_NE(s.lines[0].find("3 runs of 5 frames, test frames"), std::string::npos) << s.lines[0];
  // A stop after 7 frames: the second run's two frames make its median; the third never starts.
  int frames = 0;
  const auto stopped = lp::bench::measure({"a"}, 3, 5,
                                          {.frame =
                                               [&](int, int i) {
                                                 ++frames;
                                                 return std::vector<double>{double(i)};
                                               },
                                           .stop = [&] { return frames >= 7; }});
  EXPECT_TRUE(stopped.stopped);
  EXPECT_EQ(stopped.frames.size(), 7u);
  EXPECT_EQ(stopped.runMedians[0], (std::vector<double>{2, 0.5}));
}

TEST(BenchHarness, ThePlotIsGnuplotsPngAndLeavesNothingElse) {
  lpt::TempDir tmp;
  lp::bench::Runs runs;
  runs.stages = {"grab", "render"};
  runs.framesPerRun = 4;
  for (int i = 0; i < 8; ++i) runs.frames.push_back({0.5, 10.0 + i});
  const std::string png = (tmp.path / "plot.png").string();
  lp::bench::drawStagePlot(png, runs, "a test");
  std::ifstream in(png, std::ios::binary);
  char magic[8] = {};
  in.read(magic, 8);
  EXPECT_EQ(std::string(magic + 1, 3), "PNG");
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& f : fs::directory_iterator(tmp.path)) ++files;
  EXPECT_EQ(files, 1u) << "gnuplot's inputs or a temporary were left";
  // Without gnuplot: one error naming the file and the package.
  const std::string path = std::getenv("PATH");
  ::setenv("PATH", "/nonexistent", 1);
  try {
    lp::bench::drawStagePlot((tmp.path / "none.png").string(), runs, "a test");
    ADD_FAILURE() << "drew without gnuplot";
  } catch (const lp::Error& e) {
    EXPECT_NE(std::string(e.what()).find("none.png: gnuplot failed (not installed: scripts/deps "
                                         "installs gnuplot-nox)"),
              std::string::npos)
        << e.what();
  }
  ::setenv("PATH", path.c_str(), 1);
  EXPECT_FALSE(fs::exists(tmp.path / "none.png"));
}

}  // namespace
