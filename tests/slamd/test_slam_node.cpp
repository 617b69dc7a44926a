// The slamd node on an in-memory bus: what it publishes per cycle, and how it survives bad input.
#include "whiskeye/slamd/slam_node.h"

#include <whiskeye/driver_status_t.hpp>
#include <whiskeye/slam_status_t.hpp>
#include <whiskeye/template_match_t.hpp>
#include <whiskeye/vita_event_t.hpp>
#include <whiskeye/vita_map_t.hpp>
#include <whiskeye/vita_pose_t.hpp>

#include <gtest/gtest.h>

#include "hostile_jpeg.h"
#include "mjpeg_pattern.h"

#include <functional>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>

// Heap use of this test binary, to prove a bound on what one message may make slamd allocate:
// every operator new records its size in front of the block.
namespace {
std::atomic<int64_t> g_heap_live{0};
std::atomic<int64_t> g_heap_peak{0};
constexpr std::size_t kHeapHeader = alignof(std::max_align_t);
}  // namespace

void* operator new(std::size_t n) {
  auto* p = static_cast<unsigned char*>(std::malloc(n + kHeapHeader));
  if (p == nullptr) throw std::bad_alloc();
  *reinterpret_cast<std::size_t*>(p) = n;
  const int64_t live = g_heap_live.fetch_add(static_cast<int64_t>(n)) + static_cast<int64_t>(n);
  int64_t peak = g_heap_peak.load();
  while (live > peak && !g_heap_peak.compare_exchange_weak(peak, live)) {
  }
  return p + kHeapHeader;
}
void operator delete(void* p) noexcept {
  if (p == nullptr) return;
  auto* block = static_cast<unsigned char*>(p) - kHeapHeader;
  g_heap_live.fetch_sub(static_cast<int64_t>(*reinterpret_cast<std::size_t*>(block)));
  std::free(block);
}
void operator delete(void* p, std::size_t) noexcept { operator delete(p); }

namespace whiskeye::slamd {
namespace {

constexpr int64_t kT0 = 1'700'000'000'000'000;
constexpr int64_t kS = 1'000'000;

// A 640x480 GREY frame of vertical stripes; different periods look like different places.
image_t stripes(int64_t utime, int period) {
  image_t im{};
  im.utime = utime;
  im.width = 640;
  im.height = 480;
  im.row_stride = 640;
  im.pixelformat = image_t::PIXEL_FORMAT_GREY;
  im.size = 640 * 480;
  im.data.resize(static_cast<std::size_t>(im.size));
  for (int y = 0; y < 480; ++y) {
    for (int x = 0; x < 640; ++x) {
      im.data[static_cast<std::size_t>(y * 640 + x)] = static_cast<uint8_t>(((x / period) % 2) ? 220 : 30 + y / 8);
    }
  }
  return im;
}

// A whisk cycle of 1 s at 500 Hz with no contact.
whisk_cycle_t free_cycle(int64_t n, int64_t end, int whiskers = kNumWhiskers) {
  whisk_cycle_t c{};
  c.cycle = n;
  c.utime = end;
  c.utime_start = end - kS + 2000;
  c.utime_end = end;
  c.num_whiskers = whiskers;
  c.num_samples = 500;
  for (int s = 0; s < 500; ++s) {
    c.sample_utime.push_back(c.utime_start + s * 2000);
    c.sample_valid.push_back(1);
    c.phase.push_back(s < 250 ? 0 : 1);
    const float theta = static_cast<float>(0.6 * std::sin(kTwoPi * s / 500.0));
    c.theta.push_back(std::vector<float>(static_cast<std::size_t>(whiskers), theta));
    c.deflection_x.push_back(std::vector<float>(static_cast<std::size_t>(whiskers), 0.0f));
    c.deflection_y.push_back(std::vector<float>(static_cast<std::size_t>(whiskers), 0.0f));
    c.contact.push_back(std::vector<int8_t>(static_cast<std::size_t>(whiskers), 0));
  }
  return c;
}

class SlamNodeTest : public ::testing::Test {
 protected:
  SlamNodeTest() {
    slam::SlamParams p;
    node_ = std::make_unique<SlamNode>(in_, out_, std::make_unique<slam::VitaSlam>(p, default_robot_geometry()),
                                       NodeParams{}, errors_);
    subscribe<vita_event_t>(out_, "VITA_EVENT", [&](const vita_event_t& m) { events_.push_back(m); }, out_errors_);
    subscribe<template_match_t>(out_, "VITA_MATCH", [&](const template_match_t& m) { matches_.push_back(m); },
                                out_errors_);
    subscribe<vita_pose_t>(out_, "VITA_POSE", [&](const vita_pose_t& m) { poses_.push_back(m); }, out_errors_);
    subscribe<vita_map_t>(out_, "VITA_MAP", [&](const vita_map_t& m) { maps_.push_back(m); }, out_errors_);
  }

