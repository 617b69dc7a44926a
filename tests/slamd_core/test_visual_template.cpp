// Visual template: formats, crop/subsample/normalise, and refusal of bad frames.
#include "whiskeye/slam/visual_template.h"

#include "whiskeye/slamd/mjpeg_decode.h"  // slamd's, at the daemon's edge: the core decodes no MJPEG itself
#include "synthetic.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

namespace whiskeye::slam {
namespace {

VisualParams plain_params() {
  VisualParams p;
  p.crop_x = p.crop_y = 0;
  p.crop_width = p.crop_height = 0;
  p.global_normalisation = 0.0;
  return p;
}

// The decoder slamd gives the core for MJPEG frames.
const FrameDecoder* mjpeg() {
  static const FrameDecoder d = slamd::mjpeg_decoder();
  return &d;
}

ImageView view(const std::vector<uint8_t>& d, int w, int h, int stride, uint32_t fmt) {
  ImageView v;
  v.width = w;
  v.height = h;
  v.row_stride = stride;
  v.pixelformat = fmt;
  v.data = d;
  return v;
}

TEST(VisualTemplate, BlockAveragesToTemplateSize) {
  // 640×400 image: left half black, right half white → 64×40 template, left 32 columns 0, right 255.
  std::vector<uint8_t> img(640 * 400, 0);
  for (int y = 0; y < 400; ++y)
    for (int x = 320; x < 640; ++x) img[static_cast<size_t>(y * 640 + x)] = 255;
  const VisualTemplate t = make_visual_template(view(img, 640, 400, 640, kPixGrey), plain_params());
  ASSERT_EQ(t.width, 64);
  ASSERT_EQ(t.height, 40);
  EXPECT_EQ(t.pixels[0], 0);
  EXPECT_EQ(t.pixels[31], 0);
  EXPECT_EQ(t.pixels[32], 255);
  EXPECT_EQ(t.pixels[39 * 64 + 63], 255);
  EXPECT_NEAR(t.mean, 0.5, 1e-6);
}

TEST(VisualTemplate, CropKeepsOnlyTheRequestedRectangle) {
  std::vector<uint8_t> img(640 * 480, 0);
  for (int y = 300; y < 480; ++y)
    for (int x = 0; x < 640; ++x) img[static_cast<size_t>(y * 640 + x)] = 255;  // the "floor"
  VisualParams p = plain_params();
  p.crop_width = 640;
  p.crop_height = 300;
  const VisualTemplate t = make_visual_template(view(img, 640, 480, 640, kPixGrey), p);
  EXPECT_EQ(t.mean, 0.0f);
}

TEST(VisualTemplate, GlobalNormalisationSetsTheMean) {
  const std::vector<uint8_t> img = test::random_image(640, 400, 3);
  std::vector<uint8_t> dark(img.size());
  for (size_t i = 0; i < img.size(); ++i) dark[i] = static_cast<uint8_t>(img[i] / 2);
  VisualParams p = plain_params();
  p.global_normalisation = 0.4;
  const VisualTemplate a = make_visual_template(view(img, 640, 400, 640, kPixGrey), p);
  const VisualTemplate b = make_visual_template(view(dark, 640, 400, 640, kPixGrey), p);
  EXPECT_NEAR(a.mean, 0.4, 0.02);
  // Halving the brightness changes the template by at most rounding.
  double diff = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) diff += std::abs(a.pixels[i] - b.pixels[i]);
  EXPECT_LT(diff / static_cast<double>(a.pixels.size()), 2.0);
}

TEST(VisualTemplate, AllPixelFormatsGiveTheSameTemplate) {
  const int w = 640, h = 400;
  const std::vector<uint8_t> grey = test::random_image(w, h, 5);
  std::vector<uint8_t> rgb(static_cast<size_t>(w * h * 3)), yuyv(static_cast<size_t>(w * h * 2));
  for (int i = 0; i < w * h; ++i) {
    for (int c = 0; c < 3; ++c) rgb[static_cast<size_t>(i * 3 + c)] = grey[static_cast<size_t>(i)];
    yuyv[static_cast<size_t>(i * 2)] = grey[static_cast<size_t>(i)];
    yuyv[static_cast<size_t>(i * 2 + 1)] = 128;
  }
  // Padded rows: the stride is honoured.
  std::vector<uint8_t> padded(static_cast<size_t>((w + 16) * h), 77);
  for (int y = 0; y < h; ++y)
    std::copy_n(&grey[static_cast<size_t>(y * w)], w, &padded[static_cast<size_t>(y * (w + 16))]);
  std::vector<uint8_t> jpeg;
  cv::imencode(".jpg", cv::Mat(h, w, CV_8UC1, const_cast<uint8_t*>(grey.data())), jpeg, {cv::IMWRITE_JPEG_QUALITY, 98});

  const VisualParams p = plain_params();
  const VisualTemplate ref = make_visual_template(view(grey, w, h, w, kPixGrey), p);
  for (const auto& [name, t] : {std::pair{"padded", make_visual_template(view(padded, w, h, w + 16, kPixGrey), p)},
                               std::pair{"rgb", make_visual_template(view(rgb, w, h, w * 3, kPixRgb24), p)},
                               std::pair{"bgr", make_visual_template(view(rgb, w, h, w * 3, kPixBgr24), p)},
                               std::pair{"yuyv", make_visual_template(view(yuyv, w, h, w * 2, kPixYuyv), p)},
                               std::pair{"mjpeg", make_visual_template(view(jpeg, w, h, 0, kPixMjpeg), p, mjpeg())}}) {
    ASSERT_EQ(t.pixels.size(), ref.pixels.size()) << name;
    int worst = 0;
    for (size_t i = 0; i < ref.pixels.size(); ++i) worst = std::max(worst, std::abs(t.pixels[i] - ref.pixels[i]));
    EXPECT_LE(worst, 3) << name;
  }
}

// The template computed with OpenCV alone: the whole image converted to grey, to float, cropped and
// shrunk by cv::resize(INTER_AREA); only the normalisation is make_visual_template_from_grey's (at
// the template's size, where its shrink is the identity). make_visual_template converts only the
// crop, with its own float conversion and area average: the templates must be byte-identical.
VisualTemplate whole_image_reference(const ImageView& im, const VisualParams& p) {
  auto* data = const_cast<uint8_t*>(im.data.data());
  const auto stride = static_cast<size_t>(im.row_stride);
  cv::Mat grey8;
  if (im.pixelformat == kPixGrey) grey8 = cv::Mat(im.height, im.width, CV_8UC1, data, stride);
  if (im.pixelformat == kPixYuyv) cv::cvtColor(cv::Mat(im.height, im.width, CV_8UC2, data, stride), grey8, cv::COLOR_YUV2GRAY_YUYV);
  if (im.pixelformat == kPixRgb24) cv::cvtColor(cv::Mat(im.height, im.width, CV_8UC3, data, stride), grey8, cv::COLOR_RGB2GRAY);
  if (im.pixelformat == kPixBgr24) cv::cvtColor(cv::Mat(im.height, im.width, CV_8UC3, data, stride), grey8, cv::COLOR_BGR2GRAY);
  if (im.pixelformat == kPixMjpeg) {
    grey8.create(im.height, im.width, CV_8UC1);
    mjpeg()->decode(im, grey8.data, grey8.step[0]);
  }
  cv::Mat grey;
  grey8.convertTo(grey, CV_32F, 1.0 / 255.0);
  const int x0 = std::min(p.crop_x, im.width), y0 = std::min(p.crop_y, im.height);
  const cv::Rect crop(x0, y0, p.crop_width == 0 ? im.width - x0 : std::min(p.crop_width, im.width - x0),
                      p.crop_height == 0 ? im.height - y0 : std::min(p.crop_height, im.height - y0));
  cv::Mat small;
  cv::resize(grey(crop), small, cv::Size(p.template_width, p.template_height), 0, 0, cv::INTER_AREA);
  VisualParams whole = p;
  whole.crop_x = whole.crop_y = whole.crop_width = whole.crop_height = 0;
  return make_visual_template_from_grey(small.ptr<float>(), small.cols, small.rows, static_cast<int>(small.step1()), whole);
}

// The area average gives cv::resize(INTER_AREA)'s floats bit for bit, for every size: shrinks by
// non-integer factors (computed by area_shrink), whole factors, no change and enlargements (handed
// to OpenCV), rows with padding.
TEST(VisualTemplate, AreaShrinkGivesOpenCvsInterAreaFloatsBitForBit) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> value(0.0f, 1.0f);
  std::uniform_int_distribution<int> size(1, 700);
  int weighted = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const int w = size(rng), h = size(rng) / 2 + 1;
    int tw = std::max(1, w / std::uniform_int_distribution<int>(1, 23)(rng)), th = std::max(1, h / std::uniform_int_distribution<int>(1, 23)(rng));
    if (trial % 10 == 0) tw += 3;  // an enlargement now and then
    if (trial == 1) {
      tw = 64;  // slam.yaml's 640x300 -> 64x40
      th = 40;
    }
    const int width = trial == 1 ? 640 : w, height = trial == 1 ? 300 : h;
    const int stride = width + trial % 5;
    std::vector<float> src(static_cast<size_t>(stride) * static_cast<size_t>(height));
    for (float& v : src) v = value(rng);
    std::vector<float> got(static_cast<size_t>(tw) * static_cast<size_t>(th));
    area_shrink(src.data(), width, height, stride, got.data(), tw, th);
    cv::Mat want;
    cv::resize(cv::Mat(height, width, CV_32FC1, src.data(), static_cast<size_t>(stride) * 4), want, cv::Size(tw, th), 0, 0,
               cv::INTER_AREA);
    ASSERT_TRUE(want.isContinuous());
    ASSERT_EQ(0, std::memcmp(got.data(), want.ptr<float>(), got.size() * sizeof(float)))
        << width << "x" << height << " -> " << tw << "x" << th;
    const double fx = static_cast<double>(width) / tw, fy = static_cast<double>(height) / th;
    if (fx >= 1.0 && fy >= 1.0 && (fx != std::floor(fx) || fy != std::floor(fy))) ++weighted;
  }
  EXPECT_GT(weighted, 200);  // most trials take the weighted path
}

