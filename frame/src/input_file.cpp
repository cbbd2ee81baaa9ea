#include "liveprobe/frame/input_file.h"

#include <filesystem>
#include <fstream>
#include <iterator>

#include "liveprobe/sh/error.h"

namespace lp {

void requireRegularFile(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);  // stat(): never blocks, even on a FIFO
  switch (st.type()) {
    case fs::file_type::regular:
      return;
    case fs::file_type::not_found:
      if (fs::is_symlink(fs::symlink_status(path, ec)))
        throw Error(path + ": a symbolic link to nothing (" + fs::read_symlink(path, ec).string() +
                    ")");
      throw Error(path + ": no such file");
    case fs::file_type::directory:
      throw Error(path + ": is a folder, not a file");
    case fs::file_type::fifo:
      throw Error(path + ": is a FIFO (named pipe), not a file");
    case fs::file_type::socket:
      throw Error(path + ": is a socket, not a file");
    case fs::file_type::block:
    case fs::file_type::character:
      throw Error(path + ": is a device, not a file");
    default:
      throw Error(path + ": cannot be read (" + (ec ? ec.message() : std::string("unknown type")) +
                  ")");
  }
}

std::string readInputFile(const std::string& path) {
  requireRegularFile(path);
  std::ifstream in(path, std::ios::binary);
  if (!in.is_open()) throw Error(path + ": cannot open the file");
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  if (in.bad()) throw Error(path + ": cannot read the file");
  return bytes;
}

}  // namespace lp
