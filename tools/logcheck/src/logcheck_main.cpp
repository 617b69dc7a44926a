// whiskeye-logcheck: what an LCM log lost. Per channel: events, rate, the longest pause, and — where
// the messages carry sequence numbers — how many never reached the log. Exit 1 when a channel lost
// more than --max-loss of its messages (default 0: any), the file is damaged, or it holds no event (an empty log is
// not "nothing lost"); 2 on a bad command line.
#include "whiskeye/common/bus.h"
#include "whiskeye/common/cli.h"
#include "whiskeye/logcheck/log_check.h"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <filesystem>
#include <string>

namespace {

// Reads `file` and prints the table: 0, or 1 when a channel lost more than `max_loss` or the file is
// damaged, unreadable or without a single event.
int check_log(const std::string& file, double max_loss, double gap_factor) {
  using namespace whiskeye;
  logcheck::LogCheck check(gap_factor);
  std::string damage;
  try {
    LogReader reader(file, LogReader::Access::kStreamed);  // one pass, nothing kept
    LogReader::EventView ev;
    while (reader.next(ev)) check.add(ev.channel, ev.utime, ev.data);
    damage = reader.damage().summary();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "whiskeye-logcheck: %s\n", e.what());
    return 1;
  }
  if (check.channels().empty()) {  // nothing recorded is no "nothing lost"
    std::error_code ec;
    const auto bytes = static_cast<unsigned long long>(std::filesystem::file_size(file, ec));
    if (!damage.empty()) std::fprintf(stderr, "whiskeye-logcheck: %s\n", damage.c_str());
    if (!ec && bytes == 0) {
      std::fprintf(stderr, "whiskeye-logcheck: %s: the log is empty (0 bytes): nothing was recorded\n", file.c_str());
    } else {
      std::fprintf(stderr, "whiskeye-logcheck: %s: no event could be read from its %llu bytes\n", file.c_str(), bytes);
    }
    return 1;
  }
  std::printf("%-20s %9s %9s %10s %6s %9s %7s %8s %8s\n", "channel", "events", "rate Hz", "max gap s", "pauses",
              "lost", "places", "in a row", "restarts");
  std::string lost_list;
  bool over = false;
  int sequenced = 0;
  for (const auto& s : check.channels()) {
    std::printf("%-20s %9lld %9.2f %10.3f %6lld ", s.channel.c_str(), static_cast<long long>(s.count), s.rate_hz(),
                static_cast<double>(s.max_interval_us) * 1e-6, static_cast<long long>(s.time_gaps));
    if (!s.sequenced) {
      std::printf("%9s %7s %8s %8s\n", "-", "-", "-", "-");
      continue;
    }
    ++sequenced;
    std::printf("%9lld %7lld %8lld %8lld\n", static_cast<long long>(s.lost), static_cast<long long>(s.loss_places),
                static_cast<long long>(s.longest_loss), static_cast<long long>(s.restarts));
    if (s.lost > 0) {
      char item[160];
      std::snprintf(item, sizeof item, "%s%s %lld of %llu (%.2f %%, at most %lld in a row)", lost_list.empty() ? "" : ", ",
                    s.channel.c_str(), static_cast<long long>(s.lost), static_cast<unsigned long long>(s.sent()),
                    100.0 * s.lost_fraction(), static_cast<long long>(s.longest_loss));
      lost_list += item;
      if (s.lost_more_than(max_loss)) over = true;
    }
  }
  if (!damage.empty()) std::fprintf(stderr, "whiskeye-logcheck: %s\n", damage.c_str());
  if (lost_list.empty()) {
    std::printf("whiskeye-logcheck: %s: nothing lost on the %d channel(s) with sequence numbers\n", file.c_str(), sequenced);
  } else {
    std::printf("whiskeye-logcheck: %s: lost %s\n", file.c_str(), lost_list.c_str());
  }
  return over || !damage.empty() ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace whiskeye;
  cli::Program program("whiskeye-logcheck",
                       "whiskeye-logcheck: per channel, what an LCM log holds and what it lost (sequence gaps, pauses)");
  CLI::App& app = program.app();
  std::string file;
  double max_loss = 0.0;
  double gap_factor = 3.0;
  app.add_option("FILE", file, "LCM log (lcm-logger's)")->required();
  app.add_option("--max-loss", max_loss, "fraction of a channel's messages that may be lost before exit 1 (default 0)")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--gap-factor", gap_factor, "a pause is an interval longer than this × the channel's median interval")
      ->check(CLI::PositiveNumber);
  return program.run(argc, argv, [&] { return check_log(file, max_loss, gap_factor); });
}