TEST(VisualTemplate, ConvertingOnlyTheCropGivesTheTemplatesOfConvertingTheWholeImage) {
  std::mt19937 rng(4);
  const int w = 640, h = 480;
  std::vector<uint8_t> bytes(static_cast<size_t>((w * 3 + 8) * h));
  for (uint8_t& b : bytes) b = static_cast<uint8_t>(rng());
  const std::vector<uint8_t> grey = test::random_image(w, h, 3);  // smooth, for the JPEG
  std::vector<uint8_t> jpeg;
  cv::imencode(".jpg", cv::Mat(h, w, CV_8UC1, const_cast<uint8_t*>(grey.data())), jpeg, {cv::IMWRITE_JPEG_QUALITY, 90});
  // The whole frame (integer ratios), slam.yaml's upper 640x300 (7.5 rows a template row), odd
  // offsets and sizes, a crop past the edges (clamped), another template size.
  const VisualParams crops[] = {
      {.crop_x = 0, .crop_y = 0, .crop_width = 0, .crop_height = 0},
      {.crop_x = 0, .crop_y = 0, .crop_width = 640, .crop_height = 300},
      {.crop_x = 3, .crop_y = 5, .crop_width = 601, .crop_height = 377},
      {.crop_x = 101, .crop_y = 77, .crop_width = 0, .crop_height = 0},
      {.crop_x = 500, .crop_y = 400, .crop_width = 400, .crop_height = 400, .template_width = 33, .template_height = 17},
      {.crop_x = 1, .crop_y = 1, .crop_width = 63, .crop_height = 41}};
  int compared = 0;
  for (const VisualParams& crop : crops) {
    for (const double norm : {0.0, 0.5}) {
      for (const int radius : {0, 2}) {
        VisualParams p = crop;
        p.global_normalisation = norm;
        p.patch_radius = radius;
        for (const auto& [format, stride] : {std::pair{kPixGrey, w + 8}, std::pair{kPixYuyv, w * 2 + 4},
                                             std::pair{kPixRgb24, w * 3}, std::pair{kPixBgr24, w * 3 + 8}}) {
          const ImageView im = view(bytes, w, h, stride, format);
          const VisualTemplate got = make_visual_template(im, p), want = whole_image_reference(im, p);
          EXPECT_EQ(got.pixels, want.pixels) << "format " << format << " crop " << p.crop_x << "," << p.crop_y << " " << p.crop_width << "x"
                                      << p.crop_height;
          EXPECT_EQ(got.mean, want.mean);
          // The rows a replay reads of the frame (visual_rows) give the same template.
          const ImageView part = visual_rows(im, p);
          EXPECT_EQ(part.height, p.crop_height == 0 || p.crop_y + p.crop_height >= h ? h : p.crop_y + p.crop_height);
          EXPECT_EQ(part.data.data(), im.data.data());
          const VisualTemplate from_part = make_visual_template(part, p);
          EXPECT_EQ(from_part.pixels, got.pixels);
          EXPECT_EQ(from_part.mean, got.mean);
          ++compared;
        }
        const ImageView im = view(jpeg, w, h, 0, kPixMjpeg);
        EXPECT_EQ(make_visual_template(im, p, mjpeg()).pixels, whole_image_reference(im, p).pixels) << "MJPEG";
      }
    }
  }
  EXPECT_EQ(compared, 96);
  // A crop outside the image is refused, naming the image's size, whatever the format.
  VisualParams outside;
  outside.crop_x = 700;
  for (const auto& [format, stride] : {std::pair{kPixGrey, w}, std::pair{kPixYuyv, w * 2}, std::pair{kPixRgb24, w * 3}}) {
    try {
      make_visual_template(view(bytes, w, h, stride, format), outside);
      ADD_FAILURE() << "no error";
    } catch (const InputError& e) {
      EXPECT_STREQ(e.what(), "image: crop (700, 0) lies outside the 640x480 image");
    }
  }
}

