#pragma once
// Helpers shared by the tests: data paths that must exist (a missing data folder fails, it is
// never skipped), temporary folders, running the liveprobe binary.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <string>

namespace lpt {

inline std::string dataPath(const std::string& rel) {
  const std::string p = std::string(LIVEPROBE_DATA_DIR) + "/" + rel;
  EXPECT_TRUE(std::filesystem::exists(p)) << "test data missing: " << p
                                          << " (scripts/data fetches it into data/; or "
                                             "-DLIVEPROBE_DATA_DIR=DIR names a folder with it)";
  return p;
}

/// A fresh folder under the system temp dir, removed with the object; each of a test's own.
struct TempDir {
  std::filesystem::path path;
  TempDir() {
    static int made = 0;
    // The process id: two runs of one suite at once (a build's tests and a sanitizer build's)
    // must not share a folder.
    path = std::filesystem::temp_directory_path() /
           ("liveprobe-test-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name() +
            (made++ ? "-" + std::to_string(made) : std::string()));
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~TempDir() { std::filesystem::remove_all(path); }
  std::string operator/(const std::string& name) const { return (path / name).string(); }
};

struct RunResult {
  int exitCode;
  std::string output;  ///< stdout and stderr together
};

/// Runs a shell command line, capturing stdout and stderr together.
inline RunResult runCommand(const std::string& commandLine) {
  const std::string cmd = commandLine + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  RunResult r{-1, {}};
  if (!p) return r;
  std::array<char, 4096> buf;
  std::size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.output.append(buf.data(), n);
  const int status = pclose(p);
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return r;
}

/// Runs `liveprobe ARGS` through the shell, capturing output.
inline RunResult runLiveprobe(const std::string& args) {
  return runCommand(std::string(LIVEPROBE_BIN) + " " + args);
}

/// Single quotes for the shell.
inline std::string shellQuote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

/// An xvfb-run prefix for one command under its own X server of `screen` ("WxHxD"). Tests run
/// in parallel, each in its own process: `-a` alone would start every search for a free display
/// number at 99, and two servers started at once can pick the same one (the second fails, and
/// its command runs on the first's display until that one goes away). Each process starts its
/// search at its own number. `-noreset`: a server resets as its last client leaves, and signals
/// xvfb-run (SIGUSR1) as it comes up again; arriving while xvfb-run removes its temporary
/// directory, that signal fails the removal, and xvfb-run exits 5 for a command that ended well.
inline std::string xvfbRun(const std::string& screen) {
  return "xvfb-run -n " + std::to_string(100 + int(::getpid() % 30000)) +
         " -a -s '-noreset -screen 0 " + screen + "' ";
}

inline int lineCount(const std::string& s) { return int(std::count(s.begin(), s.end(), '\n')); }

/// A bad input gives exit status 1 and exactly one line that names the input and says what is
/// wrong.
inline void expectOneLineError(const std::string& args, const std::string& names,
                               const std::string& says) {
  const auto r = runLiveprobe(args);
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_EQ(lineCount(r.output), 1) << r.output;
  EXPECT_NE(r.output.find(names), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(says), std::string::npos) << r.output;
}

}  // namespace lpt
