// Camera frame → small JPEG for the page (camera_jpeg.h).
#include "whiskeye/viewer/camera_jpeg.h"

#include "whiskeye/common/message_layout.h"
#include "whiskeye/slamd/mjpeg_decode.h"

#include <whiskeye/image_t.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <vector>

namespace whiskeye::viewer {

std::shared_ptr<const std::string> frame_to_jpeg(const Frame& f, int max_width, int quality, std::string* reason) {
  if (std::string bad = camera_frame_error(f); !bad.empty()) {
    if (reason) *reason = bad;
    return nullptr;
  }
  // OpenCV wants a non-const pointer for a header over foreign data; it is only read.
  auto* data = const_cast<uint8_t*>(f.data.data());
  const auto stride = static_cast<std::size_t>(f.row_stride);
  cv::Mat image;
  try {
    if (f.pixelformat == image_t::PIXEL_FORMAT_GREY) {
      image = cv::Mat(f.height, f.width, CV_8UC1, data, stride);
    } else if (f.pixelformat == image_t::PIXEL_FORMAT_YUYV) {
      cv::cvtColor(cv::Mat(f.height, f.width, CV_8UC2, data, stride), image, cv::COLOR_YUV2BGR_YUYV);
    } else if (f.pixelformat == image_t::PIXEL_FORMAT_RGB24) {
      cv::cvtColor(cv::Mat(f.height, f.width, CV_8UC3, data, stride), image, cv::COLOR_RGB2BGR);
    } else if (f.pixelformat == image_t::PIXEL_FORMAT_BGR24) {
      image = cv::Mat(f.height, f.width, CV_8UC3, data, stride);
    } else {
      // slamd's decoder: checks the frame before allocating what its header claims, refuses a
      // damaged one with libjpeg's reason, and writes nothing to stderr.
      slamd::check_mjpeg_frame(f.data, f.width, f.height);
      image.create(f.height, f.width, CV_8UC1);
      slamd::decode_mjpeg_grey(f.data, f.width, f.height, image.data, image.step[0]);
    }
  } catch (const std::exception& e) {
    if (reason) *reason = e.what();
    return nullptr;
  }
  if (max_width > 0 && image.cols > max_width) {
    const int h = std::max(1, static_cast<int>(static_cast<int64_t>(image.rows) * max_width / image.cols));
    cv::Mat small;
    cv::resize(image, small, cv::Size(max_width, h), 0, 0, cv::INTER_AREA);
    image = small;
  }
  std::vector<uint8_t> out;
  if (!cv::imencode(".jpg", image, out, {cv::IMWRITE_JPEG_QUALITY, std::clamp(quality, 1, 100)})) {
    if (reason) *reason = "CAMERA: JPEG encoding failed";
    return nullptr;
  }
  return std::make_shared<const std::string>(out.begin(), out.end());
}

}  // namespace whiskeye::viewer
