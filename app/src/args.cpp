#include "args.h"

#include <cctype>
#include <cmath>
#include <sstream>

#include "capture/error.h"

namespace lp::cli {

Args::Args(const CommandSpec& spec, const std::vector<std::string>& argv) {
  for (std::size_t i = 0; i < argv.size(); ++i) {
    const std::string& a = argv[i];
    if (a == "--help" || a == "-h") {
      help_ = true;
      return;
    }
    if (a.size() > 2 && a.rfind("--", 0) == 0) {
      std::string name = a, value;
      bool inlineValue = false;
      if (auto eq = a.find('='); eq != std::string::npos) {
        name = a.substr(0, eq);
        value = a.substr(eq + 1);
        inlineValue = true;
      }
      const OptionSpec* opt = nullptr;
      for (const auto& o : spec.options)
        if (o.name == name) opt = &o;
      if (!opt)
        throw Error(spec.name + ": unknown option " + name + " (see liveprobe " + spec.name +
                    " --help)");
      if (!opt->repeatable && values_.count(name))
        throw Error(spec.name + ": option " + name + " given twice");
      if (opt->value.empty()) {
        if (inlineValue) throw Error(spec.name + ": option " + name + " takes no value");
        values_.emplace(name, "");
      } else {
        if (!inlineValue) {
          // An optional value is taken only when the next word looks like one (a number).
          const bool next = i + 1 < argv.size() && argv[i + 1].rfind("--", 0) != 0;
          const bool numeric = next && (std::isdigit(static_cast<unsigned char>(argv[i + 1][0])) || argv[i + 1][0] == '.');
          if (opt->optionalValue && !numeric) {
            values_.emplace(name, "");
            continue;
          }
          if (i + 1 >= argv.size()) throw Error(spec.name + ": option " + name + " needs a value (" + opt->value + ")");
          value = argv[++i];
        }
        values_.emplace(name, value);
      }
      continue;
    }
    positional_.push_back(a);
  }
  if (int(positional_.size()) < spec.minPositional)
    throw Error(spec.name + ": missing argument (usage: liveprobe " + spec.name + " " +
                spec.synopsis + ")");
  if (int(positional_.size()) > spec.maxPositional)
    throw Error(spec.name + ": unexpected argument '" + positional_[spec.maxPositional] + "'");
}

std::string Args::get(const std::string& name, const std::string& fallback) const {
  auto it = values_.find(name);
  return it == values_.end() ? fallback : it->second;
}

std::vector<std::string> Args::all(const std::string& name) const {
  std::vector<std::string> out;
  for (auto [it, end] = values_.equal_range(name); it != end; ++it) out.push_back(it->second);
  return out;
}

double Args::number(const std::string& name, double fallback) const {
  return has(name) ? parseNumber(get(name), name) : fallback;
}

int Args::integer(const std::string& name, int fallback) const {
  if (!has(name)) return fallback;
  const double v = parseNumber(get(name), name);
  if (v != std::floor(v) || std::abs(v) > 1e9) throw Error(name + " " + get(name) + ": not an integer");
  return int(v);
}

std::string usage(const CommandSpec& spec) {
  std::ostringstream s;
  s << "usage: liveprobe " << spec.name << " " << spec.synopsis << "\n\n" << spec.summary << "\n";
  if (!spec.options.empty()) s << "\noptions:\n";
  for (const auto& o : spec.options) {
    std::string left = "  " + o.name + (o.value.empty() ? "" : o.optionalValue ? " [" + o.value + "]" : " " + o.value);
    if (left.size() < 28) left.resize(28, ' ');
    else left += "\n" + std::string(28, ' ');
    s << left << o.help << "\n";
  }
  s << "  --help                    this text\n";
  return s.str();
}

std::pair<int, int> parseSize(const std::string& text, const std::string& what) {
  int w = 0, h = 0;
  char x = 0, extra = 0;
  std::istringstream s(text);
  if (!(s >> w >> x >> h) || (x != 'x' && x != 'X') || (s >> extra) || w <= 0 || h <= 0 ||
      w > 65536 || h > 65536)
    throw Error(what + " " + text + ": expected a size like 256x128");
  return {w, h};
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

}  // namespace lp::cli
