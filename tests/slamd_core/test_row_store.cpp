#include "whiskeye/slam/row_store.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace whiskeye::slam {
namespace {

TEST(RowStore, RowsNeverMoveWhenTheStoreGrows) {
  RowStore<int> s(5);
  std::vector<int*> where;
  for (int r = 0; r < 2000; ++r) {  // many chunks
    int* row = s.append();
    for (int k = 0; k < 5; ++k) {
      EXPECT_EQ(row[k], 0);  // a new row is zeroed
      row[k] = r * 10 + k;
    }
    where.push_back(row);
  }
  ASSERT_EQ(s.rows(), 2000u);
  EXPECT_EQ(s.elements(), 10000u);
  for (int r = 0; r < 2000; ++r) {
    EXPECT_EQ(s.row(static_cast<size_t>(r)), where[static_cast<size_t>(r)]);  // same address as when appended
    EXPECT_EQ(s.row(static_cast<size_t>(r))[4], r * 10 + 4);
  }
}

TEST(RowStore, RowsOfWholeCacheLinesStartOnACacheLine) {
  // A 64×40 template (2,560 bytes) in every chunk, and its copy: the matcher's 64-byte loads of a row
  // then never straddle two cache lines.
  RowStore<unsigned char> s(2560);
  for (int r = 0; r < 600; ++r) s.append();  // three chunks
  const RowStore<unsigned char> copy = s;
  for (size_t r = 0; r < 600; ++r) {
    EXPECT_EQ(reinterpret_cast<uintptr_t>(s.row(r)) % 64, 0u) << "row " << r;
    EXPECT_EQ(reinterpret_cast<uintptr_t>(copy.row(r)) % 64, 0u) << "copied row " << r;
  }
}

TEST(RowStore, RunsCoverEveryRowInOrder) {
  RowStore<int> s(2);
  for (int r = 0; r < 700; ++r) {
    int* row = s.append();
    row[0] = r;
    row[1] = -r;
  }
  std::vector<int> seen;
  s.for_each_run([&](const int* data, size_t n) { seen.insert(seen.end(), data, data + n); });
  ASSERT_EQ(seen.size(), 1400u);
  for (int r = 0; r < 700; ++r) {
    EXPECT_EQ(seen[static_cast<size_t>(2 * r)], r);
    EXPECT_EQ(seen[static_cast<size_t>(2 * r + 1)], -r);
  }
}

TEST(RowStore, ACopyIsDeepAndEqualityComparesContents) {
  RowStore<float> a(3);
  for (int r = 0; r < 300; ++r) a.append()[1] = static_cast<float>(r);
  RowStore<float> b = a;
  EXPECT_EQ(a, b);
  EXPECT_NE(a.row(0), b.row(0));
  b.row(299)[1] = -1.0f;
  EXPECT_FALSE(a == b);
  EXPECT_EQ(a.row(299)[1], 299.0f);
  RowStore<float> shorter(3);
  shorter.append();
  EXPECT_FALSE(a == shorter);
}

TEST(RowStore, EmptyRowsAreCountedWithoutStorage) {
  RowStore<unsigned char> s(0);  // e.g. no 4-row blocks in a template under 4 rows high
  EXPECT_EQ(s.append(), nullptr);
  EXPECT_EQ(s.rows(), 1u);
  EXPECT_EQ(s.elements(), 0u);
  int runs = 0;
  s.for_each_run([&](const unsigned char*, size_t) { ++runs; });
  EXPECT_EQ(runs, 0);
}

}  // namespace
}  // namespace whiskeye::slam
