// Fuzz target: a `candump -l` log as whiskeye-calibrate reads one (--input): split into lines in two
// pieces (CandumpLines, the split at the first byte's share of the input), each line classified
// (classify_candump_line), its frames into a Recording, then the bus check, the rest estimate and the
// push search over whatever it holds. Input: the log's bytes.
// Checks beyond "no crash": no line handed out is longer than kMaxCandumpLineBytes, and a data frame
// parsed from a line formats back into a line that parses to the same frame.
#include <cstdlib>
#include <string>
#include <string_view>

#include "whiskeye/calibrate/estimators.h"
#include "whiskeye/can/candump.h"

using namespace whiskeye;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view log(reinterpret_cast<const char*>(data), size);
  const std::size_t split = size == 0 ? 0 : size * data[0] / 256;
  calibrate::Recording r(wp::BusMode::kFd, wp::ProtocolIds{});
  can::CandumpLines lines;
  can::LoggedFrame f, back;
  std::string interface, back_interface;
  const auto take = [&](int64_t, std::string_view line) {
    if (line.size() > can::kMaxCandumpLineBytes) std::abort();
    switch (can::classify_candump_line(line, f, interface)) {
      case can::CandumpLine::kFrame:
        if (!can::parse_candump_line(can::format_candump_line(f, interface), back, back_interface) ||
            back.utime != f.utime || back.id != f.id || back.fd != f.fd || back.fd_flags != f.fd_flags || back.data != f.data ||
            back_interface != interface) {
          std::abort();
        }
        r.add_frame(f.utime, f.id, f.fd, f.data);
        break;
      case can::CandumpLine::kErrorFrame: r.add_error_frame(f.utime); break;
      default: break;
    }
  };
  if (lines.feed(log.substr(0, split), take) && lines.feed(log.substr(split), take)) lines.finish(take);
  if (r.first_utime() < 0) return 0;
  const double span_s = static_cast<double>(r.span_us()) / 1e6 + 1.0 / 500.0;
  calibrate::format_bus_report(calibrate::check_bus(r, 500.0, span_s));
  calibrate::estimate_rest(r, whiskerd::CoreParams{}, calibrate::RestLimits{});
  calibrate::find_pushes(r);
  return 0;
}
