// The page's files (tools/viewer/web/), embedded in the binary at build time (embed_assets.cmake).
// A request is answered from this table by exact name only: no path is ever joined, decoded into a
// file name or looked up on disk, so no request can reach a file outside it ("/../etc/passwd",
// "%2e%2e", an absolute path or a NUL byte simply name no asset).
#pragma once

#include <span>
#include <string_view>

namespace whiskeye::viewer {

struct Asset {
  std::string_view path;  // "/index.html"
  std::string_view content_type;
  std::string_view body;
};

// Every embedded file (generated).
std::span<const Asset> embedded_assets();

// The asset a request path names ("/" is "/index.html"), or null.
const Asset* find_asset(std::string_view request_path);

}  // namespace whiskeye::viewer