  // Streams 50 Hz odometry (still robot), 5 Hz frames of `periods[i]` during second i (0: no frame),
  // and a whisk cycle at the end of every second, in time order, from second `first_second` on.
  void stream(const std::vector<int>& periods, int first_second = 0) {
    for (std::size_t i = 0; i < periods.size(); ++i) {
      const auto sec = static_cast<std::size_t>(first_second) + i;
      for (int k = 1; k <= 50; ++k) {
        const int64_t t = kT0 + static_cast<int64_t>(sec) * kS + k * 20'000;
        odometry_t o{};
        o.utime = t;
        publish(in_, "ODOMETRY", o);
        if (periods[i] > 0 && k % 10 == 0) publish_camera(stripes(t, periods[i]));
        if (k == 50) publish(in_, "WHISK_CYCLE", free_cycle(static_cast<int64_t>(sec), t));
      }
    }
  }

  // With share_frames_, as in a replay: the bytes come with an owner, which the node must hold for
  // as long as it keeps the frame (the publisher lets go at once; the owner's deleter overwrites
  // the bytes, so a frame kept without its owner would show a different image).
  void publish_camera(const image_t& im) {
    if (!share_frames_) return publish(in_, "CAMERA", im);
    auto* bytes = new std::vector<uint8_t>(encode_message(im));
    const std::shared_ptr<const std::vector<uint8_t>> owner(bytes, [](const std::vector<uint8_t>* b) {
      std::fill(const_cast<std::vector<uint8_t>*>(b)->begin() + 44, const_cast<std::vector<uint8_t>*>(b)->end(), 0);
      delete b;
    });
    in_.publish_shared("CAMERA", *owner, owner);
  }

