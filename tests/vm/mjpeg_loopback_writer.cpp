// VM test program: the "camera" of the MJPEG scenario (scenario_camerad_mjpeg.sh). Writes known MJPEG
// frames (tests/support/mjpeg_pattern.h: frame n carries its number n in its pixels) into a
// v4l2loopback device, which hands them to camerad as a capture device would, and damages frames on
// command. Commands, one a line on standard input (the scenario writes them into a FIFO):
//   cut N       the next N frames are cut short (their first half, no end-of-image marker)
//   garbage N   the next N frames are their header followed by bytes that are no JPEG data, and an
//               end-of-image marker
//   pause       stop writing (the device stays open: a camera that goes silent)
//   resume      write again
//   quit        close the device and exit (also at the end of the input)
// Every frame written, damaged or not, takes the next number. One line on stdout per command and a
// summary at the end. --pause-after N pauses by itself once N frames are written ("paused after N
// frames"), as if told "pause": a reader then opens a ring that holds no frame written since.
//   mjpeg_loopback_writer --device /dev/video10 [--width 640 --height 480 --fps 10 --first-number N]
//                         [--pause-after N]
#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "mjpeg_pattern.h"

namespace {

using Clock = std::chrono::steady_clock;

[[noreturn]] void die(const std::string& what) {
  std::cerr << "mjpeg_loopback_writer: " << what << ": " << std::strerror(errno) << std::endl;
  std::exit(1);
}

// The header of `jpeg` up to its first scan's data, then `bytes` of what no JPEG holds there
// (random bytes, fixed seed), then an end-of-image marker.
std::vector<uint8_t> garbage_after_header(const std::vector<uint8_t>& jpeg, std::size_t bytes, uint32_t seed) {
  std::size_t pos = 2;
  while (jpeg[pos + 1] != 0xda) pos += 2 + ((jpeg[pos + 2] << 8) | jpeg[pos + 3]);
  pos += 2 + ((jpeg[pos + 2] << 8) | jpeg[pos + 3]);
  std::vector<uint8_t> out(jpeg.begin(), jpeg.begin() + static_cast<std::ptrdiff_t>(pos));
  std::mt19937 rng(seed);
  for (std::size_t i = 0; i < bytes; ++i) out.push_back(static_cast<uint8_t>(rng()));
  out.push_back(0xff);
  out.push_back(0xd9);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"mjpeg_loopback_writer: known MJPEG frames into a v4l2loopback device"};
  std::string device;
  int width = 640, height = 480;
  double fps = 10;
  uint32_t number = 0;
  long pause_after = -1;
  app.add_option("--device", device)->required();
  app.add_option("--first-number", number, "of the first frame (a writer started again goes on counting)");
  app.add_option("--width", width);
  app.add_option("--height", height);
  app.add_option("--fps", fps);
  app.add_option("--pause-after", pause_after, "frames written before pausing by itself");
  CLI11_PARSE(app, argc, argv);

  const int fd = ::open(device.c_str(), O_RDWR);
  if (fd < 0) die("open " + device);
  v4l2_format fmt{};
  fmt.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
  fmt.fmt.pix.width = static_cast<uint32_t>(width);
  fmt.fmt.pix.height = static_cast<uint32_t>(height);
  fmt.fmt.pix.pixelformat = V4L2_PIX_FMT_MJPEG;
  fmt.fmt.pix.field = V4L2_FIELD_NONE;
  if (::ioctl(fd, VIDIOC_S_FMT, &fmt) < 0) die("VIDIOC_S_FMT (output, MJPG)");
  if (fmt.fmt.pix.pixelformat != V4L2_PIX_FMT_MJPEG || fmt.fmt.pix.width != static_cast<uint32_t>(width)) {
    errno = EINVAL;
    die("the device keeps another format (" + std::to_string(fmt.fmt.pix.width) + "x" +
        std::to_string(fmt.fmt.pix.height) + ")");
  }
  std::cout << "writing " << width << "x" << height << " MJPG at " << fps << " fps to " << device << std::endl;

  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / fps));
  auto next = Clock::now();
  const uint32_t first_number = number;
  int cut = 0, garbage = 0;
  bool paused = false;
  long written_good = 0, written_cut = 0, written_garbage = 0;
  std::string pending;
  while (true) {
    // Commands until the next frame is due.
    const auto wait = std::chrono::duration_cast<std::chrono::milliseconds>(next - Clock::now()).count();
    pollfd p{0, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(std::max<long>(0, wait))) > 0) {
      char buf[256];
      const ssize_t n = ::read(0, buf, sizeof(buf));
      if (n <= 0) break;  // end of the input: quit
      pending.append(buf, static_cast<std::size_t>(n));
      std::size_t eol;
      bool quit = false;
      while ((eol = pending.find('\n')) != std::string::npos) {
        std::istringstream line(pending.substr(0, eol));
        pending.erase(0, eol + 1);
        std::string command;
        int count = 0;
        line >> command >> count;
        if (command == "cut") cut += count;
        else if (command == "garbage") garbage += count;
        else if (command == "pause") paused = true;
        else if (command == "resume") paused = false;
        else if (command == "quit") quit = true;
        else std::cout << "unknown command '" << command << "'" << std::endl;
        std::cout << "command " << command << (count ? " " + std::to_string(count) : "") << " at frame " << number
                  << std::endl;
      }
      if (quit) break;
      continue;
    }
    next += period;
    if (Clock::now() > next + 10 * period) next = Clock::now() + period;  // a stalled guest: no burst
    if (paused) continue;
    const std::vector<uint8_t> jpeg = whiskeye::test::mjpeg_pattern_jpeg(width, height, number & 0xffff);
    std::vector<uint8_t> frame;
    if (cut > 0) {
      frame.assign(jpeg.begin(), jpeg.begin() + static_cast<std::ptrdiff_t>(jpeg.size() / 2));
      --cut;
      ++written_cut;
    } else if (garbage > 0) {
      frame = garbage_after_header(jpeg, jpeg.size() / 2, number);
      --garbage;
      ++written_garbage;
    } else {
      frame = jpeg;
      ++written_good;
    }
    // v4l2loopback takes one write() as one frame.
    if (::write(fd, frame.data(), frame.size()) != static_cast<ssize_t>(frame.size())) die("write");
    ++number;
    if (number - first_number == pause_after) {
      paused = true;
      std::cout << "paused after " << pause_after << " frames" << std::endl;
    }
  }
  ::close(fd);
  std::cout << "wrote " << number - first_number << " frames: good=" << written_good << " cut=" << written_cut
            << " garbage=" << written_garbage << std::endl;
  return 0;
}
