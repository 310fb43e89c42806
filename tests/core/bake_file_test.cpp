#include "core/bake_file.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <set>

#include <gtest/gtest.h>
#include <unistd.h>

#include "core/color.h"
#include "core/hash.h"
#include "core/sh.h"
#include "core/sky.h"

namespace pic {
namespace {

namespace fs = std::filesystem;

constexpr std::string_view kAllSections[] = {
    "params",       "surfels",      "surfel_weights", "nodes",          "levels",
    "caches",       "grid",         "grid_index",     "lightmap",       "lightmap_index",
    "lightmap_uvs", "links",        "links_rtp",      "links_sh_nodes", "links_sh_coeffs",
    "links_tint",   "links_offset", "links_spread_share", "surfel_sky",   "cache_sky",
};

/// A hand-made bake: 4 surfels under a balanced hierarchy of 7 nodes, 2 grid caches and 1
/// light-map cache, 2 links per cache in `mode`.
BakeData makeBake(LinkMode mode) {
    BakeData bake;
    bake.params = {.surfels = 4,
                   .linksPerCache = 2,
                   .bandsY = 3,
                   .bandsC = 2,
                   .gridCell = 0.25f,
                   .lightmapTexel = 0.1f,
                   .linkMode = mode,
                   .hierarchy = HierarchyMethod::KdTree,
                   .linkSamples = 8,
                   .linkFinalSamples = 24,
                   .skyRays = 16,
                   .relaxIterations = 3,
                   .seed = 0x123456789ABCDEF0ull};
    bake.sceneHash = 0xFEEDFACE12345678ull;
    bake.defaults = {{"grid_cell", "2 × mean surfel spacing"}, {"surfels", "scene area / 0.01 m²"}};

    const float area = 0.125f;
    for (uint32_t i = 0; i < 4; ++i) {
        Surfel s{};
        s.position = {0.5f * i, 1.0f, -0.25f * i};
        s.area = area;
        s.normal = {0.0f, 1.0f, 0.0f};
        s.material = i % 2;
        s.albedo = {0.1f * i, 0.5f, 0.9f};
        s.radius = std::sqrt(area / 3.14159265f);
        s.emission = {i == 3 ? 2.0f : 0.0f, 0.0f, 0.0f};
        s.triangle = i / 2;
        bake.surfels.push_back(s);
    }
    // Leaves 0-3, inner nodes 4 = (0, 1) and 5 = (2, 3), root 6 = (4, 5).
    const auto node = [](uint32_t left, uint32_t right, uint32_t parent, uint32_t first,
                         uint32_t count, uint32_t level) {
        Node n{};
        n.center = {0.1f * first, 1.0f, 0.2f * count};
        n.area = 0.125f * count;
        n.normal = {0.0f, 1.0f, 0.0f};
        n.radius = 0.3f * count;
        n.left = left;
        n.right = right;
        n.parent = parent;
        n.firstSurfel = first;
        n.surfelCount = count;
        n.level = level;
        return n;
    };
    bake.nodes = {node(kNoNode, kNoNode, 4, 0, 1, 0),
                  node(kNoNode, kNoNode, 4, 1, 1, 0),
                  node(kNoNode, kNoNode, 5, 2, 1, 0),
                  node(kNoNode, kNoNode, 5, 3, 1, 0),
                  node(0, 1, 6, 0, 2, 1),
                  node(2, 3, 6, 2, 2, 1),
                  node(4, 5, kNoNode, 0, 4, 2)};
    bake.levelOffsets = {4, 6, 7};

    bake.caches = {{{-1.0f, 0.0f, -1.0f}, gpu::kCacheKindGrid, {0.0f, 0.0f, 0.0f}, 0},
                   {{-0.75f, 0.25f, -1.0f}, gpu::kCacheKindGrid, {0.0f, 0.0f, 0.0f}, 5},
                   {{0.3f, 1.0f, 0.1f}, gpu::kCacheKindLightmap, {0.0f, 1.0f, 0.0f}, 2}};

    bake.grid.origin = {-1.0f, 0.0f, -1.0f};
    bake.grid.cellSize = 0.25f;
    bake.grid.dims = {2, 2, 2};
    bake.grid.cacheIndex = {0, kNoCache, kNoCache, kNoCache, kNoCache, 1, kNoCache, kNoCache};

    bake.lightmap.width = 4;
    bake.lightmap.height = 2;
    bake.lightmap.texelSize = 0.1f;
    bake.lightmap.cacheIndex = {kNoCache, kNoCache, 2,        kNoCache,
                                kNoCache, kNoCache, kNoCache, kNoCache};
    bake.lightmap.triangleUvs = {{0.0f, 0.0f}, {0.5f, 0.0f}, {0.0f, 0.5f},
                                 {0.5f, 0.5f}, {1.0f, 0.5f}, {0.5f, 1.0f}};
    bake.lightmap.chartCount = 1;

    const uint32_t nLinks = 3 * 2;
    bake.links.mode = mode;
    bake.links.linksPerCache = 2;
    if (mode == LinkMode::Rtp) {
        for (uint32_t i = 0; i < nLinks; ++i)
            bake.links.rtp.push_back({(3 * i) % 7, 0.01f * (i + 1), 0x7FFF0000u + i, 0.02f * i});
        bake.links.rtp.back() = {kNoNode, 0.0f, 0, 0.0f};  // padding
    } else {
        bake.links.bands = 3;
        for (uint32_t i = 0; i < nLinks; ++i) bake.links.shNodes.push_back((2 * i + 1) % 7);
        bake.links.shNodes.back() = kNoNode;  // padding
        for (uint32_t i = 0; i < nLinks * 9; ++i)
            bake.links.shCoefficients.push_back(static_cast<uint16_t>(0x3C00 + 37 * i));
    }
    for (uint32_t i = 0; i < nLinks; ++i) bake.links.tint.push_back(kNeutralLinkTint - 1025 * i);
    for (uint32_t i = 0; i < nLinks * 3; ++i)
        bake.links.offset.push_back(floatToHalf(0.125f * float(i) - 1.0f));
    for (uint32_t i = 0; i < nLinks; ++i) bake.links.spreadShare.push_back(encodeSpreadShare(0.2f * float(i)));
    bake.surfelWeights = {0.5f, 1.0f, 2.0f, 1.25f};
    for (uint32_t i = 0; i < 4 * kSkyCoefficients; ++i) bake.surfelSky.push_back(0.03f * i - 0.5f);
    const uint32_t visibility = shCount(skyVisibilityBands(3));
    for (uint32_t i = 0; i < 3 * visibility; ++i) bake.cacheSky.push_back(1.0f - 0.01f * i);
    return bake;
}

/// Compares two arrays of records byte for byte, i.e. every field bit-exactly.
template <class T>
void expectSameRecords(const std::vector<T>& a, const std::vector<T>& b, const char* name) {
    SCOPED_TRACE(name);
    ASSERT_EQ(a.size(), b.size());
    if (!a.empty()) {
        EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(T)), 0);
    }
}

