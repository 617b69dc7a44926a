// A camera frame (image_t: GREY, YUYV, RGB24, BGR24 or MJPEG, docs/lcm-channels.md) as a small JPEG
// for a browser: converted, downscaled, encoded. Pure computation (OpenCV and libjpeg), no I/O.
#pragma once

#include "whiskeye/common/message_layout.h"  // CameraFrame: image_t's header, the pixels as a view

#include <memory>
#include <string>

namespace whiskeye::viewer {

using Frame = CameraFrame;

// The frame as a JPEG at most `max_width` wide (aspect kept), colour where the format has colour
// (MJPEG is decoded to grey by slamd's checked decoder). Null, with `reason` set, when the frame is
// not convertible (camera_frame_error(), a damaged MJPEG frame).
std::shared_ptr<const std::string> frame_to_jpeg(const Frame& frame, int max_width, int quality,
                                                 std::string* reason = nullptr);

}  // namespace whiskeye::viewer
