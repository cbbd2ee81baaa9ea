#pragma once
// A source whose frames are exposure-bracketed (a bracketing camera, a recording of one): what the
// frame path asks of it to merge its frames, beside the FrameSource it also is.
#include <cstddef>
#include <string>

#include "liveprobe/frame/frame.h"

namespace lp {

class BracketedSource {
 public:
  virtual ~BracketedSource() = default;
  /// The frames in one bracket, each with its own exposure, to be merged (liveprobe/hdr/merge.h);
  /// 0: this source's frames are not bracketed (a recording without a bracket).
  virtual int bracketFrames() const = 0;
  /// The camera response the bracket was recorded with (CameraResponse::json()); empty: none
  /// recorded.
  virtual std::string bracketResponse() const { return {}; }
  /// Bracketed frames left out because their exposure could not be told (a camera without
  /// per-frame exposure times, a frame taken while its sensor changed).
  virtual std::size_t unidentifiedFrames() const { return 0; }
  /// Those frames by stop and cause, as a sentence's end; empty when none.
  virtual std::string unidentifiedReport() const { return {}; }
};

/// The source's bracket, where it has one (bracketFrames() > 0); null otherwise.
inline const BracketedSource* bracketOf(const FrameSource& source) {
  const auto* b = dynamic_cast<const BracketedSource*>(&source);
  return b && b->bracketFrames() > 0 ? b : nullptr;
}

}  // namespace lp
