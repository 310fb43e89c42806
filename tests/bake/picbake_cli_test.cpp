// The picbake command line as users and scripts call it (ARCHITECTURE.md §5).

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "tests/support/baked_scene.h"
#include "tests/support/command.h"

namespace {

namespace fs = std::filesystem;
namespace test = pic::test;

class PicbakeCli : public ::testing::Test {
protected:
    test::CommandResult run(const std::string& args) {
        return test::runCommand(std::string(PIC_PICBAKE) + " --quiet " + args, mDir.path());
    }

    std::string scene(const std::string& name) const { return test::testScenePath(name); }

    std::string smallBake(const std::string& name, const std::string& out) {
        return "bake " + scene(name) + " -o " + out +
               " --surfels 4096 --links 32 --grid-cell 0.25 --lightmap-texel 0.1";
    }

    test::ScratchDir mDir{"picbake_cli"};
};

TEST_F(PicbakeCli, BakeThenInfoJsonHasTheContractKeys) {
    std::string bake = (mDir / "cornell.pic").string();
    test::CommandResult baked = run(smallBake("cornell", bake));
    ASSERT_EQ(baked.exitCode, 0) << baked.err;
    EXPECT_NE(baked.out.find("surfels"), std::string::npos);
    EXPECT_NE(baked.out.find("seconds"), std::string::npos);
    test::CommandResult info = run("info " + bake + " --json");
    ASSERT_EQ(info.exitCode, 0) << info.err;
    auto json = nlohmann::json::parse(info.out);
    for (const char* key : {"format_version", "scene_hash", "surfels", "nodes", "caches",
                            "links_per_cache", "link_mode", "bands", "bytes", "seconds"})
        EXPECT_TRUE(json.contains(key)) << key;
    EXPECT_EQ(json["surfels"], 4096);
    EXPECT_EQ(json["nodes"], 2 * 4096 - 1);
    EXPECT_EQ(json["links_per_cache"], 32);
    EXPECT_EQ(json["link_mode"], "rtp");
    EXPECT_TRUE(json["caches"].contains("grid") && json["caches"].contains("lightmap") &&
                json["caches"].contains("unique"));
    EXPECT_GT(json["caches"]["unique"].get<int>(), 0);
    EXPECT_TRUE(json["bands"].contains("y") && json["bands"].contains("c"));
    EXPECT_TRUE(json["seconds"].contains("links"));
    EXPECT_TRUE(json["bytes"].contains("surfels"));
    // Every cornell surface is light-mapped, so by default no grid cache is kept.
    EXPECT_EQ(json["caches"]["grid"], 0);
    EXPECT_EQ(json["params"]["grid_caches"], "surfaces");
    EXPECT_NE(baked.out.find("that only dynamic objects would read left out"), std::string::npos) << baked.out;

    test::CommandResult volume = run(smallBake("cornell", bake) + " --grid-caches volume");
    ASSERT_EQ(volume.exitCode, 0) << volume.err;
    info = run("info " + bake + " --json");
    json = nlohmann::json::parse(info.out);
    EXPECT_GT(json["caches"]["grid"].get<int>(), 0);
    EXPECT_EQ(json["params"]["grid_caches"], "volume");
    EXPECT_NE(run(smallBake("cornell", bake) + " --grid-caches everywhere").exitCode, 0);
}

TEST_F(PicbakeCli, TooFewSurfelsForTheSurfacesIsANote) {
    // 64 surfels of 18 cm radius overhang cornell's boxes: the bake keeps the count it was
    // given, prints the share of the discs on their surfaces and says what it costs.
    const std::string bake = (mDir / "coarse.pic").string();
    test::CommandResult coarse =
        run("bake " + scene("cornell") + " -o " + bake + " --surfels 64 --links 8");
    ASSERT_EQ(coarse.exitCode, 0) << coarse.err;
    EXPECT_NE(coarse.out.find("surfel discs"), std::string::npos) << coarse.out;
    EXPECT_NE(coarse.err.find("note: only 0."), std::string::npos) << coarse.err;
    test::CommandResult fine = run(smallBake("cornell", bake));
    ASSERT_EQ(fine.exitCode, 0) << fine.err;
    EXPECT_EQ(fine.err.find("note: only"), std::string::npos) << fine.err;
}

TEST_F(PicbakeCli, SameSceneFlagsAndSeedGiveAByteIdenticalFile) {
    std::string a = (mDir / "a.pic").string(), b = (mDir / "b.pic").string();
    ASSERT_EQ(run(smallBake("cornell", a) + " --seed 5").exitCode, 0);
    ASSERT_EQ(run(smallBake("cornell", b) + " --seed 5 --threads 1").exitCode, 0);
    EXPECT_EQ(test::readFile(a), test::readFile(b));
    std::string c = (mDir / "c.pic").string();
    ASSERT_EQ(run(smallBake("cornell", c) + " --seed 6").exitCode, 0);
    EXPECT_NE(test::readFile(a), test::readFile(c));
}

TEST_F(PicbakeCli, ShLinkModeBakes) {
    std::string bake = (mDir / "sh.pic").string();
    test::CommandResult r =
        run(smallBake("cornell", bake) + " --link-mode sh --bands 4 --chroma-bands 3");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    auto json = nlohmann::json::parse(run("info " + bake + " --json").out);
    EXPECT_EQ(json["link_mode"], "sh");
    EXPECT_EQ(json["bands"]["y"], 4);
    EXPECT_EQ(json["bands"]["c"], 3);
}

TEST_F(PicbakeCli, TruncatedBakeIsACleanErrorWithExitCode2) {
    std::string bake = (mDir / "t.pic").string();
    ASSERT_EQ(run(smallBake("cornell", bake)).exitCode, 0);
    std::string bytes = test::readFile(bake);
    std::ofstream(bake, std::ios::binary | std::ios::trunc).write(bytes.data(), bytes.size() / 2);
    test::CommandResult r = run("info " + bake);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("truncated"), std::string::npos) << r.err;
}

