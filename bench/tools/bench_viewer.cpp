// viewer-bench: what whiskeye-viewer costs per message of the full stack's traffic, and per second of
// it (5 Hz camera 640x480 YUYV, 50 Hz VITA_POSE, 1 Hz VITA_MAP / WHISK_CYCLE / VITA_EVENT /
// VITA_MATCH, DRIVER_STATUS from three drivers and SLAM_STATUS at 1 Hz, and the page's updates at
// 10 Hz), against a plain reference in the same run: decoding the same messages into their LCM types
// and nothing else, which any subscriber pays. Figures in docs/performance.md ("## whiskeye-viewer").
#include "whiskeye/common/bus.h"
#include "whiskeye/common/channels.h"
#include "whiskeye/viewer/viewer_state.h"

#include <benchmark/benchmark.h>
#include <whiskeye/image_t.hpp>

#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace {

using namespace whiskeye;
using namespace whiskeye::viewer;
constexpr int64_t kT0 = 1'700'000'000'000'000;

struct Message {
  const char* channel;
  std::vector<uint8_t> bytes;
};

// A camera-like 640x480 YUYV frame: a bright ceiling, walls with vertical edges, a floor, sensor noise
// (a flat or random frame would make the JPEG unrealistically small or large).
std::vector<uint8_t> camera(int64_t utime) {
  image_t im{};
  im.utime = utime;
  im.width = 640;
  im.height = 480;
  im.row_stride = 1280;
  im.pixelformat = image_t::PIXEL_FORMAT_YUYV;
  im.data.resize(1280 * 480);
  std::mt19937 rng(static_cast<unsigned>(utime));
  std::uniform_int_distribution<int> noise(-6, 6);
  for (int y = 0; y < 480; ++y) {
    for (int x = 0; x < 640; ++x) {
      int v = y < 120 ? 230 : y < 330 ? 110 + (x / 40 % 2) * 60 + (x % 160 < 8 ? -80 : 0) : 60 + y / 12;
      v = std::clamp(v + noise(rng), 0, 255);
      im.data[static_cast<std::size_t>(y * 1280 + 2 * x)] = static_cast<uint8_t>(v);
      im.data[static_cast<std::size_t>(y * 1280 + 2 * x + 1)] = static_cast<uint8_t>(128 + (x % 2 ? 6 : -4));
    }
  }
  im.size = static_cast<int32_t>(im.data.size());
  return encode_message(im);
}

std::vector<uint8_t> pose(int i) {
  vita_pose_t p{};
  p.utime = kT0 + i * 20'000;
  p.x = 2.0 * std::cos(0.002 * i);
  p.y = 2.0 * std::sin(0.002 * i);
  p.theta = 0.002 * i;
  p.experience_id = i / 50;
  return encode_message(p);
}

std::vector<uint8_t> map(int n) {
  vita_map_t m{};
  m.utime = kT0;
  m.current_experience_id = n - 1;
  for (int i = 0; i < n; ++i) {
    experience_t e{};
    e.id = i;
    e.x = 2.0 * std::cos(0.1 * i);
    e.y = 2.0 * std::sin(0.1 * i);
    e.dense = i % 3 == 0;
    m.experiences.push_back(e);
    if (i > 0) m.links.push_back(link_t{i - 1, i, 0.1, 0.0, 0.1, kT0, 0, 0.002, 1.0, false});
  }
  m.num_experiences = n;
  m.num_links = static_cast<int32_t>(m.links.size());
  return encode_message(m);
}

std::vector<uint8_t> whisk_cycle() {
  whisk_cycle_t c{};
  c.cycle = 1;
  c.utime_start = kT0;
  c.num_whiskers = 24;
  c.num_samples = 500;
  for (int s = 0; s < 500; ++s) {
    c.sample_utime.push_back(kT0 + s * 2000);
    c.sample_valid.push_back(1);
    c.phase.push_back(0);
    c.theta.emplace_back(24, 0.3f);
    c.deflection_x.emplace_back(24, s > 200 && s < 260 ? 0.4f : 0.01f);
    c.deflection_y.emplace_back(24, 0.0f);
    c.contact.emplace_back(24, s > 200 && s < 260 ? 1 : 0);
  }
  c.utime_end = c.utime = kT0 + 499 * 2000;
  return encode_message(c);
}

