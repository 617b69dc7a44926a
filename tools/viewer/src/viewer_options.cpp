// whiskeye-viewer's options (see viewer_options.h).
#include "viewer_options.h"

#include <CLI/CLI.hpp>

namespace whiskeye::viewer {

void add_viewer_options(cli::Program& program, ViewerOptions& o) {
  CLI::App& app = program.app();
  app.add_option("--listen", o.listen, "ADDR:PORT to serve the page on (default 127.0.0.1:8088: this host only; port 0: any free one)");
  app.add_option("--allow-host", o.server.allow_hosts,
                 "a further name or address the page may be opened by (a Host header), e.g. a name that reaches the robot "
                 "through a proxy; repeatable (default: only the names and addresses it serves on)");
  program.add_lcm_url(o.lcm_url);
  app.add_option("--log", o.log, "serve this recorded LCM log with a time slider instead of live LCM traffic")
      ->check(CLI::ExistingFile);
  app.add_option("--max-clients", o.server.max_clients, "live pages served at once; more are refused (default 8)")
      ->check(CLI::Range(1, 64));
  app.add_option("--queue", o.server.queue, "updates queued per page before a slow one skips to the current state (default 64)")
      ->check(CLI::Range(1, 10000));
  app.add_option("--update-ms", o.update_ms, "how often pages are sent what changed, ms (default 100)")
      ->check(CLI::Range(20, 10000));
}

}  // namespace whiskeye::viewer
