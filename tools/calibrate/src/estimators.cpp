// whiskeye-calibrate's estimators (see estimators.h).
#include "whiskeye/calibrate/estimators.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

namespace whiskeye::calibrate {

namespace {

std::string fmt(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

struct Moments {
  double mean = 0, sd = 0;
};
template <typename F>
Moments moments(const std::vector<ChannelSample>& s, F value) {
  Moments m;
  if (s.empty()) return m;
  for (const ChannelSample& c : s) m.mean += value(c);
  m.mean /= static_cast<double>(s.size());
  for (const ChannelSample& c : s) m.sd += (value(c) - m.mean) * (value(c) - m.mean);
  m.sd = std::sqrt(m.sd / static_cast<double>(s.size()));
  return m;
}

// One line per silent board among the whiskers' channels.
void silent_boards(const Recording& r, Problems& problems) {
  for (int b = 0; b < wp::kNumBoards; ++b) {
    if (r.board(b).samples == 0) {
      problems.push_back("board " + std::to_string(b) + " (CAN node " + std::to_string(b + 1) +
                         ") sent no samples: channels " + std::to_string(b * 4) + ".." + std::to_string(b * 4 + 3) +
                         " not measured (power, cable, termination or node id)");
    }
  }
}

double wrap_half_turn(double a) {  // to (-pi/2, pi/2]
  while (a > kPi / 2) a -= kPi;
  while (a <= -kPi / 2) a += kPi;
  return a;
}

}  // namespace

std::string whisker_name(int w) {
  return "whisker " + std::to_string(w) + " (row " + std::to_string(w / kWhiskerColumns) + ", column " +
         std::to_string(w % kWhiskerColumns) + ")";
}

// ---------------------------------------------------------------- bus

BusReport check_bus(const Recording& r, double rate_hz, double duration_s) {
  BusReport rep;
  rep.error_frames = r.error_frames();
  rep.rejected = r.rejected();
  rep.load = duration_s > 0 ? r.busy_us() / (duration_s * 1e6) : 0.0;
  rep.expected_load = wp::bus_load(r.mode(), rate_hz, wp::kArbitrationBps, wp::kFdDataBps).busy_fraction;
  rep.ok = rep.error_frames == 0 && rep.rejected == 0 && rep.load <= rep.expected_load;
  for (int b = 0; b < wp::kNumBoards; ++b) {
    const BoardCounts& c = r.board(b);
    BoardVerdict& v = rep.boards[static_cast<std::size_t>(b)];
    v.board = b;
    v.sample_hz = duration_s > 0 ? static_cast<double>(c.samples) / duration_s : 0.0;
    v.heartbeat_hz = duration_s > 0 ? static_cast<double>(c.heartbeats) / duration_s : 0.0;
    v.gaps = c.gaps;
    if (c.samples == 0 && c.heartbeats == 0) {
      v.reason = "absent: no frame at all (power, cable, termination or node id)";
    } else if (c.samples == 0) {
      v.reason = "heartbeats but no samples (not operational?)";
    } else if (std::abs(v.sample_hz - rate_hz) > 0.05 * rate_hz) {
      v.reason = "sample rate " + fmt("%.1f", v.sample_hz) + " Hz, configured " + fmt("%.0f", rate_hz) + " Hz";
    } else if (std::abs(v.heartbeat_hz - wp::kHeartbeatHz) > 0.3 * wp::kHeartbeatHz) {
      v.reason = "heartbeat rate " + fmt("%.1f", v.heartbeat_hz) + " Hz, expected " + fmt("%.0f", wp::kHeartbeatHz) + " Hz";
    } else if (c.nmt_state != 0x05) {
      v.reason = "NMT state " + fmt("0x%02x", c.nmt_state) + ", not operational (0x05)";
    } else if (static_cast<double>(c.gaps) > 0.001 * static_cast<double>(c.samples)) {
      v.reason = std::to_string(c.gaps) + " samples lost in sequence gaps";
    } else if (c.fault_samples > 0) {
      v.reason = "reports a fault in " + std::to_string(c.fault_samples) + " samples";
    }
    v.ok = v.reason.empty();
    rep.ok = rep.ok && v.ok;
  }
  return rep;
}

std::string format_bus_report(const BusReport& rep) {
  std::string out = "board  node  samples/s  heartbeats/s  gaps  verdict\n";
  for (const BoardVerdict& v : rep.boards) {
    char line[160];
    std::snprintf(line, sizeof line, "%5d  %4d  %9.1f  %12.1f  %4lld  %s\n", v.board, v.board + 1, v.sample_hz,
                  v.heartbeat_hz, static_cast<long long>(v.gaps), v.ok ? "ok" : ("FAIL: " + v.reason).c_str());
    out += line;
  }
  out += "bus load " + fmt("%.1f", 100 * rep.load) + " % heard (motors off), " + fmt("%.1f", 100 * rep.expected_load) +
         " % with commands (wp::bus_load); error frames " + std::to_string(rep.error_frames) + ", rejected frames " +
         std::to_string(rep.rejected) + "\n";
  out += rep.ok ? "bus: ok\n" : "bus: FAIL\n";
  return out;
}

// ---------------------------------------------------------------- bounds

Problems check_bounds(const std::vector<Estimate>& estimates) {
  Problems problems;
  for (const Estimate& e : estimates) {
    if (const std::string why = whiskerd::implausible_calibration(e.key, e.new_value); !why.empty()) {
      problems.push_back(whisker_name(e.whisker) + ": " + e.key + " = " + fmt("%.6g", e.new_value) + " " + why);
    }
  }
  return problems;
}

// ---------------------------------------------------------------- rest

Result estimate_rest(const Recording& r, const whiskerd::CoreParams& current, const RestLimits& limits) {
  Result res;
  silent_boards(r, res.problems);
  for (int b = 0; b < wp::kNumBoards; ++b) {
    const int64_t n = r.board(b).samples;
    if (n > 0 && n < limits.min_samples) {
      res.problems.push_back("board " + std::to_string(b) + " (CAN node " + std::to_string(b + 1) + ") sent " +
                             std::to_string(n) + (n == 1 ? " sample" : " samples") + ", fewer than the " +
                             std::to_string(limits.min_samples) + " that estimate its channels' offsets and noise " +
                             "(record longer: --seconds)");
    }
  }
  for (int w = 0; w < kNumWhiskers; ++w) {
    const int ch = current.channel[static_cast<std::size_t>(w)];
    const std::vector<ChannelSample>& s = r.channel(ch);
    if (static_cast<int64_t>(s.size()) < limits.min_samples) continue;  // its board is reported above
    const std::string who = whisker_name(w) + " (channel " + std::to_string(ch) + ")";
    const auto faults = std::count_if(s.begin(), s.end(), [](const ChannelSample& c) { return c.fault; });
    const Moments mx = moments(s, [](const ChannelSample& c) { return double(c.x); });
    const Moments my = moments(s, [](const ChannelSample& c) { return double(c.y); });
    const bool saturated = std::any_of(s.begin(), s.end(), [](const ChannelSample& c) {
      return std::abs(c.x) >= wp::kHallLimit || std::abs(c.y) >= wp::kHallLimit;
    });
    if (faults > 0) {
      res.problems.push_back(who + ": its board reports a fault in " + std::to_string(faults) + " of " +
                             std::to_string(s.size()) + " samples");
    } else if (saturated) {
      res.problems.push_back(who + ": saturated: the Hall sensor reads the ADC limit (±2047; magnet missing or too close?)");
    } else if (mx.sd == 0.0 || my.sd == 0.0) {
      res.problems.push_back(who + ": stuck: all " + std::to_string(s.size()) + " samples read x = " +
                             fmt("%.0f", s.front().x) + (mx.sd == 0.0 ? "" : " (varying)") + ", y = " +
                             fmt("%.0f", s.front().y) + (my.sd == 0.0 ? "" : " (varying)") +
                             " (sensor disconnected or dead)");
    } else if (std::max(mx.sd, my.sd) > limits.max_noise_counts) {
      res.problems.push_back(who + ": noisy: sigma x " + fmt("%.1f", mx.sd) + ", y " + fmt("%.1f", my.sd) +
                             " counts, more than " + fmt("%g", limits.max_noise_counts) +
                             " (touched during the recording, or a loose magnet)");
    }
    const double n = static_cast<double>(s.size());
    const wp::WhiskerCalibration& c = current.calibration[static_cast<std::size_t>(w)];
    res.estimates.push_back({w, "offset_x", c.offset_x, mx.mean, mx.sd / std::sqrt(n)});
    res.estimates.push_back({w, "offset_y", c.offset_y, my.mean, my.sd / std::sqrt(n)});
  }
  return res;
}

// ---------------------------------------------------------------- pushes

std::vector<Push> find_pushes(const Recording& r) {
  constexpr int64_t kMinPushUs = 50000;   // shorter excursions are noise or a knock
  // A push ends at the first run of this many samples back at rest: counted in samples, not time, so
  // frames that arrive late or in bursts (a loaded host, a replay) never split a push.
  constexpr std::size_t kRestRun = 10;
  constexpr double kPlateau = 0.8;        // the plateau: where the push is within 80 % of its peak
  std::vector<Push> found;
  for (int ch = 0; ch < kChannels; ++ch) {
    const std::vector<ChannelSample>& s = r.channel(ch);
    if (s.size() < 10) continue;
    std::vector<double> xs, ys;
    for (const ChannelSample& c : s) {
      xs.push_back(c.x);
      ys.push_back(c.y);
    }
    const double bx = median(xs), by = median(ys);
    std::vector<double> dev;
    for (const ChannelSample& c : s) dev.push_back(std::hypot(c.x - bx, c.y - by));
    const double sigma = std::max(1.0, 1.4826 * median(dev) / 1.1774);  // MAD of a 2-D Gaussian's radius
    const double threshold = std::max(10.0 * sigma, 30.0);
    std::size_t i = 0;
    while (i < s.size()) {
      if (dev[i] <= threshold) {
        ++i;
        continue;
      }
      std::size_t end = i;  // last active sample of this push
      for (std::size_t j = i + 1; j < s.size() && j - end <= kRestRun; ++j) {
        if (dev[j] > threshold) end = j;
      }
      if (s[end].utime - s[i].utime >= kMinPushUs) {
        double peak = 0;
        for (std::size_t j = i; j <= end; ++j) peak = std::max(peak, dev[j]);
        Push p;
        p.channel = ch;
        p.start_utime = s[i].utime;
        p.end_utime = s[end].utime;
        // The plateau: near the peak, then only the samples at the plateau's own level (the ramps'
        // upper ends would pull the mean down).
        std::vector<double> top;
        for (std::size_t j = i; j <= end; ++j) {
          if (dev[j] >= kPlateau * peak) top.push_back(dev[j]);
        }
        const double level = median(top);
        const double band = std::max(4.0 * sigma, 0.02 * level);
        int n = 0;
        for (std::size_t j = i; j <= end; ++j) {
          if (std::abs(dev[j] - level) > band) continue;
          p.dx += s[j].x - bx;
          p.dy += s[j].y - by;
          ++n;
        }
        p.dx /= n;
        p.dy /= n;
        p.sigma = sigma / std::sqrt(static_cast<double>(n));
        found.push_back(p);
      }
      i = end + 1;
    }
  }
  std::sort(found.begin(), found.end(), [](const Push& a, const Push& b) { return a.start_utime < b.start_utime; });
  // Overlapping pushes of two channels: the weaker is crosstalk.
  std::vector<Push> pushes;
  for (const Push& p : found) {
    if (!pushes.empty() && p.start_utime <= pushes.back().end_utime) {
      if (std::hypot(p.dx, p.dy) > std::hypot(pushes.back().dx, pushes.back().dy)) pushes.back() = p;
      continue;
    }
    pushes.push_back(p);
  }
  return pushes;
}

namespace {

// `order`, or every whisker 0..23 when it is empty.
std::vector<int> whiskers_in(const std::vector<int>& order) {
  if (!order.empty()) return order;
  std::vector<int> all;
  for (int w = 0; w < kNumWhiskers; ++w) all.push_back(w);
  return all;
}

// The pushes of `order` as (x push, y push) pairs on one channel each, or problems.
bool pair_pushes(const std::vector<Push>& pushes, const std::vector<int>& order, Problems& problems) {
  if (pushes.size() != 2 * order.size()) {
    problems.push_back("found " + std::to_string(pushes.size()) +
                       " pushes in the recording, expected 2 per whisker (forward, then up) for the " +
                       std::to_string(order.size()) + " whiskers of --expect: " + std::to_string(2 * order.size()));
    return false;
  }
  bool ok = true;
  std::map<int, int> whisker_on;
  for (std::size_t i = 0; i < order.size(); ++i) {
    const Push& px = pushes[2 * i];
    const Push& py = pushes[2 * i + 1];
    if (px.channel != py.channel) {
      problems.push_back(whisker_name(order[i]) + ": the forward push moved channel " + std::to_string(px.channel) +
                         " but the upward push channel " + std::to_string(py.channel));
      ok = false;
      continue;
    }
    const auto [it, inserted] = whisker_on.emplace(px.channel, order[i]);
    if (!inserted) {
      problems.push_back("channel " + std::to_string(px.channel) + " moved for both " + whisker_name(it->second) +
                         " and " + whisker_name(order[i]));
      ok = false;
    }
  }
  return ok;
}

}  // namespace

Result map_whiskers(const std::vector<Push>& pushes, const std::vector<int>& expect, const whiskerd::CoreParams& current) {
  Result res;
  const std::vector<int> order = whiskers_in(expect);
  if (!pair_pushes(pushes, order, res.problems)) return res;
  std::array<int, kNumWhiskers> channel = current.channel;
  for (std::size_t i = 0; i < order.size(); ++i) {
    const int w = order[i];
    const Push& px = pushes[2 * i];
    const Push& py = pushes[2 * i + 1];
    channel[static_cast<std::size_t>(w)] = px.channel;
    // raw - offset = diag(1/gx, 1/gy) R(-rotation) d: a forward push reads (cos r / gx, -sin r / gy),
    // an upward one (sin r / gx, cos r / gy); a mirrored board (gy < 0) turns the pair's handedness.
    const bool mirrored = px.dx * py.dy - px.dy * py.dx < 0;
    double sx = 1.0, sy = mirrored ? -1.0 : 1.0;
    const double ru = std::atan2(-sy * px.dy, px.dx);
    const double rv = std::atan2(py.dx, sy * py.dy);
    double rot = std::atan2(std::sin(ru) + std::sin(rv), std::cos(ru) + std::cos(rv));
    if (rot > kPi / 2 || rot <= -kPi / 2) {  // R(r + pi) = -R(r): the same calibration with both gains negated
      rot = wrap_half_turn(rot);
      sx = -sx;
      sy = -sy;
    }
    const wp::WhiskerCalibration& c = current.calibration[static_cast<std::size_t>(w)];
    const double spread = std::abs(std::remainder(ru - rv, 2 * kPi)) / 2;
    res.estimates.push_back({w, "channel", double(current.channel[static_cast<std::size_t>(w)]), double(px.channel), 0});
    res.estimates.push_back({w, "rotation", c.rotation, rot, spread});
    res.estimates.push_back({w, "gain_x", c.gain_x, sx * std::abs(c.gain_x), 0});
    res.estimates.push_back({w, "gain_y", c.gain_y, sy * std::abs(c.gain_y), 0});
  }
  // Whiskers not in --expect keep their channels: the whole wiring must still be a permutation.
  std::array<int, kNumWhiskers> whisker_on{};
  whisker_on.fill(-1);
  for (int w = 0; w < kNumWhiskers; ++w) {
    const int ch = channel[static_cast<std::size_t>(w)];
    if (whisker_on[static_cast<std::size_t>(ch)] >= 0) {
      res.problems.push_back("map: channel " + std::to_string(ch) + " is now " +
                             whisker_name(whisker_on[static_cast<std::size_t>(ch)]) + "'s and " + whisker_name(w) +
                             "'s: map every whisker whose channel changes (--expect)");
      break;
    }
    whisker_on[static_cast<std::size_t>(ch)] = w;
  }
  return res;
}

Result fit_gains(const std::vector<Push>& pushes, const std::vector<int>& expect, double deflection,
                 const whiskerd::CoreParams& current) {
  Result res;
  const std::vector<int> order = whiskers_in(expect);
  if (!pair_pushes(pushes, order, res.problems)) return res;
  for (std::size_t i = 0; i < order.size(); ++i) {
    const int w = order[i];
    const Push& px = pushes[2 * i];
    const Push& py = pushes[2 * i + 1];
    const int wired = current.channel[static_cast<std::size_t>(w)];
    if (px.channel != wired) {
      res.problems.push_back(whisker_name(w) + ": the jig moved channel " + std::to_string(px.channel) +
                             ", but whiskerd wires it to channel " + std::to_string(wired) +
                             " (run map first, or check the jig's order)");
      continue;
    }
    // M = [u v] / D = diag(1/gx, 1/gy) R(-r); its inverse C = R(r) diag(gx, gy) is the calibration.
    const double m00 = px.dx / deflection, m10 = px.dy / deflection;
    const double m01 = py.dx / deflection, m11 = py.dy / deflection;
    const double det = m00 * m11 - m01 * m10;
    if (std::abs(det) < 1e-9) {
      res.problems.push_back(whisker_name(w) + ": its forward and upward pushes moved the sensor along one line");
      continue;
    }
    const double c00 = m11 / det, c01 = -m01 / det, c10 = -m10 / det, c11 = m00 / det;
    const double r0 = std::atan2(c10, c00);   // column 0 = gx (cos r, sin r)
    const double r1 = std::atan2(-c01, c11);  // column 1 = gy (-sin r, cos r)
    const double rot = 0.5 * std::atan2(std::sin(2 * r0) + std::sin(2 * r1), std::cos(2 * r0) + std::cos(2 * r1));
    const double gx = c00 * std::cos(rot) + c10 * std::sin(rot);
    const double gy = -c01 * std::sin(rot) + c11 * std::cos(rot);
    const double rel = std::max(px.sigma / std::hypot(px.dx, px.dy), py.sigma / std::hypot(py.dx, py.dy));
    const double spread = std::abs(wrap_half_turn(r0 - r1)) / 2;
    const wp::WhiskerCalibration& c = current.calibration[static_cast<std::size_t>(w)];
    res.estimates.push_back({w, "gain_x", c.gain_x, gx, std::abs(gx) * rel});
    res.estimates.push_back({w, "gain_y", c.gain_y, gy, std::abs(gy) * rel});
    res.estimates.push_back({w, "rotation", c.rotation, rot, spread + rel});
  }
  return res;
}

// ---------------------------------------------------------------- theta

Result fit_theta(const Recording& r, double stop_rad, const whiskerd::CoreParams& current) {
  constexpr int kMinAtStop = 20;  // samples resting at an end stop (40 ms at 500 Hz)
  Result res;
  silent_boards(r, res.problems);
  // A fault anywhere in the sweep: the motors were off from then on, the end stops are not to be trusted.
  for (int b = 0; b < wp::kNumBoards; ++b) {
    for (int k = 0; k < wp::kWhiskersPerBoard; ++k) {
      const std::vector<ChannelSample>& s = r.channel(b * 4 + k);
      const auto f = std::find_if(s.begin(), s.end(), [](const ChannelSample& c) { return c.fault; });
      if (f == s.end()) continue;
      res.problems.push_back("sweep interrupted by a fault: board " + std::to_string(b) + " reports a fault from " +
                             fmt("%.2f", static_cast<double>(f->utime - r.first_utime()) / 1e6) +
                             " s into the recording (motors off): run the sweep again once the fault is cleared");
      break;
    }
  }
  if (!res.problems.empty()) return res;
  for (int w = 0; w < kNumWhiskers; ++w) {
    const int ch = current.channel[static_cast<std::size_t>(w)];
    const std::vector<ChannelSample>& s = r.channel(ch);
    const wp::WhiskerCalibration& c = current.calibration[static_cast<std::size_t>(w)];
    const auto [lo_it, hi_it] =
        std::minmax_element(s.begin(), s.end(), [](const ChannelSample& a, const ChannelSample& b) { return a.theta < b.theta; });
    const double expected_span = 2 * stop_rad / std::abs(c.theta_gain);
    if (!(hi_it->theta - lo_it->theta > 0.5 * expected_span)) {
      res.problems.push_back(whisker_name(w) + ": θ moved over " + std::to_string(hi_it->theta - lo_it->theta) +
                             " counts, expected about " + fmt("%.0f", expected_span) + " between the end stops");
      continue;
    }
    // An end stop: the samples within 2 counts of the extreme.
    auto at_stop = [&](int extreme, Moments& m) {
      std::vector<ChannelSample> near;
      for (const ChannelSample& x : s) {
        if (std::abs(x.theta - extreme) <= 2) near.push_back(x);
      }
      m = moments(near, [](const ChannelSample& x) { return double(x.theta); });
      return static_cast<int>(near.size());
    };
    Moments hi, lo;
    const int n_hi = at_stop(hi_it->theta, hi), n_lo = at_stop(lo_it->theta, lo);
    if (n_hi < kMinAtStop || n_lo < kMinAtStop) {
      res.problems.push_back(whisker_name(w) + ": θ did not rest at " + (n_hi < kMinAtStop ? "the upper" : "the lower") +
                             " end stop (the sweep did not reach it, or was cut short)");
      continue;
    }
    // Protraction is +θ: the stop the encoder counts up to is +stop_rad when theta_gain > 0.
    const double sign = c.theta_gain > 0 ? 1.0 : -1.0;
    const double span = hi.mean - lo.mean;
    const double gain = sign * 2 * stop_rad / span;
    const double offset = (hi.mean + lo.mean) / 2;
    // Encoder quantisation (1/sqrt(12) count) on each stop's mean, plus its scatter.
    const double se = std::sqrt(hi.sd * hi.sd / n_hi + lo.sd * lo.sd / n_lo + 2.0 / 12.0);
    res.estimates.push_back({w, "theta_offset", c.theta_offset, offset, se / 2});
    res.estimates.push_back({w, "theta_gain", c.theta_gain, gain, std::abs(gain) * se / span});
  }
  return res;
}

// ---------------------------------------------------------------- output

std::vector<whiskerd::CalibrationEntry> dropin_entries(const std::vector<Estimate>& estimates) {
  std::map<int, whiskerd::CalibrationEntry> by_whisker;
  for (const Estimate& e : estimates) {
    whiskerd::CalibrationEntry& entry = by_whisker[e.whisker];
    entry.index = e.whisker;
    entry.keys.emplace_back(e.key, e.new_value);
  }
  std::vector<whiskerd::CalibrationEntry> entries;
  for (auto& [w, entry] : by_whisker) entries.push_back(std::move(entry));
  return entries;
}

std::string format_table(const std::vector<Estimate>& estimates) {
  std::string out = "whisker  key            old            new            ±\n";
  for (const Estimate& e : estimates) {
    char line[128];
    std::snprintf(line, sizeof line, "%7d  %-12s  %13.6g  %13.6g  %11.3g\n", e.whisker, e.key.c_str(), e.old_value,
                  e.new_value, e.uncertainty);
    out += line;
  }
  return out;
}

}  // namespace whiskeye::calibrate
