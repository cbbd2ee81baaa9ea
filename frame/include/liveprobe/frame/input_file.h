#pragma once
// Inputs are regular files. Checked before anything opens them: open() on a FIFO blocks until a
// writer appears, and a folder, socket or device is no image, video, model or JSON either.
#include <string>

namespace lp {

/// Throws lp::Error naming `path` unless it is a regular file (links followed): "no such file",
/// "is a folder", "is a FIFO (named pipe), not a file", "is a socket, not a file", "is a device,
/// not a file".
void requireRegularFile(const std::string& path);

/// The whole of a regular file's bytes (a JSON document, a sidecar, a baseline). Throws lp::Error
/// naming `path` when it is no regular file or cannot be read.
std::string readInputFile(const std::string& path);

}  // namespace lp