TEST_F(PicbakeCli, CorruptedBakeIsACleanErrorWithExitCode2) {
    std::string bake = (mDir / "c.pic").string();
    ASSERT_EQ(run(smallBake("cornell", bake)).exitCode, 0);
    std::string bytes = test::readFile(bake);
    bytes[bytes.size() * 3 / 4] ^= 0x5A;
    std::ofstream(bake, std::ios::binary | std::ios::trunc).write(bytes.data(), bytes.size());
    test::CommandResult r = run("info " + bake);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("checksum"), std::string::npos) << r.err;
}

TEST_F(PicbakeCli, MissingFilesAreCleanErrorsWithExitCode2) {
    test::CommandResult info = run("info " + (mDir / "nope.pic").string());
    EXPECT_EQ(info.exitCode, 2);
    EXPECT_NE(info.err.find("nope.pic"), std::string::npos) << info.err;
    test::CommandResult bake =
        run("bake " + (mDir / "nope.gltf").string() + " -o " + (mDir / "x.pic").string());
    EXPECT_EQ(bake.exitCode, 2);
    EXPECT_NE(bake.err.find("nope.gltf"), std::string::npos) << bake.err;
}

TEST_F(PicbakeCli, NonTriangleGltfIsRefusedWithExitCode2) {
    test::CommandResult r = run("bake " + scene("bad_points") + " -o " + (mDir / "p.pic").string());
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("POINTS"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(mDir / "p.pic"));
}

TEST_F(PicbakeCli, GltfWithoutGeometryIsRefusedWithExitCode2) {
    test::CommandResult r = run("bake " + scene("bad_empty") + " -o " + (mDir / "e.pic").string());
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("no triangle"), std::string::npos) << r.err;
}

TEST_F(PicbakeCli, BadUsageExitsWith2) {
    EXPECT_EQ(run("bake").exitCode, 2);
    EXPECT_EQ(run("bake " + scene("cornell") + " -o x.pic --no-such-flag").exitCode, 2);
    test::CommandResult r = run(smallBake("cornell", (mDir / "x.pic").string()) + " --bands 12");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("12"), std::string::npos) << r.err;
}

