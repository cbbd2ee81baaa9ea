// libFuzzer target: the command line of every subcommand. The first byte picks the command, the
// rest is its arguments, one per line. Parsing (every value into its typed setting: sizes,
// numbers, lists, ranges, choices), then what the scene derives from the settings, must end in
// values or in lp::Error: never a crash, a hang or another exception.
#include <cstdint>
#include <string>
#include <vector>

#include "args.h"
#include "commands.h"
#include "environment.h"
#include "liveprobe/sh/error.h"
#include "scene.h"
#include "scene_gl.h"

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
    // Every value was parsed into its typed field as the line was read; what the commands derive
    // from the settings without opening a file must end in values or lp::Error too.
    const Settings& st = a.settings();
    tryParse([&] { (void)envOrientation(st.panorama); });
    tryParse([&] { (void)layoutSpec(st.panorama); });
    tryParse([&] { (void)cameraFrom(st.scene); });
    tryParse([&] { (void)glBackend(st.scene); });
    tryParse([&] { (void)shadingFrom(st.scene, lp::Sh9{}, false); });
    tryParse([&] { (void)chooseLights(st); });
  });
  return 0;
}