void expectSameBake(const BakeData& a, const BakeData& b) {
    EXPECT_EQ(a.params.surfels, b.params.surfels);
    EXPECT_EQ(a.params.linksPerCache, b.params.linksPerCache);
    EXPECT_EQ(a.params.bandsY, b.params.bandsY);
    EXPECT_EQ(a.params.bandsC, b.params.bandsC);
    EXPECT_EQ(a.params.gridCell, b.params.gridCell);
    EXPECT_EQ(a.params.lightmapTexel, b.params.lightmapTexel);
    EXPECT_EQ(a.params.linkMode, b.params.linkMode);
    EXPECT_EQ(a.params.hierarchy, b.params.hierarchy);
    EXPECT_EQ(a.params.linkSamples, b.params.linkSamples);
    EXPECT_EQ(a.params.linkFinalSamples, b.params.linkFinalSamples);
    EXPECT_EQ(a.params.relaxIterations, b.params.relaxIterations);
    EXPECT_EQ(a.params.skyRays, b.params.skyRays);
    EXPECT_EQ(a.params.seed, b.params.seed);
    EXPECT_EQ(a.sceneHash, b.sceneHash);
    EXPECT_EQ(a.defaults, b.defaults);
    expectSameRecords(a.surfels, b.surfels, "surfels");
    expectSameRecords(a.nodes, b.nodes, "nodes");
    EXPECT_EQ(a.levelOffsets, b.levelOffsets);
    expectSameRecords(a.caches, b.caches, "caches");
    EXPECT_EQ(a.grid.origin, b.grid.origin);
    EXPECT_EQ(a.grid.cellSize, b.grid.cellSize);
    EXPECT_EQ(a.grid.dims, b.grid.dims);
    EXPECT_EQ(a.grid.cacheIndex, b.grid.cacheIndex);
    EXPECT_EQ(a.lightmap.width, b.lightmap.width);
    EXPECT_EQ(a.lightmap.height, b.lightmap.height);
    EXPECT_EQ(a.lightmap.texelSize, b.lightmap.texelSize);
    EXPECT_EQ(a.lightmap.cacheIndex, b.lightmap.cacheIndex);
    EXPECT_EQ(a.lightmap.triangleUvs, b.lightmap.triangleUvs);
    EXPECT_EQ(a.lightmap.chartCount, b.lightmap.chartCount);
    EXPECT_EQ(a.links.mode, b.links.mode);
    EXPECT_EQ(a.links.linksPerCache, b.links.linksPerCache);
    EXPECT_EQ(a.links.bands, b.links.bands);
    expectSameRecords(a.links.rtp, b.links.rtp, "links.rtp");
    EXPECT_EQ(a.links.shNodes, b.links.shNodes);
    EXPECT_EQ(a.links.shCoefficients, b.links.shCoefficients);
    EXPECT_EQ(a.links.tint, b.links.tint);
    EXPECT_EQ(a.links.offset, b.links.offset);
    EXPECT_EQ(a.links.spreadShare, b.links.spreadShare);
    EXPECT_EQ(a.surfelWeights, b.surfelWeights);
    EXPECT_EQ(a.surfelSky, b.surfelSky);
    EXPECT_EQ(a.cacheSky, b.cacheSky);
}

