#include "reference.h"

#include <algorithm>
#include <sstream>
#include <vector>

#include "commands.h"

namespace lp::cli {

namespace {

struct Variable {
  const char* name;
  const char* text;
};

// The environment the program reads (main.cpp, progress.cpp, cmd_replay.cpp, the SH core).
const Variable kEnvironment[] = {
    {"LIVEPROBE_SIMD",
     "scalar, avx2, avx512, neon or native: the SIMD path of the SH kernels (default: the best "
     "this CPU runs)."},
    {"LIVEPROBE_MAX_PIXELS",
     "the most pixels an image file may declare before it is decoded (default 268435456)."},
    {"LIVEPROBE_PROGRESS_SECONDS", "the interval of the progress line (default 5)."},
    {"LIVEPROBE_DEFAULT_RECORDING",
     "the source replay and bench play when none is given (default: the bundled recording in "
     "share/liveprobe beside the program)."},
    {"LIVEPROBE_WEB_DIR",
     "the folder --serve serves the web page from (default: share/liveprobe/web)."},
    {"LIVEPROBE_MQTT_PASSWORD", "the MQTT password, kept off the command line."},
    {"DISPLAY, WAYLAND_DISPLAY",
     "without either, windowed commands render headless: EGL on a GPU where there is one, "
     "else OSMesa on the CPU (--gl picks)."},
};

struct ExitCode {
  int code;
  const char* text;
};
const ExitCode kExitCodes[] = {
    {0, "success"},
    {1, "a bad input, command line or device: one line on standard error names it"},
    {2, "bench: a stage over the threshold, but the machine was too busy to tell (run it again)"},
    {3, "the run failed at run time: --publish reached no MQTT broker, or an internal error"},
    {129, "stopped by SIGHUP, the terminal closed (outputs are finalised first)"},
    {130, "stopped by SIGINT or SIGTERM (outputs are finalised first)"},
};

struct Example {
  const char* text;
  const char* command;  ///< as the manual writes it (its examples run in the test suite)
};
const Example kExamples[] = {
    {"Replay the bundled recording, the sun taken out as a light that casts a shadow on a ground:",
     "liveprobe replay recordings/sky.mkv --sun --ground"},
    {"A 360 camera over UVC as a live light probe:",
     "liveprobe live /dev/video0 --layout fisheye --size 1920x960 --pixel-format mjpeg "
     "--lock-exposure "
     "--sun"},
    {"The coefficients and the sun of a map, in three.js's frame and order:",
     "liveprobe coeffs data/equirect/pedestrian_overpass_1k.hdr --sun --format three > "
     "three.json"},
    {"A camera's response for --response, from an exposure sweep:",
     "liveprobe calibrate /dev/video0 --out response.json --stops -6,3"},
    {"A frame-time baseline, then a run compared with it:",
     "liveprobe bench --json base.json --quiet && liveprobe bench --baseline base.json --threshold "
     "50 --plot frame-times.png"},
    {"A command's options:", "liveprobe help coeffs"},
};

const char* const kDescription =
    "liveprobe computes the nine spherical-harmonic coefficients of the diffuse light an "
    "environment casts (Ramamoorthi and Hanrahan, 2001) from panoramas: still maps, recordings, "
    "image sequences and V4L2 cameras, in equirect, angular, mirror-ball, dual-fisheye and cube "
    "layouts and through calibrated lenses. It re-projects them every frame, lights a model with "
    "them in a window or headless, "
    "and exports them to engines, a WebSocket stream and MQTT.";

// "line one\nline two" -> "line one line two"
std::string oneParagraph(const std::string& text) {
  std::string out;
  for (char c : text) out += c == '\n' ? ' ' : c;
  return out;
}

std::string synopsis(const CommandSpec& spec) {
  std::string s = "liveprobe " + spec.name;
  if (!spec.options.empty()) s += " [OPTIONS]";
  if (!spec.positional.empty()) s += " " + spec.positional;
  return s;
}

// Options in their help sections, in declaration order ("Options" first, as --help shows them).
std::vector<std::pair<std::string, std::vector<const OptionSpec*>>> groups(const CommandSpec& s) {
  std::vector<std::pair<std::string, std::vector<const OptionSpec*>>> out;
  for (const auto& o : s.options) {
    const std::string g = o.group.empty() ? "Options" : o.group;
    auto it = std::find_if(out.begin(), out.end(), [&](const auto& p) { return p.first == g; });
    if (it == out.end()) {
      out.push_back({g, {}});
      it = out.end() - 1;
    }
    it->second.push_back(&o);
  }
  std::stable_partition(out.begin(), out.end(), [](const auto& p) { return p.first == "Options"; });
  return out;
}

std::string optionLabel(const OptionSpec& o) {
  std::string names;
  for (const auto& n : namesOf(o)) names += (names.empty() ? "" : ", ") + n;
  if (o.value.empty()) return names;
  return names + (o.optionalValue ? " [" + o.value + "]" : " " + o.value);
}

// ---- Markdown ---------------------------------------------------------------------------------

std::string cell(const std::string& text) {
  std::string out;
  for (char c : oneParagraph(text)) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

std::string markdown() {
  std::ostringstream m;
  m << "# Command reference\n\n"
       "Generated from the declarations the parser and `--help` use (`app/src/reference.cpp`); "
       "`scripts/reference` rewrites this file and the man page `docs/liveprobe.1`, and a test "
       "fails when either differs from what the build makes. What the commands share (layouts, "
       "sources, the model and the look, keys, errors and limits) is in "
       "[Commands](commands.md).\n\n"
    << "```text\nliveprobe COMMAND [OPTIONS] [ARGUMENTS]\nliveprobe COMMAND --help\n"
       "liveprobe --version\n```\n\n"
    << oneParagraph(kDescription) << "\n\n| command | |\n|---|---|\n";
  for (const auto& c : commands())
    m << "| [`" << c.spec.name << "`](#liveprobe-" << c.spec.name << ") | " << cell(c.brief)
      << " |\n";
  for (const auto& c : commands()) {
    const CommandSpec& s = c.spec;
    m << "\n## `liveprobe " << s.name << "`\n\n```text\n"
      << synopsis(s) << "\n```\n\n"
      << oneParagraph(s.summary) << "\n";
    if (!s.positional.empty() && !s.positionalHelp.empty())
      m << "\n`" << s.positional << "`: " << oneParagraph(s.positionalHelp) << "\n";
    for (const auto& [name, opts] : groups(s)) {
      m << "\n| " << name << " | |\n|---|---|\n";
      for (const OptionSpec* o : opts)
        m << "| `" << cell(optionLabel(*o)) << "` | " << cell(o->help)
          << (o->repeatable ? " (may be repeated)" : "") << " |\n";
    }
  }
  m << "\n## Environment\n\n| variable | |\n|---|---|\n";
  for (const auto& v : kEnvironment) m << "| `" << v.name << "` | " << cell(v.text) << " |\n";
  m << "\n## Exit status\n\n| code | |\n|---|---|\n";
  for (const auto& e : kExitCodes) m << "| " << e.code << " | " << cell(e.text) << " |\n";
  return m.str();
}

// ---- man(7) -------------------------------------------------------------------------------------

// Text for roff: backslashes escaped, hyphens as \- (so they copy as ASCII), a leading dot or
// quote protected.
std::string roff(const std::string& text) {
  std::string out;
  for (char c : oneParagraph(text)) {
    if (c == '\\')
      out += "\\e";
    else if (c == '-')
      out += "\\-";
    else
      out += c;
  }
  if (!out.empty() && (out[0] == '.' || out[0] == '\'')) out = "\\&" + out;
  return out;
}

std::string man(const std::string& version) {
  std::ostringstream m;
  m << ".TH LIVEPROBE 1 \"\" \"liveprobe " << version << "\" \"User Commands\"\n"
    << ".SH NAME\nliveprobe \\- real-time diffuse lighting from panoramas with nine "
       "spherical-harmonic coefficients\n"
    << ".SH SYNOPSIS\n.B liveprobe\n.I COMMAND\n[\\fIOPTIONS\\fR] [\\fIARGUMENTS\\fR]\n.br\n"
       ".B liveprobe\n.I COMMAND\n.B \\-\\-help\n.br\n.B liveprobe \\-\\-version\n"
    << ".SH DESCRIPTION\n"
    << roff(kDescription) << "\n.SH COMMANDS\n";
  for (const auto& c : commands()) {
    const CommandSpec& s = c.spec;
    m << ".SS \"" << roff(synopsis(s)) << "\"\n" << roff(s.summary) << "\n";
    if (!s.positional.empty() && !s.positionalHelp.empty())
      m << ".TP\n.I " << roff(s.positional) << "\n" << roff(s.positionalHelp) << "\n";
    for (const auto& [name, opts] : groups(s)) {
      if (name != "Options") m << ".PP\n" << roff(name) << ":\n";
      for (const OptionSpec* o : opts)
        m << ".TP\n.B " << roff(optionLabel(*o)) << "\n"
          << roff(o->help + (o->repeatable ? " (may be repeated)" : "")) << "\n";
    }
  }
  m << ".SH EXAMPLES\n";
  for (const auto& e : kExamples)
    m << ".PP\n" << roff(e.text) << "\n.PP\n.RS 4\n.nf\n" << roff(e.command) << "\n.fi\n.RE\n";
  m << ".SH ENVIRONMENT\n";
  for (const auto& v : kEnvironment)
    m << ".TP\n.B " << roff(v.name) << "\n" << roff(v.text) << "\n";
  m << ".SH EXIT STATUS\n";
  for (const auto& e : kExitCodes) m << ".TP\n.B " << e.code << "\n" << roff(e.text) << "\n";
  m << ".SH FILES\n.TP\n.I PREFIX/share/liveprobe/\nthe bundled recording (recordings/sky.mkv "
       "with its sidecar) and the web page of \\-\\-serve, found beside the program.\n"
    << ".TP\n.I /usr/share/doc/liveprobe/\nthe manual, where the package installed it: README.md "
       "and the pages of docs/ (README.md and docs/ in the source).\n"
    << ".SH SEE ALSO\nThe manual in /usr/share/doc/liveprobe/ (README.md, then docs/), and "
       "docs/reference.md, this page's own text.\n";
  return m.str();
}

// ---- bash completion ----------------------------------------------------------------------------

std::string bashCompletion() {
  std::ostringstream b;
  b << "# bash completion for liveprobe, generated from its option declarations.\n"
       "_liveprobe() {\n"
       "  local cur=${COMP_WORDS[COMP_CWORD]} opts\n"
       "  if ((COMP_CWORD == 1)); then\n"
       "    COMPREPLY=($(compgen -W \"";
  for (const auto& c : commands()) b << c.spec.name << " ";
  b << "--help --version\" -- \"$cur\"))\n"
       "    return\n"
       "  fi\n"
       "  case ${COMP_WORDS[1]} in\n";
  for (const auto& c : commands()) {
    b << "    " << c.spec.name << ") opts=\"";
    for (const auto& o : c.spec.options)
      for (const auto& n : namesOf(o)) b << n << " ";
    b << "--help\" ;;\n";
  }
  b << "    *) return ;;\n"
       "  esac\n"
       "  # Options after a dash; otherwise bash's own file names (complete -o default).\n"
       "  [[ $cur == -* ]] && COMPREPLY=($(compgen -W \"$opts\" -- \"$cur\"))\n"
       "}\n"
       "complete -o default -F _liveprobe liveprobe\n";
  return b.str();
}

}  // namespace

std::string commandReference(ReferenceFormat format, const std::string& version) {
  switch (format) {
    case ReferenceFormat::Markdown:
      return markdown();
    case ReferenceFormat::Man:
      return man(version);
    case ReferenceFormat::BashCompletion:
      return bashCompletion();
  }
  return {};
}

}  // namespace lp::cli
