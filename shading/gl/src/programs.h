#pragma once
// Compiling and linking GL programs (private to liveprobe::gl): errors as ContextError with the
// driver's log, naming the program.
#include "liveprobe/gl/handles.h"

namespace lp::gl {

/// A vertex and fragment program.
Program linkProgram(const char* vs, const char* fs, const char* name);
/// A compute program (GL 4.3).
Program linkCompute(const char* cs, const char* name);

}  // namespace lp::gl
