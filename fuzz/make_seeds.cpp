// Makes the seed corpora of the fuzz targets from real simulator output, shortened so the committed
// corpora stay small (KBs): scripts/fuzz --make-seeds runs it on a 3 s vita-sim log and its candump.
//   fuzz_make_seeds SIM.lcmlog SIM.candump OUT_DIR
// Writes OUT_DIR/{slamd_edge,lcm_log,checkpoint,odometry_reply,whisker_frame,mjpeg_frame}/seed-*. The
// YAML corpora (params, world) are the files of config/, copied by scripts/fuzz.
#include "whiskeye/slamd/checkpoint_store.h"
#include "whiskeye/slamd/slam_node.h"

#include "whiskeye/common/bus.h"
#include "whiskeye/common/log_reader.h"
#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/slam/vita_slam.h"

#include <whiskeye/image_t.hpp>
#include <whiskeye/odometry_t.hpp>
#include <whiskeye/whisk_cycle_t.hpp>

#include "hostile_jpeg.h"
#include "mjpeg_pattern.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

using namespace whiskeye;
namespace fs = std::filesystem;

namespace {

void write_file(const fs::path& path, const std::vector<uint8_t>& bytes) {
  fs::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

// The first `n` samples of a whisk cycle, as a cycle of its own.
whisk_cycle_t shorten(whisk_cycle_t c, int n) {
  n = std::min(n, c.num_samples);
  c.num_samples = n;
  c.sample_utime.resize(static_cast<std::size_t>(n));
  c.sample_valid.resize(static_cast<std::size_t>(n));
  c.phase.resize(static_cast<std::size_t>(n));
  c.theta.resize(static_cast<std::size_t>(n));
  c.deflection_x.resize(static_cast<std::size_t>(n));
  c.deflection_y.resize(static_cast<std::size_t>(n));
  c.contact.resize(static_cast<std::size_t>(n));
  c.utime_end = c.utime = c.sample_utime.back();
  c.num_missing = 0;
  for (int8_t v : c.sample_valid) c.num_missing += v ? 0 : 1;
  return c;
}

// A w×h crop of the frame's top-left corner, in its own format (YUYV, GREY or RGB).
image_t crop(const image_t& im, int w, int h) {
  const int bpp = im.row_stride / im.width;
  image_t out = im;
  out.width = w;
  out.height = h;
  out.row_stride = w * bpp;
  out.data.clear();
  for (int y = 0; y < h; ++y) {
    const auto* row = im.data.data() + static_cast<std::ptrdiff_t>(y) * im.row_stride;
    out.data.insert(out.data.end(), row, row + w * bpp);
  }
  out.size = static_cast<int32_t>(out.data.size());
  return out;
}

image_t to_mjpeg(const image_t& yuyv) {
  cv::Mat src(yuyv.height, yuyv.width, CV_8UC2, const_cast<uint8_t*>(yuyv.data.data()), static_cast<std::size_t>(yuyv.row_stride));
  cv::Mat bgr;
  cv::cvtColor(src, bgr, cv::COLOR_YUV2BGR_YUYV);
  image_t out = yuyv;
  out.pixelformat = image_t::PIXEL_FORMAT_MJPEG;
  out.row_stride = 0;
  cv::imencode(".jpg", bgr, out.data, {cv::IMWRITE_JPEG_QUALITY, 50});
  out.size = static_cast<int32_t>(out.data.size());
  return out;
}

// Records of the slamd_edge input: [channel 0/1/2][length, 2 bytes big-endian][message].
void add_record(std::vector<uint8_t>& out, int channel, const std::vector<uint8_t>& msg) {
  if (msg.size() > 0xFFFF) throw std::runtime_error("seed message too large for a record");
  out.push_back(static_cast<uint8_t>(channel));
  out.push_back(static_cast<uint8_t>(msg.size() >> 8));
  out.push_back(static_cast<uint8_t>(msg.size() & 0xFF));
  out.insert(out.end(), msg.begin(), msg.end());
}

void add_log_event(std::vector<uint8_t>& out, int64_t n, int64_t utime, const std::string& channel,
                   const std::vector<uint8_t>& data) {
  const auto be = [&](uint64_t v, int bytes) {
    for (int i = bytes - 1; i >= 0; --i) out.push_back(static_cast<uint8_t>(v >> (8 * i)));
  };
  be(lcm_log::kSyncWord, 4);
  be(static_cast<uint64_t>(n), 8);
  be(static_cast<uint64_t>(utime), 8);
  be(channel.size(), 4);
  be(data.size(), 4);
  out.insert(out.end(), channel.begin(), channel.end());
  out.insert(out.end(), data.begin(), data.end());
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: fuzz_make_seeds SIM.lcmlog SIM.candump OUT_DIR\n");
    return 2;
  }
  const fs::path out_dir = argv[3];
  std::vector<whisk_cycle_t> cycles;
  std::vector<image_t> frames;
  std::vector<odometry_t> odometry;
  std::vector<LogEvent> small_events;  // the first events of the small channels, as logged
  {
    LogReader reader(argv[1]);
    LogEvent ev;
    while (reader.next(ev)) {
      if (ev.channel == "WHISK_CYCLE") {
        whisk_cycle_t c;
        if (decode_message(ev.data, c)) cycles.push_back(c);
      } else if (ev.channel == "CAMERA") {
        image_t im;
        if (decode_message(ev.data, im) && frames.size() < 4) frames.push_back(im);
      } else if (ev.channel == "ODOMETRY") {
        odometry_t o;
        if (decode_message(ev.data, o)) odometry.push_back(o);
      }
      if (ev.data.size() < 600 && small_events.size() < 24) small_events.push_back(ev);
    }
  }
  if (cycles.empty() || frames.empty() || odometry.empty()) {
    std::fprintf(stderr, "fuzz_make_seeds: %s lacks WHISK_CYCLE, CAMERA or ODOMETRY\n", argv[1]);
    return 1;
  }

  // slamd_edge: odometry, a shortened whisk cycle, and a cropped frame (raw, then MJPEG) at its end.
  const whisk_cycle_t cycle = shorten(cycles.front(), 12);
  image_t frame = crop(frames.front(), 48, 32);
  frame.utime = cycle.utime_end;
  const image_t jpeg = to_mjpeg(frame);
  int seed = 0;
  for (const image_t* im : {static_cast<const image_t*>(&frame), &jpeg}) {
    std::vector<uint8_t> input;
    for (const auto& o : odometry) {
      if (o.utime > cycle.utime_start - 200'000 && o.utime <= cycle.utime_end + 200'000) add_record(input, 2, encode_message(o));
    }
    add_record(input, 0, encode_message(cycle));
    add_record(input, 1, encode_message(*im));
    write_file(out_dir / "slamd_edge" / ("seed-" + std::to_string(seed++)), input);
  }
  {
    std::vector<uint8_t> input;
    for (std::size_t i = 0; i < std::min<std::size_t>(odometry.size(), 3); ++i) add_record(input, 2, encode_message(odometry[i]));
    write_file(out_dir / "slamd_edge" / ("seed-" + std::to_string(seed++)), input);
  }

  // lcm_log: the first small events, then the shortened cycle and frame, as lcm-logger writes them.
  {
    std::vector<uint8_t> log;
    int64_t n = 0;
    for (const auto& ev : small_events) add_log_event(log, n++, ev.utime, ev.channel, ev.data);
    add_log_event(log, n++, cycle.utime_end, "WHISK_CYCLE", encode_message(cycle));
    add_log_event(log, n++, frame.utime, "CAMERA", encode_message(jpeg));
    write_file(out_dir / "lcm_log" / "seed-0", log);
    // The same with 8 kB of repeated sync words after the first event: garbage every 4 bytes of which
    // is a candidate to resynchronise on (skipping it must stay linear).
    std::vector<uint8_t> garbage;
    add_log_event(garbage, 0, small_events.front().utime, small_events.front().channel, small_events.front().data);
    const std::size_t first = garbage.size();
    constexpr uint32_t sync = lcm_log::kSyncWord;
    for (int i = 0; i < 2048; ++i) {
      garbage.insert(garbage.end(), {static_cast<uint8_t>(sync >> 24), static_cast<uint8_t>(sync >> 16),
                                     static_cast<uint8_t>(sync >> 8), static_cast<uint8_t>(sync)});
    }
    garbage.insert(garbage.end(), log.begin() + static_cast<std::ptrdiff_t>(first), log.end());
    write_file(out_dir / "lcm_log" / "seed-sync-garbage", garbage);
  }

  // checkpoint: the state after the shortened cycle in each mode, unsealed (selector odd: bits 1-2
  // the mode), and one whole file (selector even).
  {
    const RobotGeometry robot = default_robot_geometry();
    const slam::Mode modes[3] = {slam::Mode::Visual, slam::Mode::Tactile, slam::Mode::Vita};
    for (int m = 0; m < 3; ++m) {
      slam::SlamParams params;
      params.mode = modes[m];
      MemoryBus in, out;
      DecodeErrors errors;
      slamd::SlamNode node(in, out, std::make_unique<slam::VitaSlam>(params, robot), slamd::NodeParams{}, errors);
      for (const auto& o : odometry) {
        if (o.utime <= cycle.utime_end + 200'000) publish(in, "ODOMETRY", o);
      }
      publish(in, "WHISK_CYCLE", cycle);
      publish(in, "CAMERA", frame);
      node.flush();
      std::vector<uint8_t> state = node.slam().serialise_unsealed();
      // Two seeds of 67 kB (mostly the pose cells): the tactile state unsealed, the ViTa one as a file.
      if (m == 1) {
        std::vector<uint8_t> input{static_cast<uint8_t>(1 | (m << 1))};
        input.insert(input.end(), state.begin(), state.end());
        write_file(out_dir / "checkpoint" / "seed-state", input);
      }
      if (m == 2) {
        slam::VitaSlam::seal(state);
        std::vector<uint8_t> file{0};
        const auto header = slamd::checkpoint_header(node.slam().stats().cycles, state);
        file.insert(file.end(), header.begin(), header.end());
        file.insert(file.end(), state.begin(), state.end());
        write_file(out_dir / "checkpoint" / "seed-file", file);
      }
    }
  }

  // odometry_reply: the simulator's odometry as the Robotino's REST server would send it.
  for (std::size_t i = 0; i < std::min<std::size_t>(odometry.size(), 3); ++i) {
    const odometry_t& o = odometry[i * 20 % odometry.size()];
    std::ostringstream body;
    body.precision(17);
    body << "[" << o.x << ", " << o.y << ", " << o.theta << ", " << o.vx << ", " << o.vy << ", " << o.omega << ", "
         << o.seq << "]";
    const std::string s = body.str();
    write_file(out_dir / "odometry_reply" / ("seed-" + std::to_string(i)), std::vector<uint8_t>(s.begin(), s.end()));
  }

  // whisker_frame: frames of the candump log, one per kind of id (samples of each board, heartbeats,
  // commands), as [id, 2 bytes][flags][data].
  {
    std::ifstream in(argv[2]);
    std::string line;
    std::vector<std::pair<uint32_t, bool>> seen;  // (id, fd)
    while (std::getline(in, line) && seen.size() < 24) {
      // "(time) can0 ID#DATA" (classic) or "(time) can0 ID##FDATA" (FD, F = flags nibble).
      std::istringstream ls(line);
      std::string ts, iface, frame_text;
      ls >> ts >> iface >> frame_text;
      const auto hash = frame_text.find('#');
      if (hash == std::string::npos) continue;
      const uint32_t id = static_cast<uint32_t>(std::stoul(frame_text.substr(0, hash), nullptr, 16));
      const bool fd = frame_text.compare(hash, 2, "##") == 0;
      if (std::find(seen.begin(), seen.end(), std::pair{id, fd}) != seen.end()) continue;
      seen.emplace_back(id, fd);
      std::string hex = frame_text.substr(hash + (fd ? 3 : 1));
      std::vector<uint8_t> input{static_cast<uint8_t>(id >> 8), static_cast<uint8_t>(id & 0xFF),
                                 static_cast<uint8_t>(fd ? 1 : 2)};
      for (std::size_t i = 0; i + 1 < hex.size(); i += 2) input.push_back(static_cast<uint8_t>(std::stoul(hex.substr(i, 2), nullptr, 16)));
      write_file(out_dir / "whisker_frame" / ("seed-" + std::to_string(seen.size() - 1)), input);
    }
  }
  // mjpeg_frame: [width, height: 2 bytes each, big-endian][JPEG]: the cropped frame as MJPEG, a 64x48
  // frame as a camera encodes it, and the probes of docs/reliability.md at that size (the hidden
  // 32000 x 32000 header, repeated AC scans, a scan per component, arithmetic coding, the costliest
  // baseline frame).
  {
    const auto mjpeg_seed = [&](const std::string& name, int w, int h, const std::vector<uint8_t>& jpeg) {
      std::vector<uint8_t> input{static_cast<uint8_t>(w >> 8), static_cast<uint8_t>(w), static_cast<uint8_t>(h >> 8),
                                 static_cast<uint8_t>(h)};
      input.insert(input.end(), jpeg.begin(), jpeg.end());
      write_file(out_dir / "mjpeg_frame" / ("seed-" + name), input);
    };
    const std::vector<uint8_t> pattern = test::mjpeg_pattern(64, 48, 5);
    mjpeg_seed("simulated", jpeg.width, jpeg.height, jpeg.data);
    mjpeg_seed("camera", 64, 48, test::mjpeg_pattern_jpeg(64, 48, 5));
    mjpeg_seed("hidden-header", 64, 48, test::camera_frame_hiding_progressive(64, 48, 32000, 32000));
    mjpeg_seed("repeated-scans", 64, 48, test::progressive_with_repeated_scans(64, 48, 100));
    mjpeg_seed("scan-per-component", 64, 48, test::encode_jpeg_scans(pattern, 64, 48, 64, test::ScanLayout::kScanPerComponent));
    mjpeg_seed("arithmetic", 64, 48, test::encode_jpeg_scans(pattern, 64, 48, 64, test::ScanLayout::kArithmetic));
    mjpeg_seed("costliest", 32, 16, test::costliest_baseline_jpeg(32, 16, 1));
  }
  std::printf("fuzz_make_seeds: seeds written under %s\n", out_dir.c_str());
  return 0;
}