std::vector<char> readBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeBytes(const std::string& path, const std::vector<char>& bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

uint64_t alignUp(uint64_t offset) {
    return (offset + kBakeSectionAlignment - 1) / kBakeSectionAlignment * kBakeSectionAlignment;
}

/// Where each section starts, derived from the documented layout and the reported sizes.
std::vector<uint64_t> sectionOffsets(const BakeFileInfo& info) {
    std::vector<uint64_t> offsets;
    uint64_t end = kBakeHeaderBytes + info.sectionBytes.size() * kBakeSectionEntryBytes;
    for (const auto& [name, size] : info.sectionBytes) {
        offsets.push_back(alignUp(end));
        end = offsets.back() + size;
    }
    return offsets;
}

template <class T>
T load(const std::vector<char>& bytes, uint64_t offset) {
    T value;
    std::memcpy(&value, bytes.data() + offset, sizeof(T));
    return value;
}

template <class T>
void store(std::vector<char>& bytes, uint64_t offset, T value) {
    std::memcpy(bytes.data() + offset, &value, sizeof(T));
}

/// Recomputes the checksums of section `index`, of the table and of the header, as a writer
/// following the documented layout would.
void resealSection(std::vector<char>& bytes, size_t index) {
    const uint64_t entry = kBakeHeaderBytes + index * kBakeSectionEntryBytes;
    const auto offset = load<uint64_t>(bytes, entry + 24);
    const auto size = load<uint64_t>(bytes, entry + 32);
    store(bytes, entry + 40, hashBytes(bytes.data() + offset, size));
    const auto sectionCount = load<uint32_t>(bytes, 12);
    store(bytes, 32,
          hashBytes(bytes.data() + kBakeHeaderBytes, sectionCount * kBakeSectionEntryBytes));
    store(bytes, 40, hashBytes(bytes.data(), 40));
}

/// The error of a result that must have failed.
template <class T>
Error errorOf(const Result<T>& result) {
    if (result) {
        ADD_FAILURE() << "expected an error";
        return {};
    }
    return result.error();
}

bool contains(const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
}

/// A fresh directory per test.
class BakeFile : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
        mDir = fs::temp_directory_path() /
               fmt::format("pic_bake_file_test_{}_{}", ::getpid(), test->name());
        fs::remove_all(mDir);
        fs::create_directories(mDir);
    }
    void TearDown() override { fs::remove_all(mDir); }

    std::string path(const std::string& name) const { return (mDir / name).string(); }

    std::vector<std::string> filesInDir() const {
        std::vector<std::string> names;
        for (const auto& entry : fs::directory_iterator(mDir))
            names.push_back(entry.path().filename().string());
        std::ranges::sort(names);
        return names;
    }

    /// Writes `bake` and returns the file's path and bytes.
    std::pair<std::string, std::vector<char>> written(const BakeData& bake,
                                                      const std::string& name = "bake.pic") {
        const std::string file = path(name);
        const Result<void> ok = writeBakeFile(file, bake);
        EXPECT_TRUE(ok) << ok.error().message;
        return {file, readBytes(file)};
    }

    /// Writes `bake`, blanks `field` of its params out (JSON whitespace keeps the section's
    /// size: a file written before the field existed) and reads the file back.
    Result<BakeData> readWithout(const BakeData& bake, const std::string& field) {
        auto [file, bytes] = written(bake);
        const std::string text(bytes.begin(), bytes.end());
        const size_t at = text.find(field);
        if (at == std::string::npos) return fail(ErrorCode::InvalidInput, "no {} in the params", field);
        std::fill(bytes.begin() + at, bytes.begin() + at + field.size(), ' ');
        resealSection(bytes, 0);
        writeBytes(file, bytes);
        return readBakeFile(file);
    }

    fs::path mDir;
};

TEST_F(BakeFile, RoundTripsRtpBakeExactly) {
    const BakeData bake = makeBake(LinkMode::Rtp);
    const auto [file, bytes] = written(bake);
    const Result<BakeData> read = readBakeFile(file);
    ASSERT_TRUE(read) << read.error().message;
    expectSameBake(bake, *read);
}

TEST_F(BakeFile, RoundTripsShBakeExactly) {
    const BakeData bake = makeBake(LinkMode::Sh);
    const auto [file, bytes] = written(bake);
    const Result<BakeData> read = readBakeFile(file);
    ASSERT_TRUE(read) << read.error().message;
    expectSameBake(bake, *read);
}

TEST_F(BakeFile, RoundTripsEmptyBake) {
    const BakeData bake;
    const auto [file, bytes] = written(bake);
    const Result<BakeData> read = readBakeFile(file);
    ASSERT_TRUE(read) << read.error().message;
    expectSameBake(bake, *read);
}

