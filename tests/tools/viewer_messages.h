// The viewer's messages for its unit tests: a map, a pose, an event, a driver status, a whisk
// cycle and a camera frame of known contents, and feeding one to a ViewerState as received.
#pragma once

#include "whiskeye/common/bus.h"
#include "whiskeye/viewer/client_hub.h"
#include "whiskeye/viewer/viewer_state.h"

#include <whiskeye/image_t.hpp>

#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace whiskeye::viewer::test {

inline constexpr int64_t kT0 = 1'700'000'000'000'000;  // an epoch time, µs

inline vita_map_t make_map(int n, int current, int64_t utime = kT0) {
  vita_map_t m{};
  m.utime = utime;
  m.mode = vita_pose_t::MODE_VITA;
  m.current_experience_id = current;
  for (int i = 0; i < n; ++i) {
    experience_t e{};
    e.id = i;
    e.x = 0.5 * i;
    e.y = -0.25 * i;
    e.visual_template_id = i;
    e.tactile_template_id = i % 3 == 0 ? i : -1;
    e.dense = i % 3 == 0;
    m.experiences.push_back(e);
    if (i > 0) {
      link_t l{};
      l.from_id = i - 1;
      l.to_id = i;
      m.links.push_back(l);
    }
  }
  m.num_experiences = n;
  m.num_links = static_cast<int32_t>(m.links.size());
  return m;
}

inline vita_pose_t make_pose(double x, double y, int64_t utime = kT0) {
  vita_pose_t p{};
  p.utime = utime;
  p.x = x;
  p.y = y;
  p.theta = 0.5;
  p.experience_id = 3;
  p.template_id = 4;
  p.mode = vita_pose_t::MODE_VITA;
  return p;
}

inline vita_event_t make_event(int8_t type, int64_t cycle, int from, int to) {
  vita_event_t e{};
  e.utime = kT0 + cycle * 1'000'000;
  e.cycle = cycle;
  e.type = type;
  e.from_id = from;
  e.to_id = to;
  e.template_id = 7;
  e.mode = vita_pose_t::MODE_VITA;
  return e;
}

inline driver_status_t make_driver_status(const std::string& name, int8_t state, int64_t utime) {
  driver_status_t s{};
  s.utime = utime;
  s.driver = name;
  s.state = state;
  s.message = state == driver_status_t::STATE_OK ? "" : "camera unplugged";
  s.counter_names = {"frames", "errors"};
  s.counter_values = {120, 2};
  s.num_counters = 2;
  s.stat_names = {"rate_hz"};
  s.stat_values = {5.0};
  s.num_stats = 1;
  return s;
}

// A whisk cycle of `samples` samples; whisker 5 touches from sample 10 on with deflection 0.6,
// whisker 7 is not measured (NaN), the others deflect 0.1.
inline whisk_cycle_t make_cycle(int64_t cycle, int samples = 50) {
  whisk_cycle_t c{};
  c.cycle = cycle;
  c.utime_start = kT0 + cycle * 1'000'000;
  c.utime_end = c.utime_start + (samples - 1) * 2000;
  c.utime = c.utime_end;
  c.num_whiskers = 24;
  c.num_samples = samples;
  c.num_missing = 0;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int s = 0; s < samples; ++s) {
    c.sample_utime.push_back(c.utime_start + s * 2000);
    c.sample_valid.push_back(1);
    c.phase.push_back(0);
    std::vector<float> theta(24, 0.3f + 0.001f * static_cast<float>(s)), dx(24, 0.1f), dy(24, 0.0f);
    std::vector<int8_t> contact(24, 0);
    if (s >= 10) {
      dx[5] = 0.6f;
      contact[5] = 1;
    }
    theta[7] = dx[7] = dy[7] = nan;
    c.theta.push_back(theta);
    c.deflection_x.push_back(dx);
    c.deflection_y.push_back(dy);
    c.contact.push_back(contact);
  }
  return c;
}

inline image_t make_yuyv_frame(int64_t utime, int width = 640, int height = 480) {
  image_t im{};
  im.utime = utime;
  im.seq = 1;
  im.width = width;
  im.height = height;
  im.row_stride = width * 2;
  im.pixelformat = image_t::PIXEL_FORMAT_YUYV;
  im.data.assign(static_cast<std::size_t>(im.row_stride * height), 128);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) im.data[static_cast<std::size_t>(y * im.row_stride + 2 * x)] = static_cast<uint8_t>(x % 256);
  }
  im.size = static_cast<int32_t>(im.data.size());
  return im;
}

template <typename T>
inline bool feed(ViewerState& s, const char* channel, const T& msg, int64_t recv = kT0) {
  const std::vector<uint8_t> bytes = encode_message(msg);
  return s.apply(channel, recv, bytes);
}

// An update as the hub broadcasts it.
inline Update text(const std::string& s) { return std::make_shared<const std::string>(s); }

}  // namespace whiskeye::viewer::test