TEST_F(PicbakeCli, TargetErrorPrintsItsChoiceAndInfoShowsIt) {
    const std::string bake = (mDir / "target.pic").string();
    const fs::path cache = mDir / "pilot_cache";
    test::CommandResult baked = run("bake " + scene("cornell") + " -o " + bake +
                                    " --surfels 2048 --links 32 --grid-cell 0.125 --lightmap-texel 0.06 --target-error 0.6 "
                                    "--pilot-size 32x24 "
                                    "--pilot-spp 32 --pilot-cache " + cache.string());
    ASSERT_EQ(baked.exitCode, 0) << baked.err;
    EXPECT_NE(baked.out.find("chose           '"), std::string::npos) << baked.out;
    EXPECT_NE(baked.out.find("combinations ranked"), std::string::npos) << baked.out;
    test::CommandResult info = run("info --json " + bake);
    ASSERT_EQ(info.exitCode, 0) << info.err;
    const nlohmann::json json = nlohmann::json::parse(info.out);
    const nlohmann::json& target = json.at("target");
    EXPECT_EQ(target.at("error").get<double>(), 0.6);
    EXPECT_EQ(target.at("met"), true);
    EXPECT_LE(target.at("predicted_error").get<double>(), 0.95 * 0.6);
    EXPECT_NE(target.at("chosen"), "base") << "a loose target buys a cheaper bake than the base";
    EXPECT_LT(json.at("links_per_cache").get<int>() * json.at("surfels").get<int>(), 32 * 2048);
    EXPECT_GT(target.at("pilot").at("reference_noise").get<double>(), 0.0);
    // The pilot's measurements stay where --pilot-cache says, and nowhere else.
    EXPECT_EQ(target.at("pilot").at("cache").get<std::string>().rfind(cache.string(), 0), 0u);
    EXPECT_TRUE(fs::exists(target.at("pilot").at("cache").get<std::string>()));
    // Baking the same file again without a target leaves no stale prediction behind.
    ASSERT_EQ(run(smallBake("cornell", bake)).exitCode, 0);
    EXPECT_FALSE(nlohmann::json::parse(run("info --json " + bake).out).contains("target"));
}

TEST_F(PicbakeCli, TargetErrorFlagsAreChecked) {
    const std::string out = (mDir / "x.pic").string();
    test::CommandResult r = run("bake " + scene("cornell") + " -o " + out + " --budget-ms 5");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("--budget-ms needs --target-error"), std::string::npos) << r.err;
    r = run("bake " + scene("cornell") + " -o " + out + " --target-error -1");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("-1"), std::string::npos) << r.err;
    r = run("bake " + scene("cornell") + " -o " + out + " --target-error 0.1 --budget-ms fast");
    EXPECT_EQ(r.exitCode, 2);
    r = run("bake " + scene("cornell") + " -o " + out + " --target-error 0.1 --pilot-size 0x9");
    EXPECT_EQ(r.exitCode, 2);
    r = run("bake " + scene("cornell") + " -o " + out + " --target-error 0.1 --pilot-camera 1,2,3");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("--pilot-camera"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
}

