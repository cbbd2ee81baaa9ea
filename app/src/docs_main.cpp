// liveprobe-docs FORMAT: prints the command reference (markdown), the man page (man) or the bash
// completion (bash) generated from the command declarations. Built beside the program, not
// installed; the build runs it for the installed man page and completion.
#include <iostream>
#include <string>

#include "reference.h"

int main(int argc, char** argv) {
  const std::string format = argc == 2 ? argv[1] : "";
  using lp::cli::ReferenceFormat;
  ReferenceFormat f;
  if (format == "markdown")
    f = ReferenceFormat::Markdown;
  else if (format == "man")
    f = ReferenceFormat::Man;
  else if (format == "bash")
    f = ReferenceFormat::BashCompletion;
  else {
    std::cerr << "usage: liveprobe-docs markdown|man|bash\n";
    return 1;
  }
  std::cout << lp::cli::commandReference(f, LIVEPROBE_VERSION);
  return std::cout.good() ? 0 : 1;
}
