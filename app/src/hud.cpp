#include "hud.h"

#include <imgui.h>
#include <imgui_impl_opengl3.h>

#include "liveprobe/backends.h"
#if LIVEPROBE_WITH_GLFW
#include <imgui_impl_glfw.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "liveprobe/capture/atomic_file.h"
#include "liveprobe/exchange/coeffs_io.h"
#include "liveprobe/sh/error.h"
#include "progress.h"

namespace lp::cli {

namespace {

// Dear ImGui's platform backend for a window (GLFW's; a build without GLFW has no windows).
#if LIVEPROBE_WITH_GLFW
bool platformInit(GLFWwindow* window) { return ImGui_ImplGlfw_InitForOpenGL(window, true); }
void platformShutdown() { ImGui_ImplGlfw_Shutdown(); }
void platformNewFrame() { ImGui_ImplGlfw_NewFrame(); }
#else
bool platformInit(GLFWwindow*) { return false; }
void platformShutdown() {}
void platformNewFrame() {}
#endif

constexpr std::size_t kHistory = 300;  // frames kept for the plots
const ImU32 kChannel[3] = {IM_COL32(235, 80, 70, 255), IM_COL32(90, 200, 90, 255),
                           IM_COL32(80, 140, 240, 255)};
// The stages the HUD plots (lp::Stage up to render), each with its colour.
constexpr std::size_t kPlotted = std::size_t(Stage::Render) + 1;
const ImU32 kStageColour[kPlotted] = {IM_COL32(100, 180, 255, 255), IM_COL32(240, 220, 80, 255),
                                      IM_COL32(255, 160, 60, 255),  IM_COL32(110, 220, 110, 255),
                                      IM_COL32(80, 210, 210, 255),  IM_COL32(255, 110, 110, 255),
                                      IM_COL32(200, 150, 255, 255)};

/// Several series on one set of axes (ImGui's PlotLines draws one), scaled to [lo, hi], clipped
/// to their box, with `label` (if any) in its top left corner.
void plotSeries(const char* id, const std::vector<std::vector<float>>& series,
                const std::vector<ImU32>& colours, ImVec2 size, float lo, float hi,
                const char* label = nullptr) {
  ImGui::PushID(id);
  const ImVec2 p0 = ImGui::GetCursorScreenPos(), p1(p0.x + size.x, p0.y + size.y);
  ImDrawList* dl = ImGui::GetWindowDrawList();
  dl->AddRectFilled(p0, p1, IM_COL32(20, 20, 24, 200));
  dl->PushClipRect(p0, p1, true);
  if (lo < 0 && hi > 0) {
    const float y0 = p1.y - size.y * (0 - lo) / (hi - lo);
    dl->AddLine({p0.x, y0}, {p1.x, y0}, IM_COL32(90, 90, 90, 255));
  }
  const float inset = 1.5f;  // the line's width stays inside the box
  for (std::size_t s = 0; s < series.size(); ++s) {
    const auto& v = series[s];
    if (v.size() < 2) continue;
    std::vector<ImVec2> pts(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) {
      const float t = std::clamp((v[i] - lo) / std::max(1e-12f, hi - lo), 0.0f, 1.0f);
      const float age = float(v.size() - 1 - i);  // the newest frame at the right edge
      pts[i] = {p1.x - size.x * age / float(kHistory - 1), p1.y - inset - (size.y - 2 * inset) * t};
    }
    dl->AddPolyline(pts.data(), int(pts.size()), colours[s], 0, 1.5f);
  }
  if (label) dl->AddText({p0.x + 2, p0.y + 1}, IM_COL32(220, 220, 220, 255), label);
  dl->PopClipRect();
  ImGui::Dummy(size);
  ImGui::PopID();
}

/// Dear ImGui's dark style as the HUD uses it, before scaling.
ImGuiStyle baseStyle() {
  ImGuiStyle style;
  ImGui::StyleColorsDark(&style);
  style.WindowRounding = 4.0f;
  style.Alpha = 0.95f;
  return style;
}

/// Whether `height` more pixels fit in the current panel below its cursor.
bool fits(float height, float maxHeight) {
  return ImGui::GetCursorPosY() + height + ImGui::GetStyle().WindowPadding.y <= maxHeight;
}

void applyKeys(const std::vector<KeyAction>& keys, ViewState& s, bool canPause) {
  for (const auto k : keys) switch (k) {
      case KeyAction::Pause:
        if (canPause) s.paused = !s.paused;
        break;
      case KeyAction::Step:
        if (canPause) s.paused = true, ++s.steps;
        break;
      case KeyAction::ResetView:
        s.camera = s.initialCamera;
        break;
      case KeyAction::ToggleBackground:
        s.shading.background = !s.shading.background;
        break;
      case KeyAction::ToggleHud:
        s.hud = !s.hud;
        break;
      case KeyAction::ExposureUp:
        s.shading.exposure *= std::sqrt(2.0f);
        break;  // half a stop
      case KeyAction::ExposureDown:
        s.shading.exposure /= std::sqrt(2.0f);
        break;
      case KeyAction::Help:
        s.help = !s.help;
        break;
      case KeyAction::Save:
        break;  // the coefficient editor's (view)
    }
}

}  // namespace

HudLayout hudLayout(glm::ivec2 size) {
  HudLayout l;
  l.size = size;
  const float w = float(std::max(1, size.x)), h = float(std::max(1, size.y));
  l.scale = std::clamp(std::min(w / 1280.0f, h / 720.0f), 0.75f, 2.0f);
  l.margin = 8.0f * l.scale;
  l.statusWidth = 330.0f * l.scale;
  l.lightWidth = 290.0f * l.scale;
  for (const auto& [status, light] : {std::pair{true, true}, {true, false}, {false, false}}) {
    const float x0 = status ? 2 * l.margin + l.statusWidth : 0.0f;
    const float x1 = w - (light ? 2 * l.margin + l.lightWidth : 0.0f);
    if (x1 - x0 >= 0.2f * w || !status) {
      l.status = status;
      l.light = light;
      l.modelFrame = {x0 / w, 0.0f, x1 / w, 1.0f};
      break;
    }
  }
  return l;
}

gl::Camera framedBesideHud(gl::Camera camera, const HudLayout& layout, bool hudShown) {
  if (hudShown) camera.frame = layout.modelFrame;
  return camera;
}

void RateTitle::tick(WindowInput& input, const std::string& prefix, const std::string& suffix) {
  ++frames_;
  const auto now = std::chrono::steady_clock::now();
  const double s = std::chrono::duration<double>(now - t0_).count();
  if (s < 1.0) return;
  char rate[64];
  std::snprintf(rate, sizeof rate, " - %.1f frames/s", double(frames_) / s);
  input.setTitle(prefix + rate + suffix);
  t0_ = now, frames_ = 0;
}

std::vector<KeyAction> handleInput(WindowInput& window, const Hud* hud, ViewState& state,
                                   bool canPause) {
  InputDelta input = window.poll();
  if (!(hud && hud->wantsKeyboard())) applyKeys(input.keys, state, canPause);
  if (!(hud && hud->wantsMouse())) {
    gl::Camera& c = state.camera;
    c.yawDeg -= 0.3f * input.drag.x;
    c.pitchDeg = std::clamp(c.pitchDeg + 0.3f * input.drag.y, -89.0f, 89.0f);
    c.distance = std::clamp(c.distance * std::pow(0.9f, input.scroll), 1.1f, 50.0f);
  }
  return std::move(input.keys);
}

Hud::Hud(gl::GlContext& ctx) : window_(!ctx.isHeadless()) {
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;  // no imgui.ini left in the user's folder
  ImGui::GetStyle() = baseStyle();
  if (window_ && !platformInit(ctx.window()))
    throw Error("HUD: cannot attach Dear ImGui to the window");
  if (!ImGui_ImplOpenGL3_Init("#version 330 core")) {
    if (window_) platformShutdown();
    ImGui::DestroyContext();
    throw Error("HUD: cannot initialise Dear ImGui's OpenGL 3 renderer");
  }
}

Hud::~Hud() {
  ImGui_ImplOpenGL3_Shutdown();
  if (window_) platformShutdown();
  ImGui::DestroyContext();
}

void Hud::setSource(std::string source, std::string layout, bool smoothing, bool still) {
  still_ = still;
  source_ = std::move(source);
  layout_ = std::move(layout);
  smoothing_ = smoothing;
}

void Hud::push(const HudSample& s) {
  history_.push_back(s);
  while (history_.size() > kHistory) history_.pop_front();
}

void Hud::enableEditor(Sh9* radiance, std::string savePath) {
  editing_ = radiance;
  savePath_ = std::move(savePath);
}

std::string Hud::saveCoefficients() {
  if (!editing_) return {};
  try {
    nlohmann::ordered_json j;
    j["source"] = "liveprobe view (edited)";
    j["coefficients"] = coefficientsJson(*editing_);
    writeFileAtomically(savePath_, j.dump() + "\n");
    saveMessage_ = "saved the coefficients to " + savePath_;
  } catch (const Error& e) {
    saveMessage_ = e.what();
  }
  return saveMessage_;
}

bool Hud::wantsMouse() const { return ImGui::GetIO().WantCaptureMouse; }
bool Hud::wantsKeyboard() const { return ImGui::GetIO().WantCaptureKeyboard; }

void Hud::applyScale(float scale) {
  if (scale == scale_) return;
  ImGui::GetStyle() = baseStyle();
  ImGui::GetStyle().ScaleAllSizes(scale);
  ImGui::GetIO().FontGlobalScale = scale;
  scale_ = scale;
}

void Hud::recordPanel(const char* name) {
  const ImVec2 pos = ImGui::GetWindowPos(), size = ImGui::GetWindowSize();
  panels_.push_back({name,
                     {pos.x, pos.y},
                     {pos.x + size.x, pos.y + size.y},
                     ImGui::GetCursorPosY() - ImGui::GetStyle().ItemSpacing.y +
                         ImGui::GetStyle().WindowPadding.y});
}

void Hud::draw(const HudLayout& layout, gl::Renderer& renderer, ViewState& state, double frameMs) {
  edited_ = false;
  ImGuiIO& io = ImGui::GetIO();
  ImGui_ImplOpenGL3_NewFrame();
  if (window_) {
    platformNewFrame();
  } else {
    io.DisplaySize = ImVec2(float(layout.size.x), float(layout.size.y));
    io.DeltaTime = 1.0f / 30.0f;
  }
  applyScale(layout.scale);
  const float maxHeight = io.DisplaySize.y - 2 * layout.margin;
  fpsSmoothed_ = fpsSmoothed_ == 0 ? frameMs : 0.9 * fpsSmoothed_ + 0.1 * frameMs;
  if (state.hud && layout.light) renderer.drawProbeViews(state.camera, state.shading);
  // ImGui sizes auto-fitting windows on their first frame and shows them from the second: a
  // headless still has only one, so lay the HUD out once unseen first.
  for (int pass = laidOut_ ? 1 : 0; pass < 2; ++pass) {
    ImGui::NewFrame();
    panels_.clear();
    if (state.hud) {
      if (layout.status) drawStatus(state, frameMs, layout, maxHeight);
      if (layout.light) drawLight(renderer, layout, maxHeight);
      if (editing_) drawEditor(layout);
    }
    if (state.help) drawHelp(state);
    if (pass == 0) ImGui::EndFrame();
  }
  laidOut_ = true;
  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

namespace {

/// A fixed-width panel at `pos` (pivot `pivot`), as tall as its content up to `maxHeight`.
void beginPanel(const char* name, ImVec2 pos, ImVec2 pivot, float width, float maxHeight) {
  ImGui::SetNextWindowPos(pos, ImGuiCond_Always, pivot);
  ImGui::SetNextWindowSizeConstraints({width, 0}, {width, maxHeight});
  ImGui::SetNextWindowSize({width, 0}, ImGuiCond_Always);
  ImGui::SetNextWindowBgAlpha(0.6f);
  ImGui::Begin(name, nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize |
                   ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoFocusOnAppearing |
                   ImGuiWindowFlags_NoScrollbar | ImGuiWindowFlags_NoScrollWithMouse);
}

}  // namespace

void Hud::drawStatus(ViewState& state, double frameMs, const HudLayout& layout, float maxHeight) {
  beginPanel("liveprobe", {layout.margin, layout.margin}, {0, 0}, layout.statusWidth, maxHeight);
  ImGui::TextWrapped("%s", source_.c_str());
  ImGui::Text("layout %s%s", layout_.c_str(), state.paused ? "   [PAUSED]" : "");
  if (!still_ && !history_.empty())
    ImGui::Text("frame %llu   t = %.3f s", static_cast<unsigned long long>(history_.back().frame),
                history_.back().time);
  ImGui::Text("%.1f frames/s   %.2f ms/frame", fpsSmoothed_ > 0 ? 1000.0 / fpsSmoothed_ : 0.0,
              frameMs);
  if (!note_.empty()) ImGui::TextColored({1.0f, 0.85f, 0.45f, 1.0f}, "%s", note_.c_str());
  if (!still_ && !history_.empty()) {
    std::vector<double> latency;
    for (const auto& h : history_) latency.push_back(h.latencyMs);
    ImGui::Text("latency p50 %.1f  p95 %.1f  p99 %.1f ms", percentile(latency, 0.5),
                percentile(latency, 0.95), percentile(latency, 0.99));
    const HudSample& h = history_.back();
    const FrameConfidence& c = h.confidence;
    const ImVec4 colour = h.held || !c.brightestMeasured ? ImVec4{1.0f, 0.7f, 0.3f, 1.0f}
                                                         : ImVec4{0.75f, 0.9f, 0.75f, 1.0f};
    ImGui::TextColored(colour, "confidence %.2f  clipped %.1f%%%s%s", c.value(),
                       100.0 * c.clippedShare, c.exposures > 1 ? "  bracket" : "",
                       h.held ? "  HELD" : "");
  }
  if (!waiting_.empty())
    ImGui::TextColored({1.0f, 0.7f, 0.3f, 1.0f}, "lighting HELD, %s", waiting_.c_str());
  const float line = ImGui::GetTextLineHeightWithSpacing();
  const int counterLines = still_ ? 0 : 2 + int(counters_.sinks.size());
  // What must stay: the counters and the exposure; the stage times go first when short of room.
  const float reserved = float(counterLines + (window_ ? 2 : 1)) * line;
  if (!still_ && !history_.empty()) drawStatusTimes(maxHeight - reserved);
  if (!still_) {
    ImGui::Text("captured %zu  drawn %zu  dropped %zu", counters_.captured, counters_.drawn,
                counters_.dropped);
    ImGui::Text("skipped %zu  saturated %.1f/frame", counters_.skipped,
                counters_.saturatedPerFrame);
    for (const std::string& sink : counters_.sinks) ImGui::TextUnformatted(sink.c_str());
  }
  float ev = std::log2(state.shading.exposure);
  if (window_) {  // the window's controls; a headless frame only says the exposure
    ImGui::SetNextItemWidth(0.5f * layout.statusWidth);
    if (ImGui::DragFloat("exposure (EV)", &ev, 0.05f, -16.0f, 16.0f, "%+.2f"))
      state.shading.exposure = std::exp2(ev);
    ImGui::Checkbox("background", &state.shading.background);
    ImGui::SameLine();
    ImGui::TextDisabled("F1: help");
  } else {
    ImGui::Text("exposure %+.2f EV", ev);
  }
  recordPanel("liveprobe");
  ImGui::End();
}

void Hud::drawStatusTimes(float maxHeight) {
  const float s = scale_, line = ImGui::GetTextLineHeightWithSpacing();
  const float plotHeight = 70.0f * s;
  if (!fits(line + plotHeight + 2 * line, maxHeight)) return;
  // The stages up to render; merge and resample only where they ran.
  std::vector<std::size_t> shown;
  for (std::size_t k = 0; k < kPlotted; ++k)
    if (!stageRunsForSomeSources(Stage(k)) ||
        std::any_of(history_.begin(), history_.end(),
                    [&](const HudSample& h) { return h.times.ms[k] > 0; }))
      shown.push_back(k);
  std::vector<std::vector<float>> series;
  std::vector<ImU32> colours;
  std::vector<float> all;
  for (const std::size_t k : shown) {
    series.emplace_back();
    colours.push_back(kStageColour[k]);
    for (const auto& h : history_) {
      series.back().push_back(float(h.times.ms[k]));
      all.push_back(float(h.times.ms[k]));
    }
  }
  // The GPU's own times where a GPU timer read them: in their stage's colour, dimmed.
  constexpr Stage kGpuStage[] = {Stage::Upload, Stage::Project, Stage::Merge,
                                 Stage::Render};  // kTimes's
  std::string gpuLine;
  for (std::size_t g = 0; g < GpuTimes::kTimes.size(); ++g) {
    const Stage stage = kGpuStage[g];
    const auto member = GpuTimes::kTimes[g].second;
    const std::optional<double>& latest = history_.back().gpu.*member;
    if (!latest) continue;
    series.emplace_back();
    colours.push_back((kStageColour[std::size_t(stage)] & 0x00FFFFFFu) | 0x90000000u);
    for (const auto& h : history_) {
      const float ms = float((h.gpu.*member).value_or(0.0));
      series.back().push_back(ms);
      all.push_back(ms);
    }
    char b[64];
    std::snprintf(b, sizeof b, "%s%s %.2f", gpuLine.empty() ? "GPU: " : ", ",
                  std::string(stageName(stage)).c_str(), *latest);
    gpuLine += b;
  }
  // The scale follows the 95th percentile: a warm-up spike does not flatten everything else.
  std::nth_element(all.begin(), all.begin() + std::ptrdiff_t(all.size() * 95 / 100), all.end());
  const float top = std::max(1.0f, 1.3f * all[all.size() * 95 / 100]);
  ImGui::TextWrapped("stage times, last %zu frames (0 .. %.1f ms)", history_.size(), top);
  plotSeries("stages", series, colours, {ImGui::GetContentRegionAvail().x, plotHeight}, 0, top);
  const StageTimes& now = history_.back().times;
  if (ImGui::BeginTable("stages", 3)) {
    for (const std::size_t k : shown) {
      ImGui::TableNextColumn();
      ImGui::TextColored(ImColor(kStageColour[k]), "%s %.1f ms",
                         std::string(kStageNames[k]).c_str(), now.ms[k]);
    }
    ImGui::EndTable();
  }
  if (!gpuLine.empty()) ImGui::TextWrapped("%s ms (timer queries)", gpuLine.c_str());
}

void Hud::drawLight(gl::Renderer& renderer, const HudLayout& layout, float maxHeight) {
  const ImGuiIO& io = ImGui::GetIO();
  beginPanel("light", {io.DisplaySize.x - layout.margin, layout.margin}, {1, 0}, layout.lightWidth,
             maxHeight);
  drawProbes(renderer, maxHeight);
  drawCoefficientBars(maxHeight);
  if (!still_) drawLightPlots(maxHeight);
  recordPanel("light");
  ImGui::End();
}

void Hud::drawProbes(gl::Renderer& renderer, float maxHeight) {
  auto imageSize = [&](gl::ProbeView v, float scale) {
    const glm::ivec2 size = renderer.probeSize(v);
    return ImVec2{float(size.x) * scale * scale_, float(size.y) * scale * scale_};
  };
  auto image = [&](gl::ProbeView v, float scale) {
    // The textures are rendered bottom-up (GL): flip v.
    ImGui::Image(
        reinterpret_cast<ImTextureID>(static_cast<std::uintptr_t>(renderer.probeTexture(v))),
        imageSize(v, scale), {0, 1}, {1, 0});
  };
  const float line = ImGui::GetTextLineHeightWithSpacing();
  const std::vector<Light> none;
  const auto& lights = history_.empty() ? none : history_.back().lights;
  if (fits(imageSize(gl::ProbeView::Panorama, 1.05f).y + float(lights.size()) * line, maxHeight)) {
    image(gl::ProbeView::Panorama, 1.05f);
    drawLightMarks(lights);
    for (const Light& l : lights)
      ImGui::TextWrapped("light %.0f%%  r %.2f deg  E %.3g%s", 100 * l.share,
                         glm::degrees(l.angularRadius), luminance(l.power),
                         l.clipped ? " clipped" : "");
  }
  if (fits(imageSize(gl::ProbeView::DiffuseBall, 1.0f).y + line, maxHeight)) {
    image(gl::ProbeView::DiffuseBall, 1.0f);
    ImGui::SameLine();
    image(gl::ProbeView::ChromeBall, 1.0f);
    ImGui::TextDisabled("grey 50%% diffuse");
    ImGui::SameLine(imageSize(gl::ProbeView::DiffuseBall, 1.0f).x +
                    ImGui::GetStyle().WindowPadding.x + ImGui::GetStyle().ItemSpacing.x);
    ImGui::TextDisabled("chrome");
  }
}

void Hud::drawLightMarks(const std::vector<Light>& lights) {
  // The lights (--sun) marked where they are on the panorama just drawn: the inset is the
  // world's equirect (azimuth left to right from +x, the zenith at the top; shaders.cpp,
  // kProbeFs mode 0).
  const ImVec2 lo = ImGui::GetItemRectMin(), hi = ImGui::GetItemRectMax();
  ImDrawList* marks = ImGui::GetWindowDrawList();
  for (const Light& l : lights) {
    float p = std::atan2(l.dir.y, l.dir.x);
    if (p < 0) p += 2 * float(kPi);
    const float t = std::acos(std::clamp(l.dir.z, -1.0f, 1.0f));
    const ImVec2 c{lo.x + (hi.x - lo.x) * p / (2 * float(kPi)),
                   lo.y + (hi.y - lo.y) * t / float(kPi)};
    marks->AddCircle(c, 7.0f * scale_, IM_COL32(255, 60, 40, 255), 16, 2.0f * scale_);
    marks->AddCircle(c, 8.5f * scale_, IM_COL32(0, 0, 0, 200), 16, 1.0f * scale_);
  }
}

void Hud::drawCoefficientBars(float maxHeight) {
  // The nine coefficients: bars per channel, scaled to the largest magnitude.
  const Sh9& L = history_.empty() ? Sh9{} : history_.back().radiance;
  float scale = 1e-12f;
  for (const auto& c : L.c) scale = std::max({scale, std::abs(c.x), std::abs(c.y), std::abs(c.z)});
  ImDrawList* dl = ImGui::GetWindowDrawList();
  const float line = ImGui::GetTextLineHeightWithSpacing();
  const float barW = 120.0f * scale_, barH = 4.0f * scale_;
  if (!fits(9 * std::max(line, 3 * barH + ImGui::GetStyle().ItemSpacing.y), maxHeight)) return;
  for (int k = 0; k < kShCount; ++k) {
    ImGui::Text("%-4s", std::string(kShNames[std::size_t(k)]).c_str());
    ImGui::SameLine(44.0f * scale_);
    const ImVec2 p = ImGui::GetCursorScreenPos();
    const float mid = p.x + barW / 2;
    dl->AddLine({mid, p.y}, {mid, p.y + 3 * barH}, IM_COL32(120, 120, 120, 255));
    for (int ch = 0; ch < 3; ++ch) {
      const float v = L.c[std::size_t(k)][ch] / scale * (barW / 2);
      dl->AddRectFilled({std::min(mid, mid + v), p.y + float(ch) * barH},
                        {std::max(mid, mid + v), p.y + float(ch + 1) * barH - 1}, kChannel[ch]);
    }
    ImGui::Dummy({barW, 3 * barH});
    ImGui::SameLine();
    ImGui::Text("%+.3f", luminance(L.c[std::size_t(k)]));
  }
}

void Hud::drawLightPlots(float maxHeight) {
  // Each coefficient's luminance over time, labelled; with --smooth the raw value is in grey.
  const float line = ImGui::GetTextLineHeightWithSpacing(), gap = ImGui::GetStyle().ItemSpacing.x;
  const ImVec2 size{(ImGui::GetContentRegionAvail().x - 2 * gap) / 3, 26.0f * scale_};
  if (!fits(2 * line + 3 * (size.y + ImGui::GetStyle().ItemSpacing.y), maxHeight)) return;
  ImGui::TextWrapped("luminance over time%s", smoothing_ ? " (grey: before --smooth)" : "");
  for (int k = 0; k < kShCount; ++k) {
    std::vector<std::vector<float>> series(2);
    float lo = 0, hi = 0;
    for (const auto& h : history_) {
      const float a = luminance(h.unsmoothed.c[std::size_t(k)]),
                  b = luminance(h.radiance.c[std::size_t(k)]);
      series[0].push_back(a);
      series[1].push_back(b);
      lo = std::min({lo, a, b});
      hi = std::max({hi, a, b});
    }
    if (!smoothing_) series.erase(series.begin());
    if (k % 3) ImGui::SameLine();
    const float pad = 0.05f * std::max(1e-9f, hi - lo);
    const std::vector<ImU32> colours =
        smoothing_ ? std::vector<ImU32>{IM_COL32(150, 150, 150, 255), IM_COL32(250, 210, 80, 255)}
                   : std::vector<ImU32>{IM_COL32(250, 210, 80, 255)};
    const std::string name(kShNames[std::size_t(k)]);
    plotSeries(name.c_str(), series, colours, size, lo - pad, hi + pad, name.c_str());
  }
}

void Hud::drawEditor(const HudLayout& layout) {
  const ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos({layout.margin, io.DisplaySize.y - layout.margin}, ImGuiCond_Always,
                          {0, 1});
  ImGui::SetNextWindowSize({layout.statusWidth, 0}, ImGuiCond_Always);
  ImGui::SetNextWindowBgAlpha(0.6f);
  ImGui::Begin(
      "coefficients", nullptr,
      ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoSavedSettings);
  float scale = 0.5f;
  for (const auto& c : editing_->c)
    scale = std::max({scale, std::abs(c.x), std::abs(c.y), std::abs(c.z)});
  for (int k = 0; k < kShCount; ++k) {
    float v[3] = {editing_->c[std::size_t(k)].x, editing_->c[std::size_t(k)].y,
                  editing_->c[std::size_t(k)].z};
    if (ImGui::SliderFloat3(std::string(kShNames[std::size_t(k)]).c_str(), v, -2 * scale, 2 * scale,
                            "%.3f")) {
      editing_->c[std::size_t(k)] = {v[0], v[1], v[2]};
      edited_ = true;
    }
  }
  if (ImGui::Button("Save JSON (Ctrl+S)")) saveCoefficients();
  ImGui::SameLine();
  if (ImGui::Button("Zero")) {
    *editing_ = Sh9{};
    edited_ = true;
  }
  if (!saveMessage_.empty()) ImGui::TextWrapped("%s", saveMessage_.c_str());
  ImGui::End();
}

void Hud::drawHelp(ViewState& state) {
  const ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos({io.DisplaySize.x / 2, io.DisplaySize.y / 2}, ImGuiCond_Always,
                          {0.5f, 0.5f});
  ImGui::SetNextWindowBgAlpha(0.85f);
  bool open = true;
  ImGui::Begin("keys", &open, ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoSavedSettings);
  const char* const rows[][2] = {
      {"left drag", "orbit"},      {"wheel", "zoom"},
      {"Space", "pause / resume"}, {"Right", "one frame (paused)"},
      {"R", "reset the view"},     {"B", "background on/off"},
      {"H", "HUD on/off"},         {"+ / -", "exposure, half a stop"},
      {"F1 or ?", "this help"},    {"Ctrl+S", "save the coefficients (view)"},
      {"Esc or Q", "quit"}};
  for (const auto& r : rows) {
    ImGui::Text("%-10s", r[0]);
    ImGui::SameLine(90.0f * scale_);
    ImGui::TextUnformatted(r[1]);
  }
  ImGui::End();
  if (!open) state.help = false;
}

}  // namespace lp::cli
