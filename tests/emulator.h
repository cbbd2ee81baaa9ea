#pragma once
// The emulated camera (tests/v4l2emu, loaded with LD_PRELOAD) around one liveprobe run: its modes
// in a temporary folder, its faults, its call log.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "sky_frames.h"
#include "test_util.h"

namespace lpt {

struct Emulator {
  lpt::TempDir tmp;
  std::string faults;
  std::string env;     ///< more LPEMU_* settings, "NAME=VALUE " each
  std::string prefix;  ///< what the run goes through (xvfb-run ...)
  /// Modes of rendered 8-bit sky frames (lpt::makeModes).
  explicit Emulator(const std::vector<std::string>& modes, std::string f = "")
      : faults(std::move(f)) {
    lpt::makeModes(tmp.path / "modes", modes);
  }
  /// One mode whose frames are these files (float files are radiance the camera renders).
  Emulator(const std::string& mode, const std::vector<std::string>& files, std::string f = "")
      : faults(std::move(f)) {
    std::filesystem::create_directories(tmp.path / "modes" / mode);
    for (std::size_t i = 0; i < files.size(); ++i) {
      const auto name = std::filesystem::path(std::to_string(10000 + i) + "_" +
                                              std::filesystem::path(files[i]).filename().string());
      std::filesystem::create_symlink(files[i], tmp.path / "modes" / mode / name);
    }
  }
  std::string log() const { return tmp / "emu.log"; }
  lpt::RunResult run(const std::string& args) const {
    const std::string vars =
        "LD_PRELOAD=" + std::string(LIVEPROBE_EMU) +
        " LPEMU_DEVICE=/dev/video7 LPEMU_SOURCE=" + (tmp.path / "modes").string() +
        " LPEMU_META_DEVICE=/dev/video8 LPEMU_LOG=" + log() + " LPEMU_FAULTS=" + faults + " " +
        this->env;
    return lpt::runCommand(prefix + (prefix.empty() ? "" : "env ") + vars + LIVEPROBE_BIN + " " +
                           args);
  }
  std::string logText() const {
    std::ifstream in(log());
    return std::string((std::istreambuf_iterator<char>(in)), {});
  }
  // Every buffer was unmapped and released before the device was closed. (Once a device is
  // unplugged its ioctls fail with ENODEV and the kernel frees its buffers at close: then only
  // the mappings are ours to undo.)
  void expectNoLeak(bool unplugged = false) const {
    const std::string l = logText();
    EXPECT_NE(l.find(unplugged ? "close mapped=0" : "close mapped=0 buffers=0 streaming=0"),
              std::string::npos)
        << l;
  }
};

inline std::vector<nlohmann::json> readJsonl(const std::string& path) {
  std::vector<nlohmann::json> out;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) out.push_back(nlohmann::json::parse(line));
  return out;
}

}  // namespace lpt
