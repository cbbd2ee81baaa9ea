// Environments and lighting from the command line: --env (any layout, oriented), --coeffs,
// --coeff.
#include "environment.h"

#include <chrono>
#include <cmath>

#include "commands.h"
#include "liveprobe/capture/ball.h"
#include "liveprobe/capture/frame_processor.h"
#include "liveprobe/capture/lens.h"
#include "liveprobe/capture/open_source.h"
#include "liveprobe/capture/photometry.h"
#include "liveprobe/exchange/coeffs_io.h"
#include "liveprobe/frame/input_file.h"
#include "liveprobe/sh/error.h"
#include "progress.h"

namespace lp::cli {

glm::mat3 envOrientation(const PanoramaSettings& p) {
  glm::mat3 o(1.0f);
  if (p.rotate) {
    const Triple& v = *p.rotate;
    o = rotationYawPitchRoll(float(v[0]), float(v[1]), float(v[2]));
  }
  if (p.flip) o = o * glm::mat3(glm::vec3(1, 0, 0), glm::vec3(0, 1, 0), glm::vec3(0, 0, -1));
  return o;
}

LayoutSpec layoutSpec(const PanoramaSettings& p, const FrameSource* source, bool findsBall) {
  const bool known = source && source->layout();
  const Layout native = known ? *source->layout() : Layout::Equirect;
  LayoutSpec spec(native);
  if (p.layout) {
    spec.layout = *p.layout;
    if (known && spec.layout != native)
      throw Error(source->describe() + ": the frames are a " + std::string(layoutName(native)) +
                  " layout; --layout " + std::string(layoutName(*p.layout)) + " does not apply");
  }
  if (p.circle || p.circleAuto) {
    if (spec.layout != Layout::MirrorBall)
      throw Error("--circle applies to --layout mirrorball only");
    if (p.circle)
      spec.circle = {float((*p.circle)[0]), float((*p.circle)[1]), float((*p.circle)[2])};
    else if (!findsBall)
      throw Error(
          "--circle auto: bench times one circle throughout: give it as --circle cx,cy,r "
          "(`liveprobe coeffs FRAME --layout mirrorball --circle auto` prints it)");
  } else if (spec.layout == Layout::MirrorBall) {
    throw Error(
        "--layout mirrorball needs --circle cx,cy,r (the mirror ball's centre and radius in "
        "pixels) or --circle auto");
  }
  if (p.fov) {
    if (spec.layout != Layout::DualFisheye) throw Error("--fov applies to --layout fisheye only");
    spec.fisheyeFovDeg = float(*p.fov);
  }
  if (p.lens && spec.layout == Layout::MirrorBall) {
    const LensCalibration camera = readLensCalibration(*p.lens);  // (its errors before the image's)
    if (p.circle) spec.lens = makeBallModel(camera, spec.circle);
  } else if (p.lens) {
    if (p.layout && spec.layout != Layout::Lens)
      throw Error("--lens applies to --layout lens or mirrorball only");
    if (known && native != Layout::Lens)
      throw Error(source->describe() + ": the frames are a " + std::string(layoutName(native)) +
                  " layout; --lens does not apply");
    spec.layout = Layout::Lens;
    spec.lens = makeLensModel(readLensCalibration(*p.lens));
  } else if (spec.layout == Layout::Lens) {
    throw Error(
        "--layout lens needs --lens FILE: the camera's calibration (OpenCV FileStorage YAML/JSON "
        "or ROS camera_info)");
  }
  if (p.unseen) spec.unseen = *p.unseen;
  return spec;
}

std::optional<FrameWindow> ballSearchWindow(const LensCalibration& camera, int width, int height) {
  // (A frame the lens does not fit is refused where it is projected.)
  if (!makeLensModel(camera)->mismatch(width, height).empty()) return std::nullopt;
  const double r = seenRadius(camera, width, height);
  if (r <= 0) return std::nullopt;
  const double cx = camera.K[2] * width / camera.width + 0.5,
               cy = camera.K[5] * height / camera.height + 0.5, half = r / std::sqrt(2.0);
  const int x0 = std::max(0, int(std::ceil(cx - half))),
            y0 = std::max(0, int(std::ceil(cy - half)));
  return FrameWindow{x0, y0, std::min(width, int(cx + half)) - x0,
                     std::min(height, int(cy + half)) - y0};
}

void ballCircle(LayoutSpec& spec, const PanoramaSettings& p, const Frame& frame,
                const std::string& source) {
  const std::optional<FrameWindow> within =
      p.lens ? ballSearchWindow(readLensCalibration(*p.lens), frame.width, frame.height)
             : std::nullopt;
  const std::optional<BallCircle> ball = within ? findBallWithin(frame, *within) : findBall(frame);
  if (!ball)
    throw Error(source +
                ": --circle auto found no mirror ball (a circle from a tenth to a half of the "
                "frame's shorter side whose rim holds); give --circle cx,cy,r");
  spec.circle = {float(ball->x), float(ball->y), float(ball->radius)};
  if (p.lens) spec.lens = makeBallModel(readLensCalibration(*p.lens), spec.circle);
  char line[256];
  std::snprintf(line, sizeof line,
                "liveprobe: %s: mirror ball found: --circle %.2f,%.2f,%.2f (the rim's fit %.2f px "
                "RMS over %d of 32 sectors)\n",
                source.c_str(), ball->x, ball->y, ball->radius, ball->rimResidual,
                ball->rimSectors);
  std::fputs(line, stderr);
}

Environment loadEnvironment(const std::string& source, const PanoramaSettings& p,
                            const LightOptions& lights, bool background,
                            const std::function<Sh9(const ProjectionJob&)>& projectWith) {
  layoutSpec(p, nullptr, true);  // option errors before the file is read
  auto src = openSource(source);
  // One map: a sequence or a video is replayed, not read as its first frame.
  if (const std::int64_t n = src->frameCount(); n > 1)
    throw Error(source + ": " + std::to_string(n) +
                " frames (a sequence or a video), not one map: name one image, or replay it");
  auto frame = std::make_shared<Frame>();
  if (!src->next(*frame)) throw Error(source + ": no frame to read");
  Environment env;
  env.layout = layoutSpec(p, src.get(), true);
  if (p.circleAuto) ballCircle(env.layout, p, *frame, source);
  env.orientation = envOrientation(p);
  FrameProcessor processor({env.layout, Photometry{}, env.orientation, 1, lights});
  FrameResult r;
  try {
    processor.fit(*frame);  // the tables, before the projection is timed
    r = processor.run(frame,
                      {.background = background, .linear = true, .projectWith = projectWith});
  } catch (const Error& e) {
    throw Error(source + ": " + e.what());
  }
  env.projectMs = r.times[Stage::Project];
  env.projectedOn = r.projectedOn;
  env.coverage = processor.projector()->coverage();
  env.radiance = r.lighting.radiance;
  env.lights = std::move(r.lighting.lights);
  env.whole = r.lighting.whole;
  env.linear = std::move(r.linear);
  env.background = std::move(r.background);
  warnIfLayoutLooksWrong(source, env.layout, p.layout || p.lens, env.image().width,
                         env.image().height, env.image().rgb.data());
  return env;
}

void warnIfLayoutLooksWrong(const std::string& source, const LayoutSpec& layout, bool given, int w,
                            int h, const float* rgb) {
  const bool guessedEquirect = layout.layout == Layout::Equirect && !given;
  const std::string scaled = layout.lens ? layout.lens->scaling(w, h) : std::string();
  if (!scaled.empty()) {
    warn(source + ": " + scaled);
  } else if (guessedEquirect && w == h) {
    warn(source +
         ": a square image taken as equirect (an angular map or a mirror ball? give --layout)");
  } else if (guessedEquirect && std::abs(double(w) / h - 16.0 / 9.0) < 0.02) {
    warn(source +
         ": a 16:9 frame taken as equirect (a 2:1 panorama stretched to 16:9 covers the sphere: "
         "give --layout equirect; a camera's view does not)");
  } else if ((layout.layout == Layout::Angular || layout.layout == Layout::DualFisheye) && rgb &&
             w >= 16 && h >= 8) {
    // Outside its discs an angular map or a dual fisheye frame is black: compare the corners'
    // pixels (of each half, for two lenses) with the discs' centres.
    const bool dual = layout.layout == Layout::DualFisheye;
    const auto at = [&](int x, int y) {
      const float* p = rgb + 3 * (std::size_t(y) * std::size_t(w) + std::size_t(x));
      return double(p[0]) + p[1] + p[2];
    };
    std::vector<int> xs = {1, w - 2}, centres = {w / 2};
    if (dual) xs = {1, w / 2 - 2, w / 2 + 1, w - 2}, centres = {w / 4, 3 * w / 4};
    double corner = 0, centre = 0;
    for (const int cy : {1, h - 2})
      for (const int cx : xs) corner += at(cx, cy);
    for (const int cx : centres) centre += at(cx, h / 2);
    if (corner / double(2 * xs.size()) > 0.01 * std::max(centre / double(centres.size()), 1e-6))
      warn(source +
           (dual ? ": a dual fisheye frame whose corners are not black"
                 : ": an angular map whose corners are not black") +
           " (is it an equirect? give --layout)");
  }
}

CoeffAssignment parseCoeffAssignment(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos)
    throw Error("--coeff " + text + ": expected NAME=VALUE, e.g. L20=-0.2");
  const std::string name = text.substr(0, eq);
  const int k = shIndex(name);
  if (k < 0)
    throw Error("--coeff " + text + ": unknown coefficient name " + name + " (L00 .. L22)");
  std::vector<float> v;
  std::stringstream s(text.substr(eq + 1));
  for (std::string part; std::getline(s, part, ',');) {
    const double x = parseNumber(part, "--coeff " + name);
    if (std::abs(x) > kMaxLightingValue)
      throw Error("--coeff " + text + ": the most liveprobe takes is " +
                  formatNumber(kMaxLightingValue));
    v.push_back(float(x));
  }
  if (v.size() == 1) v = {v[0], v[0], v[0]};
  if (v.size() != 3) throw Error("--coeff " + text + ": expected one value or r,g,b");
  return {k, {v[0], v[1], v[2]}};
}

