# cmake -DOUT=file.cpp -DHTML=index.html -DJS=app.js -P embed.cmake
# Writes the page's files as C++ raw string literals (static_files.hpp declares them).
file(READ "${HTML}" html)
file(READ "${JS}" js)
foreach(text html js)
  string(FIND "${${text}}" ")rover_web\"" bad)
  if(NOT bad EQUAL -1)
    message(FATAL_ERROR "${text} holds the raw string's closing delimiter )rover_web\"")
  endif()
endforeach()
file(WRITE "${OUT}.tmp"
  "// Generated from tools/web_console/static by embed.cmake: edit those files instead.\n"
  "#include \"web_console/static_files.hpp\"\n"
  "namespace rover::web {\n"
  "const char* const kIndexHtml = R\"rover_web(${html})rover_web\";\n"
  "const char* const kAppJs = R\"rover_web(${js})rover_web\";\n"
  "}  // namespace rover::web\n")
file(COPY_FILE "${OUT}.tmp" "${OUT}" ONLY_IF_DIFFERENT)
file(REMOVE "${OUT}.tmp")
