// The page, embedded at build time from static/ (embed.cmake), so rover_web needs no
// files beside it.
#pragma once

namespace rover::web {
extern const char* const kIndexHtml;
extern const char* const kAppJs;
}  // namespace rover::web