std::optional<Lighting> lightingFrom(const Settings& st,
                                     const std::function<Sh9(const ProjectionJob&)>& projectWith) {
  const LightingSettings& ls = st.lighting;
  const int kinds = int(ls.env.has_value()) + int(ls.coeffs.has_value()) + int(!ls.coeff.empty());
  if (kinds > 1) throw Error("give only one of --env, --coeffs and --coeff");
  if (kinds == 0) return std::nullopt;
  const LightOptions lights = chooseLights(st);
  if (lights.maxLights > 0 && !ls.env)
    throw Error(
        "--sun and --lights take the lights out of an --env map (a --coeffs file carries "
        "its own)");
  Lighting l;
  if (ls.env) {
    Environment env = loadEnvironment(*ls.env, st.panorama, lights, true, projectWith);
    l.lights = env.lights;
    l.layout = env.layout;
    l.orientation = env.orientation;
    l.radiance = env.radiance;
    l.background = std::move(env.background);
    l.projectedOn = env.projectedOn;
  } else {
    if (ls.coeffs) {
      l.radiance = loadCoefficients(*ls.coeffs, &l.lights);
    } else {
      for (const CoeffAssignment& c : ls.coeff) l.radiance.c[std::size_t(c.index)] = c.value;
    }
    LightSplit turned = rotateSplit({l.radiance, l.lights}, envOrientation(st.panorama));
    l.radiance = turned.residual;
    l.lights = std::move(turned.lights);
  }
  return l;
}

}  // namespace lp::cli
