#include "args.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <map>
#include <sstream>
#include <stdexcept>

#include "liveprobe/sh/error.h"
#include "settings.h"

namespace lp::cli {

struct Args::Parsed {
  CLI::App app;
  std::map<std::string, std::vector<std::string>> values;  // storage bound to the options
  std::map<std::string, CLI::Option*> options;
  std::vector<std::string> positional;
};

namespace {

// "[DEVICE...]" -> "DEVICE"
std::string positionalName(const std::string& s) {
  std::string n;
  for (char c : s)
    if (c != '[' && c != ']' && c != '.' && c != ' ') n += c;
  return n;
}

// "--env-rotate,--rotate" (a name and its aliases) is known by its first name.
std::string optionKey(const OptionSpec& o) { return o.name.substr(0, o.name.find(',')); }

// Every name of every option ("--env-rotate", "--rotate", ...), and whether it takes a value.
std::map<std::string, bool> optionNames(const CommandSpec& spec) {
  std::map<std::string, bool> names{{"--help", false}, {"-h", false}};
  for (const auto& o : spec.options) {
    for (const auto& n : namesOf(o)) names[n] = !o.value.empty() && !o.optionalValue;
  }
  return names;
}

// An option that is not declared, named before CLI11 reads the line (which would otherwise
// count it, or its value, as a surplus positional argument), with the nearest declared name.
void refuseUnknownOptions(const CommandSpec& spec, const std::vector<std::string>& argv) {
  const auto names = optionNames(spec);
  std::vector<std::string> list;
  for (const auto& [n, takesValue] : names) list.push_back(n);
  for (std::size_t i = 0; i < argv.size(); ++i) {
    const std::string& a = argv[i];
    if (a == "--") return;  // what follows is positional
    if (a.rfind("--", 0) != 0) continue;
    const std::string name = a.substr(0, a.find('='));
    const auto it = names.find(name);
    if (it == names.end()) {
      const std::string near = nearestName(name, list);
      throw Error("unknown option " + name + (near.empty() ? "" : " (did you mean " + near + "?)") +
                  " (see liveprobe " + spec.name + " --help)");
    }
    if (it->second && a.find('=') == std::string::npos) ++i;  // its value, whatever it looks like
  }
}

void declare(Args::Parsed& p, const CommandSpec& spec) {
  CLI::App& app = p.app;
  app.name("liveprobe " + spec.name);
  app.description(spec.summary);
  app.get_formatter()->column_width(34);
  app.get_formatter()->label("REQUIRED", "");
  for (const auto& o : spec.options) {
    const std::string key = optionKey(o);
    auto& store = p.values[key];
    CLI::Option* opt = nullptr;
    if (o.value.empty()) {
      opt = app.add_flag(o.name, o.help)->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    } else {
      // A value that may be left out is shown as the reference shows it: [VALUE].
      opt = app.add_option(o.name, store, o.help)
                ->type_name(o.optionalValue ? "[" + o.value + "]" : o.value)
                ->allow_extra_args(false);
      if (o.optionalValue)
        opt->expected(0, 1);
      else
        opt->expected(1);
      opt->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);  // repeats are judged below
    }
    if (!o.group.empty()) opt->group(o.group);
    p.options[key] = opt;
  }
  if (spec.maxPositional > 0) {
    auto* pos = app.add_option(positionalName(spec.positional), p.positional, spec.positionalHelp);
    pos->expected(0, spec.maxPositional)->type_name("");
  }
}

}  // namespace

Args::Args(const CommandSpec& spec, const std::vector<std::string>& argv)
    : p_(std::make_unique<Parsed>()), settings_(std::make_unique<Settings>()) {
  declare(*p_, spec);
  refuseUnknownOptions(spec, argv);
  std::vector<std::string> reversed(argv.rbegin(), argv.rend());  // CLI11 takes them reversed
  try {
    p_->app.parse(reversed);
  } catch (const CLI::CallForHelp&) {
    help_ = true;
    return;
  } catch (const CLI::ExtrasError& e) {
    // "The following argument was not expected: --bogus": name it as what it most likely is.
    std::string extra = e.what();
    extra = extra.substr(extra.find(':') + 1);
    extra.erase(0, extra.find_first_not_of(' '));
    const bool option = extra.rfind("-", 0) == 0;
    throw Error((option ? "unknown option " : "unexpected argument ") + extra + " (see liveprobe " +
                spec.name + " --help)");
  } catch (const CLI::ParseError& e) {
    std::string what = e.what();
    std::replace(what.begin(), what.end(), '\n', ' ');
    throw Error(what + " (see liveprobe " + spec.name + " --help)");
  }
  for (const auto& o : spec.options)
    if (!o.repeatable && p_->options[optionKey(o)]->count() > 1)
      throw Error("option " + optionKey(o) + " given more than once");
  positional_ = p_->positional;
  if (int(positional_.size()) < spec.minPositional)
    throw Error("missing argument " + positionalName(spec.positional) + " (see liveprobe " +
                spec.name + " --help)");
  if (int(positional_.size()) > spec.maxPositional)
    throw Error("unexpected argument '" + positional_[std::size_t(spec.maxPositional)] + "'");
  // Every value into its typed field, in the order the options are declared.
  for (const auto& o : spec.options) {
    const CLI::Option* opt = p_->options[optionKey(o)];
    if (!o.set) throw std::logic_error(o.name + ": declared without its field");
    if (opt->count() == 0) continue;
    const auto& values = p_->values[optionKey(o)];
    if (o.value.empty() || values.empty())
      o.set(*settings_, "");
    else
      for (const auto& v : values) o.set(*settings_, v);
  }
  if (spec.check) spec.check(*settings_);
}