TEST_F(PicbakeCli, ShardedBakeMergesIntoTheUnshardedFileByteForByte) {
    // cornell is open at the front, so some caches see no surface and the merge drops them.
    for (const std::string mode : {"rtp", "sh"}) {
        SCOPED_TRACE(mode);
        const std::string flags = " --link-mode " + mode + " --seed 3";
        const std::string whole = (mDir / ("whole_" + mode + ".pic")).string();
        ASSERT_EQ(run(smallBake("cornell", whole) + flags).exitCode, 0);
        std::vector<std::string> parts;
        for (int i = 0; i < 3; ++i) {
            parts.push_back((mDir / fmt::format("{}_part{}.pic", mode, i)).string());
            // One part on one thread: the split of the work between threads changes nothing.
            test::CommandResult r = run(smallBake("cornell", parts.back()) + flags +
                                        fmt::format(" --shard {}/3", i) + (i == 1 ? " --threads 1" : ""));
            ASSERT_EQ(r.exitCode, 0) << r.err;
            EXPECT_NE(r.out.find(fmt::format("pic bake part {}/3", i)), std::string::npos) << r.out;
            EXPECT_TRUE(fs::exists(parts.back() + ".timings.json"));
        }
        // A part holds a third of the links, not all of them.
        EXPECT_LT(fs::file_size(parts[0]), fs::file_size(whole));
        const std::string merged = (mDir / ("merged_" + mode + ".pic")).string();
        test::CommandResult r = run("merge " + parts[2] + " " + parts[0] + " " + parts[1] + " -o " + merged);
        ASSERT_EQ(r.exitCode, 0) << r.err;
        EXPECT_NE(r.out.find("pic merge: 3 parts"), std::string::npos) << r.out;
        EXPECT_EQ(test::readFile(merged), test::readFile(whole));
        EXPECT_EQ(run("info " + merged).exitCode, 0);
    }
    // More shards than some have caches to link, and one shard alone, still give the same file.
    const std::string whole = (mDir / "whole_rtp.pic").string();
    const std::string single = (mDir / "single.pic").string(), merged = (mDir / "merged_single.pic").string();
    ASSERT_EQ(run(smallBake("cornell", single) + " --link-mode rtp --seed 3 --shard 0/1").exitCode, 0);
    ASSERT_EQ(run("merge " + single + " -o " + merged).exitCode, 0);
    EXPECT_EQ(test::readFile(merged), test::readFile(whole));
}

TEST_F(PicbakeCli, MergeRefusesMissingRepeatedAndForeignPartsWithExitCode2) {
    std::vector<std::string> parts;
    for (int i = 0; i < 3; ++i) {
        parts.push_back((mDir / fmt::format("p{}.pic", i)).string());
        ASSERT_EQ(run(smallBake("cornell", parts.back()) + fmt::format(" --shard {}/3", i)).exitCode, 0);
    }
    const std::string out = (mDir / "out.pic").string();
    test::CommandResult r = run("merge " + parts[0] + " " + parts[2] + " -o " + out);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("shard 1 of 3 missing"), std::string::npos) << r.err;
    r = run("merge " + parts[0] + " " + parts[1] + " " + parts[1] + " " + parts[2] + " -o " + out);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("both shard 1 of 3"), std::string::npos) << r.err;

    // A part of a bake with another seed, or of a split two ways, is not one of these.
    const std::string otherSeed = (mDir / "seed.pic").string(), halves = (mDir / "half.pic").string();
    ASSERT_EQ(run(smallBake("cornell", otherSeed) + " --seed 9 --shard 1/3").exitCode, 0);
    r = run("merge " + parts[0] + " " + otherSeed + " " + parts[2] + " -o " + out);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("parts of different bakes"), std::string::npos) << r.err;
    ASSERT_EQ(run(smallBake("cornell", halves) + " --shard 1/2").exitCode, 0);
    r = run("merge " + parts[0] + " " + halves + " -o " + out);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("is shard 1 of 2"), std::string::npos) << r.err;

    // A whole bake is no part, and a part no bake.
    const std::string whole = (mDir / "whole.pic").string();
    ASSERT_EQ(run(smallBake("cornell", whole)).exitCode, 0);
    r = run("merge " + whole + " -o " + out);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("is a whole bake, not a part"), std::string::npos) << r.err;
    r = run("info " + parts[0]);
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("picbake merge"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
}

TEST_F(PicbakeCli, ShardFlagIsChecked) {
    const std::string out = (mDir / "x.pic").string();
    for (const std::string bad : {"3/3", "1/0", "a/3", "1", "1/", "/3", "1/4097", "0/3x"}) {
        test::CommandResult r = run(smallBake("cornell", out) + " --shard " + bad);
        EXPECT_EQ(r.exitCode, 2) << bad;
        EXPECT_NE(r.err.find("--shard " + bad), std::string::npos) << r.err;
    }
    test::CommandResult r = run("bake " + scene("cornell") + " -o " + out + " --target-error 0.1 --shard 0/2");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("--shard cannot be combined with --target-error"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
}

}  // namespace
