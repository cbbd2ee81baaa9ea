// Subcommands on still environment maps: coeffs, irradiance, compare.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>

#include "commands.h"
#include "environment.h"
#include "liveprobe/capture/accuracy.h"
#include "liveprobe/capture/image.h"
#include "liveprobe/exchange/coeffs_io.h"
#include "liveprobe/exchange/engine_export.h"
#include "liveprobe/sh/brute.h"
#include "liveprobe/sh/error.h"
#include "liveprobe/sh/layout.h"
#include "progress.h"
#include "scene.h"

namespace lp::cli {

namespace {

/// --window: none, auto, cmgen, or a Hann width above 2.
OptionSpec windowOption() {
  OptionSpec o{
      "--window", "none|auto|cmgen|W",
      "Hann window of width W (above 2) against ringing; auto = mildest keeping E >= 0; cmgen = "
      "Filament cmgen's default (--sh-window=auto: sinc^4, its cutoff search)"};
  o.set = [](Settings& s, const std::string& v) {
    using Kind = WindowChoice::Kind;
    WindowChoice& w = s.still.window;
    w = {};
    if (v == "auto" || v == "cmgen" || v == "none") {
      w.kind = v == "auto" ? Kind::Auto : v == "cmgen" ? Kind::Cmgen : Kind::None;
      return;
    }
    w = {Kind::Hann, parseNumber(v, "--window")};
    if (!(w.width > 2.0)) throw Error("--window " + v + ": the Hann width must be greater than 2");
  };
  return o;
}

std::vector<OptionSpec> withLayout(std::vector<OptionSpec> o) {
  const auto l = layoutOptions();
  o.insert(o.begin(), l.begin(), l.end());
  return o;
}

Environment loadEnvironment(const Args& a, const LightOptions& lights = {.maxLights = 0}) {
  return cli::loadEnvironment(a.positional().at(0), a.settings().panorama, lights);
}

/// The brute force integrates the pixels the frame measured. Where the frame does not see the
/// whole sphere the coefficients also hold the --unseen fill: like is compared with like only
/// when the fill is nothing.
void requireMeasuredOnly(const Environment& env, const std::string& what) {
  if (env.coverage < 1.0 && env.layout.unseen.fill != UnseenRule::Fill::Black) {
    char share[32];
    std::snprintf(share, sizeof share, "%.1f%%", 100 * env.coverage);
    throw Error(what + ": the brute force integrates what the frame measured (" + share +
                " of the sphere), not the --unseen fill: give --unseen black");
  }
}

/// What the coefficients cover, for the JSON outputs: the measured share and, below 1, the fill.
void addCoverage(nlohmann::ordered_json& j, const Environment& env) {
  j["coverage"] = env.coverage;
  if (env.coverage < 1.0) j["unseen"] = unseenName(env.layout.unseen);
}

/// Resolves --window against the coefficients; reports an automatic choice on stderr.
BandWindow chooseWindow(const StillSettings& s, const Sh9& radiance) {
  using Kind = WindowChoice::Kind;
  const WindowChoice& w = s.window;
  if (w.kind == Kind::None) return {};
  if (w.kind == Kind::Auto) {
    const AutoWindow aw = autoWindow(radiance);
    if (std::isinf(aw.width))
      errs() << "liveprobe: --window auto: irradiance is already non-negative, no window\n";
    else
      errs() << "liveprobe: --window auto: Hann width " << aw.width << " (sigma1 "
             << aw.window.sigma1 << ", sigma2 " << aw.window.sigma2 << ")\n";
    return aw.window;
  }
  if (w.kind == Kind::Cmgen) {
    const CmgenWindow cw = cmgenWindow(radiance);
    errs() << "liveprobe: --window cmgen: cutoff " << cw.cutoff << " bands (sigma1 "
           << cw.window.sigma1 << ", sigma2 " << cw.window.sigma2 << ")\n";
    return cw.window;
  }
  return hannWindow(float(w.width));
}

}  // namespace

const CommandSpec kCoeffsSpec{
    "coeffs",
    "FILE",
    "Prints the nine radiance coefficients L_lm (R&H convention, before the A_l factors) of an\n"
    "environment map (.hdr, .exr, or 8-bit PNG/JPEG decoded from sRGB).",
    [] {
      auto o = withLayout(
          {opt::format("json (liveprobe's), text, glsl, or an engine's: three, babylon, filament, "
                       "unity, gltf, webxr (docs/engines.md)",
                       {}, "json"),
           windowOption()});
      for (auto& l : lightOptionSpecs()) o.push_back(l);
      return o;
    }(),
    1,
    1,
    "an environment map (.hdr, .exr, .png, .jpg), or a folder of six cube faces"};

int runCoeffs(const Args& a) {
  const Settings& s = a.settings();
  const CoeffFormat cf = s.output.format.value_or(CoeffFormat{});
  const std::string& format = cf.name;
  const LightOptions lights = chooseLights(s);
  const Environment env = loadEnvironment(a, lights);
  const Sh9 L = applyWindow(env.radiance, chooseWindow(s.still, env.radiance));
  if (cf.engine == Engine::Gltf) {
    std::cout << gltfDocument(env.image(), env.layout, env.orientation, L, env.lights).dump()
              << "\n";
  } else if (cf.engine) {
    nlohmann::ordered_json j;
    j["source"] = a.positional()[0];
    j["format"] = format;
    j["coefficients"] = engineJson(*cf.engine, L, env.lights);
    std::cout << j.dump() << "\n";
  } else if (format == "json") {
    nlohmann::ordered_json j;
    j["source"] = a.positional()[0];
    j["layout"] = std::string(layoutName(env.layout.layout));
    j["width"] = env.image().width;
    j["height"] = env.image().height;
    addCoverage(j, env);
    j["coefficients"] = coefficientsJson(L);
    if (lights.maxLights > 0) j["lights"] = lightsJson(env.lights);
    std::cout << j.dump() << "\n";
  } else if (format == "text") {
    std::cout << a.positional()[0] << " (" << layoutName(env.layout.layout) << ", "
              << env.image().width << "x" << env.image().height << ")\n";
    if (env.coverage < 1.0)
      std::printf("coverage: %.1f%% of the sphere measured, the rest filled by --unseen %s\n",
                  100 * env.coverage, unseenName(env.layout.unseen).c_str());
    std::cout << coefficientsText(L);
    if (lights.maxLights > 0 && env.lights.empty())
      std::printf("lights: none (no compact source holds 5%% of the power)\n");
    for (const Light& l : env.lights) std::printf("light: %s\n", lightText(l).c_str());
    const MinIrradiance mn = minIrradiance(L);
    std::printf("min irradiance over the sphere / L00-irradiance: %.4f %.4f %.4f\n",
                mn.value.x / (kA0 * kY00 * L.c[0].x), mn.value.y / (kA0 * kY00 * L.c[0].y),
                mn.value.z / (kA0 * kY00 * L.c[0].z));
  } else {
    if (!env.lights.empty())
      throw Error("--format glsl: carries the coefficients only; use json for the lights");
    std::cout << coefficientsGlsl(L);
  }
  return 0;
}

const CommandSpec kIrradianceSpec{
    "irradiance",
    "FILE",
    "Writes the irradiance environment map E(n), equirectangular and indexed by normal (or a cube\n"
    "map with --cube), computed from nine coefficients (sh) or by brute-force hemispherical\n"
    "integration (brute).\n"
    "PNG output is sRGB-encoded E/pi (the radiance of a white diffuse surface), clamped to 1.",
    withLayout(
        {opt::out("FILE", "output image (.hdr, .exr: linear irradiance; .png: 8-bit); required",
                  {".hdr", ".exr", ".png"}),
         opt::size("output size", 8192, "256x128"),
         integerOption("--cube", "N",
                       "write a cube map instead: six N x N faces in OpenGL's convention, "
                       "as a 4N x 3N horizontal cross",
                       1, 4096, "", LP_FIELD(still.cube)),
         choiceOption("--method", "how to compute E", {"sh", "brute"}, "sh", LP_FIELD(still.brute),
                      {}, [](const std::string& v) { return v == "brute"; }),
         windowOption()}),
    1,
    1,
    "an environment map (.hdr, .exr, .png, .jpg), or a folder of six cube faces",
    [](const Settings& s) {
      if (!s.output.out) throw Error("--out FILE is required");
      if (s.still.cube && s.output.size) throw Error("give --size or --cube, not both");
      if (s.still.brute && s.still.window.kind != WindowChoice::Kind::None)
        throw Error("--window applies to --method sh only");
    }};

int runIrradiance(const Args& a) {
  const Settings& s = a.settings();
  const std::string ext = requireExtension(*s.output.out, "--out", {".hdr", ".exr", ".png"});
  // The equirect indexed by normal, or (--cube N) the six faces as a 4N x 3N horizontal cross in
  // OpenGL's face convention: the cube layout that liveprobe reads (liveprobe/sh/layout.h).
  const bool cube = s.still.cube.has_value();
  const int faceSize = s.still.cube.value_or(0);
  const auto [w, h] =
      cube ? std::pair{4 * faceSize, 3 * faceSize} : s.output.size.value_or(Size{256, 128});
  Environment env = loadEnvironment(a);
  const auto grid = cube ? layoutSamples(LayoutSpec(Layout::Cube), w, h) : equirectSamples(w, h);
  std::vector<glm::vec3> normals(grid.size());
  for (std::size_t i = 0; i < grid.size(); ++i) normals[i] = grid[i].dir;
  std::vector<Rgb> e(grid.size());
  if (!s.still.brute) {
    const auto m =
        irradianceMatrices(applyWindow(env.radiance, chooseWindow(s.still, env.radiance)));
    for (std::size_t i = 0; i < normals.size(); ++i) e[i] = evalIrradianceQuadratic(m, normals[i]);
  } else {
    requireMeasuredOnly(env, "irradiance --brute");
    auto samples = layoutSamples(env.layout, env.image().width, env.image().height);
    for (auto& smp : samples) smp.dir = env.orientation * smp.dir;
    ThreadPool pool(0);
    // O(normals x pixels): minutes on a large map, so it shows its progress and a signal stops
    // it between normals, with nothing written.
    Progress progress("irradiance: brute force", std::int64_t(normals.size()), false, "normals");
    std::size_t done = 0;
    e = bruteIrradiance(env.image().rgb.data(), 3, samples.data(), samples.size(), normals, &pool,
                        [&](std::size_t n) {
                          progress.update(std::int64_t(done = n));
                          return !stopRequested();
                        });
    progress.finish();
    if (stopRequested()) {
      std::fprintf(stderr,
                   "liveprobe: irradiance stopped by a signal after %zu of %zu normals; %s not "
                   "written\n",
                   done, normals.size(), s.output.out->c_str());
      return kExitInterrupted;
    }
  }
  Image out(w, h);
  for (std::size_t i = 0; i < e.size(); ++i)  // (cells of the cross outside the faces: black)
    if (grid[i].solidAngle > 0) std::copy_n(&e[i].x, 3, out.rgb.data() + 3 * i);
  if (ext != ".hdr" && ext != ".exr")
    for (float& v : out.rgb) v /= kA0;  // 8-bit: the radiance of a white Lambertian surface
  saveImage(*s.output.out, out);
  return 0;
}

const CommandSpec kCompareSpec{
    "compare",
    "FILE",
    "Compares SH irradiance with the brute-force integral on a WxH equirect grid of normals\n"
    "(luminance, solid-angle weighted). Errors are given as a fraction of the total intensity\n"
    "(the paper's measure) and of the mean irradiance. With --sun, SH of the rest plus the\n"
    "lights is measured beside SH alone.",
    withLayout({opt::size("grid of normals", 4096, "64x32"),
                opt::out("PNG", "figure: SH map, brute-force map and error, with a colour scale",
                         {".png"}),
                opt::format("what it prints", {"text", "json"}, "text"), quietOption(),
                windowOption(), lightOptionSpecs()[0], lightOptionSpecs()[1]}),
    1,
    1,
    "an environment map (.hdr, .exr, .png, .jpg), or a folder of six cube faces"};

int runCompare(const Args& a) {
  const Settings& s = a.settings();
  const auto [w, h] = s.output.size.value_or(Size{64, 32});
  // The map is projected once, here, and the comparison takes that projection and its time.
  const LightOptions lights = chooseLights(s);
  Environment env = loadEnvironment(a, lights);
  requireMeasuredOnly(env, "compare");
  installStopHandlers();
  Progress progress("compare: brute force", std::int64_t(w) * h, s.output.quiet, "normals");
  const CompareResult r =
      compareIrradiance(env.image(), env.layout, FrameLighting{env.radiance, env.lights, env.whole},
                        env.projectMs, lights.maxLights > 0, w, h, chooseWindow(s.still, env.whole),
                        0, env.orientation, [&](std::size_t done) {
                          progress.update(std::int64_t(done));
                          return !stopRequested();
                        });
  progress.finish();
  if (stopRequested()) {
    std::fprintf(stderr, "liveprobe: compare stopped by a signal after %s\n", "part of the grid");
    return kExitInterrupted;
  }
  if (s.output.out) saveCompareFigure(*s.output.out, r);
  if (s.output.format && s.output.format->name == "json") {
    nlohmann::ordered_json j;
    j["source"] = a.positional()[0];
    j["layout"] = std::string(layoutName(env.layout.layout));
    j["input"] = std::to_string(env.image().width) + "x" + std::to_string(env.image().height);
    j["size"] = std::to_string(w) + "x" + std::to_string(h);
    addCoverage(j, env);
    j["mean_frac_total"] = r.meanFracTotal;
    j["max_frac_total"] = r.maxFracTotal;
    j["mean_rel_mean"] = r.meanRelMean;
    j["max_rel_mean"] = r.maxRelMean;
    j["min_sh_over_mean"] = r.minShOverMean;
    j["sh_ms"] = r.shMs;
    j["brute_ms"] = r.bruteMs;
    j["speed_ratio"] = r.bruteMs / r.shMs;
    j["coefficients"] = coefficientsJson(r.radiance);
    if (r.sun) {
      j["sun_mean_frac_total"] = r.meanFracTotalSun;
      j["sun_max_frac_total"] = r.maxFracTotalSun;
      j["lights"] = lightsJson(r.lights);
    }
    std::cout << j.dump(2) << "\n";
  } else {
    std::printf("%s (%s, %dx%d), %dx%d normals\n", a.positional()[0].c_str(),
                std::string(layoutName(env.layout.layout)).c_str(), env.image().width,
                env.image().height, w, h);
    std::printf("  |E_sh - E| / total intensity: mean %.3f%%  max %.3f%%\n", 100 * r.meanFracTotal,
                100 * r.maxFracTotal);
    if (r.sun) {
      std::printf("  with %zu light%s, |E_sh+lights - E| / total: mean %.3f%%  max %.3f%%\n",
                  r.lights.size(), r.lights.size() == 1 ? "" : "s", 100 * r.meanFracTotalSun,
                  100 * r.maxFracTotalSun);
      for (const Light& l : r.lights) std::printf("    light: %s\n", lightText(l).c_str());
    }
    std::printf("  |E_sh - E| / mean irradiance: mean %.3f%%  max %.3f%%\n", 100 * r.meanRelMean,
                100 * r.maxRelMean);
    std::printf("  min E_sh / mean irradiance:   %.4f%s\n", r.minShOverMean,
                r.minShOverMean < 0 ? "  (negative: ringing)" : "");
    std::printf("  time: sh %.3f ms, brute force %.1f ms, ratio %.0f\n", r.shMs, r.bruteMs,
                r.bruteMs / r.shMs);
  }
  return 0;
}

}  // namespace lp::cli