// What visual_rows leaves whole: a compressed frame, a crop to the image's edge, and frames that
// must be refused with the whole frame's numbers (a crop right of the image, data too short).
TEST(VisualTemplate, VisualRowsKeepsTheWholeFrameWhereTheCropCannotSayWhichRowsAreRead) {
  const auto error_of = [](const ImageView& im, const VisualParams& p) -> std::string {
    const ImageView part = visual_rows(im, p);
    EXPECT_EQ(part.height, im.height);
    try {
      make_visual_template(part, p);
    } catch (const InputError& e) {
      return e.what();
    }
    return "no error";
  };
  const std::vector<uint8_t> bytes(640 * 480 * 2, 100);
  VisualParams p;
  p.crop_height = 300;
  const ImageView yuyv = view(bytes, 640, 480, 1280, kPixYuyv);
  EXPECT_EQ(visual_rows(yuyv, p).height, 300);
  EXPECT_EQ(visual_rows(yuyv, p).data.size(), 300u * 1280u);
  const ImageView jpeg = view(bytes, 640, 480, 0, kPixMjpeg);
  EXPECT_EQ(visual_rows(jpeg, p).data.size(), bytes.size());
  p.crop_height = 0;
  EXPECT_EQ(visual_rows(yuyv, p).height, 480);
  VisualParams right = p;
  right.crop_x = 700;
  right.crop_y = 10;
  right.crop_height = 290;
  EXPECT_EQ(error_of(yuyv, right), "image: crop (700, 10) lies outside the 640x480 image");
  VisualParams below = p;
  below.crop_y = 500;
  below.crop_height = 10;
  EXPECT_EQ(error_of(yuyv, below), "image: crop (0, 500) lies outside the 640x480 image");
  VisualParams tall = p;  // a bottom past INT_MAX is past the image's last row
  tall.crop_y = 10;
  tall.crop_height = std::numeric_limits<int>::max();
  EXPECT_EQ(error_of(yuyv, tall), "no error");
  p.crop_height = 300;
  const std::vector<uint8_t> short_data(640 * 479 * 2, 100);
  EXPECT_EQ(error_of(view(short_data, 640, 480, 1280, kPixYuyv), p),
            "image: 613120 bytes of data, 614400 needed for 640x480 YUYV");
}

