#!/bin/sh
# Doxygen's INPUT_FILTER for common/'s headers (docs/Doxyfile, ./rover docs): the headers
# are commented with plain // lines, as the rest of the code is; this hands them to
# Doxygen as documentation without changing the files. A comment block that opens the
# file documents the file; a comment on lines of its own documents what follows it; a
# comment after a member on its line documents that member.
exec awk '
  NR == 1 && /^\/\/ / { sub(/^\/\/ /, "/** @file */ /// "); print; next }
  /^[ \t]*\/\/ / || /^[ \t]*\/\/$/ { sub(/\/\//, "///"); print; next }
  /[;,{][ \t]*\/\/ / { sub(/[ \t]*\/\/ /, "  ///< "); print; next }
  { print }
' "$1"
