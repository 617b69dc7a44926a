// Prints the counters of the last DRIVER_STATUS a driver published within a time, one "name=value"
// per line, for VM scenarios to check with grep (the guest has no LCM for Python). With --until-state
// (and --until-message), the first status in that state (whose message contains the text) instead,
// as soon as it comes: a state that lasts a second or two is caught whenever its status falls, where
// a window as short as the status period could see none (vm.camerad once got no status at all).
//   driver_status_probe --driver whiskerd --seconds 3 [--until-state N [--until-message TEXT]]
#include "whiskeye/common/bus.h"

#include <whiskeye/driver_status_t.hpp>

#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdio>
#include <optional>

int main(int argc, char** argv) {
  CLI::App app{"driver_status_probe: the last DRIVER_STATUS counters of one driver"};
  std::string driver;
  double seconds = 3.0;
  app.add_option("--driver", driver, "driver name (whiskerd, camerad, based)")->required();
  app.add_option("--seconds", seconds, "how long to listen");
  std::optional<int> until_state;
  std::string until_message;
  app.add_option("--until-state", until_state, "stop at the first status in this state");
  app.add_option("--until-message", until_message, "... whose message contains this text")->needs("--until-state");
  CLI11_PARSE(app, argc, argv);
  whiskeye::LcmBus bus;
  whiskeye::DecodeErrors errors;
  std::optional<whiskeye::driver_status_t> last;
  bool found = false;
  whiskeye::subscribe<whiskeye::driver_status_t>(
      bus, "DRIVER_STATUS",
      [&](const whiskeye::driver_status_t& m) {
        if (m.driver != driver || found) return;
        last = m;
        found = until_state && m.state == *until_state && m.message.find(until_message) != std::string::npos;
      },
      errors);
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (!found && std::chrono::steady_clock::now() < end) bus.handle_timeout(50);
  if (!last) {
    std::fprintf(stderr, "driver_status_probe: no DRIVER_STATUS from %s in %.1f s\n", driver.c_str(), seconds);
    return 1;
  }
  for (int i = 0; i < last->num_counters; ++i) {
    std::printf("%s=%lld\n", last->counter_names[i].c_str(), static_cast<long long>(last->counter_values[i]));
  }
  std::printf("state=%d\nmessage=%s\n", last->state, last->message.c_str());
  return 0;
}
