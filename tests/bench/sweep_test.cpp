// The sweep's grid and flag bookkeeping (bench/sweep_benchmark.h), without baking anything.

#include "bench/sweep_benchmark.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>

namespace {

using pic::SweepDefaults;
using pic::SweepSetting;

SweepDefaults cornellLike() {
    return {.surfels = 16384, .links = 128, .bandsY = 3, .bandsC = 2, .gridCell = 0.125f,
            .lightmapTexel = 0.02f, .linkSamples = 16};
}

/// The value of `flag` in `args`, or "" when absent.
std::string valueOf(const std::vector<std::string>& args, const std::string& flag) {
    auto it = std::find(args.begin(), args.end(), flag);
    return it == args.end() || it + 1 == args.end() ? "" : *(it + 1);
}

TEST(SweepGrid, CoarseVariesEachParameterAroundTheDefault) {
    auto grid = pic::sweepGrid("coarse", cornellLike());
    ASSERT_TRUE(grid) << grid.error().message;
    ASSERT_GE(grid->size(), 20u);
    EXPECT_EQ(grid->front().name, "default");
    EXPECT_TRUE(grid->front().bakeArgs.empty());
    std::set<std::string> keys, axes;
    for (const SweepSetting& s : *grid) {
        SCOPED_TRACE(s.name);
        EXPECT_TRUE(keys.insert(s.key()).second) << "duplicate key " << s.key();
        axes.insert(s.axis);
        // Flags come in pairs, each at most once.
        ASSERT_EQ(s.bakeArgs.size() % 2, 0u);
        std::set<std::string> flags;
        for (size_t i = 0; i < s.bakeArgs.size(); i += 2) {
            EXPECT_TRUE(s.bakeArgs[i].starts_with("--"));
            EXPECT_TRUE(flags.insert(s.bakeArgs[i]).second);
        }
        // Chroma never has more bands than luma.
        const std::string y = valueOf(s.bakeArgs, "--bands"), c = valueOf(s.bakeArgs, "--chroma-bands");
        EXPECT_LE(c.empty() ? 2 : std::stoi(c), y.empty() ? 3 : std::stoi(y));
        // A setting is the default but for its own axis (the diagonal moves them all).
        if (s.axis != "diagonal" && s.axis != "lY") {
            EXPECT_LE(s.bakeArgs.size(), 2u);
        }
    }
    for (const char* axis : {"default", "nS", "nL", "lY", "lC", "link form", "grid cell", "texel",
                             "link samples", "visibility", "diagonal"})
        EXPECT_TRUE(axes.count(axis)) << axis;
    // The visibility point bakes the default and times the shadow maps.
    auto maps = std::find_if(grid->begin(), grid->end(), [](const SweepSetting& s) { return s.axis == "visibility"; });
    ASSERT_NE(maps, grid->end());
    EXPECT_EQ(maps->visibility, "shadow-maps");
    EXPECT_TRUE(maps->bakeArgs.empty());
    EXPECT_NE(maps->key(), grid->front().key());
}

TEST(SweepGrid, FineHasMorePointsAndUnknownGridsAreRefused) {
    auto coarse = pic::sweepGrid("coarse", cornellLike());
    auto fine = pic::sweepGrid("fine", cornellLike());
    ASSERT_TRUE(coarse && fine);
    EXPECT_GT(fine->size(), coarse->size());
    auto bad = pic::sweepGrid("medium", cornellLike());
    ASSERT_FALSE(bad);
    EXPECT_EQ(bad.error().code, pic::ErrorCode::InvalidInput);
    EXPECT_NE(bad.error().message.find("medium"), std::string::npos);
}

TEST(SweepGrid, KeysNameTheFlags) {
    SweepSetting s{"nL 32", "nL", {"--links", "32", "--grid-cell", "0.25"}, "rays"};
    EXPECT_EQ(s.key(), "links32_grid-cell0.25");
    s.visibility = "shadow-maps";
    EXPECT_EQ(s.key(), "links32_grid-cell0.25_shadow-maps");
    EXPECT_EQ((SweepSetting{"default", "default", {}, "rays"}.key()), "default");
}

TEST(SweepFlags, OverridesReplaceTheBaseFlagsOfTheSameName) {
    const std::vector<std::string> base{"--surfels", "2048", "--links", "32"};
    EXPECT_EQ(pic::mergeFlags(base, {}), base);
    EXPECT_EQ(pic::mergeFlags(base, {"--links", "8"}),
              (std::vector<std::string>{"--surfels", "2048", "--links", "8"}));
    EXPECT_EQ(pic::mergeFlags(base, {"--bands", "2"}),
              (std::vector<std::string>{"--surfels", "2048", "--links", "32", "--bands", "2"}));
}

}  // namespace