TEST_F(BakeFile, ParamFloatsRoundTripExactly) {
    const float values[] = {0.1f,
                            std::nextafter(0.3f, 1.0f),
                            std::numeric_limits<float>::min(),
                            std::numeric_limits<float>::denorm_min(),
                            std::numeric_limits<float>::max(),
                            16777217.0f,
                            1.0f / 3.0f};
    for (const float value : values) {
        SCOPED_TRACE(value);
        BakeData bake = makeBake(LinkMode::Rtp);
        bake.params.gridCell = value;
        bake.params.lightmapTexel = std::nextafter(value, 0.0f);
        const auto [file, bytes] = written(bake);
        const Result<BakeData> read = readBakeFile(file);
        ASSERT_TRUE(read) << read.error().message;
        EXPECT_EQ(std::bit_cast<uint32_t>(read->params.gridCell), std::bit_cast<uint32_t>(value));
        EXPECT_EQ(std::bit_cast<uint32_t>(read->params.lightmapTexel),
                  std::bit_cast<uint32_t>(bake.params.lightmapTexel));
    }
}

TEST_F(BakeFile, ParamsUseReadableNames) {
    const auto [file, bytes] = written(makeBake(LinkMode::Sh));
    const std::string text(bytes.begin(), bytes.end());
    EXPECT_TRUE(contains(text, R"("link_mode": "sh")"));
    EXPECT_TRUE(contains(text, R"("hierarchy": "kdtree")"));
    EXPECT_TRUE(contains(text, R"("grid_cell": "2 × mean surfel spacing")"));
    EXPECT_TRUE(contains(text, R"("lightmap_texel": 0.1,)"));
}

TEST_F(BakeFile, ParamsWithoutFinalLinkSamplesReadThemAsLinkSamples) {
    // Bakes written before "link_final_samples" existed re-estimated linked nodes with
    // link_samples rays.
    const Result<BakeData> read = readWithout(makeBake(LinkMode::Rtp), R"("link_final_samples": 24,)");
    ASSERT_TRUE(read) << read.error().message;
    EXPECT_EQ(read->params.linkSamples, 8u);
    EXPECT_EQ(read->params.linkFinalSamples, 8u);
}

TEST_F(BakeFile, ParamsWithoutALinkCutReadAsTheSolidAngleCut) {
    // The link cut round-trips by name, and bakes written before "link_cut" existed refined
    // their cuts by solid angle: a file without the field (blanked out as above) reads so.
    BakeData bake = makeBake(LinkMode::Rtp);
    for (const LinkCut cut : {LinkCut::SolidAngle, LinkCut::ErrorBound}) {
        bake.params.linkCut = cut;
        const auto [file, bytes] = written(bake);
        const Result<BakeData> read = readBakeFile(file);
        ASSERT_TRUE(read) << read.error().message;
        EXPECT_EQ(read->params.linkCut, cut);
    }
    const Result<BakeData> read = readWithout(bake, R"("link_cut": "error",)");
    ASSERT_TRUE(read) << read.error().message;
    EXPECT_EQ(read->params.linkCut, LinkCut::SolidAngle);
}

TEST_F(BakeFile, ParamsWithoutGridCachesReadAsTheVolume) {
    // Where grid caches go round-trips by name; bakes written before grid caches could be
    // limited to what surfaces read placed them in the whole volume.
    BakeData bake = makeBake(LinkMode::Rtp);
    for (const GridCaches mode : {GridCaches::Surfaces, GridCaches::Volume, GridCaches::Space}) {
        bake.params.gridCaches = mode;
        const auto [file, bytes] = written(bake);
        const Result<BakeData> read = readBakeFile(file);
        ASSERT_TRUE(read) << read.error().message;
        EXPECT_EQ(read->params.gridCaches, mode);
    }
    bake.params.gridCaches = GridCaches::Surfaces;
    const Result<BakeData> read = readWithout(bake, R"("grid_caches": "surfaces",)");
    ASSERT_TRUE(read) << read.error().message;
    EXPECT_EQ(read->params.gridCaches, GridCaches::Volume);
}

TEST_F(BakeFile, WritesByteIdenticalFiles) {
    const BakeData bake = makeBake(LinkMode::Sh);
    const auto [first, firstBytes] = written(bake, "a.pic");
    const auto [second, secondBytes] = written(bake, "b.pic");
    EXPECT_EQ(firstBytes, secondBytes);
    // Writing over an existing file replaces it with the same bytes.
    const auto [again, againBytes] = written(bake, "a.pic");
    EXPECT_EQ(firstBytes, againBytes);
    // A different bake gives different bytes.
    const auto [other, otherBytes] = written(makeBake(LinkMode::Rtp), "c.pic");
    EXPECT_NE(firstBytes, otherBytes);
}