  bool share_frames_ = false;
  MemoryBus in_;
  MemoryBus out_;
  DecodeErrors errors_;
  DecodeErrors out_errors_;
  std::unique_ptr<SlamNode> node_;
  std::vector<vita_event_t> events_;
  std::vector<template_match_t> matches_;
  std::vector<vita_pose_t> poses_;
  std::vector<vita_map_t> maps_;
};

TEST_F(SlamNodeTest, PublishesOneEventAndMatchPerCycleAndPosesAfterTheFirst) {
  stream({8, 40, 8, 8});
  node_->flush();
  ASSERT_EQ(events_.size(), 4u);
  ASSERT_EQ(matches_.size(), 4u);
  EXPECT_TRUE(matches_[0].is_new);
  EXPECT_TRUE(matches_[1].is_new) << "a different view is a new template";
  EXPECT_FALSE(matches_[2].is_new) << "the first view again matches its template";
  EXPECT_EQ(matches_[2].template_id, matches_[0].template_id);
  EXPECT_TRUE(matches_[0].visual_used);
  EXPECT_EQ(events_[0].type, vita_event_t::NEW_EXPERIENCE);
  EXPECT_EQ(events_[0].cycle, 0);
  EXPECT_EQ(events_[0].utime, kT0 + kS);
  // Poses only once there is a map frame (after the first cycle), one per odometry sample.
  ASSERT_FALSE(poses_.empty());
  EXPECT_GT(poses_.front().utime, kT0 + kS);
  EXPECT_GE(poses_.front().experience_id, 0);
  ASSERT_FALSE(maps_.empty());
  EXPECT_EQ(maps_.back().num_experiences, static_cast<int32_t>(maps_.back().experiences.size()));
  EXPECT_GE(maps_.back().num_experiences, 2);
  EXPECT_EQ(node_->counters().cycles, 4);
  EXPECT_EQ(node_->counters().cycles_without_contact, 4);
}

TEST_F(SlamNodeTest, KeepsTheOwnerOfSharedCameraFramesInsteadOfCopying) {
  share_frames_ = true;
  stream({8, 40, 8, 8});
  node_->flush();
  ASSERT_EQ(matches_.size(), 4u);
  EXPECT_TRUE(matches_[1].is_new) << "a different view is a new template";
  EXPECT_FALSE(matches_[2].is_new) << "the first view again matches its template";
  EXPECT_EQ(matches_[2].template_id, matches_[0].template_id);
  EXPECT_EQ(matches_[2].visual_error, 0.0);
  EXPECT_EQ(node_->counters().cycles_without_camera, 0);
}

// A replay reads a camera frame's pixels only when a cycle takes the frame, and only the part the
// SLAM reads: the rows down to the crop's bottom in a mode that uses vision, none in tactile mode.
TEST(SlamNodePixels, AReplayIsAskedForTheRowsTheCropReadsAndForNoneInTactileMode) {
  for (const slam::Mode mode : {slam::Mode::Vita, slam::Mode::Visual, slam::Mode::Tactile}) {
    SCOPED_TRACE(static_cast<int>(mode));
    slam::SlamParams p;
    p.mode = mode;
    p.visual.crop_y = 10;
    p.visual.crop_height = 290;
    MemoryBus in, out;
    DecodeErrors errors;
    SlamNode node(in, out, std::make_unique<slam::VitaSlam>(p, default_robot_geometry()), NodeParams{}, errors);
    std::vector<std::size_t> wanted;
    node.set_pixel_reader([&wanted](const std::shared_ptr<const void>& owner, std::span<const uint8_t> part) {
      EXPECT_NE(owner, nullptr);
      wanted.push_back(part.size());
    });
    for (int sec = 0; sec < 3; ++sec) {
      for (int k = 1; k <= 50; ++k) {
        const int64_t t = kT0 + sec * kS + k * 20'000;
        odometry_t o{};
        o.utime = t;
        publish(in, "ODOMETRY", o);
        if (k % 10 == 0) publish(in, "CAMERA", stripes(t, 8 + 16 * sec));
        if (k == 50) publish(in, "WHISK_CYCLE", free_cycle(sec, t));
      }
    }
    node.flush();
    EXPECT_EQ(node.counters().cycles, 3);
    if (mode == slam::Mode::Tactile) {
      EXPECT_TRUE(wanted.empty());
    } else {
      // One frame a cycle; rows 0..299 of 640 bytes, not the frame's 480.
      EXPECT_EQ(wanted, std::vector<std::size_t>(3, 300u * 640u));
      EXPECT_EQ(node.slam().stats().bad_images, 0);
    }
  }
}

TEST_F(SlamNodeTest, AWhiskCycleWhoseCountsDoNotFitItsLengthIsADecodeErrorNotACrash) {
  stream({8});
  node_->flush();
  const std::vector<uint8_t> good = encode_message(free_cycle(7, kT0 + 5 * kS));
  EXPECT_EQ(whisk_cycle_size_error(good), "");
  constexpr std::size_t kNumSamples = 8 + 4 * 8 + 4;
  auto with_samples = [&](uint32_t n) {
    std::vector<uint8_t> b = good;
    for (int i = 0; i < 4; ++i) b[kNumSamples + static_cast<std::size_t>(i)] = static_cast<uint8_t>(n >> (24 - 8 * i));
    return b;
  };
  // -1 made the decoder throw out of the handler (slamd exited); 0x7fffffff made it allocate
  // 16 GB before reading past the message.
  for (uint32_t n : {0xffffffffu, 0x7fffffffu, 499u}) in_.publish_raw("WHISK_CYCLE", with_samples(n));
  in_.publish_raw("WHISK_CYCLE", std::vector<uint8_t>(good.begin(), good.begin() + 30));
  EXPECT_EQ(errors_.total(), 4);
  EXPECT_EQ(errors_.count("WHISK_CYCLE"), 4);
  // Counts whose product wraps modulo 2^64 to the message's length (test_message_layout).
  std::vector<uint8_t> wraps(1024, 0);
  std::copy(good.begin(), good.begin() + 40, wraps.begin());
  auto put_be32 = [&](std::size_t at, uint32_t v) {
    for (int i = 0; i < 4; ++i) wraps[at + static_cast<std::size_t>(i)] = static_cast<uint8_t>(v >> (24 - 8 * i));
  };
  put_be32(40, 1982474090u);  // num_whiskers
  put_be32(44, 2147287049u);  // num_samples
  in_.publish_raw("WHISK_CYCLE", wraps);
  EXPECT_EQ(errors_.count("WHISK_CYCLE"), 5);
  // Still running: the same cycle, intact, is processed.
  const int64_t before = node_->counters().cycles;
  in_.publish_raw("WHISK_CYCLE", good);
  node_->flush();
  EXPECT_EQ(node_->counters().cycles, before + 1);
}

TEST_F(SlamNodeTest, AWhiskCycleOutsideTheContractIsRejectedBeforeTheDecoderAllocatesForIt) {
  // 0 whiskers and 2 M samples: a 20 MB message whose size fits its counts. Decoded, it took a
  // vector per sample and field (11× its size; 20 M samples took 2.3 GB) before validation refused it.
  constexpr int32_t kSamples = 2'000'000;
  whisk_cycle_t c{};
  c.utime = c.utime_start = c.utime_end = kT0;
  c.num_whiskers = 0;
  c.num_samples = 1;
  c.sample_utime = {kT0};
  c.sample_valid = {1};
  c.phase = {0};
  c.theta.resize(1);
  c.deflection_x.resize(1);
  c.deflection_y.resize(1);
  c.contact.resize(1);
  std::vector<uint8_t> bytes = encode_message(c);
  bytes.resize(bytes.size() + 10 * static_cast<std::size_t>(kSamples - 1), 0);
  for (int i = 0; i < 4; ++i) bytes[44 + static_cast<std::size_t>(i)] = static_cast<uint8_t>(kSamples >> (24 - 8 * i));
  ASSERT_EQ(whisk_cycle_size_error(bytes), "");
  EXPECT_EQ(whisk_cycle_contract_error(bytes), "WHISK_CYCLE: num_whiskers 0 (expected 24)");

  g_heap_peak = g_heap_live.load();
  const int64_t before = g_heap_live.load();
  in_.publish_raw("WHISK_CYCLE", bytes);
  const int64_t used = g_heap_peak.load() - before;
  EXPECT_LT(used, static_cast<int64_t>(bytes.size()) / 10) << "bytes allocated for a " << bytes.size() << "-byte message";
  EXPECT_EQ(node_->counters().validation_errors, 1);
  EXPECT_EQ(errors_.total(), 0) << "it decodes: a contract violation, not a decode error";
  // 20,001 samples, the rest as a real cycle: the same.
  whisk_cycle_t many = free_cycle(0, kT0 + kS);
  many.num_samples = 20001;
  for (int s = 500; s < 20001; ++s) {
    many.sample_utime.push_back(many.utime_end);
    many.sample_valid.push_back(1);
    many.phase.push_back(1);
    many.theta.push_back(many.theta.back());
    many.deflection_x.push_back(many.deflection_x.back());
    many.deflection_y.push_back(many.deflection_y.back());
    many.contact.push_back(many.contact.back());
  }
  in_.publish_raw("WHISK_CYCLE", encode_message(many));
  EXPECT_EQ(node_->counters().validation_errors, 2);
  EXPECT_EQ(errors_.total(), 0);
}

TEST_F(SlamNodeTest, AWhiskerNotMeasuredIsNaNAndAcceptedButAHalfNaNWhiskerIsRejected) {
  whisk_cycle_t gap = free_cycle(0, kT0 + kS);
  const float nan = std::nanf("");
  gap.theta[10][3] = gap.deflection_x[10][3] = gap.deflection_y[10][3] = nan;  // its board was stale
  publish(in_, "WHISK_CYCLE", gap);
  whisk_cycle_t broken = free_cycle(1, kT0 + 2 * kS);
  broken.deflection_x[10][3] = nan;  // theta and deflection_y measured: not a missing whisker
  publish(in_, "WHISK_CYCLE", broken);
  node_->flush();
  EXPECT_EQ(node_->counters().validation_errors, 1);
  EXPECT_EQ(node_->counters().cycles, 1);
}

TEST_F(SlamNodeTest, ImplausibleSampleTimesAreRejectedAndNeitherStallNorMovePoses) {
  stream({8, 8});
  node_->flush();
  const std::size_t poses = poses_.size();
  const int64_t errors = node_->counters().validation_errors;
  whisk_cycle_t forever = free_cycle(9, kT0 + 3 * kS);
  forever.utime_end = INT64_MAX;
  publish(in_, "WHISK_CYCLE", forever);
  odometry_t ahead{};
  ahead.utime = kT0 + 3600 * kS;  // one corrupt sample an hour ahead
  publish(in_, "ODOMETRY", ahead);
  odometry_t behind{};
  behind.utime = kT0 + kS;  // already delivered
  publish(in_, "ODOMETRY", behind);
  EXPECT_EQ(node_->counters().validation_errors, errors + 3);
  EXPECT_EQ(poses_.size(), poses) << "no pose published for a dropped sample";
  const slam_status_t st = node_->status(kT0 + 2 * kS);
  EXPECT_EQ(st.time_jumps, 1);
  EXPECT_EQ(st.out_of_order, 1);
  EXPECT_EQ(st.jumps_followed, 0);
  // Nothing of the corrupt times stuck: the inputs that follow, in line, are mapped as before.
  const int64_t cycles = node_->counters().cycles;
  stream({8, 8}, 2);
  node_->flush();
  EXPECT_EQ(node_->counters().validation_errors, errors + 3);
  EXPECT_EQ(node_->counters().cycles, cycles + 2);
  EXPECT_EQ(node_->counters().cycles_without_camera, 0);
  EXPECT_GT(poses_.size(), poses + 90);
}

TEST_F(SlamNodeTest, AClockSteppedBackIsFollowedAndMappingGoesOn) {
  // NTP steps the robot's clock back an hour. Every message used to be dropped as out of order
  // until the clock had caught up: an hour with no event, no pose and no map.
  stream({8, 40, 8, 8, 40}, 3600);
  ASSERT_EQ(events_.size(), 4u) << "the last cycle waits for its next frame";
  const std::size_t maps_before = maps_.size();
  stream({8, 40, 8, 40}, 0);  // an hour earlier
  EXPECT_EQ(events_.size(), 8u) << "the pending cycle was handed out, and the new ones mapped";
  EXPECT_LT(events_.back().utime, kT0 + 3600 * kS);
  EXPECT_LT(poses_.back().utime, kT0 + 3600 * kS) << "poses on the new time line";
  ASSERT_GT(maps_.size(), maps_before);
  EXPECT_LT(maps_.back().utime, kT0 + 3600 * kS) << "the map is not held back by the old time line";
  const slam_status_t st = node_->status(kT0 + 4 * kS);
  EXPECT_EQ(st.jumps_followed, 1);
  EXPECT_EQ(st.out_of_order, 0);
  EXPECT_EQ(st.cycles_without_camera, 0);
  node_->flush();
  EXPECT_EQ(events_.size(), 9u);
  EXPECT_EQ(matches_[5].template_id, matches_[0].template_id) << "the map made before the step is still used";
}

TEST_F(SlamNodeTest, AFullOdometryBufferIsLoggedOncePerStretchWithoutWhiskCycles) {
  MemoryBus in;  // a node with a small buffer of its own: the fixture's node stays subscribed to in_
  NodeParams params;
  params.sync.odometry_buffer = 100;
  SlamNode node(in, out_, std::make_unique<slam::VitaSlam>(slam::SlamParams{}, default_robot_geometry()), params,
                errors_);
  std::vector<std::string> lines;
  node.set_logger([&](const std::string& l) { lines.push_back(l); });
  int64_t t = kT0;
  auto odometry = [&](int n) {
    for (int k = 0; k < n; ++k) {
      odometry_t o{};
      o.utime = t += 20'000;
      publish(in, "ODOMETRY", o);
    }
  };
  odometry(101);  // one sample too many: the oldest goes
  EXPECT_EQ(lines.size(), 1u);
  publish(in, "WHISK_CYCLE", free_cycle(0, t));
  odometry(60);  // the cycle is processed (without a frame) and takes its odometry: nothing more to say
  EXPECT_EQ(node.counters().cycles, 1);
  EXPECT_EQ(lines.size(), 1u);
  const int64_t dropped = node.status(t).odometry_overflow;
  odometry(60);  // a second stretch without whisk cycles overflows again
  EXPECT_GT(node.status(t).odometry_overflow, dropped);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_NE(lines[1].find("no whisk cycle for 100 odometry samples"), std::string::npos) << lines[1];
}

TEST_F(SlamNodeTest, ACameraTooFastForItsBufferWithoutOdometryIsLoggedAndTheCyclesWithoutVisionCounted) {
  // The base is down (no odometry, each cycle waits max_wait_s) and the camera runs at 30 fps for
  // 6 s, a whisk cycle ending every second; a node of its own with `camera_buffer` frames.
  const image_t im = stripes(kT0, 8);
  auto run = [&](int camera_buffer, std::vector<std::string>& lines) {
    MemoryBus in;
    NodeParams params;
    params.sync.camera_buffer = camera_buffer;
    SlamNode node(in, out_, std::make_unique<slam::VitaSlam>(slam::SlamParams{}, default_robot_geometry()),
                  params, errors_);
    int64_t now_us = 0;  // the log clock runs with the data
    node.set_log_clock([&] { return now_us; });
    node.set_logger([&](const std::string& l) { lines.push_back(l); });
    for (int k = 1; k <= 30 * 6; ++k, now_us += 33'333) {
      image_t f = im;
      f.utime = kT0 + k * 33'333;
      publish(in, "CAMERA", f);
      if (k % 30 == 0) publish(in, "WHISK_CYCLE", free_cycle(k / 30, f.utime));
    }
    EXPECT_GE(node.counters().cycles, 4);
    return node.status(kT0 + 6 * kS);
  };
  // 8 frames: the frame at a cycle's end is dropped before the cycle runs. Said, rate-limited.
  std::vector<std::string> lines;
  EXPECT_GE(run(8, lines).cycles_without_camera, 4);
  ASSERT_FALSE(lines.empty());
  EXPECT_NE(lines[0].find("camera_buffer (8 frames) is too small"), std::string::npos) << lines[0];
  EXPECT_LE(lines.size(), 3u) << "rate-limited: ~150 frames were dropped";
  // The default buffer keeps them: every cycle sees, nothing to say.
  std::vector<std::string> none;
  EXPECT_EQ(run(NodeParams{}.sync.camera_buffer, none).cycles_without_camera, 0);
  EXPECT_TRUE(none.empty()) << none.front();
}

TEST_F(SlamNodeTest, AWhiskCycleWithoutAValidSampleIsMappedWithoutTouchAndIsNotAnError) {
  MemoryBus in;  // a tactile-mode node of its own: the fixture's node stays subscribed to in_
  slam::SlamParams p;
  p.mode = slam::Mode::Tactile;
  SlamNode node(in, out_, std::make_unique<slam::VitaSlam>(p, default_robot_geometry()), NodeParams{}, errors_);
  std::vector<std::string> lines;
  node.set_logger([&](const std::string& l) { lines.push_back(l); });
  whisk_cycle_t lost = free_cycle(0, kT0 + kS);
  for (auto& v : lost.sample_valid) v = 0;
  for (auto& row : lost.contact) row.assign(row.size(), 1);  // a lost sample's flags say nothing
  lost.num_missing = lost.num_samples;
  publish(in, "WHISK_CYCLE", lost);
  publish(in, "WHISK_CYCLE", free_cycle(1, kT0 + 2 * kS));
  node.flush();
  EXPECT_EQ(node.counters().cycles, 2);
  EXPECT_EQ(node.counters().validation_errors, 0);
  EXPECT_EQ(node.counters().cycles_without_contact, 2);
  EXPECT_EQ(node.slam().stats().empty_whisk_cycles, 1);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_NE(lines[0].find("whisk cycle 0 has no valid sample: mapped without touch"), std::string::npos) << lines[0];
}

// A frame the core cannot use, whatever is wrong with it (the hostile ones from
// tests/support/hostile_jpeg.h): counted, its reason logged, the cycle mapped without vision.
TEST_F(SlamNodeTest, AFrameTheCoreCannotUseIsCountedAndLoggedAndTheCycleRunsWithoutVision) {
  const std::vector<std::pair<std::vector<uint8_t>, std::string>> frames{
      {std::vector<uint8_t>(500, 0x42), "cycle 0: image: MJPEG frame"},
      {test::camera_frame_hiding_progressive(640, 480, 32000, 32000),
       "cycle 1: image: MJPEG frame is 32000x32000 by its JPEG header, the message says 640x480"},
      {test::progressive_with_repeated_scans(640, 480, 1000), "cycle 2: image: MJPEG frame is a progressive JPEG"},
  };
  std::vector<std::string> lines;
  node_->set_logger([&](const std::string& l) { lines.push_back(l); });
  int64_t now = 0;
  node_->set_log_clock([&] { return now; });
  for (std::size_t i = 0; i < frames.size(); ++i) {
    now += 11 * kS;  // past the log's rate limit: each refusal gets its line
    const int64_t t = kT0 + static_cast<int64_t>(i + 1) * kS;
    image_t frame{};
    frame.utime = t;
    frame.width = 640;
    frame.height = 480;
    frame.pixelformat = image_t::PIXEL_FORMAT_MJPEG;
    frame.data = frames[i].first;
    frame.size = static_cast<int32_t>(frame.data.size());
    publish(in_, "CAMERA", frame);
    publish(in_, "WHISK_CYCLE", free_cycle(static_cast<int64_t>(i), t));
    node_->flush();
    ASSERT_EQ(matches_.size(), i + 1);
    EXPECT_FALSE(matches_[i].visual_used);
    EXPECT_EQ(node_->counters().validation_errors, static_cast<int64_t>(i + 1));
    ASSERT_EQ(lines.size(), i + 1);
    EXPECT_NE(lines[i].find(frames[i].second), std::string::npos) << lines[i];
  }
}

// The core decodes no MJPEG itself: the node gives it slamd's decoder (mjpeg_decode.h).
TEST_F(SlamNodeTest, AnMjpegFrameIsDecodedAtTheEdgeAndUsedForVision) {
  image_t frame{};
  frame.utime = kT0 + kS;
  frame.width = 640;
  frame.height = 480;
  frame.pixelformat = image_t::PIXEL_FORMAT_MJPEG;
  frame.data = test::mjpeg_pattern_jpeg(640, 480, 7);
  frame.size = static_cast<int32_t>(frame.data.size());
  publish(in_, "CAMERA", frame);
  publish(in_, "WHISK_CYCLE", free_cycle(0, kT0 + kS));
  node_->flush();
  ASSERT_EQ(matches_.size(), 1u);
  EXPECT_TRUE(matches_[0].visual_used);
  EXPECT_EQ(node_->counters().validation_errors, 0);
  EXPECT_EQ(node_->slam().stats().bad_images, 0);
}

// Finite but impossible values (found by fuzzing): each rejected with a line naming the field, counted,
// and nothing of it stored; valid input goes on being mapped.
TEST_F(SlamNodeTest, ImpossibleWhiskerAndOdometryValuesAreRejectedNamingTheField) {
  struct Case {
    std::function<void(whisk_cycle_t&, odometry_t&)> change;
    bool odometry;
    std::string says;
  };
  const std::vector<Case> cases{
      // INT64_MIN - 1 overflowed in the contact estimator (UBSan); now it never gets that far.
      {[](whisk_cycle_t& c, odometry_t&) { c.sample_utime[0] = INT64_MIN; }, false, "at sample 0 is outside the cycle"},
      {[](whisk_cycle_t& c, odometry_t&) { c.sample_utime[499] = c.utime_end + 3'600 * kS; }, false,
       "at sample 499 is outside the cycle"},
      {[](whisk_cycle_t& c, odometry_t&) { c.utime_start = c.sample_utime[0] = c.utime_end - 3'600 * kS; }, false,
       "(more than 60 s)"},
      {[](whisk_cycle_t& c, odometry_t&) { c.sample_valid[7] = 127; }, false, "sample_valid 127 at sample 7 (0 or 1)"},
      {[](whisk_cycle_t& c, odometry_t&) { c.num_missing = -5; }, false, "num_missing -5 but 0 samples are marked lost"},
      {[](whisk_cycle_t& c, odometry_t&) { c.theta[3][2] = 3e38f; }, false, "at sample 3, whisker 2 (beyond ±pi)"},
      {[](whisk_cycle_t& c, odometry_t&) { c.deflection_x[4][5] = 1e30f; }, false,
       "at sample 4, whisker 5 (calibrated -1..1)"},
      {[](whisk_cycle_t&, odometry_t& o) { o.x = 1e300; }, true, "is beyond 100 km"},
      {[](whisk_cycle_t&, odometry_t& o) { o.theta = 10.0; }, true, "theta 10.000000 rad is not in (-pi, pi]"},
  };
  const auto bad_message = [](const Case& c, MemoryBus& bus) {
    whisk_cycle_t cycle = free_cycle(1, kT0 + 2 * kS);
    odometry_t odo{};
    odo.utime = kT0 + kS + 30'000;
    c.change(cycle, odo);
    if (c.odometry) {
      publish(bus, "ODOMETRY", odo);
    } else {
      publish(bus, "WHISK_CYCLE", cycle);
    }
  };
  // Each on a node of its own: the log names what was wrong (a node logs the first of a burst).
  for (const Case& c : cases) {
    MemoryBus in, out;
    DecodeErrors errors;
    SlamNode node(in, out, std::make_unique<slam::VitaSlam>(slam::SlamParams{}, default_robot_geometry()),
                  NodeParams{}, errors);
    std::vector<std::string> lines;
    node.set_logger([&](const std::string& l) { lines.push_back(l); });
    bad_message(c, in);
    EXPECT_EQ(node.counters().validation_errors, 1) << c.says;
    ASSERT_EQ(lines.size(), 1u) << c.says;
    EXPECT_NE(lines[0].find(c.says), std::string::npos) << lines[0];
  }
  // All of them amid valid input: counted, nothing stored, and mapping goes on.
  stream({8});
  node_->flush();
  const int64_t cycles = node_->counters().cycles;
  const int32_t templates = node_->status(kT0 + kS).num_templates;
  for (const Case& c : cases) bad_message(c, in_);
  EXPECT_EQ(node_->counters().validation_errors, static_cast<int64_t>(cases.size()));
  stream({8, 8}, 1);
  node_->flush();
  EXPECT_EQ(node_->counters().cycles, cycles + 2) << "valid cycles are mapped as before";
  EXPECT_LE(node_->status(kT0 + 3 * kS).num_templates, templates + 2) << "nothing of the rejected cycles was stored";
}

TEST_F(SlamNodeTest, RejectsBadMessagesCountsThemAndCarriesOn) {
  stream({8});
  // Undecodable bytes, then decodable but inconsistent messages.
  const std::vector<uint8_t> garbage{0xde, 0xad, 0xbe, 0xef};
  in_.publish_raw("WHISK_CYCLE", garbage);
  publish(in_, "WHISK_CYCLE", free_cycle(7, kT0 + 5 * kS, /*whiskers=*/23));
  odometry_t nan_odo{};
  nan_odo.utime = kT0 + kS + 30'000;
  nan_odo.vx = std::nan("");
  publish(in_, "ODOMETRY", nan_odo);
  image_t short_frame = stripes(kT0 + kS + 40'000, 8);
  short_frame.data.resize(1000);
  short_frame.size = 1000;
  publish(in_, "CAMERA", short_frame);
  image_t odd_format = stripes(kT0 + kS + 50'000, 8);
  odd_format.pixelformat = 0x12345678;
  publish(in_, "CAMERA", odd_format);

  EXPECT_EQ(errors_.total(), 1);
  EXPECT_EQ(node_->counters().validation_errors, 4);
  const slam_status_t st = node_->status(kT0);
  EXPECT_EQ(st.decode_errors, 1);
  EXPECT_EQ(st.validation_errors, 4);
  EXPECT_EQ(st.state, driver_status_t::STATE_DEGRADED);

  // Still running: later valid input is processed normally.
  const std::size_t before = events_.size();
  for (int k = 1; k <= 50; ++k) {
    const int64_t t = kT0 + kS + k * 20'000 + 40'000;
    odometry_t o{};
    o.utime = t;
    publish(in_, "ODOMETRY", o);
    if (k % 10 == 0) publish(in_, "CAMERA", stripes(t, 8));
  }
  publish(in_, "WHISK_CYCLE", free_cycle(1, kT0 + 2 * kS));
  node_->flush();
  EXPECT_EQ(events_.size(), before + 1 + 1) << "the first cycle (pending) and the new one";
  // Degraded while it happens, not forever: 10 s without a new rejection is OK again.
  EXPECT_EQ(node_->status(kT0 + 5 * kS).state, driver_status_t::STATE_DEGRADED);
  const slam_status_t later = node_->status(kT0 + 11 * kS);
  EXPECT_EQ(later.state, driver_status_t::STATE_OK) << later.message;
  EXPECT_EQ(later.validation_errors, 4) << "the counters stay";
}

// 2,000 undecodable messages gave 2,000 stderr lines in 2 s: the journal on an eMMC is not free.
TEST_F(SlamNodeTest, RepeatedWarningsAreRateLimitedWithACountOfWhatWasSuppressed) {
  std::vector<std::string> lines;
  int64_t now = 0;
  node_->set_logger([&](const std::string& l) { lines.push_back(l); });
  node_->set_log_clock([&] { return now; });
  const std::vector<uint8_t> garbage{0xde, 0xad, 0xbe, 0xef};
  for (int i = 0; i < 2000; ++i, now += 1000) in_.publish_raw("WHISK_CYCLE", garbage);
  EXPECT_EQ(errors_.total(), 2000) << "every one counted";
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_NE(lines[0].find("WHISK_CYCLE: cannot decode 4 bytes"), std::string::npos) << lines[0];
  now += 10 * kS;
  in_.publish_raw("WHISK_CYCLE", garbage);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_NE(lines[1].find("; 1999 more like it suppressed in the last 12 s"), std::string::npos) << lines[1];

  // Rejected messages likewise: the first of a burst, then one per 10 s (it was every 100th).
  lines.clear();
  odometry_t nan_odo{};
  nan_odo.utime = kT0;
  nan_odo.vx = std::nan("");
  for (int i = 0; i < 2000; ++i, now += 1000) publish(in_, "ODOMETRY", nan_odo);
  EXPECT_EQ(node_->counters().validation_errors, 2000);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_NE(lines[0].find("rejected ODOMETRY: non-finite value"), std::string::npos) << lines[0];
  now += 10 * kS;
  publish(in_, "ODOMETRY", nan_odo);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_NE(lines[1].find("(2001 rejected so far); 1999 more like it suppressed"), std::string::npos) << lines[1];
}

// Messages lost before slamd took them (LCM's subscription queue, a fragment lost on the wire, a
// recording's gap) show only in the inputs' sequence numbers: counted in input_gaps and logged,
// rate-limited. A number that goes back is a sender restarting, not a loss; a rejected message
// arrived: a bad value at its place in the sequence is no gap (once counted as one, "lost on the
// way", beside its validation error), and a stale copy changes nothing.
TEST_F(SlamNodeTest, MessagesMissingByTheirSequenceNumbersAreCountedAndLoggedButARestartIsNot) {
  std::vector<std::string> lines;
  int64_t now = 0;
  node_->set_logger([&](const std::string& l) { lines.push_back(l); });
  node_->set_log_clock([&] { return now; });
  int64_t odo_seq = 0, frame_seq = 0;
  // Seconds 0..5; in second 2 odometry samples 5..7 and one frame never come, and WHISK_CYCLE 3 is
  // lost; in second 4 the base restarts its numbering (back to 0).
  for (int sec = 0; sec < 6; ++sec) {
    for (int k = 1; k <= 50; ++k) {
      const int64_t t = kT0 + sec * kS + k * 20'000;
      if (sec == 4 && k == 1) odo_seq = 0;
      const int64_t seq = odo_seq++;
      if (!(sec == 2 && k >= 5 && k <= 7)) {
        odometry_t o{};
        o.utime = t;
        o.seq = seq;
        if (sec == 5 && k == 10) o.vx = std::numeric_limits<double>::quiet_NaN();  // refused: no gap
        publish(in_, "ODOMETRY", o);
      }
      if (k % 10 == 0) {
        const int64_t fs = frame_seq++;
        image_t im = stripes(t, 8);
        im.seq = fs;
        if (!(sec == 2 && k == 20)) publish_camera(im);
      }
      if (k == 50 && sec != 3) publish(in_, "WHISK_CYCLE", free_cycle(sec, t));
    }
    if (sec == 1) {  // a stale copy of an earlier sample: rejected (out of order), not a restart or a gap
      odometry_t stale{};
      stale.utime = kT0 + 10'000;
      stale.seq = 0;
      publish(in_, "ODOMETRY", stale);
    }
  }
  node_->flush();
  EXPECT_EQ(node_->counters().validation_errors, 1 + 1) << "the stale copy and the NaN";
  EXPECT_EQ(node_->counters().input_gaps, 3 + 1 + 1);
  EXPECT_EQ(node_->status(kT0 + 6 * kS).input_gaps, 5);
  std::string all;
  for (const std::string& l : lines) all += l + "\n";
  EXPECT_NE(all.find("ODOMETRY: samples missing by the sequence numbers: 3 before 107"), std::string::npos) << all;
  EXPECT_NE(all.find("CAMERA: frames missing by the sequence numbers: 1 before 12"), std::string::npos) << all;
  EXPECT_NE(all.find("WHISK_CYCLE: cycles missing by the sequence numbers: 1 before 4"), std::string::npos) << all;
  EXPECT_EQ(all.find("before 0 "), std::string::npos) << "a restart is no loss: " << all;

  // Rate-limited: a gap at every message gives one line per 10 s.
  lines.clear();
  now += 20 * kS;
  for (int i = 0; i < 100; ++i, now += 1000) {
    odometry_t o{};
    o.utime = kT0 + 6 * kS + (i + 1) * 20'000;
    o.seq = 1000 + 2 * i;
    publish(in_, "ODOMETRY", o);
  }
  EXPECT_EQ(node_->counters().input_gaps, 5 + 1000 - 100 + 99);
  EXPECT_EQ(lines.size(), 1u);
}

TEST_F(SlamNodeTest, MissingCameraDegradesToTouchAndIsCounted) {
  stream({0, 0, 0});
  node_->flush();
  ASSERT_EQ(matches_.size(), 3u);
  for (const auto& m : matches_) EXPECT_FALSE(m.visual_used);
  EXPECT_EQ(node_->counters().cycles_without_camera, 3);
  const slam_status_t st = node_->status(kT0);
  EXPECT_EQ(st.cycles_without_camera, 3);
  EXPECT_EQ(st.state, driver_status_t::STATE_DEGRADED) << "a camera that is gone is worth a look";
  EXPECT_NE(st.message.find("without a camera frame"), std::string::npos) << st.message;
}

TEST_F(SlamNodeTest, TheDegradedWindowRunsOnItsOwnClockNotOnTheStamp) {
  stream({0});
  node_->flush();
  // Live the window clock is monotonic: a wall clock stepped an hour ahead does not end it early,
  // nor does one stepped back stretch it.
  constexpr int64_t kMono = 5'000'000;
  EXPECT_EQ(node_->status(kT0, kMono).state, driver_status_t::STATE_DEGRADED);
  EXPECT_EQ(node_->status(kT0 + 3600 * kS, kMono + kS).state, driver_status_t::STATE_DEGRADED);
  EXPECT_EQ(node_->status(kT0 - 3600 * kS, kMono + 11 * kS).state, driver_status_t::STATE_OK);
}

TEST_F(SlamNodeTest, StatusReportsMapSizeAndOkState) {
  stream({8, 40});
  node_->flush();
  const slam_status_t st = node_->status(kT0 + 10 * kS);
  EXPECT_EQ(st.cycles, 2);
  EXPECT_EQ(st.num_templates, 2);
  EXPECT_EQ(st.num_experiences, 2);
  EXPECT_EQ(st.state, driver_status_t::STATE_OK);
  EXPECT_EQ(st.mode, vita_pose_t::MODE_VITA);
}

}  // namespace
}  // namespace whiskeye::slamd