Args::~Args() = default;
Args::Args(Args&&) noexcept = default;

std::string rangeText(const Range& r) {
  std::ostringstream s;
  s << std::setprecision(10);
  if (r.aboveLo)
    s << "above " << r.lo << " and up to " << r.hi;
  else
    s << r.lo << " to " << r.hi;
  return s.str();
}

double parseNumberIn(const std::string& name, const std::string& v, const Range& r) {
  const double x = parseNumber(v, name);
  if (!((r.aboveLo ? x > r.lo : x >= r.lo) && x <= r.hi))
    throw Error(name + " " + v + ": expected " + rangeText(r));
  return x;
}

std::int64_t parseIntegerIn(const std::string& name, const std::string& v, std::int64_t lo,
                            std::int64_t hi) {
  const double x = parseNumber(v, name);
  if (x != std::floor(x) || x < double(lo) || x > double(hi))
    throw Error(name + " " + v + ": expected an integer from " + std::to_string(lo) + " to " +
                std::to_string(hi));
  return std::int64_t(x);
}

Triple parseTriple(const std::string& name, const std::string& v, const std::string& expected) {
  const auto n = parseNumberList(v, name, 3, expected);
  return {n[0], n[1], n[2]};
}

std::string joinChoices(const std::vector<std::string>& choices, const std::string& separator) {
  std::string text;
  for (std::size_t i = 0; i < choices.size(); ++i)
    text += (i == 0 ? "" : (separator == "|" || i + 1 < choices.size() ? separator : " or ")) +
            choices[i];
  return text;
}

std::string parseChoice(const std::string& name, const std::string& v,
                        const std::vector<std::string>& choices) {
  if (std::find(choices.begin(), choices.end(), v) == choices.end())
    throw Error(name + " " + v + ": expected " + joinChoices(choices, ", "));
  return v;
}

std::vector<std::string> namesOf(const OptionSpec& option) {
  std::vector<std::string> names;
  std::stringstream s(option.name);
  for (std::string n; std::getline(s, n, ',');) names.push_back(n);
  return names;
}

std::string usage(const CommandSpec& spec) {
  Args::Parsed p;
  declare(p, spec);
  return p.app.help();
}

std::string nearestName(const std::string& typed, const std::vector<std::string>& names) {
  std::string best;
  std::size_t bestDistance = std::string::npos;
  for (const auto& n : names) {
    // Levenshtein distance, one row at a time.
    std::vector<std::size_t> row(n.size() + 1);
    for (std::size_t j = 0; j <= n.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= typed.size(); ++i) {
      std::size_t diagonal = row[0];
      row[0] = i;
      for (std::size_t j = 1; j <= n.size(); ++j) {
        const std::size_t up = row[j];
        row[j] =
            std::min({row[j] + 1, row[j - 1] + 1, diagonal + (typed[i - 1] == n[j - 1] ? 0 : 1)});
        diagonal = up;
      }
    }
    if (row[n.size()] < bestDistance) bestDistance = row[n.size()], best = n;
  }
  const std::size_t allowed = std::min<std::size_t>(3, std::max<std::size_t>(1, typed.size() / 3));
  return bestDistance <= allowed ? best : std::string();
}

std::pair<int, int> parseSize(const std::string& text, const std::string& what, int maxSide) {
  long long w = 0, h = 0;
  char x = 0, extra = 0;
  std::istringstream s(text);
  if (!(s >> w >> x >> h) || (x != 'x' && x != 'X') || (s >> extra))
    throw Error(what + " " + text + ": expected a size like 256x128");
  if (w <= 0 || h <= 0)
    throw Error(what + " " + text + ": the width and the height must be at least 1");
  if (w > maxSide || h > maxSide)
    throw Error(what + " " + text + ": each side must be at most " + std::to_string(maxSide));
  return {int(w), int(h)};
}

double parseNumber(const std::string& text, const std::string& what) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (...) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(v))
    throw Error(what + " " + text + ": not a number");
  return v;
}

std::vector<double> parseNumberList(const std::string& text, const std::string& what,
                                    std::size_t count, const std::string& expected) {
  std::vector<double> v;
  std::stringstream s(text);
  for (std::string part; std::getline(s, part, ',');) v.push_back(parseNumber(part, what));
  if (v.size() != count) throw Error(what + " " + text + ": expected " + expected);
  return v;
}

std::string requireExtension(const std::string& path, const std::string& what,
                             const std::vector<std::string>& allowed) {
  const auto dot = path.find_last_of('.');
  std::string ext = dot == std::string::npos ? "" : path.substr(dot);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  if (std::find(allowed.begin(), allowed.end(), ext) != allowed.end()) return ext;
  std::string list;
  for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw Error(what + " " + path + ": is a folder; name a file (" + list + ")");
  throw Error(what + " " + path + ": unsupported extension (expected " + list + ")");
}

}  // namespace lp::cli