TEST_F(BakeFile, InspectSectionSizesAddUpToFileSize) {
    const BakeData bake = makeBake(LinkMode::Rtp);
    const auto [file, bytes] = written(bake);
    const Result<BakeFileInfo> info = inspectBakeFile(file);
    ASSERT_TRUE(info) << info.error().message;
    EXPECT_EQ(info->fileSize, bytes.size());

    std::vector<std::string> names;
    for (const auto& [name, size] : info->sectionBytes) names.push_back(name);
    EXPECT_EQ(names, std::vector<std::string>(std::begin(kAllSections), std::end(kAllSections)));

    // Header, table, sections and the zero padding that aligns them make up the whole file.
    const std::vector<uint64_t> offsets = sectionOffsets(*info);
    uint64_t covered = kBakeHeaderBytes + info->sectionBytes.size() * kBakeSectionEntryBytes;
    for (size_t i = 0; i < offsets.size(); ++i) {
        EXPECT_EQ(offsets[i] % kBakeSectionAlignment, 0u);
        EXPECT_LT(offsets[i] - covered, kBakeSectionAlignment);
        for (uint64_t pad = covered; pad < offsets[i]; ++pad) EXPECT_EQ(bytes[pad], 0) << pad;
        covered = offsets[i] + info->sectionBytes[i].second;
    }
    EXPECT_EQ(covered, bytes.size());

    const std::map<std::string, uint64_t> sizes(info->sectionBytes.begin(),
                                                info->sectionBytes.end());
    EXPECT_EQ(sizes.at("surfels"), 4 * sizeof(Surfel));
    EXPECT_EQ(sizes.at("nodes"), 7 * sizeof(Node));
    EXPECT_EQ(sizes.at("links_rtp"), 6 * sizeof(RtpLink));
    EXPECT_EQ(sizes.at("links_sh_coeffs"), 0u);

    EXPECT_EQ(info->formatVersion, kBakeFormatVersion);
    EXPECT_EQ(info->sceneHash, bake.sceneHash);
    EXPECT_EQ(info->surfels, 4u);
    EXPECT_EQ(info->nodes, 7u);
    EXPECT_EQ(info->caches, 3u);
    EXPECT_EQ(info->gridCaches, 2u);
    EXPECT_EQ(info->lightmapCaches, 1u);
    EXPECT_EQ(info->linksPerCache, 2u);
    EXPECT_EQ(info->params.seed, bake.params.seed);
    EXPECT_EQ(info->params.linkMode, LinkMode::Rtp);
    EXPECT_EQ(info->defaults, bake.defaults);
}

TEST_F(BakeFile, TruncatedFileIsReportedAsTruncated) {
    const auto [file, bytes] = written(makeBake(LinkMode::Rtp));
    const Result<BakeFileInfo> info = inspectBakeFile(file);
    ASSERT_TRUE(info) << info.error().message;
    const uint64_t nodesOffset = sectionOffsets(*info)[3];
    ASSERT_EQ(info->sectionBytes[3].first, "nodes");

    const uint64_t cuts[] = {10,                                             // in the header
                             kBakeHeaderBytes + kBakeSectionEntryBytes + 5,  // in the table
                             nodesOffset + 100,                              // in a section
                             bytes.size() - 1};                              // last byte missing
    for (const uint64_t cut : cuts) {
        SCOPED_TRACE(cut);
        const std::string truncated = path("truncated.pic");
        writeBytes(truncated, std::vector<char>(bytes.begin(), bytes.begin() + cut));
        const Result<BakeData> read = readBakeFile(truncated);
        ASSERT_FALSE(read);
        EXPECT_EQ(read.error().code, ErrorCode::Corrupt);
        EXPECT_TRUE(contains(read.error().message, "truncated")) << read.error().message;
        EXPECT_TRUE(contains(read.error().message, std::to_string(cut))) << read.error().message;
        if (cut >= kBakeHeaderBytes) {
            EXPECT_TRUE(contains(read.error().message, std::to_string(bytes.size())))
                << read.error().message;
        }
        const Result<BakeFileInfo> inspected = inspectBakeFile(truncated);
        ASSERT_FALSE(inspected);
        EXPECT_EQ(inspected.error().message, read.error().message);
    }
}

TEST_F(BakeFile, FlippedByteNamesTheSection) {
    std::set<std::string> tested;
    for (const LinkMode mode : {LinkMode::Rtp, LinkMode::Sh}) {
        const auto [file, bytes] = written(makeBake(mode));
        const Result<BakeFileInfo> info = inspectBakeFile(file);
        ASSERT_TRUE(info) << info.error().message;
        const std::vector<uint64_t> offsets = sectionOffsets(*info);
        for (size_t i = 0; i < offsets.size(); ++i) {
            const auto& [name, size] = info->sectionBytes[i];
            if (size == 0) continue;
            SCOPED_TRACE(name);
            std::vector<char> damaged = bytes;
            damaged[offsets[i] + size / 2] ^= 0x10;
            const std::string damagedPath = path("damaged.pic");
            writeBytes(damagedPath, damaged);
            for (const Error& error :
                 {errorOf(readBakeFile(damagedPath)), errorOf(inspectBakeFile(damagedPath))}) {
                EXPECT_EQ(error.code, ErrorCode::Corrupt);
                EXPECT_TRUE(contains(error.message, "'" + name + "'")) << error.message;
                EXPECT_TRUE(contains(error.message, "checksum")) << error.message;
            }
            tested.insert(name);
        }
    }
    EXPECT_EQ(tested, std::set<std::string>(std::begin(kAllSections), std::end(kAllSections)));
}

TEST_F(BakeFile, FlippedHeaderOrTableByteIsRefused) {
    const auto [file, bytes] = written(makeBake(LinkMode::Rtp));
    const std::pair<uint64_t, const char*> cases[] = {
        {20, "header"},                                                     // scene hash
        {kBakeHeaderBytes + kBakeSectionEntryBytes + 26, "section table"},  // an offset
    };
    for (const auto& [offset, part] : cases) {
        std::vector<char> damaged = bytes;
        damaged[offset] ^= 0x01;
        writeBytes(path("damaged.pic"), damaged);
        const Result<BakeData> read = readBakeFile(path("damaged.pic"));
        ASSERT_FALSE(read);
        EXPECT_EQ(read.error().code, ErrorCode::Corrupt);
        EXPECT_TRUE(contains(read.error().message, part)) << read.error().message;
    }
}

