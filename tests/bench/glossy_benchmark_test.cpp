// The glossy benchmark's pieces (bench/glossy_benchmark.h); its runs are picbench_glossy_test's.

#include <gtest/gtest.h>

#include <vector>

#include "bench/glossy_benchmark.h"

namespace {

// Truncation keeps each cache's first bands² coefficients, luma and chroma alike.
TEST(GlossyBenchmark, TruncationKeepsEachCachesFirstBands) {
    pic::CacheValues values = pic::CacheValues::zeros(2, 3, 3);
    for (size_t i = 0; i < values.y.size(); ++i) values.y[i] = float(i);
    for (size_t i = 0; i < values.co.size(); ++i) values.co[i] = -float(i);
    const pic::CacheValues two = pic::truncateBands(values, 2);
    EXPECT_EQ(two.bandsY, 2u);
    EXPECT_EQ(two.bandsC, 2u);
    EXPECT_EQ(two.y, (std::vector<float>{0, 1, 2, 3, 9, 10, 11, 12}));
    EXPECT_EQ(two.co, (std::vector<float>{0, -1, -2, -3, -9, -10, -11, -12}));
    EXPECT_EQ(two.cg.size(), 8u);
    EXPECT_EQ(two.cacheCount(), 2u);
}

}  // namespace
