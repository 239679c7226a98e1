#!/bin/sh
# The API docs of common/ (docs/Doxyfile, as ./rover docs builds them) build with no
# Doxygen warning, and the pages hold the headers' comments. Skips (77) without doxygen.
# usage: api_docs_test.sh SOURCE_DIR OUT_DIR
src="$1" out="$2"
command -v doxygen >/dev/null || { echo "SKIPPED: doxygen is not installed (./rover docs installs it)"; exit 77; }
rm -rf "$out" && mkdir -p "$out" || exit 1
cd "$src" || exit 1
(cat docs/Doxyfile; echo "OUTPUT_DIRECTORY = $out"; echo "WARN_LOGFILE = $out/warnings.txt") | doxygen - >"$out/doxygen.log" 2>&1
rc=$?
if [ "$rc" -ne 0 ] || [ -s "$out/warnings.txt" ]; then
  echo "FAIL: doxygen exited $rc with these warnings on common/'s headers:"
  cat "$out/warnings.txt" "$out/doxygen.log"
  exit 1
fi
# The comments reached the pages (docs/doxygen_filter.sh hands the // comments over).
page="$out/html/classrover_1_1bus_1_1Process.html"
grep -q "Rover time in microseconds" "$page" || { echo "FAIL: $page lacks bus::Process's comments"; exit 1; }
echo "API docs: $(ls "$out/html" | wc -l) files, no warnings"
