// SimSink → LCM messages (see lcm_sink.h).
#include "whiskeye/sim/lcm_sink.h"

#include "whiskeye/common/channels.h"

#include <whiskeye/contact_truth_t.hpp>
#include <whiskeye/odometry_t.hpp>
#include <whiskeye/pose2d_t.hpp>

#include <turbojpeg.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace whiskeye::sim {

namespace {

int16_t to_counts(double v, double scale) {
  return static_cast<int16_t>(std::clamp(std::lround(v * scale), -32768L, 32767L));
}

}  // namespace

whisker_sample_t to_lcm(const rcp::WhiskerSample& s, const WhiskerHealth& health, double saturation) {
  rcp::PerWhisker<int16_t> raw_x, raw_y, raw_theta;
  rcp::PerWhisker<int8_t> status;
  for (int w = 0; w < rcp::kNumWhiskers; ++w) {
    raw_x[w] = to_counts(s.deflection_x[w], kRawHallPerUnit);
    raw_y[w] = to_counts(s.deflection_y[w], kRawHallPerUnit);
    raw_theta[w] = to_counts(s.theta[w], kRawThetaPerRad);
    status[w] = whisker_sample_t::STATUS_OK;
    if (std::max(std::abs(s.deflection_x[w]), std::abs(s.deflection_y[w])) >= saturation) {
      status[w] |= whisker_sample_t::STATUS_SATURATED;
    }
    if (health.stale[w]) status[w] |= whisker_sample_t::STATUS_STALE;
    if (health.fault[w] || (!s.valid[w] && !health.stale[w])) status[w] |= whisker_sample_t::STATUS_FAULT;
  }
  whisker_sample_t m;
  rcp::fill_whisker_sample(s.utime, s.seq, s.theta, s.deflection_x, s.deflection_y, raw_x, raw_y, raw_theta, status, m);
  return m;
}

sim_fault_t to_lcm(const FaultEvent& e) {
  sim_fault_t m;
  m.utime = e.utime;
  m.kind = static_cast<int8_t>(e.kind);
  m.active = e.active;
  m.index = e.index;
  m.value = e.value;
  m.x = e.pose.x;
  m.y = e.pose.y;
  m.theta = e.pose.theta;
  return m;
}

LcmSink::LcmSink(Bus& bus, std::function<void(int64_t)> set_time, const CameraNoise& camera, double saturation)
    : bus_(bus),
      set_time_(std::move(set_time)),
      format_(camera.format),
      jpeg_quality_(camera.jpeg_quality),
      saturation_(saturation) {
  if (format_ != CameraFormat::Mjpeg) return;
  if (!(jpeg_quality_ >= 1 && jpeg_quality_ <= 100)) {
    throw std::invalid_argument("JPEG quality " + std::to_string(jpeg_quality_) + " is out of range [1, 100]");
  }
  jpeg_ = {tjInitCompress(), tjDestroy};
  if (!jpeg_) throw std::runtime_error(std::string("libturbojpeg: cannot create a compressor: ") + tjGetErrorStr());
}

template <typename T>
void LcmSink::put(const std::string& channel, int64_t utime, const T& msg) {
  if (set_time_) set_time_(utime);
  publish(bus_, channel, msg);
  ++counts_[channel];
}

void LcmSink::whisker_sample(const rcp::WhiskerSample& sample, const WhiskerHealth& health) {
  put(channels::kWhiskerSample, sample.utime, to_lcm(sample, health, saturation_));
}

void LcmSink::rcp_state(const rcp::ControlOutput& out) { put(channels::kRcpState, out.utime, to_lcm(out)); }

void LcmSink::whisk_cycle(const rcp::WhiskCycle& cycle) { put(channels::kWhiskCycle, cycle.utime_end, to_lcm(cycle)); }

void LcmSink::contact_truth(const ContactTruth& truth) {
  contact_truth_t m;
  m.utime = truth.utime;
  m.cycle = truth.cycle;
  m.num_points = static_cast<int32_t>(truth.points.size());
  for (const ContactTruth::Point& p : truth.points) {
    m.whisker.push_back(p.whisker);
    m.point_utime.push_back(p.utime);
    m.x.push_back(p.p_in_head.x);
    m.y.push_back(p.p_in_head.y);
    m.z.push_back(p.p_in_head.z);
  }
  put(channels::kSimContactTruth, truth.utime, m);
}

void LcmSink::odometry(int64_t utime, int64_t seq, const OdometrySample& odom) {
  odometry_t m;
  m.utime = utime;
  m.seq = seq;
  m.x = odom.pose.x;
  m.y = odom.pose.y;
  m.theta = odom.pose.theta;
  m.vx = odom.vx;
  m.vy = odom.vy;
  m.omega = odom.omega;
  put(channels::kOdometry, utime, m);
}

void LcmSink::ground_truth(int64_t utime, const Pose2& T_world_base) {
  pose2d_t m;
  m.utime = utime;
  m.x = T_world_base.x;
  m.y = T_world_base.y;
  m.theta = T_world_base.theta;
  put(channels::kGroundTruth, utime, m);
}

void LcmSink::camera(int64_t utime, int64_t seq, const std::vector<uint8_t>& grey, int width, int height) {
  image_.utime = utime;
  image_.seq = seq;
  image_.width = width;
  image_.height = height;
  switch (format_) {
    case CameraFormat::Yuyv:
      grey_to_yuyv(grey, width, height, image_.data);
      image_.row_stride = 2 * width;
      image_.pixelformat = image_t::PIXEL_FORMAT_YUYV;
      break;
    case CameraFormat::Grey:
      image_.data = grey;
      image_.row_stride = width;
      image_.pixelformat = image_t::PIXEL_FORMAT_GREY;
      break;
    case CameraFormat::Mjpeg: {
      // What a UVC camera sends: baseline JPEG, YCbCr 4:2:2 (the grey image is the luma, the
      // chroma neutral). Compressed from planes, so no RGB image is made; libjpeg's default
      // integer DCT, so the same frame gives the same bytes.
      const auto chroma = static_cast<std::size_t>(tjPlaneSizeYUV(1, width, 0, height, TJSAMP_422));
      if (neutral_chroma_.size() < chroma) neutral_chroma_.assign(chroma, 128);
      const auto capacity = static_cast<std::size_t>(tjBufSize(width, height, TJSAMP_422));
      if (jpeg_buffer_.size() < capacity) jpeg_buffer_.resize(capacity);
      const unsigned char* planes[3] = {grey.data(), neutral_chroma_.data(), neutral_chroma_.data()};
      const int strides[3] = {width, 0, 0};  // 0: the plane's own width
      unsigned char* out = jpeg_buffer_.data();
      unsigned long size = capacity;
      if (tjCompressFromYUVPlanes(jpeg_.get(), planes, width, strides, height, TJSAMP_422, &out, &size, jpeg_quality_,
                                  TJFLAG_NOREALLOC) != 0) {
        throw std::runtime_error(std::string("libturbojpeg: cannot encode a camera frame: ") +
                                 tjGetErrorStr2(jpeg_.get()));
      }
      image_.data.assign(out, out + size);
      image_.row_stride = 0;  // as camerad publishes a compressed frame
      image_.pixelformat = image_t::PIXEL_FORMAT_MJPEG;
      break;
    }
  }
  image_.size = static_cast<int32_t>(image_.data.size());
  put(channels::kCamera, utime, image_);
}

void LcmSink::fault(const FaultEvent& event) { put(channels::kSimFault, event.utime, to_lcm(event)); }

}  // namespace whiskeye::sim
