#pragma once
// A small command-line parser: each subcommand declares its options with help text; unknown
// options and missing values are errors that name the option.
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace lp::cli {

struct OptionSpec {
  std::string name;     ///< "--size"
  std::string value;    ///< placeholder for the value ("WxH"); empty for a flag
  std::string help;
  bool repeatable = false;
  bool optionalValue = false;  ///< the value may be left out (then the option is a flag)
};

struct CommandSpec {
  std::string name;
  std::string synopsis;  ///< "FILE [--layout equirect|angular] ..."
  std::string summary;
  std::vector<OptionSpec> options;
  int minPositional = 0;
  int maxPositional = 0;
};

class Args {
 public:
  /// Parses argv (without the subcommand name). Throws lp::Error on a bad command line.
  Args(const CommandSpec& spec, const std::vector<std::string>& argv);

  bool help() const { return help_; }
  bool has(const std::string& name) const { return values_.count(name) > 0; }
  std::string get(const std::string& name, const std::string& fallback = {}) const;
  std::vector<std::string> all(const std::string& name) const;
  const std::vector<std::string>& positional() const { return positional_; }

  double number(const std::string& name, double fallback) const;
  int integer(const std::string& name, int fallback) const;

 private:
  std::multimap<std::string, std::string> values_;
  std::vector<std::string> positional_;
  bool help_ = false;
};

std::string usage(const CommandSpec& spec);

/// "256x128" -> {256, 128}; throws lp::Error naming `what`.
std::pair<int, int> parseSize(const std::string& text, const std::string& what);
double parseNumber(const std::string& text, const std::string& what);

}  // namespace lp::cli
