#pragma once
// For fuzz targets whose reader takes a path: the input written to a file of this process, with
// the extension the reader dispatches on. Aborts when it cannot be written (not a finding).
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

inline std::string writeFuzzInput(const char* kind, const char* ext, const std::uint8_t* data,
                                  std::size_t size) {
  const std::string path =
      std::string("/tmp/liveprobe-fuzz-") + kind + "-" + std::to_string(::getpid()) + ext;
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f || std::fwrite(data, 1, size, f) != size || std::fclose(f) != 0) std::abort();
  return path;
}