std::vector<uint8_t> driver_status(const char* name) {
  driver_status_t s{};
  s.utime = kT0;
  s.driver = name;
  s.state = driver_status_t::STATE_OK;
  for (int i = 0; i < 8; ++i) {
    s.counter_names.push_back("counter_" + std::to_string(i));
    s.counter_values.push_back(i * 1000);
    s.stat_names.push_back("stat_" + std::to_string(i));
    s.stat_values.push_back(i * 0.5);
  }
  s.num_counters = s.num_stats = 8;
  return encode_message(s);
}

// One second of the full stack's traffic, in the order it arrives.
std::vector<Message> one_second(int map_size) {
  std::vector<Message> out;
  for (int i = 0; i < 50; ++i) {
    out.push_back({channels::kVitaPose, pose(i)});
    if (i % 10 == 0) out.push_back({channels::kCamera, camera(kT0 + i * 20'000)});
  }
  out.push_back({channels::kWhiskCycle, whisk_cycle()});
  vita_event_t ev{};
  ev.utime = kT0;
  ev.type = vita_event_t::NEW_EXPERIENCE;
  out.push_back({channels::kVitaEvent, encode_message(ev)});
  template_match_t match{};
  match.utime = kT0;
  match.error = 0.4;
  out.push_back({channels::kVitaMatch, encode_message(match)});
  out.push_back({channels::kVitaMap, map(map_size)});
  for (const char* d : {"whiskerd", "camerad", "based"}) out.push_back({channels::kDriverStatus, driver_status(d)});
  slam_status_t slam{};
  slam.utime = kT0;
  out.push_back({channels::kSlamStatus, encode_message(slam)});
  return out;
}

// The viewer: every message applied, each camera frame encoded for the page (as when a page is
// open: the JPEG is made when a page asks for it, once per frame), and the page's update (the delta
// as SSE text) built 10 times a second.
void BM_ViewerFullStackSecond(benchmark::State& state) {
  const std::vector<Message> second = one_second(static_cast<int>(state.range(0)));
  ViewerState viewer;
  ViewerState::Cursor cursor;
  int64_t now = 0;
  std::size_t sent = 0;
  for (auto _ : state) {
    int tick = 0;
    for (std::size_t i = 0; i < second.size(); ++i) {
      const Message& m = second[i];
      viewer.apply(m.channel, kT0 + now, m.bytes);
      if (m.channel == channels::kCamera) benchmark::DoNotOptimize(viewer.camera_jpeg());
      // Ten updates spread over the second.
      if (i * 10 / second.size() >= static_cast<std::size_t>(tick)) {
        ++tick;
        now += 100'000;
        const nlohmann::json d = viewer.delta(cursor, now);
        if (!d.empty()) sent += ("event: delta\ndata: " + d.dump() + "\n\n").size();
      }
    }
  }
  state.counters["update_bytes_per_s"] = benchmark::Counter(static_cast<double>(sent), benchmark::Counter::kAvgIterations);
  state.SetLabel("one second of traffic, map of " + std::to_string(state.range(0)) + " experiences");
}
BENCHMARK(BM_ViewerFullStackSecond)->Arg(100)->Arg(1000)->Unit(benchmark::kMillisecond);

// The plain reference: the same second decoded into the LCM types, nothing kept or sent.
template <typename T>
void decode(const std::vector<uint8_t>& bytes) {
  T msg;
  benchmark::DoNotOptimize(decode_message(bytes, msg));
}

void BM_DecodeOnlyFullStackSecond(benchmark::State& state) {
  const std::vector<Message> second = one_second(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    for (const Message& m : second) {
      const std::string_view c = m.channel;
      if (c == channels::kVitaPose) decode<vita_pose_t>(m.bytes);
      else if (c == channels::kCamera) decode<image_t>(m.bytes);
      else if (c == channels::kWhiskCycle) decode<whisk_cycle_t>(m.bytes);
      else if (c == channels::kVitaEvent) decode<vita_event_t>(m.bytes);
      else if (c == channels::kVitaMatch) decode<template_match_t>(m.bytes);
      else if (c == channels::kVitaMap) decode<vita_map_t>(m.bytes);
      else if (c == channels::kDriverStatus) decode<driver_status_t>(m.bytes);
      else if (c == channels::kSlamStatus) decode<slam_status_t>(m.bytes);
    }
  }
  state.SetLabel("reference: decode only, map of " + std::to_string(state.range(0)) + " experiences");
}
BENCHMARK(BM_DecodeOnlyFullStackSecond)->Arg(100)->Arg(1000)->Unit(benchmark::kMillisecond);

// Per message, where the second's time goes.
void BM_ViewerApplyPose(benchmark::State& state) {
  ViewerState viewer;
  std::vector<std::vector<uint8_t>> poses;
  for (int i = 0; i < 1000; ++i) poses.push_back(pose(i));
  std::size_t i = 0;
  for (auto _ : state) viewer.apply(channels::kVitaPose, kT0, poses[i++ % poses.size()]);
}
BENCHMARK(BM_ViewerApplyPose);

void BM_ViewerApplyCamera(benchmark::State& state) {
  ViewerState viewer;
  const std::vector<uint8_t> frame = camera(kT0);
  for (auto _ : state) viewer.apply(channels::kCamera, kT0, frame);
  state.SetLabel("640x480 YUYV: decode, check, copy");
}
BENCHMARK(BM_ViewerApplyCamera)->Unit(benchmark::kMicrosecond);

void BM_ViewerCameraJpeg(benchmark::State& state) {
  ViewerState viewer;
  const std::vector<uint8_t> frame = camera(kT0);
  std::size_t bytes = 0;
  for (auto _ : state) {
    viewer.apply(channels::kCamera, kT0, frame);
    bytes = viewer.camera_jpeg()->size();
  }
  state.SetLabel("640x480 YUYV -> 320x240 JPEG of " + std::to_string(bytes / 1024) + " KiB, with the apply");
}
BENCHMARK(BM_ViewerCameraJpeg)->Unit(benchmark::kMicrosecond);

void BM_ViewerApplyMap(benchmark::State& state) {
  ViewerState viewer;
  const std::vector<uint8_t> m = map(static_cast<int>(state.range(0)));
  for (auto _ : state) viewer.apply(channels::kVitaMap, kT0, m);
}
BENCHMARK(BM_ViewerApplyMap)->Arg(100)->Arg(1000)->Unit(benchmark::kMicrosecond);

void BM_ViewerApplyWhiskCycle(benchmark::State& state) {
  ViewerState viewer;
  const std::vector<uint8_t> c = whisk_cycle();
  for (auto _ : state) viewer.apply(channels::kWhiskCycle, kT0, c);
}
BENCHMARK(BM_ViewerApplyWhiskCycle)->Unit(benchmark::kMicrosecond);

void BM_ViewerSnapshot(benchmark::State& state) {
  ViewerState viewer;
  for (const Message& m : one_second(static_cast<int>(state.range(0)))) viewer.apply(m.channel, kT0, m.bytes);
  for (int i = 0; i < 2000; ++i) viewer.apply(channels::kVitaPose, kT0, pose(i));  // a full trail
  std::size_t size = 0;
  for (auto _ : state) size = viewer.snapshot().dump().size();
  state.SetLabel("the whole state as JSON text (a page connecting), " + std::to_string(size / 1024) + " KiB");
}
BENCHMARK(BM_ViewerSnapshot)->Arg(100)->Arg(1000)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