TEST(VisualTemplate, AnMjpegFrameLargerThanItsMessageSaysIsRefusedBeforeDecoding) {
  const std::vector<uint8_t> grey(16 * 16, 100);
  std::vector<uint8_t> jpeg;
  cv::imencode(".jpg", cv::Mat(16, 16, CV_8UC1, const_cast<uint8_t*>(grey.data())), jpeg);
  const VisualParams p = plain_params();
  EXPECT_NO_THROW(make_visual_template(view(jpeg, 16, 16, 0, kPixMjpeg), p, mjpeg()));
  // The frame header (SOF0: FF C0, length, precision, height, width) patched to 32752 x 32752: a
  // 300-byte message that decoded into 1 GB of pixels (5 GB once converted) and took 12 s.
  std::size_t sof = 2;
  while (!(jpeg[sof] == 0xff && jpeg[sof + 1] == 0xc0)) sof += 2 + ((jpeg[sof + 2] << 8) | jpeg[sof + 3]);
  for (std::size_t at : {sof + 5, sof + 7}) {
    jpeg[at] = 0x7f;
    jpeg[at + 1] = 0xf0;
  }
  try {
    make_visual_template(view(jpeg, 16, 16, 0, kPixMjpeg), p, mjpeg());
    FAIL() << "a frame that does not match its message must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("32752x32752 by its JPEG header, the message says 16x16"), std::string::npos)
        << e.what();
  }
  const std::vector<uint8_t> not_jpeg{0xff, 0xd8, 0xff, 0xda, 0x00, 0x02, 0x00, 0x00};
  EXPECT_THROW(make_visual_template(view(not_jpeg, 16, 16, 0, kPixMjpeg), p, mjpeg()), InputError);
  // A header claiming 10000 x 10000 for a message that says the same: refused before decoding
  // (it took 2 s and 550 MB, and the grey it decoded to became a template).
  for (std::size_t at : {sof + 5, sof + 7}) {
    jpeg[at] = 10000 >> 8;
    jpeg[at + 1] = 10000 & 0xff;
  }
  try {
    make_visual_template(view(jpeg, 10000, 10000, 0, kPixMjpeg), p, mjpeg());
    FAIL() << "a 100 MP MJPEG frame must be refused before decoding";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("10000x10000 is larger than 4096x4096"), std::string::npos) << e.what();
  }
}

