// seq_check FILE...: checks sequence files with no rover attached (LANGUAGE.md).
// Prints "FILE: OK (N commands)" or "FILE:LINE:COL: message (expected ...)" per file.
// Exit status: 0 when every file passes, 1 when any fails, 2 on a usage error.
#include "sequence/parser.hpp"

#include <cstring>
#include <iostream>
#include <string>
#include <vector>

namespace {

void Usage(std::ostream& os) {
  os << "usage: seq_check [--all] FILE...\n"
        "  Checks operator sequence files without a rover attached.\n"
        "  Prints 'FILE: OK (N commands)' or the first error as 'FILE:LINE:COL: message\n"
        "  (expected ...)'. --all prints every error, one per line.\n"
        "  Exit status: 0 all files pass, 1 some file fails, 2 usage error.\n";
}

}  // namespace

int main(int argc, char** argv) {
  bool all = false;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      Usage(std::cout);
      return 0;
    }
    if (arg == "--all") {
      all = true;
    } else if (arg.rfind("--", 0) == 0) {
      std::cerr << "seq_check: unknown option '" << arg << "' (expected --all or --help)\n";
      return 2;
    } else {
      files.push_back(arg);
    }
  }
  if (files.empty()) {
    std::cerr << "seq_check: no sequence file given\n";
    Usage(std::cerr);
    return 2;
  }
  bool ok = true;
  for (const auto& file : files) {
    const rover::sequence::ParseResult r = rover::sequence::ParseSequenceFile(file);
    if (r.ok()) {
      std::cout << file << ": OK (" << r.sequence.commands.size() << " commands)\n";
      continue;
    }
    ok = false;
    for (const auto& e : r.errors) {
      std::cout << e.ToString() << "\n";
      if (!all) break;
    }
  }
  return ok ? 0 : 1;
}
