// whiskeye::jpeg: a JPEG's marker structure read without decoding (camerad's MJPEG check, slamd's
// end-marker check), on frames encoded as a camera sends them (tests/support/mjpeg_pattern.h) and
// hostile ones made from them (tests/support/hostile_jpeg.h).
#include <gtest/gtest.h>

#include <whiskeye/common/jpeg_markers.h>

#include <random>

#include "hostile_jpeg.h"
#include "mjpeg_pattern.h"

using namespace whiskeye::jpeg;

namespace {

const std::vector<uint8_t>& frame() {
  static const std::vector<uint8_t> f = whiskeye::test::mjpeg_pattern_jpeg(640, 480, 1234);
  return f;
}

// Where the first scan's entropy-coded data begins (just after the SOS segment).
std::size_t scan_data_start(const std::vector<uint8_t>& j) {
  std::size_t pos = 2;
  while (j[pos + 1] != 0xda) pos += 2 + ((j[pos + 2] << 8) | j[pos + 3]);
  return pos + 2 + ((j[pos + 2] << 8) | j[pos + 3]);
}

std::vector<uint8_t> with_end_marker(std::vector<uint8_t> v) {
  v.push_back(0xff);
  v.push_back(0xd9);
  return v;
}

FrameSize size_of(const std::vector<uint8_t>& j) {
  FrameSize size{-1, -1};
  check_structure(j, &size);
  return size;
}

}  // namespace

TEST(JpegMarkers, ACameraFrameIsWholeAndSaysItsSize) {
  EXPECT_EQ(check_structure(frame()), Structure::kWhole);
  EXPECT_EQ(size_of(frame()).width, 640);
  EXPECT_EQ(size_of(frame()).height, 480);
  EXPECT_TRUE(ends_with_eoi(frame()));
}

TEST(JpegMarkers, ZeroPaddingAfterTheEndMarkerIsAllowed) {
  std::vector<uint8_t> padded = frame();
  padded.resize(padded.size() + 4000, 0x00);  // some UVC cameras send whole buffers
  EXPECT_EQ(check_structure(padded), Structure::kWhole);
}

TEST(JpegMarkers, AFrameCutShortHasNoEndMarker) {
  for (const double part : {0.01, 0.5, 0.99}) {
    const std::vector<uint8_t> cut(frame().begin(), frame().begin() + static_cast<std::ptrdiff_t>(frame().size() * part));
    EXPECT_EQ(check_structure(cut), Structure::kCutShort) << part;
    EXPECT_FALSE(ends_with_eoi(cut));
  }
}

TEST(JpegMarkers, GarbageAfterAValidHeaderIsDamagedData) {
  const std::size_t data = scan_data_start(frame());
  std::vector<uint8_t> garbage(frame().begin(), frame().begin() + static_cast<std::ptrdiff_t>(data));
  std::mt19937 rng(29);
  for (int i = 0; i < 30000; ++i) garbage.push_back(static_cast<uint8_t>(rng()));
  EXPECT_EQ(check_structure(with_end_marker(garbage)), Structure::kDamagedData);
  EXPECT_EQ(size_of(with_end_marker(garbage)).width, 0) << "a size only of a whole JPEG";
}

TEST(JpegMarkers, OnlyStuffedBytesRestartMarkersAndFillBytesMayStandInTheData) {
  const std::size_t mid = scan_data_start(frame()) + 1000;
  for (const std::vector<uint8_t>& legal : {std::vector<uint8_t>{0xff, 0x00}, {0xff, 0xd3}, {0xff, 0xff, 0xd7}}) {
    std::vector<uint8_t> j = frame();
    j.insert(j.begin() + static_cast<std::ptrdiff_t>(mid), legal.begin(), legal.end());
    EXPECT_EQ(check_structure(j), Structure::kWhole) << int(legal.back());
  }
  for (const std::vector<uint8_t>& illegal : {std::vector<uint8_t>{0xff, 0x05}, {0xff, 0xd8}, {0xff, 0xf3},
                                             {0xff, 0xd9, 0x12}}) {
    std::vector<uint8_t> j = frame();
    j.insert(j.begin() + static_cast<std::ptrdiff_t>(mid), illegal.begin(), illegal.end());
    EXPECT_EQ(check_structure(j), Structure::kDamagedData) << int(illegal[1]);
  }
}

TEST(JpegMarkers, WhatIsNoJpegOrHasABrokenHeaderIsNamedSo) {
  EXPECT_EQ(check_structure(std::vector<uint8_t>(1000, 0x80)), Structure::kNoStartMarker);  // YUYV bytes
  EXPECT_EQ(check_structure(std::vector<uint8_t>{}), Structure::kNoStartMarker);
  // A segment whose length runs past the end.
  std::vector<uint8_t> j = frame();
  j[4] = 0xff;
  EXPECT_EQ(check_structure(j), Structure::kBadHeader);
  // A scan before any frame header.
  EXPECT_EQ(check_structure(std::vector<uint8_t>{0xff, 0xd8, 0xff, 0xda, 0x00, 0x02, 0x12, 0x34, 0xff, 0xd9}), Structure::kBadHeader);
  EXPECT_EQ(size_of(std::vector<uint8_t>{0xff, 0xd8, 0xff, 0xda, 0x00, 0x02, 0xff, 0xd9}).width, 0);
  // SOI and EOI alone: no scan.
  EXPECT_EQ(check_structure(std::vector<uint8_t>{0xff, 0xd8, 0xff, 0xd9}), Structure::kBadHeader);
}

// A frame cut short and given an end marker (a camera's buffer recycled mid-frame) is put together
// like a JPEG: only decoding shows the missing data (slamd's decoder refuses it with libjpeg's words).
TEST(JpegMarkers, AFrameCutShortWithAnEndMarkerAppendedIsLeftToTheDecoder) {
  const std::vector<uint8_t> cut(frame().begin(), frame().begin() + static_cast<std::ptrdiff_t>(frame().size() / 2));
  EXPECT_EQ(check_structure(with_end_marker(cut)), Structure::kWhole);
}

// FF 00 after SOI, as a hostile sender puts it to hide a frame header: a walk taking it for a segment
// read the 640x480 header inside the APP1 libjpeg skips, while libjpeg decodes the 32000 x 32000 one
// behind it. Only markers where the segment before ended pass: the header does not parse, no size.
TEST(JpegMarkers, AFrameHeaderHiddenBehindAStuffedZeroIsABrokenHeaderWithoutASize) {
  const std::vector<uint8_t> hostile = whiskeye::test::camera_frame_hiding_progressive(640, 480, 32000, 32000);
  EXPECT_EQ(check_structure(hostile), Structure::kBadHeader);
  EXPECT_EQ(size_of(hostile).width, 0);
  EXPECT_EQ(size_of(hostile).height, 0);
}