TEST(VisualTemplate, AnMjpegFrameCutOffInTransferIsRefusedNotDecodedToGrey) {
  std::vector<uint8_t> grey(64 * 48);
  for (std::size_t i = 0; i < grey.size(); ++i) grey[i] = static_cast<uint8_t>(i * 7);
  std::vector<uint8_t> jpeg;
  cv::imencode(".jpg", cv::Mat(48, 64, CV_8UC1, grey.data()), jpeg);
  const VisualParams p = plain_params();
  std::vector<uint8_t> padded = jpeg;  // zero padding after the end marker, as some cameras send
  padded.resize(padded.size() + 100, 0x00);
  EXPECT_NO_THROW(make_visual_template(view(padded, 64, 48, 0, kPixMjpeg), p, mjpeg()));
  std::vector<uint8_t> cut(jpeg.begin(), jpeg.begin() + static_cast<std::ptrdiff_t>(jpeg.size() * 2 / 3));
  try {
    make_visual_template(view(cut, 64, 48, 0, kPixMjpeg), p, mjpeg());
    FAIL() << "OpenCV decodes a cut-off JPEG, greying out the rest";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cut off (no end-of-image marker)"), std::string::npos) << e.what();
  }
}

// A frame cut short in transfer with an end-of-image marker appended (a camera's buffer recycled
// mid-frame) was decoded, greyed out where data was missing, and stored as a template; libjpeg said
// "Corrupt JPEG data" on stderr, unprefixed. Refused with libjpeg's words in the reason, nothing on stderr.
TEST(VisualTemplate, AnMjpegFrameCutShortWithAnEndMarkerAppendedIsRefusedAndLibjpegStaysQuiet) {
  std::vector<uint8_t> grey(64 * 48);
  for (std::size_t i = 0; i < grey.size(); ++i) grey[i] = static_cast<uint8_t>(i * 7);
  std::vector<uint8_t> jpeg;
  cv::imencode(".jpg", cv::Mat(48, 64, CV_8UC1, grey.data()), jpeg);
  std::vector<uint8_t> cut(jpeg.begin(), jpeg.begin() + static_cast<std::ptrdiff_t>(jpeg.size() * 2 / 3));
  cut.push_back(0xff);
  cut.push_back(0xd9);
  const VisualParams p = plain_params();
  ::testing::internal::CaptureStderr();
  std::string why;
  try {
    make_visual_template(view(cut, 64, 48, 0, kPixMjpeg), p, mjpeg());
  } catch (const InputError& e) {
    why = e.what();
  }
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(why.find("image: MJPEG frame is damaged (Corrupt JPEG data"), std::string::npos) << why;
  EXPECT_EQ(err, "") << "libjpeg's own line";
  EXPECT_NO_THROW(make_visual_template(view(jpeg, 64, 48, 0, kPixMjpeg), p, mjpeg())) << "the whole frame still decodes";
}

