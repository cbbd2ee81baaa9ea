#pragma once
// The command reference, the man page liveprobe(1) and the bash completion, written from the
// same declarations (CommandSpec, OptionSpec) the parser and --help use, so none of them can
// disagree with what the program accepts. app/src/docs_main.cpp prints them; the build installs
// the man page and the completion, and docs/reference.md and docs/liveprobe.1 are checked
// against them by a test.
#include <string>

namespace lp::cli {

enum class ReferenceFormat { Markdown, Man, BashCompletion };

/// The whole reference in one format; `version` goes into the man page's header.
std::string commandReference(ReferenceFormat format, const std::string& version);

}  // namespace lp::cli
