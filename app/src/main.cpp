// liveprobe: real-time diffuse lighting from panoramas with nine SH coefficients.
// The one place that prints errors and chooses the exit code.
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "args.h"
#include "capture/error.h"
#include "commands.h"

namespace {

void printOverview() {
  std::cout << "usage: liveprobe COMMAND [ARGS...]   (liveprobe COMMAND --help for details)\n\n"
               "commands:\n";
  for (const auto& c : lp::cli::commands()) {
    std::string name = "  " + c.spec.name;
    name.resize(14, ' ');
    std::cout << name << c.brief << "\n";
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
    printOverview();
    return args.empty() ? 2 : 0;
  }
  for (const auto& c : lp::cli::commands()) {
    if (c.spec.name != args[0]) continue;
    try {
      lp::cli::Args parsed(c.spec, {args.begin() + 1, args.end()});
      if (parsed.help()) {
        std::cout << lp::cli::usage(c.spec);
        return 0;
      }
      return c.run(parsed);
    } catch (const lp::Error& e) {
      std::cerr << "liveprobe " << c.spec.name << ": " << e.what() << "\n";
      return 1;
    } catch (const std::exception& e) {
      std::cerr << "liveprobe " << c.spec.name << ": internal error: " << e.what() << "\n";
      return 3;
    }
  }
  std::cerr << "liveprobe: unknown command '" << args[0] << "' (liveprobe --help lists them)\n";
  return 2;
}