TEST(VisualTemplate, RefusesBadFramesWithAReason) {
  const std::vector<uint8_t> small(100, 0);
  const VisualParams p = plain_params();
  EXPECT_THROW(make_visual_template(view(small, 640, 480, 640, kPixGrey), p), InputError);
  EXPECT_THROW(make_visual_template(view(small, 10, 10, 5, kPixGrey), p), InputError);
  EXPECT_THROW(make_visual_template(view(small, 10, 10, 10, fourcc('H', '2', '6', '4')), p), InputError);
  EXPECT_THROW(make_visual_template(view(small, 10, 10, 0, kPixMjpeg), p, mjpeg()), InputError);
  EXPECT_THROW(make_visual_template(view(small, 0, 10, 10, kPixGrey), p), InputError);
  try {
    make_visual_template(view(small, 10, 10, 10, fourcc('H', '2', '6', '4')), p);
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("H264"), std::string::npos) << e.what();
  }
}

TEST(VisualTemplate, WithoutADecoderAnMjpegFrameIsAFormatTheCoreDoesNotRead) {
  const std::vector<uint8_t> grey(16 * 16, 100);
  std::vector<uint8_t> jpeg;
  cv::imencode(".jpg", cv::Mat(16, 16, CV_8UC1, const_cast<uint8_t*>(grey.data())), jpeg);
  const VisualParams p = plain_params();
  EXPECT_NO_THROW(make_visual_template(view(jpeg, 16, 16, 0, kPixMjpeg), p, mjpeg()));
  try {
    make_visual_template(view(jpeg, 16, 16, 0, kPixMjpeg), p);
    FAIL() << "the core has no JPEG decoder of its own";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("unsupported pixel format 'MJPG'"), std::string::npos) << e.what();
  }
}

TEST(VisualTemplate, PatchNormalisationRemovesAnIlluminationGradient) {
  const int w = 640, h = 400;
  const std::vector<uint8_t> img = test::random_image(w, h, 9);
  std::vector<uint8_t> lit(img.size());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double g = 0.6 + 0.4 * x / w;  // brighter to the right
      lit[static_cast<size_t>(y * w + x)] = static_cast<uint8_t>(img[static_cast<size_t>(y * w + x)] * g);
    }
  VisualParams p = plain_params();
  auto mean_diff = [&](const VisualParams& q) {
    const VisualTemplate a = make_visual_template(view(img, w, h, w, kPixGrey), q);
    const VisualTemplate b = make_visual_template(view(lit, w, h, w, kPixGrey), q);
    double d = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i) d += std::abs(a.pixels[i] - b.pixels[i]);
    return d / static_cast<double>(a.pixels.size());
  };
  const double plain = mean_diff(p);
  p.patch_radius = 3;
  EXPECT_LT(mean_diff(p), 0.5 * plain);
}

}  // namespace
}  // namespace whiskeye::slam