TEST_F(BakeFile, WrongMagicIsNotABakeFile) {
    auto [file, bytes] = written(makeBake(LinkMode::Rtp));
    bytes[0] = 'Q';
    const std::vector<std::vector<char>> contents = {bytes, {}, {'P', 'I', 'C'}, {'h', 'i', '\n'}};
    for (const std::vector<char>& content : contents) {
        writeBytes(file, content);
        const Result<BakeData> read = readBakeFile(file);
        ASSERT_FALSE(read);
        EXPECT_EQ(read.error().code, ErrorCode::Corrupt);
        EXPECT_TRUE(contains(read.error().message, "not a pic bake file")) << read.error().message;
        EXPECT_TRUE(contains(read.error().message, file)) << read.error().message;
    }
}

TEST_F(BakeFile, WrongVersionNamesBothVersions) {
    auto [file, bytes] = written(makeBake(LinkMode::Rtp));
    store<uint32_t>(bytes, 8, kBakeFormatVersion + 1);
    writeBytes(file, bytes);
    for (const Error& error : {errorOf(readBakeFile(file)), errorOf(inspectBakeFile(file))}) {
        EXPECT_EQ(error.code, ErrorCode::Corrupt);
        EXPECT_TRUE(contains(error.message, fmt::format("version {}", kBakeFormatVersion + 1)))
            << error.message;
        EXPECT_TRUE(contains(error.message, fmt::format("version {}", kBakeFormatVersion)))
            << error.message;
    }
}

TEST_F(BakeFile, ResealedInconsistentCountsAreRefused) {
    // A file whose checksums are right but whose counts disagree: nL raised from 2 to 3 in the
    // "links" record, so nC·nL no longer matches the RTP links stored.
    auto [file, bytes] = written(makeBake(LinkMode::Rtp));
    const Result<BakeFileInfo> info = inspectBakeFile(file);
    ASSERT_TRUE(info) << info.error().message;
    const size_t links = 11;
    ASSERT_EQ(info->sectionBytes[links].first, "links");
    const uint64_t offset = sectionOffsets(*info)[links];
    ASSERT_EQ(load<uint32_t>(bytes, offset + 4), 2u);
    store<uint32_t>(bytes, offset + 4, 3);
    resealSection(bytes, links);
    writeBytes(file, bytes);
    const Result<BakeData> read = readBakeFile(file);
    ASSERT_FALSE(read);
    EXPECT_EQ(read.error().code, ErrorCode::Corrupt);
    EXPECT_TRUE(contains(read.error().message, "need 9 RTP links")) << read.error().message;

    // Resealing with the original value makes the file valid again.
    store<uint32_t>(bytes, offset + 4, 2);
    resealSection(bytes, links);
    writeBytes(file, bytes);
    EXPECT_TRUE(readBakeFile(file));
}

TEST_F(BakeFile, MissingFileIsNotFound) {
    const std::string missing = path("missing.pic");
    const Result<BakeData> read = readBakeFile(missing);
    ASSERT_FALSE(read);
    EXPECT_EQ(read.error().code, ErrorCode::NotFound);
    EXPECT_TRUE(contains(read.error().message, missing)) << read.error().message;
    const Result<BakeFileInfo> info = inspectBakeFile(missing);
    ASSERT_FALSE(info);
    EXPECT_EQ(info.error().code, ErrorCode::NotFound);
}

TEST_F(BakeFile, NoTempFileAfterSuccess) {
    written(makeBake(LinkMode::Rtp));
    EXPECT_EQ(filesInDir(), std::vector<std::string>{"bake.pic"});
}

TEST_F(BakeFile, FailedWriteIsIoErrorAndLeavesNoTempFile) {
    // Into a directory that does not exist: the temp file cannot even be created.
    const std::string noDir = path("no/such/dir/bake.pic");
    const Result<void> intoNowhere = writeBakeFile(noDir, makeBake(LinkMode::Rtp));
    ASSERT_FALSE(intoNowhere);
    EXPECT_EQ(intoNowhere.error().code, ErrorCode::Io);
    EXPECT_TRUE(contains(intoNowhere.error().message, noDir)) << intoNowhere.error().message;
    EXPECT_TRUE(contains(intoNowhere.error().message, "No such file or directory"))
        << intoNowhere.error().message;

    // Over a directory: the temp file is written, the rename fails, and the temp file goes.
    fs::create_directories(path("taken.pic/child"));
    const Result<void> overDir = writeBakeFile(path("taken.pic"), makeBake(LinkMode::Rtp));
    ASSERT_FALSE(overDir);
    EXPECT_EQ(overDir.error().code, ErrorCode::Io);
    EXPECT_TRUE(contains(overDir.error().message, path("taken.pic"))) << overDir.error().message;
    EXPECT_EQ(filesInDir(), std::vector<std::string>{"taken.pic"});
}

