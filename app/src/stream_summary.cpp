// The stream's tally and summary.
#include "stream_summary.h"

#include <algorithm>
#include <cstdio>

#include "commands.h"
#include "liveprobe/sh/error.h"
#include "progress.h"

namespace lp::cli {

double StreamTally::median(Stage s) const { return percentile(stages[std::size_t(s)], 0.5); }

double StreamTally::deliveredFps(double minSeconds) const {
  const double span = lastTimestamp - firstTimestamp;
  if (frames() < 2 || !(span >= minSeconds) || lastSequence <= firstSequence) return 0;
  return double(lastSequence - firstSequence) / span;
}

void recordSample(StreamTally& t, const ProcessedFrame& f, double uploadMs, double renderMs,
                  double latencyMs, Hud* hud, const PipelineStats& st, const RecordSinks& sinks,
                  const GpuTimes& gpu) {
  for (std::size_t k = 0; k < GpuTimes::kTimes.size(); ++k)
    if (const auto& ms = gpu.*GpuTimes::kTimes[k].second) t.gpu[k].push_back(*ms);
  StageTimes times = f.times;
  times[Stage::Upload] = uploadMs;
  times[Stage::Render] = renderMs;
  if (t.latency.empty()) {
    t.firstSequence = f.sequence;
    t.firstTimestamp = f.timestamp;
  }
  t.lastSequence = f.sequence;
  t.lastTimestamp = f.timestamp;
  t.latency.push_back(latencyMs);
  for (std::size_t k = 0; k < kStageCount; ++k) t.stages[k].push_back(times.ms[k]);
  t.saturated += f.saturated;
  t.confidence.push_back(f.confidence.value());
  t.brightestMeasured += f.confidence.brightestMeasured;
  if (!f.lights.empty()) ++t.withLight;
  if (std::any_of(f.lights.begin(), f.lights.end(), [](const Light& l) { return l.clipped; }))
    ++t.clippedLight;
  if (!hud) return;
  HudSample s;
  s.frame = f.index;
  s.time = f.timestamp;
  s.times = times;
  s.latencyMs = latencyMs;
  s.radiance = f.radiance;
  s.unsmoothed = f.unsmoothed;
  s.lights = f.lights;
  s.confidence = f.confidence;
  s.held = f.held;
  s.gpu = gpu;
  hud->push(s);
  HudCounters c{st.captured, t.drawn, st.dropped, st.skipped,
                double(t.saturated) / double(t.frames())};
  sinks.fill(c);
  hud->setCounters(c);
}

std::string stageMedians(const StreamTally& t) {
  std::string out;
  char one[64];
  for (std::size_t k = 0; k <= std::size_t(Stage::Render); ++k) {
    if (stageRunsForSomeSources(Stage(k)) && !(t.median(Stage(k)) > 0)) continue;
    std::snprintf(one, sizeof one, "%s%s %.2f", out.empty() ? "" : ", ",
                  std::string(kStageNames[k]).c_str(), t.median(Stage(k)));
    out += one;
  }
  return out;
}

std::string gpuTimeLine(const StreamTally& t, const std::string& gl) {
  std::string line;
  for (std::size_t k = 0; k < GpuTimes::kTimes.size(); ++k) {
    if (t.gpu[k].empty()) continue;
    char b[64];
    std::snprintf(b, sizeof b, "%s%s %.3f ms", line.empty() ? "" : ", ", GpuTimes::kTimes[k].first,
                  percentile(t.gpu[k], 0.5));
    line += b;
  }
  return line.empty() ? "GPU time: no GPU timer (" + gl + ")"
                      : "GPU time (medians, timer queries): " + line;
}

void printSummary(const std::string& description, const PipelineStats& st, const StreamTally& t,
                  double smoothSeconds, bool interrupted, const RecordSinks& sinks) {
  std::fprintf(
      stderr,
      "liveprobe: %s: %zu frames captured, %zu drawn, %zu dropped (stale), %zu skipped "
      "(corrupt)%s%s%s%s%s\n"
      "  median ms: %s; saturated values %.1f per frame\n",
      description.c_str(), st.captured, t.drawn, st.dropped, st.skipped,
      st.unidentified == 0
          ? ""
          : (", " + std::to_string(st.unidentified) + " left out of the bracket (" +
             (st.unidentifiedReport.empty() ? "exposure not told" : st.unidentifiedReport) + ")")
                .c_str(),
      ((st.stale == 0 ? std::string()
                      : ", " + std::to_string(st.stale) + " replaced at the source (stale)") +
       (st.reconnects == 0 ? std::string()
                           : ", " + std::to_string(st.reconnects) +
                                 (st.reconnects == 1 ? " reconnect" : " reconnects")))
          .c_str(),
      st.endReason.empty() ? "" : "; ", st.endReason.c_str(),
      interrupted ? "; stopped by a signal" : "", stageMedians(t).c_str(),
      t.frames() == 0 ? 0.0 : double(t.saturated) / double(t.frames()));
  if (!t.latency.empty())
    std::fprintf(stderr, "  latency ms (capture to shown): p50 %.1f, p95 %.1f, p99 %.1f\n",
                 percentile(t.latency, 0.5), percentile(t.latency, 0.95),
                 percentile(t.latency, 0.99));
  if (t.withLight > 0 || t.clippedLight > 0)
    std::fprintf(stderr, "  lights: in %zu of %zu frames%s\n", t.withLight, t.frames(),
                 t.clippedLight > 0 ? (", clipped (8-bit maximum: power is a lower bound) in " +
                                       std::to_string(t.clippedLight))
                                          .c_str()
                                    : "");
  if (st.captured > 0 && (st.beforeBall > 0 || st.ballMoves > 0 || st.ballLost > 0))
    std::fprintf(stderr,
                 "  mirror ball (--circle auto): found after %zu frames, moved %zu times, lost in "
                 "%zu frames\n",
                 st.beforeBall, st.ballMoves, st.ballLost);
  for (const auto& sink : sinks.all)
    if (const std::string line = sink->summary(); !line.empty())
      std::fprintf(stderr, "  %s\n", line.c_str());
  if (!t.confidence.empty() &&
      (st.held > 0 || t.median(Stage::Merge) > 0 || percentile(t.confidence, 0.0) < 1.0))
    std::fprintf(stderr,
                 "  confidence: median %.3f, lowest %.3f; brightest source measured unclipped in "
                 "%zu of %zu frames; %zu held (last good lighting)\n",
                 percentile(t.confidence, 0.5), percentile(t.confidence, 0.0), t.brightestMeasured,
                 t.confidence.size(), st.held);
  if (st.gapsShortened > 0)
    warn(std::to_string(st.gapsShortened) + " gap(s) in the source's timestamps over " +
         formatNumber(PipelineOptions{}.maxGapSeconds) + " s were played as one frame interval");
  if (smoothSeconds > 0)
    std::fprintf(stderr,
                 "  --smooth %.3g s: lighting lags a step change by %.3g s (63%% of the step)\n",
                 smoothSeconds, smoothSeconds);
}

void printCameraHints(const StreamTally& t, const PipelineStats& st, bool bracketed,
                      double modeFps) {
  const std::size_t n = t.frames();
  if (n == 0) return;
  // The camera sent fewer frames than its mode asks, over two seconds or more: the driver's own
  // sequence and timestamps, so frames lost on the way count as sent.
  if (const double fps = t.deliveredFps(2.0); fps > 0 && modeFps > 0 && fps < 0.8 * modeFps)
    std::fprintf(stderr,
                 "liveprobe live: hint: the camera sent %.1f frames/s, not the %s of its mode: "
                 "in dim light its auto exposure lengthens each frame (--lock-exposure keeps "
                 "the rate), or the USB link is full (--pixel-format mjpeg, or a smaller --size)\n",
                 fps, formatFps(modeFps).c_str());
  const std::size_t unmeasured = n - std::min(n, t.brightestMeasured);
  if (!bracketed) {
    // Most frames clipped their brightest light: a sun or a lamp the 8-bit codes cannot hold.
    if (2 * unmeasured > n)
      std::fprintf(stderr,
                   "liveprobe live: hint: the brightest light clipped at 255 in %zu of %zu frames "
                   "(%.0f values a frame): its power is a lower bound; --bracket -12,-6,0 "
                   "measures it (docs/hdr.md)\n",
                   unmeasured, n, double(t.saturated) / double(n));
    return;
  }
  // The exposures contradict each other in most merges (every frame captured, drawn or not):
  // the codes are not turned into light as the camera made them.
  if (st.mergesTelling > 0 && 2 * st.mergesDisagreeing > st.mergesTelling)
    std::fprintf(stderr,
                 "liveprobe live: hint: the exposures disagree with each other in %zu of %zu "
                 "merges: is the camera's response the one merged (sRGB unless --gamma or "
                 "--response)? liveprobe calibrate DEVICE --out response.json measures it; then "
                 "--response response.json\n",
                 st.mergesDisagreeing, st.mergesTelling);
  else if (2 * unmeasured > n)
    std::fprintf(stderr,
                 "liveprobe live: hint: the brightest light clipped even in the shortest "
                 "exposure in %zu of %zu frames: its share is a lower bound (confidence at most "
                 "0.5); a shorter stop, or a neutral-density filter where the control is at its "
                 "limit, measures it (docs/hdr.md)\n",
                 unmeasured, n);
}

}  // namespace lp::cli
