#include "liveprobe/bench/plot.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "liveprobe/capture/atomic_file.h"
#include "liveprobe/capture/stages.h"
#include "liveprobe/sh/error.h"

namespace lp::bench {

namespace {

namespace fs = std::filesystem;

/// The frames' stages stacked, one line a frame, into `data`; the totals.
std::vector<double> writeStackedStages(const std::string& data, const std::string& path,
                                       const std::vector<std::vector<double>>& frames) {
  std::vector<double> total;
  std::ofstream d(data);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    double cum = 0;
    d << i;
    for (double v : frames[i]) d << ' ' << (cum += v);
    d << '\n';
    total.push_back(cum);
  }
  if (!d) throw Error(path + ": cannot write the plot's data beside it");
  return total;
}

/// A histogram of the totals in `bins` bins up to `top`, into `hist`.
void writeHistogram(const std::string& hist, const std::vector<double>& total, double top,
                    int bins) {
  const double width = top / bins;
  std::vector<int> counts(std::size_t(bins), 0);
  for (double t : total) counts[std::size_t(std::min(bins - 1, int(t / width)))]++;
  std::ofstream h(hist);
  for (int b = 0; b < bins; ++b) h << (b + 0.5) * width << ' ' << counts[std::size_t(b)] << '\n';
}

/// The gnuplot script: the stacked stages with the warm-up bands, then the histogram with the
/// median and p95 marked.
std::string plotScript(const std::string& png, const std::string& data, const std::string& hist,
                       const Runs& p, const std::string& title, double top, int bins, double med,
                       double p95) {
  const std::size_t frameCount = p.frames.size();
  std::ostringstream g;
  g << "set terminal pngcairo size 1400,480 font 'sans,10'\nset output '" << png << "'\n"
    << "set multiplot layout 1,2 title '" << title << "'\n"
    << "set style fill solid 0.85 noborder\nset grid ytics lc rgb '#dddddd'\n"
    << "set xlabel 'frame (all runs in order)'\nset ylabel 'time per frame (ms), stages stacked'\n"
    << "set key outside right top vertical\nset yrange [0:" << top
    << "]\nset xrange [0:" << std::max<std::size_t>(1, frameCount - 1) << "]\n";
  for (std::size_t start = 0, k = 1; start < frameCount;
       start += std::size_t(std::max(1, p.framesPerRun)), ++k)
    g << "set object " << k << " rect from " << start << ",0 to " << start + kWarmupFrames - 1
      << "," << top << " fc rgb '#909090' fs solid 0.35 noborder behind\n";
  g << "set label 1 'grey bands: the warm-up frames of each run' at graph 0.01, graph 0.96\n";
  static const char* colours[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#17becf",
                                  "#d62728", "#9467bd", "#8c564b", "#e377c2"};
  g << "plot ";
  for (int s = int(p.stages.size()) - 1; s >= 0; --s) {
    g << "'" << data << "' using 1:" << (s + 2) << " with filledcurves x1 lc rgb '"
      << colours[std::size_t(s) % std::size(colours)] << "' title '" << p.stages[std::size_t(s)]
      << "'";
    g << (s ? ", " : "\n");
  }
  g << "unset object\nunset label\nset xlabel 'frame time (ms)'\nset ylabel 'frames'\nset xrange "
       "[0:"
    << top << "]\nset yrange [0:*]\nset boxwidth " << top / bins * 0.9 << "\n"
    << "set arrow 1 from " << med << ", graph 0 to " << med
    << ", graph 1 nohead lc rgb '#2ca02c' lw 2\n"
    << "set arrow 2 from " << p95 << ", graph 0 to " << p95
    << ", graph 1 nohead lc rgb '#d62728' lw 2 dt 2\n"
    << "set label 2 sprintf('median %.2f ms', " << med << ") at " << med
    << ", graph 0.95 offset 1,0 tc rgb '#2ca02c'\n"
    << "set label 3 sprintf('p95 %.2f ms', " << p95 << ") at " << p95
    << ", graph 0.88 offset 1,0 tc rgb '#d62728'\n"
    << "plot '" << hist
    << "' using 1:2 with boxes lc rgb '#777777' title 'frames'\nunset multiplot\n";
  return g.str();
}

/// Runs gnuplot on `script`; lp::Error naming `path` with gnuplot's first line when it fails.
void runGnuplot(const std::string& script, const std::string& png, const std::string& path) {
  const std::string cmd = "gnuplot '" + script + "' 2>&1";
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (!pipe) throw Error(path + ": cannot run gnuplot");
  std::string said;
  char buf[256];
  while (std::fgets(buf, sizeof buf, pipe)) said += buf;
  const int rc = ::pclose(pipe);
  if (rc != 0 || !fs::exists(png)) {
    const auto nl = said.find('\n');
    throw Error(path + ": gnuplot failed (" +
                (rc == 127 * 256 ? std::string("not installed: scripts/deps installs gnuplot-nox")
                                 : said.substr(0, nl)) +
                ")");
  }
}

}  // namespace

void drawStagePlot(const std::string& path, const Runs& p, const std::string& title) {
  AtomicOutput plot(path);  // gnuplot writes the PNG under its temporary name
  const std::string& png = plot.temporary();
  const std::string stem = png.substr(0, png.size() - fs::path(png).extension().string().size());
  const std::string data = stem + ".dat", hist = stem + ".hist", script = stem + ".gp";
  struct Cleanup {  // gnuplot's inputs
    std::vector<std::string> files;
    ~Cleanup() {
      std::error_code ec;
      for (const auto& f : files) fs::remove(f, ec);
    }
  } cleanup{{data, hist, script}};

  const std::vector<double> total = writeStackedStages(data, path, p.frames);
  const double med = percentile(total, 0.5), p95 = percentile(total, 0.95);
  // A warm-up spike does not set the scale.
  const double top = std::max(1e-3, percentile(total, 0.99) * 1.25);
  constexpr int kBins = 40;
  writeHistogram(hist, total, top, kBins);
  {
    std::ofstream f(script);
    f << plotScript(png, data, hist, p, title, top, kBins, med, p95);
    if (!f) throw Error(path + ": cannot write the plot's script beside it");
  }
  runGnuplot(script, png, path);
  plot.commit();
}

}  // namespace lp::bench