TEST_F(BakeFile, InconsistentBakeIsNotWritten) {
    BakeData missingNode = makeBake(LinkMode::Rtp);
    missingNode.nodes.pop_back();
    BakeData badGridIndex = makeBake(LinkMode::Rtp);
    badGridIndex.grid.cacheIndex[3] = 3;
    BakeData shortCoefficients = makeBake(LinkMode::Sh);
    shortCoefficients.links.shCoefficients.pop_back();
    BakeData badNodeChild = makeBake(LinkMode::Sh);
    badNodeChild.nodes[5].right = 7;
    BakeData badSurfelRange = makeBake(LinkMode::Rtp);
    badSurfelRange.nodes[6].surfelCount = 5;
    BakeData badLevels = makeBake(LinkMode::Rtp);
    badLevels.levelOffsets = {4, 7, 6};
    BakeData zeroArea = makeBake(LinkMode::Rtp);
    zeroArea.nodes[5].area = 0.0f;
    BakeData badCacheKind = makeBake(LinkMode::Rtp);
    badCacheKind.caches[1].kind = 2;
    BakeData badUvs = makeBake(LinkMode::Rtp);
    badUvs.lightmap.triangleUvs.pop_back();
    BakeData badRtpNode = makeBake(LinkMode::Rtp);
    badRtpNode.links.rtp[1].node = 9;
    BakeData shortTints = makeBake(LinkMode::Sh);
    shortTints.links.tint.pop_back();
    BakeData badTint = makeBake(LinkMode::Rtp);
    badTint.links.tint[4] = 0x40000000u;
    BakeData shortOffsets = makeBake(LinkMode::Rtp);
    shortOffsets.links.offset.pop_back();
    BakeData nanOffset = makeBake(LinkMode::Sh);
    nanOffset.links.offset[7] = 0x7E00u;
    BakeData shortShares = makeBake(LinkMode::Sh);
    shortShares.links.spreadShare.pop_back();
    BakeData badShare = makeBake(LinkMode::Rtp);
    badShare.links.spreadShare[3] = 64;
    BakeData zeroWeight = makeBake(LinkMode::Rtp);
    zeroWeight.surfelWeights[2] = 0.0f;
    BakeData missingWeights = makeBake(LinkMode::Sh);
    missingWeights.surfelWeights.clear();
    const std::pair<const BakeData*, const char*> cases[] = {
        {&missingNode, "2·nS − 1 = 7"},
        {&badGridIndex, "grid_index entry 3 refers to cache 3"},
        {&shortCoefficients, "found 6 SH nodes, 53 SH coefficients"},
        {&badNodeChild, "node 5 has right child 7"},
        {&badSurfelRange, "node 6 covers surfels [0, 5) but there are 4"},
        {&badLevels, "level offset 2 is 6"},
        {&zeroArea, "node 5 has area 0 m²"},
        {&badCacheKind, "cache 1 has kind 2"},
        {&badUvs, "5 light-map UVs"},
        {&badRtpNode, "RTP link 1 refers to node 9"},
        {&shortTints, "need 6 tints, found 5"},
        {&badTint, "tint 1073741824 of link 4"},
        {&shortOffsets, "need 18 offset components, found 17"},
        {&nanOffset, "offset of link 2 is not finite"},
        {&shortShares, "need 6 spread shares, found 5"},
        {&badShare, "spread share code 64 of link 3 exceeds 63"},
        {&zeroWeight, "flux weight of surfel 2 is 0"},
        {&missingWeights, "0 surfel flux weights for nS = 4"},
    };
    for (const auto& [bake, expected] : cases) {
        const Result<void> ok = writeBakeFile(path("bad.pic"), *bake);
        ASSERT_FALSE(ok);
        EXPECT_EQ(ok.error().code, ErrorCode::InvalidInput);
        EXPECT_TRUE(contains(ok.error().message, expected)) << ok.error().message;
    }
    EXPECT_TRUE(filesInDir().empty());
}

/// Shard `index` of `count` of `bake`: every array, the links and sky visibilities of caches
/// [begin, end) only.
BakePart partOf(const BakeData& bake, uint32_t index, uint32_t count, uint64_t begin, uint64_t end) {
    BakePart part;
    part.index = index;
    part.count = count;
    part.cacheBegin = begin;
    part.cacheEnd = end;
    part.seesSurfel.assign(end - begin, 1);
    part.bake = bake;
    LinkSet& links = part.bake.links;
    const size_t nL = links.linksPerCache, coefficients = size_t{links.bands} * links.bands;
    const auto keep = [&](auto& values, size_t perLink) {
        if (values.empty()) return;
        values = {values.begin() + begin * nL * perLink, values.begin() + end * nL * perLink};
    };
    keep(links.rtp, 1);
    keep(links.shNodes, 1);
    keep(links.shCoefficients, coefficients);
    keep(links.tint, 1);
    keep(links.offset, 3);
    keep(links.spreadShare, 1);
    const size_t perCache = part.bake.cacheSky.size() / bake.caches.size();
    part.bake.cacheSky = {bake.cacheSky.begin() + begin * perCache,
                          bake.cacheSky.begin() + end * perCache};
    return part;
}

