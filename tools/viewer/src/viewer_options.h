// whiskeye-viewer's options (the program's; viewer_main.cpp wires them to ViewerServer).
#pragma once

#include "whiskeye/common/cli.h"
#include "whiskeye/viewer/viewer_server.h"

#include <string>

namespace whiskeye::viewer {

struct ViewerOptions {
  std::string listen = "127.0.0.1:8088";
  std::string lcm_url;
  std::string log;
  ServerOptions server;
  int update_ms = 100;
};

// Adds every whiskeye-viewer option to `program` (which has --help and --version), bound to `options`.
void add_viewer_options(cli::Program& program, ViewerOptions& options);

}  // namespace whiskeye::viewer
