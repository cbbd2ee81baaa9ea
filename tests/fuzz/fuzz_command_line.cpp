// libFuzzer target: the command line of every subcommand. The first byte picks the command, the
// rest is its arguments, one per line. Parsing, then every value through the parsers the
// commands use (sizes, numbers, lists, ranges, the scene's options), must end in values or in
// lp::Error: never a crash, a hang or another exception.
#include <cstdint>
#include <string>
#include <vector>

#include "args.h"
#include "commands.h"
#include "liveprobe/sh/error.h"
#include "scene.h"

namespace {

template <class F>
void tryParse(F&& f) {
  try {
    f();
  } catch (const lp::Error&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace lp::cli;
  if (size == 0) return 0;
  const auto& all = commands();
  const CommandSpec& spec = all[data[0] % all.size()].spec;
  std::vector<std::string> argv(1);
  for (std::size_t i = 1; i < size && argv.size() <= 64; ++i) {
    if (data[i] == '\n')
      argv.emplace_back();
    else
      argv.back() += char(data[i]);
  }
  tryParse([&] {
    const Args a(spec, argv);
    if (a.help()) {
      (void)usage(spec);
      return;
    }
    for (const auto& o : spec.options) {
      if (o.value.empty()) continue;
      const std::string name = o.name.substr(0, o.name.find(','));
      for (const auto& v : a.all(name)) {
        tryParse([&] { (void)parseSize(v, name); });
        tryParse([&] { (void)parseNumber(v, name); });
        tryParse([&] { (void)parseNumberList(v, name, 3, "three numbers"); });
      }
      tryParse([&] { (void)a.numberIn(name, 0.0, -1e6, 1e6); });
      tryParse([&] { (void)a.integerIn(name, 0, -1000000, 1000000); });
    }
    // The scene's options, parsed as render, view, replay and live parse them (no file opened).
    tryParse([&] { (void)envOrientationFromArgs(a); });
    tryParse([&] { (void)layoutFromArgs(a); });
    tryParse([&] { (void)cameraFromArgs(a); });
    tryParse([&] { (void)backendFromArgs(a); });
    tryParse([&] { (void)shadingFromArgs(a, lp::Sh9{}, false); });
  });
  return 0;
}
