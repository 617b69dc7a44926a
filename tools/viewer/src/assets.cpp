// Lookup of the embedded page files (assets.h).
#include "whiskeye/viewer/assets.h"

namespace whiskeye::viewer {

const Asset* find_asset(std::string_view request_path) {
  if (request_path == "/") request_path = "/index.html";
  for (const Asset& a : embedded_assets()) {
    if (a.path == request_path) return &a;
  }
  return nullptr;
}

}  // namespace whiskeye::viewer
