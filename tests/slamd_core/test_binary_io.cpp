// The checkpoint's byte layout (slamd/core/src/binary_io.h): little-endian whatever the host, arrays
// as a uint64 count then the elements. Pinned byte by byte, so the bulk copy used on little-endian
// hosts and the per-value path used elsewhere must both produce exactly these bytes.
#include "binary_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace whiskeye::slam::bin {
namespace {

using ::testing::ElementsAre;

TEST(BinaryIo, ScalarsAreLittleEndianIeeeBitPatterns) {
  std::vector<uint8_t> out;
  put<uint32_t>(out, 0x01020304u);
  put<int16_t>(out, -2);
  put<double>(out, 1.0);
  EXPECT_THAT(out, ElementsAre(0x04, 0x03, 0x02, 0x01, 0xfe, 0xff, 0, 0, 0, 0, 0, 0, 0xf0, 0x3f));
  size_t pos = 0;
  EXPECT_EQ(get<uint32_t>(out, pos), 0x01020304u);
  EXPECT_EQ(get<int16_t>(out, pos), -2);
  EXPECT_EQ(get<double>(out, pos), 1.0);
  EXPECT_EQ(pos, out.size());
}

TEST(BinaryIo, AnArrayIsItsCountThenItsElementsAndReadsBackExactly) {
  std::vector<uint8_t> out{0xaa};  // arrays are appended after what is there
  put_vec<uint16_t>(out, {0x0102, 0x0304});
  put_vec<float>(out, {-1.5f});
  put_vec<double>(out, {});
  EXPECT_THAT(out, ElementsAre(0xaa,                                            //
                               2, 0, 0, 0, 0, 0, 0, 0, 0x02, 0x01, 0x04, 0x03,  // uint16 ×2
                               1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0xc0, 0xbf,        // float −1.5
                               0, 0, 0, 0, 0, 0, 0, 0));                        // empty
  size_t pos = 1;
  EXPECT_THAT(get_vec<uint16_t>(out, pos), ElementsAre(0x0102, 0x0304));
  EXPECT_THAT(get_vec<float>(out, pos), ElementsAre(-1.5f));
  EXPECT_TRUE(get_vec<double>(out, pos).empty());
  EXPECT_EQ(pos, out.size());
}

TEST(BinaryIo, AnArrayLongerThanTheDataIsRefusedNamingWhere) {
  std::vector<uint8_t> out;
  put_vec<uint32_t>(out, {1, 2, 3});
  out.resize(out.size() - 1);  // cut inside the last element
  size_t pos = 0;
  try {
    get_vec<uint32_t>(out, pos);
    FAIL() << "a truncated array was read";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("array of 3 elements at byte 8 is longer than the data"));
  }
}

TEST(BinaryIo, RowsAreWrittenExactlyAsOneArrayOfTheSameValuesAndReadBackRowByRow) {
  RowStore<uint16_t> rows(3);
  std::vector<uint16_t> flat;
  for (uint16_t r = 0; r < 600; ++r) {  // more than one chunk
    uint16_t* row = rows.append();
    for (uint16_t k = 0; k < 3; ++k) flat.push_back(row[k] = static_cast<uint16_t>(r * 3 + k));
  }
  std::vector<uint8_t> a, b;
  put_rows(a, rows);
  put_vec(b, flat);
  EXPECT_EQ(a, b);
  size_t pos = 0;
  RowStore<uint16_t> back(3);
  get_rows(b, pos, back);
  EXPECT_EQ(pos, b.size());
  EXPECT_EQ(back, rows);
  RowStore<uint16_t> sevens(7);  // 1,800 values are not whole rows of 7
  pos = 0;
  try {
    get_rows(b, pos, sevens);
    FAIL() << "1,800 values were read as rows of 7";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("array of 1800 elements at byte 0 is not whole rows of 7"));
  }
}

}  // namespace
}  // namespace whiskeye::slam::bin