TEST_F(BakeFile, PartRoundTripsWithItsShard) {
    for (const LinkMode mode : {LinkMode::Rtp, LinkMode::Sh}) {
        BakePart part = partOf(makeBake(mode), 1, 2, 1, 3);
        part.seesSurfel = {1, 0};
        const std::string file = path("part.pic");
        ASSERT_TRUE(writeBakePart(file, part));
        const Result<BakePart> read = readBakePart(file);
        ASSERT_TRUE(read) << read.error().message;
        EXPECT_EQ(read->index, 1u);
        EXPECT_EQ(read->count, 2u);
        EXPECT_EQ(read->cacheBegin, 1u);
        EXPECT_EQ(read->cacheEnd, 3u);
        EXPECT_EQ(read->seesSurfel, part.seesSurfel);
        expectSameBake(part.bake, read->bake);
    }
    EXPECT_EQ(filesInDir(), std::vector<std::string>{"part.pic"});
}

TEST_F(BakeFile, APartIsNoBakeAndABakeNoPart) {
    const BakeData bake = makeBake(LinkMode::Rtp);
    const auto [bakeFile, bytes] = written(bake);
    const std::string partFile = path("part.pic");
    ASSERT_TRUE(writeBakePart(partFile, partOf(bake, 0, 2, 0, 1)));
    for (const Error& error : {errorOf(readBakeFile(partFile)), errorOf(inspectBakeFile(partFile))}) {
        EXPECT_EQ(error.code, ErrorCode::Corrupt);
        EXPECT_TRUE(contains(error.message, "one part of a sharded bake")) << error.message;
        EXPECT_TRUE(contains(error.message, "picbake merge")) << error.message;
    }
    const Error error = errorOf(readBakePart(bakeFile));
    EXPECT_EQ(error.code, ErrorCode::Corrupt);
    EXPECT_TRUE(contains(error.message, "is a whole bake, not a part")) << error.message;
    EXPECT_TRUE(contains(error.message, bakeFile)) << error.message;
}

TEST_F(BakeFile, InconsistentPartIsNotWrittenAndResealedOneIsRefused) {
    const BakeData bake = makeBake(LinkMode::Rtp);
    const std::string file = path("part.pic");
    BakePart part = partOf(bake, 2, 2, 1, 3);  // shard 2 of 2 does not exist
    EXPECT_EQ(errorOf(writeBakePart(file, part)).code, ErrorCode::InvalidInput);
    part = partOf(bake, 1, 2, 1, 3);
    part.cacheEnd = 4;  // past the 3 caches
    EXPECT_EQ(errorOf(writeBakePart(file, part)).code, ErrorCode::InvalidInput);
    part = partOf(bake, 1, 2, 1, 3);
    part.seesSurfel = {1, 2};
    EXPECT_EQ(errorOf(writeBakePart(file, part)).code, ErrorCode::InvalidInput);
    part = partOf(bake, 1, 2, 1, 3);
    part.cacheBegin = 0;  // links of two caches said to be of three
    part.seesSurfel = {1, 1, 1};
    const Error error = errorOf(writeBakePart(file, part));
    EXPECT_EQ(error.code, ErrorCode::InvalidInput);
    EXPECT_TRUE(contains(error.message, "3 caches")) << error.message;
    EXPECT_TRUE(filesInDir().empty());

    // Checksums right, shard record wrong: index 5 of 2.
    ASSERT_TRUE(writeBakePart(file, partOf(bake, 1, 2, 1, 3)));
    std::vector<char> bytes = readBytes(file);
    const size_t shardSection = std::size(kAllSections);
    const auto offset = load<uint64_t>(bytes, kBakeHeaderBytes + shardSection * kBakeSectionEntryBytes + 24);
    store<uint32_t>(bytes, offset, 5);
    resealSection(bytes, shardSection);
    writeBytes(file, bytes);
    const Error corrupt = errorOf(readBakePart(file));
    EXPECT_EQ(corrupt.code, ErrorCode::Corrupt);
    EXPECT_TRUE(contains(corrupt.message, "shard 5 of 2")) << corrupt.message;
}

TEST_F(BakeFile, SceneMismatchIsRefused) {
    const BakeData bake = makeBake(LinkMode::Rtp);
    const auto [file, bytes] = written(bake);
    const Result<BakeFileInfo> info = inspectBakeFile(file);
    ASSERT_TRUE(info) << info.error().message;
    EXPECT_TRUE(checkSceneMatches(*info, bake.sceneHash, "scene.gltf"));
    const Result<void> other = checkSceneMatches(*info, 0x1234, "other.gltf");
    ASSERT_FALSE(other);
    EXPECT_EQ(other.error().code, ErrorCode::Corrupt);
    EXPECT_TRUE(contains(other.error().message, "different scene")) << other.error().message;
    EXPECT_TRUE(contains(other.error().message, file)) << other.error().message;
    EXPECT_TRUE(contains(other.error().message, "other.gltf")) << other.error().message;
    EXPECT_TRUE(contains(other.error().message, "feedface12345678")) << other.error().message;
    EXPECT_TRUE(contains(other.error().message, "0000000000001234")) << other.error().message;
}

}  // namespace
}  // namespace pic
