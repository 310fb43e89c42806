#include "core/bake_file.h"

#include "core/sh.h"
#include "core/sky.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <optional>
#include <set>
#include <span>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <utility>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "core/hash.h"

namespace pic {

// The file holds the in-memory records verbatim, which is only the documented format on
// little-endian machines with IEEE-754 floats.
static_assert(std::endian::native == std::endian::little, "bake files are little-endian");
static_assert(std::numeric_limits<float>::is_iec559, "bake files hold IEEE-754 floats");

namespace {

constexpr size_t kMagicBytes = 8;
constexpr size_t kNameBytes = 24;

struct FileHeader {
    char magic[8];
    uint32_t formatVersion;
    uint32_t sectionCount;
    uint64_t sceneHash;
    uint64_t fileSize;
    uint64_t tableChecksum;
};
static_assert(sizeof(FileHeader) + sizeof(uint64_t) == kBakeHeaderBytes);
static_assert(offsetof(FileHeader, formatVersion) == 8);

struct SectionEntry {
    char name[kNameBytes];
    uint64_t offset;
    uint64_t size;
    uint64_t checksum;
};
static_assert(sizeof(SectionEntry) == kBakeSectionEntryBytes);

struct GridRecord {
    float origin[3];
    float cellSize;
    uint32_t dims[3];
    uint32_t zero;
};
static_assert(sizeof(GridRecord) == 32);

struct LightmapRecord {
    uint32_t width;
    uint32_t height;
    float texelSize;
    uint32_t chartCount;
};
static_assert(sizeof(LightmapRecord) == 16);

struct LinksRecord {
    uint32_t mode;
    uint32_t linksPerCache;
    uint32_t bands;
    uint32_t zero;
};
static_assert(sizeof(LinksRecord) == 16);

struct ShardRecord {
    uint32_t index;
    uint32_t count;
    uint64_t cacheBegin;
    uint64_t cacheEnd;
};
static_assert(sizeof(ShardRecord) == 24);

static_assert(sizeof(glm::vec2) == 8 && std::is_trivially_copyable_v<glm::vec2>);

/// Section names in the order the writer emits them; a file must hold each exactly once.
constexpr std::array<std::string_view, 20> kSectionNames = {
    "params",         "surfels",         "surfel_weights", "nodes",        "levels",
    "caches",         "grid",            "grid_index",     "lightmap",     "lightmap_index",
    "lightmap_uvs",   "links",           "links_rtp",      "links_sh_nodes", "links_sh_coeffs",
    "links_tint",     "links_offset",    "links_spread_share", "surfel_sky", "cache_sky",
};
constexpr size_t kSectionCount = kSectionNames.size();
static_assert(std::ranges::all_of(kSectionNames,
                                  [](std::string_view n) { return n.size() < kNameBytes; }));

/// A part's sections: a bake's, then its shard.
constexpr auto kPartSectionNames = [] {
    std::array<std::string_view, kSectionCount + 2> names{};
    std::ranges::copy(kSectionNames, names.begin());
    names[kSectionCount] = "shard";
    names[kSectionCount + 1] = "shard_sees";
    return names;
}();

/// What tells a bake from a part on disk and in messages.
struct FileKind {
    std::array<char, kMagicBytes> magic;
    std::span<const std::string_view> sections;
    std::string_view noun;
};
constexpr FileKind kBakeKind{{'P', 'I', 'C', 'B', 'A', 'K', 'E', '\0'}, kSectionNames, "bake file"};
constexpr FileKind kPartKind{{'P', 'I', 'C', 'P', 'A', 'R', 'T', '\0'}, kPartSectionNames, "bake part"};

/// The arrays of a bake, borrowed from a BakeData or from a mapped file.
struct BakeView {
    std::span<const Surfel> surfels;
    std::span<const float> surfelWeights;
    std::span<const Node> nodes;
    std::span<const uint32_t> levelOffsets;
    std::span<const Cache> caches;
    GridRecord grid{};
    std::span<const uint32_t> gridIndex;
    LightmapRecord lightmap{};
    std::span<const uint32_t> lightmapIndex;
    std::span<const glm::vec2> lightmapUvs;
    LinksRecord links{};
    std::span<const RtpLink> rtp;
    std::span<const uint32_t> shNodes;
    std::span<const uint16_t> shCoefficients;
    std::span<const uint32_t> tint;
    std::span<const uint16_t> offset;
    std::span<const uint8_t> spreadShare;
    std::span<const float> surfelSky;
    std::span<const float> cacheSky;
};

std::string errnoText(int err) {
    return std::generic_category().message(err);
}

uint64_t alignUp(uint64_t offset) {
    return (offset + kBakeSectionAlignment - 1) / kBakeSectionAlignment * kBakeSectionAlignment;
}

/// Product of the factors, or nullopt if it overflows 64 bits.
std::optional<uint64_t> checkedProduct(std::initializer_list<uint64_t> factors) {
    uint64_t result = 1;
    for (uint64_t f : factors)
        if (__builtin_mul_overflow(result, f, &result)) return std::nullopt;
    return result;
}

const char* linkModeName(LinkMode mode) {
    return mode == LinkMode::Sh ? "sh" : "rtp";
}

const char* linkReadsName(LinkReads reads) {
    return reads == LinkReads::Node ? "node" : "visible";
}

// ---------------------------------------------------------------------------------------
// Validation shared by the writer (InvalidInput) and the reader (Corrupt).

Result<void> checkParams(const BakeParams& p, ErrorCode code, const std::string& what) {
    if (p.linkMode != LinkMode::Sh && p.linkMode != LinkMode::Rtp)
        return fail(code, "{}: link mode {} is neither sh (0) nor rtp (1)", what,
                    static_cast<uint32_t>(p.linkMode));
    if (p.hierarchy != HierarchyMethod::Agglomerative && p.hierarchy != HierarchyMethod::KdTree &&
        p.hierarchy != HierarchyMethod::Visible)
        return fail(code,
                    "{}: hierarchy method {} is none of agglomerative (0), kdtree (1), visible (2)",
                    what, static_cast<uint32_t>(p.hierarchy));
    if (!std::isfinite(p.gridCell) || p.gridCell < 0.0f)
        return fail(code, "{}: grid cell {} m is not a finite non-negative length", what,
                    p.gridCell);
    if (!std::isfinite(p.lightmapTexel) || p.lightmapTexel < 0.0f)
        return fail(code, "{}: light-map texel {} m is not a finite non-negative length", what,
                    p.lightmapTexel);
    return {};
}

Result<void> checkCacheIndices(std::span<const uint32_t> indices, uint64_t nC,
                               std::string_view section, ErrorCode code, const std::string& what) {
    for (size_t i = 0; i < indices.size(); ++i)
        if (indices[i] != kNoCache && indices[i] >= nC)
            return fail(code, "{}: {} entry {} refers to cache {} but there are {} caches", what,
                        section, i, indices[i], nC);
    return {};
}

Result<void> checkNodes(const BakeView& v, ErrorCode code, const std::string& what) {
    const uint64_t nS = v.surfels.size();
    const uint64_t nNodes = v.nodes.size();
    const uint64_t expectedNodes = nS == 0 ? 0 : 2 * nS - 1;
    if (nNodes != expectedNodes)
        return fail(code, "{}: {} nodes for nS = {} surfels, expected 2·nS − 1 = {}", what, nNodes,
                    nS, expectedNodes);
    if (v.surfelWeights.size() != nS)
        return fail(code, "{}: {} surfel flux weights for nS = {} surfels", what,
                    v.surfelWeights.size(), nS);
    for (size_t i = 0; i < v.surfelWeights.size(); ++i)
        if (!(std::isfinite(v.surfelWeights[i]) && v.surfelWeights[i] > 0.0f))
            return fail(code, "{}: flux weight of surfel {} is {}, expected finite and positive",
                        what, i, v.surfelWeights[i]);
    for (size_t i = 0; i < v.nodes.size(); ++i) {
        const Node& node = v.nodes[i];
        const std::pair<const char*, uint32_t> relatives[] = {
            {"left child", node.left}, {"right child", node.right}, {"parent", node.parent}};
        for (const auto& [relation, index] : relatives)
            if (index != kNoNode && index >= nNodes)
                return fail(code, "{}: node {} has {} {} but there are {} nodes", what, i, relation,
                            index, nNodes);
        // The runtime turns a node's flux into radiance Φ / (π·A).
        if (!(std::isfinite(node.area) && node.area > 0.0f))
            return fail(code, "{}: node {} has area {} m², expected a finite positive area", what,
                        i, node.area);
        if (uint64_t{node.firstSurfel} + node.surfelCount > nS)
            return fail(code, "{}: node {} covers surfels [{}, {}) but there are {}", what, i,
                        node.firstSurfel, uint64_t{node.firstSurfel} + node.surfelCount, nS);
    }
    for (size_t k = 0; k < v.levelOffsets.size(); ++k) {
        const uint32_t offset = v.levelOffsets[k];
        if (offset > nNodes || (k > 0 && offset < v.levelOffsets[k - 1]))
            return fail(code,
                        "{}: level offset {} is {}, offsets must be non-decreasing and at most "
                        "the node count {}",
                        what, k, offset, nNodes);
    }
    return {};
}

Result<void> checkCachesAndLayouts(const BakeView& v, ErrorCode code, const std::string& what) {
    const uint64_t nC = v.caches.size();
    for (size_t i = 0; i < v.caches.size(); ++i)
        if (v.caches[i].kind != gpu::kCacheKindGrid && v.caches[i].kind != gpu::kCacheKindLightmap)
            return fail(code, "{}: cache {} has kind {}, expected grid (0) or light map (1)", what,
                        i, v.caches[i].kind);

    const GridRecord& g = v.grid;
    if (!std::isfinite(g.origin[0]) || !std::isfinite(g.origin[1]) || !std::isfinite(g.origin[2]) ||
        !std::isfinite(g.cellSize) || g.cellSize < 0.0f)
        return fail(code, "{}: grid origin ({}, {}, {}) or cell size {} is not finite", what,
                    g.origin[0], g.origin[1], g.origin[2], g.cellSize);
    if (checkedProduct({g.dims[0], g.dims[1], g.dims[2]}) != v.gridIndex.size())
        return fail(code, "{}: grid of {}×{}×{} vertices has {} cache indices", what, g.dims[0],
                    g.dims[1], g.dims[2], v.gridIndex.size());
    if (auto ok = checkCacheIndices(v.gridIndex, nC, "grid_index", code, what); !ok) return ok;

    const LightmapRecord& l = v.lightmap;
    if (!std::isfinite(l.texelSize) || l.texelSize < 0.0f)
        return fail(code, "{}: light-map texel size {} is not a finite non-negative length", what,
                    l.texelSize);
    if (checkedProduct({l.width, l.height}) != v.lightmapIndex.size())
        return fail(code, "{}: light map of {}×{} texels has {} cache indices", what, l.width,
                    l.height, v.lightmapIndex.size());
    if (auto ok = checkCacheIndices(v.lightmapIndex, nC, "lightmap_index", code, what); !ok)
        return ok;
    if (v.lightmapUvs.size() % 3 != 0)
        return fail(code, "{}: {} light-map UVs is not 3 per triangle", what, v.lightmapUvs.size());
    return {};
}

/// The link records of the link mode for nC linked caches, and no others.
Result<void> checkLinkRecords(const BakeView& v, uint64_t nC, ErrorCode code,
                              const std::string& what) {
    const LinksRecord& links = v.links;
    const uint64_t nNodes = v.nodes.size();
    const uint64_t nL = links.linksPerCache;
    const uint64_t nLinks = nC * nL;  // both below 2³², cannot overflow
    if (links.mode == static_cast<uint32_t>(LinkMode::Rtp)) {
        if (v.rtp.size() != nLinks || !v.shNodes.empty() || !v.shCoefficients.empty())
            return fail(code,
                        "{}: RTP links of {} caches × {} links need {} RTP links and no SH "
                        "links, found {} RTP links, {} SH nodes and {} SH coefficients",
                        what, nC, nL, nLinks, v.rtp.size(), v.shNodes.size(),
                        v.shCoefficients.size());
        for (size_t i = 0; i < v.rtp.size(); ++i)
            if (v.rtp[i].node >= nNodes && v.rtp[i].factor != 0.0f)
                return fail(code, "{}: RTP link {} refers to node {} but there are {} nodes", what,
                            i, v.rtp[i].node, nNodes);
        return {};
    }
    if (links.mode == static_cast<uint32_t>(LinkMode::Sh)) {
        const std::optional<uint64_t> nCoefficients =
            checkedProduct({nLinks, links.bands, links.bands});
        if (v.shNodes.size() != nLinks || nCoefficients != v.shCoefficients.size() ||
            !v.rtp.empty())
            return fail(code,
                        "{}: SH links of {} caches × {} links × {}² coefficients need {} SH "
                        "nodes, as many coefficients and no RTP links, found {} SH nodes, {} SH "
                        "coefficients and {} RTP links",
                        what, nC, nL, links.bands, nLinks, v.shNodes.size(),
                        v.shCoefficients.size(), v.rtp.size());
        for (size_t i = 0; i < v.shNodes.size(); ++i)
            if (v.shNodes[i] != kNoNode && v.shNodes[i] >= nNodes)
                return fail(code, "{}: SH link {} refers to node {} but there are {} nodes", what,
                            i, v.shNodes[i], nNodes);
        return {};
    }
    return fail(code, "{}: link mode {} is neither sh (0) nor rtp (1)", what, links.mode);
}

/// The links of nC caches: the bake's, or a part's range.
Result<void> checkLinks(const BakeView& v, uint64_t nC, ErrorCode code, const std::string& what) {
    PIC_TRY(checkLinkRecords(v, nC, code, what));
    const uint64_t nLinks = nC * v.links.linksPerCache;
    if (v.tint.size() != nLinks)
        return fail(code, "{}: links of {} caches × {} links need {} tints, found {}", what, nC,
                    v.links.linksPerCache, nLinks, v.tint.size());
    for (size_t i = 0; i < v.tint.size(); ++i)
        if (v.tint[i] >> 30 != 0)
            return fail(code, "{}: tint {} of link {} sets bits above the 30 of its channels", what,
                        v.tint[i], i);
    if (v.offset.size() != nLinks * 3)
        return fail(code, "{}: links of {} caches × {} links need {} offset components, found {}",
                    what, nC, v.links.linksPerCache, nLinks * 3, v.offset.size());
    for (size_t i = 0; i < v.offset.size(); ++i)
        if ((v.offset[i] & 0x7C00u) == 0x7C00u)
            return fail(code, "{}: offset of link {} is not finite (half bits {:#06x})", what,
                        i / 3, v.offset[i]);
    if (v.spreadShare.size() != nLinks)
        return fail(code, "{}: links of {} caches × {} links need {} spread shares, found {}", what,
                    nC, v.links.linksPerCache, nLinks, v.spreadShare.size());
    for (size_t i = 0; i < v.spreadShare.size(); ++i)
        if (v.spreadShare[i] > kSpreadShareSteps)
            return fail(code, "{}: spread share code {} of link {} exceeds {}", what,
                        v.spreadShare[i], i, kSpreadShareSteps);
    return {};
}

/// The sky transfer: none without sky rays, else kSkyCoefficients finite values per surfel and
/// skyVisibilityBands(lY)² per linked cache.
Result<void> checkSky(const BakeView& v, const BakeParams& p, uint64_t linkedCaches,
                      ErrorCode code, const std::string& what) {
    const uint64_t perCache = skyValuesPerCache(p);
    const uint64_t perSurfel = p.skyRays ? uint64_t(kSkyCoefficients) : 0;
    if (v.surfelSky.size() != v.surfels.size() * perSurfel)
        return fail(code, "{}: {} surfel sky transfer values for {} surfels and {} sky rays, "
                    "expected {}", what, v.surfelSky.size(), v.surfels.size(), p.skyRays,
                    v.surfels.size() * perSurfel);
    if (v.cacheSky.size() != linkedCaches * perCache)
        return fail(code, "{}: {} cache sky visibility values for {} caches and {} sky rays, "
                    "expected {}", what, v.cacheSky.size(), linkedCaches, p.skyRays,
                    linkedCaches * perCache);
    for (const auto& [values, name] : {std::pair{v.surfelSky, "surfel sky transfer"},
                                       std::pair{v.cacheSky, "cache sky visibility"}})
        if (const auto bad = std::ranges::find_if(values, [](float x) { return !std::isfinite(x); });
            bad != values.end())
            return fail(code, "{}: {} value {} is {}, expected finite", what, name,
                        bad - values.begin(), *bad);
    return {};
}

/// Checks that counts agree across arrays and that every index lies in range, so that the
/// runtime can use the arrays without bounds checks; the links and cache sky visibilities are
/// those of `linkedCaches` caches (all of them in a bake).
Result<void> checkContents(const BakeView& v, const BakeParams& p, uint64_t linkedCaches,
                           ErrorCode code, const std::string& what) {
    if (auto ok = checkNodes(v, code, what); !ok) return ok;
    if (auto ok = checkCachesAndLayouts(v, code, what); !ok) return ok;
    if (auto ok = checkSky(v, p, linkedCaches, code, what); !ok) return ok;
    return checkLinks(v, linkedCaches, code, what);
}

// ---------------------------------------------------------------------------------------
// Parameters as JSON.

/// The double nearest to the float's shortest decimal form, so that the JSON shows 0.1 rather
/// than 0.10000000149011612; it rounds back to the same float because 53 ≥ 2·24 + 2 bits.
double shortestDouble(float value) {
    const std::string text = fmt::format("{}", value);
    double result = 0.0;
    PIC_CHECK(std::from_chars(text.data(), text.data() + text.size(), result).ec == std::errc{});
    return result;
}

Result<std::string> paramsJson(const BakeParams& p,
                               const std::map<std::string, std::string>& defaults,
                               const std::string& what) {
    nlohmann::ordered_json json;
    json["surfels"] = p.surfels;
    json["links_per_cache"] = p.linksPerCache;
    json["bands_y"] = p.bandsY;
    json["bands_c"] = p.bandsC;
    json["grid_cell"] = shortestDouble(p.gridCell);
    json["grid_caches"] = gridCachesName(p.gridCaches);
    json["lightmap_texel"] = shortestDouble(p.lightmapTexel);
    json["link_mode"] = linkModeName(p.linkMode);
    json["hierarchy"] = hierarchyName(p.hierarchy);
    json["link_samples"] = p.linkSamples;
    json["link_final_samples"] = p.linkFinalSamples;
    json["exposure_rays"] = p.exposureRays;
    json["sky_rays"] = p.skyRays;
    json["link_reads"] = linkReadsName(p.linkReads);
    json["link_cut"] = linkCutName(p.linkCut);
    json["relax_iterations"] = p.relaxIterations;
    json["seed"] = p.seed;
    json["defaults"] = defaults;
    // dump() throws only on strings that are not UTF-8, which only `defaults` can hold.
    try {
        return json.dump(2);
    } catch (const nlohmann::json::exception& e) {
        return fail(ErrorCode::InvalidInput, "{}: parameter defaults are not UTF-8 text ({})", what,
                    e.what());
    }
}

/// Reads the fields of the params object, remembering which it saw to report unknown ones.
class ParamsReader {
public:
    ParamsReader(const nlohmann::json& object, const std::string& file)
        : mObject(object), mFile(file) {}

    Result<const nlohmann::json*> field(const char* key) {
        const auto it = mObject.find(key);
        if (it == mObject.end())
            return fail(ErrorCode::Corrupt, "params of {} lack \"{}\"", mFile, key);
        mSeen.insert(key);
        return &*it;
    }

    Result<uint64_t> unsignedField(const char* key, uint64_t max) {
        PIC_TRY_ASSIGN(const nlohmann::json* value, field(key));
        if (!value->is_number_unsigned() || value->get<uint64_t>() > max)
            return fail(ErrorCode::Corrupt,
                        "params of {}: \"{}\" is {}, not an integer in [0, {}]", mFile,
                        key, value->dump(), max);
        return value->get<uint64_t>();
    }

    Result<uint32_t> u32(const char* key) {
        PIC_TRY_ASSIGN(const uint64_t value,
                       unsignedField(key, std::numeric_limits<uint32_t>::max()));
        return static_cast<uint32_t>(value);
    }

    bool contains(const char* key) const { return mObject.contains(key); }

    /// An optional field: `fallback` where the file does not have it.
    Result<uint32_t> u32Or(const char* key, uint32_t fallback) {
        return mObject.contains(key) ? u32(key) : fallback;
    }

    Result<float> f32(const char* key) {
        PIC_TRY_ASSIGN(const nlohmann::json* value, field(key));
        if (!value->is_number())
            return fail(ErrorCode::Corrupt, "params of {}: \"{}\" is {}, not a number",
                        mFile, key, value->dump());
        return static_cast<float>(value->get<double>());
    }

    /// The index of the field's value in `names`.
    Result<uint32_t> oneOf(const char* key, std::initializer_list<const char*> names) {
        PIC_TRY_ASSIGN(const nlohmann::json* value, field(key));
        uint32_t index = 0;
        for (const char* name : names) {
            if (value->is_string() && value->get_ref<const std::string&>() == name) return index;
            ++index;
        }
        return fail(ErrorCode::Corrupt, "params of {}: \"{}\" is {}, expected one of {}",
                    mFile, key, value->dump(), fmt::join(names, ", "));
    }

    Result<std::map<std::string, std::string>> stringMap(const char* key) {
        PIC_TRY_ASSIGN(const nlohmann::json* value, field(key));
        if (!value->is_object())
            return fail(ErrorCode::Corrupt, "params of {}: \"{}\" is not an object",
                        mFile, key);
        std::map<std::string, std::string> result;
        for (const auto& [name, text] : value->items()) {
            if (!text.is_string())
                return fail(ErrorCode::Corrupt,
                            "params of {}: \"{}\".\"{}\" is {}, not a string", mFile, key,
                            name, text.dump());
            result.emplace(name, text.get<std::string>());
        }
        return result;
    }

    /// Corrupt if the object holds a field no one asked for.
    Result<void> checkAllSeen() const {
        for (const auto& [key, value] : mObject.items())
            if (!mSeen.contains(key))
                return fail(ErrorCode::Corrupt, "params of {} hold unknown field \"{}\"",
                            mFile, key);
        return {};
    }

private:
    const nlohmann::json& mObject;
    const std::string& mFile;
    std::set<std::string, std::less<>> mSeen;
};

struct ParsedParams {
    BakeParams params;
    std::map<std::string, std::string> defaults;
};

Result<ParsedParams> parseParams(std::span<const std::byte> bytes, const std::string& file) {
    const auto* text = reinterpret_cast<const char*>(bytes.data());
    const nlohmann::json json = nlohmann::json::parse(text, text + bytes.size(), nullptr, false);
    if (json.is_discarded() || !json.is_object())
        return fail(ErrorCode::Corrupt, "params section of {} is not a JSON object",
                    file);
    ParamsReader reader(json, file);
    ParsedParams parsed;
    BakeParams& p = parsed.params;
    PIC_TRY_ASSIGN(p.surfels, reader.u32("surfels"));
    PIC_TRY_ASSIGN(p.linksPerCache, reader.u32("links_per_cache"));
    PIC_TRY_ASSIGN(p.bandsY, reader.u32("bands_y"));
    PIC_TRY_ASSIGN(p.bandsC, reader.u32("bands_c"));
    PIC_TRY_ASSIGN(p.gridCell, reader.f32("grid_cell"));
    // Bakes written before grid caches could be limited to what surfaces read filled the volume.
    PIC_TRY_ASSIGN(const uint32_t gridCaches, reader.contains("grid_caches")
                                                  ? reader.oneOf("grid_caches", {"surfaces", "volume", "space"})
                                                  : Result<uint32_t>(1u));
    p.gridCaches = static_cast<GridCaches>(gridCaches);
    PIC_TRY_ASSIGN(p.lightmapTexel, reader.f32("lightmap_texel"));
    // The name lists follow the enumerators' values.
    PIC_TRY_ASSIGN(const uint32_t linkMode, reader.oneOf("link_mode", {"sh", "rtp"}));
    PIC_TRY_ASSIGN(const uint32_t hierarchy,
                   reader.oneOf("hierarchy", {"agglomerative", "kdtree", "visible"}));
    p.linkMode = static_cast<LinkMode>(linkMode);
    p.hierarchy = static_cast<HierarchyMethod>(hierarchy);
    PIC_TRY_ASSIGN(p.linkSamples, reader.u32("link_samples"));
    // Bakes written before the final estimate had its own count re-estimated with link_samples.
    PIC_TRY_ASSIGN(p.linkFinalSamples, reader.u32Or("link_final_samples", p.linkSamples));
    PIC_TRY_ASSIGN(p.exposureRays, reader.u32("exposure_rays"));
    PIC_TRY_ASSIGN(p.skyRays, reader.u32("sky_rays"));
    PIC_TRY_ASSIGN(const uint32_t linkReads, reader.oneOf("link_reads", {"node", "visible"}));
    p.linkReads = static_cast<LinkReads>(linkReads);
    // Bakes written before the error-bound cut refined by solid angle.
    PIC_TRY_ASSIGN(const uint32_t linkCut, reader.contains("link_cut")
                                               ? reader.oneOf("link_cut", {"solid-angle", "error"})
                                               : Result<uint32_t>(0u));
    p.linkCut = static_cast<LinkCut>(linkCut);
    PIC_TRY_ASSIGN(p.relaxIterations, reader.u32("relax_iterations"));
    PIC_TRY_ASSIGN(p.seed, reader.unsignedField("seed", std::numeric_limits<uint64_t>::max()));
    PIC_TRY_ASSIGN(parsed.defaults, reader.stringMap("defaults"));
    if (auto ok = reader.checkAllSeen(); !ok) return std::unexpected(ok.error());
    if (auto ok = checkParams(p, ErrorCode::Corrupt, file); !ok)
        return std::unexpected(ok.error());
    return parsed;
}

// ---------------------------------------------------------------------------------------
// Files.

/// Owns a POSIX file descriptor.
class FileDescriptor {
public:
    explicit FileDescriptor(int fd) : mFd(fd) {}
    FileDescriptor(const FileDescriptor&) = delete;
    FileDescriptor& operator=(const FileDescriptor&) = delete;
    ~FileDescriptor() {
        if (mFd >= 0) ::close(mFd);
    }
    int get() const { return mFd; }
    /// Closes now and returns close()'s errno (0 on success).
    int close() {
        const int result = ::close(std::exchange(mFd, -1));
        return result == 0 ? 0 : errno;
    }

private:
    int mFd;
};

/// A whole file mapped read-only; the mapping outlives the descriptor.
class MappedFile {
public:
    /// `file` names it in messages ("bake file PATH").
    static Result<MappedFile> open(const std::string& path, const std::string& file) {
        const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
        if (fd < 0) {
            const int err = errno;
            if (err == ENOENT) return fail(ErrorCode::NotFound, "{} does not exist", file);
            return fail(ErrorCode::Io, "cannot open {}: {}", file, errnoText(err));
        }
        FileDescriptor descriptor(fd);
        struct stat info {};
        if (::fstat(fd, &info) != 0)
            return fail(ErrorCode::Io, "cannot stat {}: {}", file, errnoText(errno));
        if (!S_ISREG(info.st_mode))
            return fail(ErrorCode::InvalidInput, "{} is not a regular file", file);
        const size_t size = static_cast<size_t>(info.st_size);
        if (size == 0) return MappedFile(nullptr, 0);
        void* data = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
        if (data == MAP_FAILED)
            return fail(ErrorCode::Io, "cannot map {}: {}", file, errnoText(errno));
        return MappedFile(data, size);
    }

    MappedFile(MappedFile&& other) noexcept
        : mData(std::exchange(other.mData, nullptr)), mSize(std::exchange(other.mSize, 0)) {}
    MappedFile& operator=(MappedFile&&) = delete;
    ~MappedFile() {
        if (mData) ::munmap(mData, mSize);
    }

    std::span<const std::byte> bytes() const {
        return {static_cast<const std::byte*>(mData), mSize};
    }

private:
    MappedFile(void* data, size_t size) : mData(data), mSize(size) {}

    void* mData;
    size_t mSize;
};

/// A validated, mapped bake file or part; the views point into `file`.
struct DecodedBake {
    MappedFile file;
    FileHeader header;
    std::vector<std::pair<std::string, uint64_t>> sectionBytes;  ///< in file order
    BakeView view;
    ParsedParams params;
    ShardRecord shard{};               ///< parts only
    std::span<const uint8_t> sees;     ///< parts only
};

using SectionMap = std::map<std::string, std::span<const std::byte>, std::less<>>;

Result<FileHeader> readHeader(std::span<const std::byte> bytes, const std::string& path,
                              const FileKind& kind, const std::string& file) {
    const auto startsWith = [&](const FileKind& k) {
        return bytes.size() >= kMagicBytes && std::memcmp(bytes.data(), k.magic.data(), kMagicBytes) == 0;
    };
    if (&kind == &kBakeKind && startsWith(kPartKind))
        return fail(ErrorCode::Corrupt,
                    "{} is one part of a sharded bake, not a whole bake: join all the parts with "
                    "`picbake merge PART... -o OUT.pic`",
                    path);
    if (&kind == &kPartKind && startsWith(kBakeKind))
        return fail(ErrorCode::Corrupt,
                    "{} is a whole bake, not a part of a sharded bake (`picbake bake --shard I/N` "
                    "writes parts)",
                    path);
    if (!startsWith(kind))
        return fail(ErrorCode::Corrupt, "{} is not a pic {} (it does not start with \"{}\")", path,
                    kind.noun, kind.magic.data());
    // The version is checked before anything else so that a newer layout is reported as such.
    uint32_t version = 0;
    if (bytes.size() >= offsetof(FileHeader, formatVersion) + sizeof(version)) {
        std::memcpy(&version, bytes.data() + offsetof(FileHeader, formatVersion), sizeof(version));
        if (version != kBakeFormatVersion)
            return fail(ErrorCode::Corrupt,
                        "{} has format version {}, this build reads version {}; "
                        "bake the scene again",
                        file, version, kBakeFormatVersion);
    }
    if (bytes.size() < kBakeHeaderBytes)
        return fail(ErrorCode::Corrupt,
                    "{} is truncated: it has {} bytes, the header alone needs {}", file,
                    bytes.size(), kBakeHeaderBytes);
    FileHeader header;
    uint64_t headerChecksum = 0;
    std::memcpy(&header, bytes.data(), sizeof(header));
    std::memcpy(&headerChecksum, bytes.data() + sizeof(header), sizeof(headerChecksum));
    if (hashBytes(&header, sizeof(header)) != headerChecksum)
        return fail(ErrorCode::Corrupt, "{} has a corrupt header (checksum mismatch)",
                    file);
    if (bytes.size() < header.fileSize)
        return fail(ErrorCode::Corrupt,
                    "{} is truncated: its header says {} bytes, the file has {}", file,
                    header.fileSize, bytes.size());
    if (bytes.size() > header.fileSize)
        return fail(ErrorCode::Corrupt,
                    "{} has {} bytes, its header says {}: trailing data", file,
                    bytes.size(), header.fileSize);
    return header;
}

/// Validates the section table and every section's placement and checksum.
Result<SectionMap> readSections(std::span<const std::byte> bytes, const FileHeader& header,
                                std::span<const std::string_view> names, const std::string& file) {
    const uint64_t fileSize = bytes.size();
    if (header.sectionCount > (fileSize - kBakeHeaderBytes) / kBakeSectionEntryBytes)
        return fail(ErrorCode::Corrupt,
                    "section table of {} ({} entries) runs past the end of the file",
                    file, header.sectionCount);
    const uint64_t tableEnd = kBakeHeaderBytes + header.sectionCount * kBakeSectionEntryBytes;
    const std::span<const std::byte> table =
        bytes.subspan(kBakeHeaderBytes, tableEnd - kBakeHeaderBytes);
    if (hashBytes(table.data(), table.size()) != header.tableChecksum)
        return fail(ErrorCode::Corrupt,
                    "{} has a corrupt section table (checksum mismatch)", file);

    SectionMap sections;
    for (uint32_t i = 0; i < header.sectionCount; ++i) {
        SectionEntry entry;
        std::memcpy(&entry, table.data() + i * kBakeSectionEntryBytes, sizeof(entry));
        const std::string name(entry.name, strnlen(entry.name, kNameBytes));
        if (std::ranges::find(names, name) == names.end())
            return fail(ErrorCode::Corrupt, "{} has unknown section '{}'", file, name);
        if (sections.contains(name))
            return fail(ErrorCode::Corrupt, "{} has section '{}' twice", file, name);
        if (entry.offset % kBakeSectionAlignment != 0 || entry.offset < tableEnd)
            return fail(ErrorCode::Corrupt,
                        "section '{}' of {} starts at byte {}, not a multiple of {} "
                        "after the section table",
                        name, file, entry.offset, kBakeSectionAlignment);
        if (entry.offset > fileSize || entry.size > fileSize - entry.offset)
            return fail(ErrorCode::Corrupt,
                        "section '{}' of {} (bytes {} to {}) runs past the end of the "
                        "file ({} bytes)",
                        name, file, entry.offset, entry.offset + entry.size, fileSize);
        const std::span<const std::byte> section = bytes.subspan(entry.offset, entry.size);
        if (hashBytes(section.data(), section.size()) != entry.checksum)
            return fail(ErrorCode::Corrupt,
                        "section '{}' of {} is corrupt (checksum mismatch)", name, file);
        sections.emplace(name, section);
    }
    for (std::string_view name : names)
        if (!sections.contains(name))
            return fail(ErrorCode::Corrupt, "{} lacks section '{}'", file, name);
    return sections;
}

template <class T>
Result<std::span<const T>> arrayIn(const SectionMap& sections, std::string_view name,
                                   const std::string& file) {
    static_assert(std::is_trivially_copyable_v<T> && alignof(T) <= kBakeSectionAlignment);
    const std::span<const std::byte> bytes = sections.find(name)->second;
    if (bytes.size() % sizeof(T) != 0)
        return fail(ErrorCode::Corrupt,
                    "section '{}' of {} has {} bytes, not a multiple of its {}-byte "
                    "records",
                    name, file, bytes.size(), sizeof(T));
    // Sections start 64-byte aligned in a page-aligned mapping, so the records are aligned.
    return std::span<const T>(reinterpret_cast<const T*>(bytes.data()), bytes.size() / sizeof(T));
}

template <class T>
Result<T> recordIn(const SectionMap& sections, std::string_view name, const std::string& file) {
    const std::span<const std::byte> bytes = sections.find(name)->second;
    if (bytes.size() != sizeof(T))
        return fail(ErrorCode::Corrupt, "section '{}' of {} has {} bytes, expected {}",
                    name, file, bytes.size(), sizeof(T));
    T record;
    std::memcpy(&record, bytes.data(), sizeof(T));
    return record;
}

Result<BakeView> viewSections(const SectionMap& s, const std::string& file) {
    BakeView v;
    PIC_TRY_ASSIGN(v.surfels, arrayIn<Surfel>(s, "surfels", file));
    PIC_TRY_ASSIGN(v.surfelWeights, arrayIn<float>(s, "surfel_weights", file));
    PIC_TRY_ASSIGN(v.nodes, arrayIn<Node>(s, "nodes", file));
    PIC_TRY_ASSIGN(v.levelOffsets, arrayIn<uint32_t>(s, "levels", file));
    PIC_TRY_ASSIGN(v.caches, arrayIn<Cache>(s, "caches", file));
    PIC_TRY_ASSIGN(v.grid, recordIn<GridRecord>(s, "grid", file));
    PIC_TRY_ASSIGN(v.gridIndex, arrayIn<uint32_t>(s, "grid_index", file));
    PIC_TRY_ASSIGN(v.lightmap, recordIn<LightmapRecord>(s, "lightmap", file));
    PIC_TRY_ASSIGN(v.lightmapIndex, arrayIn<uint32_t>(s, "lightmap_index", file));
    PIC_TRY_ASSIGN(v.lightmapUvs, arrayIn<glm::vec2>(s, "lightmap_uvs", file));
    PIC_TRY_ASSIGN(v.links, recordIn<LinksRecord>(s, "links", file));
    PIC_TRY_ASSIGN(v.rtp, arrayIn<RtpLink>(s, "links_rtp", file));
    PIC_TRY_ASSIGN(v.shNodes, arrayIn<uint32_t>(s, "links_sh_nodes", file));
    PIC_TRY_ASSIGN(v.shCoefficients, arrayIn<uint16_t>(s, "links_sh_coeffs", file));
    PIC_TRY_ASSIGN(v.tint, arrayIn<uint32_t>(s, "links_tint", file));
    PIC_TRY_ASSIGN(v.offset, arrayIn<uint16_t>(s, "links_offset", file));
    PIC_TRY_ASSIGN(v.spreadShare, arrayIn<uint8_t>(s, "links_spread_share", file));
    PIC_TRY_ASSIGN(v.surfelSky, arrayIn<float>(s, "surfel_sky", file));
    PIC_TRY_ASSIGN(v.cacheSky, arrayIn<float>(s, "cache_sky", file));
    return v;
}

/// Maps the bake or part at `path` and runs every check of its format on it.
Result<DecodedBake> decodeBakeFile(const std::string& path, const FileKind& kind) {
    const std::string file = fmt::format("{} {}", kind.noun, path);
    PIC_TRY_ASSIGN(MappedFile mapped, MappedFile::open(path, file));
    const std::span<const std::byte> bytes = mapped.bytes();
    PIC_TRY_ASSIGN(const FileHeader header, readHeader(bytes, path, kind, file));
    PIC_TRY_ASSIGN(const SectionMap sections, readSections(bytes, header, kind.sections, file));
    PIC_TRY_ASSIGN(BakeView view, viewSections(sections, file));
    PIC_TRY_ASSIGN(ParsedParams params, parseParams(sections.find("params")->second, file));
    const uint64_t nC = view.caches.size();
    ShardRecord shard{0, 1, 0, nC};
    std::span<const uint8_t> sees;
    if (&kind == &kPartKind) {
        PIC_TRY_ASSIGN(shard, recordIn<ShardRecord>(sections, "shard", file));
        PIC_TRY_ASSIGN(sees, arrayIn<uint8_t>(sections, "shard_sees", file));
        if (shard.count == 0 || shard.index >= shard.count)
            return fail(ErrorCode::Corrupt, "{} says it is shard {} of {}", file, shard.index,
                        shard.count);
        if (shard.cacheBegin > shard.cacheEnd || shard.cacheEnd > nC)
            return fail(ErrorCode::Corrupt, "{} links caches [{}, {}) of {}", file,
                        shard.cacheBegin, shard.cacheEnd, nC);
        if (sees.size() != shard.cacheEnd - shard.cacheBegin)
            return fail(ErrorCode::Corrupt, "{} has {} shard_sees entries for {} caches", file,
                        sees.size(), shard.cacheEnd - shard.cacheBegin);
        if (const auto bad = std::ranges::find_if(sees, [](uint8_t x) { return x > 1; });
            bad != sees.end())
            return fail(ErrorCode::Corrupt, "{}: shard_sees entry {} is {}, expected 0 or 1", file,
                        bad - sees.begin(), *bad);
    }
    if (auto ok = checkContents(view, params.params, shard.cacheEnd - shard.cacheBegin,
                                ErrorCode::Corrupt, file);
        !ok)
        return std::unexpected(ok.error());

    // Section sizes in file order, as the table lists them.
    std::vector<std::pair<std::string, uint64_t>> sectionBytes;
    for (uint32_t i = 0; i < header.sectionCount; ++i) {
        SectionEntry entry;
        std::memcpy(&entry, bytes.data() + kBakeHeaderBytes + i * kBakeSectionEntryBytes,
                    sizeof(entry));
        sectionBytes.emplace_back(std::string(entry.name, strnlen(entry.name, kNameBytes)),
                                  entry.size);
    }
    return DecodedBake{std::move(mapped), header, std::move(sectionBytes), view, std::move(params),
                       shard, sees};
}

template <class T>
std::vector<T> toVector(std::span<const T> s) {
    return {s.begin(), s.end()};
}

BakeView viewOf(const BakeData& bake) {
    BakeView v;
    v.surfels = bake.surfels;
    v.surfelWeights = bake.surfelWeights;
    v.nodes = bake.nodes;
    v.levelOffsets = bake.levelOffsets;
    v.caches = bake.caches;
    const GridLayout& g = bake.grid;
    v.grid = {{g.origin.x, g.origin.y, g.origin.z}, g.cellSize, {g.dims.x, g.dims.y, g.dims.z}, 0};
    v.gridIndex = g.cacheIndex;
    const LightmapLayout& l = bake.lightmap;
    v.lightmap = {l.width, l.height, l.texelSize, l.chartCount};
    v.lightmapIndex = l.cacheIndex;
    v.lightmapUvs = l.triangleUvs;
    const LinkSet& links = bake.links;
    v.links = {static_cast<uint32_t>(links.mode), links.linksPerCache, links.bands, 0};
    v.rtp = links.rtp;
    v.shNodes = links.shNodes;
    v.shCoefficients = links.shCoefficients;
    v.tint = links.tint;
    v.offset = links.offset;
    v.spreadShare = links.spreadShare;
    v.surfelSky = bake.surfelSky;
    v.cacheSky = bake.cacheSky;
    return v;
}

template <class T>
std::span<const std::byte> bytesOf(const T& record) {
    return std::as_bytes(std::span<const T, 1>(&record, 1));
}

/// The bytes of every section, in kSectionNames order.
std::array<std::span<const std::byte>, kSectionCount> sectionBytesOf(const BakeView& v,
                                                                     const std::string& params) {
    return {
        std::as_bytes(std::span(params)),
        std::as_bytes(v.surfels),
        std::as_bytes(v.surfelWeights),
        std::as_bytes(v.nodes),
        std::as_bytes(v.levelOffsets),
        std::as_bytes(v.caches),
        bytesOf(v.grid),
        std::as_bytes(v.gridIndex),
        bytesOf(v.lightmap),
        std::as_bytes(v.lightmapIndex),
        std::as_bytes(v.lightmapUvs),
        bytesOf(v.links),
        std::as_bytes(v.rtp),
        std::as_bytes(v.shNodes),
        std::as_bytes(v.shCoefficients),
        std::as_bytes(v.tint),
        std::as_bytes(v.offset),
        std::as_bytes(v.spreadShare),
        std::as_bytes(v.surfelSky),
        std::as_bytes(v.cacheSky),
    };
}

/// Writes all of `bytes`, retrying short writes; returns errno or 0.
int writeAll(int fd, std::span<const std::byte> bytes) {
    while (!bytes.empty()) {
        const ssize_t written = ::write(fd, bytes.data(), bytes.size());
        if (written < 0) {
            if (errno == EINTR) continue;
            return errno;
        }
        bytes = bytes.subspan(static_cast<size_t>(written));
    }
    return 0;
}

/// Removes a file on destruction unless released.
class RemoveOnExit {
public:
    explicit RemoveOnExit(std::string path) : mPath(std::move(path)) {}
    RemoveOnExit(const RemoveOnExit&) = delete;
    RemoveOnExit& operator=(const RemoveOnExit&) = delete;
    ~RemoveOnExit() {
        if (!mPath.empty()) ::unlink(mPath.c_str());
    }
    void release() { mPath.clear(); }

private:
    std::string mPath;
};

/// Writes `sections` (in `kind.sections` order) to `path` atomically: a temporary file in the
/// same directory, fsync, rename, fsync of the directory. `what` starts every message.
Result<void> writeSections(const std::string& path, const FileKind& kind, uint64_t sceneHash,
                           std::span<const std::span<const std::byte>> sections,
                           const std::string& what) {
    PIC_CHECK(sections.size() == kind.sections.size());
    // Lay the sections out one after another at aligned offsets; value-initialised records
    // keep every unused name byte zero.
    std::vector<SectionEntry> table(sections.size());
    const uint64_t tableBytes = table.size() * sizeof(SectionEntry);
    uint64_t offset = kBakeHeaderBytes + tableBytes;
    for (size_t i = 0; i < table.size(); ++i) {
        SectionEntry& entry = table[i];
        kind.sections[i].copy(entry.name, kNameBytes);
        entry.offset = alignUp(offset);
        entry.size = sections[i].size();
        entry.checksum = hashBytes(sections[i].data(), sections[i].size());
        offset = entry.offset + entry.size;
    }
    FileHeader header{};
    std::memcpy(header.magic, kind.magic.data(), kMagicBytes);
    header.formatVersion = kBakeFormatVersion;
    header.sectionCount = static_cast<uint32_t>(table.size());
    header.sceneHash = sceneHash;
    header.fileSize = offset;
    header.tableChecksum = hashBytes(table.data(), tableBytes);
    const uint64_t headerChecksum = hashBytes(&header, sizeof(header));

    const auto ioError = [&](std::string_view step, int err) {
        return fail(ErrorCode::Io, "{}: {}: {}", what, step, errnoText(err));
    };
    const std::string tempPath = fmt::format("{}.tmp.{}", path, ::getpid());
    const int fd = ::open(tempPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) return ioError(fmt::format("creating {}", tempPath), errno);
    FileDescriptor file(fd);
    RemoveOnExit removeTemp(tempPath);

    static constexpr std::array<std::byte, kBakeSectionAlignment> kZeros{};
    uint64_t written = 0;
    const auto append = [&](std::span<const std::byte> bytes) {
        written += bytes.size();
        return writeAll(fd, bytes);
    };
    int err = append(bytesOf(header));
    if (err == 0) err = append(bytesOf(headerChecksum));
    if (err == 0) err = append(std::as_bytes(std::span(table)));
    for (size_t i = 0; i < table.size() && err == 0; ++i) {
        err = append(std::span(kZeros).first(table[i].offset - written));
        if (err == 0) err = append(sections[i]);
    }
    if (err != 0) return ioError(fmt::format("writing {}", tempPath), err);
    if (::fsync(fd) != 0) return ioError(fmt::format("syncing {}", tempPath), errno);
    if (const int closeErr = file.close(); closeErr != 0)
        return ioError(fmt::format("closing {}", tempPath), closeErr);
    if (::rename(tempPath.c_str(), path.c_str()) != 0)
        return ioError(fmt::format("renaming {} over it", tempPath), errno);
    removeTemp.release();

    // Make the rename itself durable; some file systems cannot sync directories (EINVAL).
    const std::filesystem::path parent = std::filesystem::path(path).parent_path();
    const std::string directory = parent.empty() ? std::string(".") : parent.string();
    const int dirFd = ::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dirFd < 0) return ioError(fmt::format("opening directory {}", directory), errno);
    FileDescriptor dirFile(dirFd);
    if (::fsync(dirFd) != 0 && errno != EINVAL)
        return ioError(fmt::format("syncing directory {}", directory), errno);
    return {};
}


/// The arrays of a decoded file, copied.
BakeData bakeOf(const DecodedBake& decoded) {
    const BakeView& v = decoded.view;
    BakeData bake;
    bake.params = decoded.params.params;
    bake.defaults = decoded.params.defaults;
    bake.sceneHash = decoded.header.sceneHash;
    bake.surfels = toVector(v.surfels);
    bake.surfelWeights = toVector(v.surfelWeights);
    bake.nodes = toVector(v.nodes);
    bake.levelOffsets = toVector(v.levelOffsets);
    bake.caches = toVector(v.caches);
    bake.grid.origin = {v.grid.origin[0], v.grid.origin[1], v.grid.origin[2]};
    bake.grid.cellSize = v.grid.cellSize;
    bake.grid.dims = {v.grid.dims[0], v.grid.dims[1], v.grid.dims[2]};
    bake.grid.cacheIndex = toVector(v.gridIndex);
    bake.lightmap.width = v.lightmap.width;
    bake.lightmap.height = v.lightmap.height;
    bake.lightmap.texelSize = v.lightmap.texelSize;
    bake.lightmap.chartCount = v.lightmap.chartCount;
    bake.lightmap.cacheIndex = toVector(v.lightmapIndex);
    bake.lightmap.triangleUvs = toVector(v.lightmapUvs);
    bake.links.mode = static_cast<LinkMode>(v.links.mode);
    bake.links.linksPerCache = v.links.linksPerCache;
    bake.links.bands = v.links.bands;
    bake.links.rtp = toVector(v.rtp);
    bake.links.shNodes = toVector(v.shNodes);
    bake.links.shCoefficients = toVector(v.shCoefficients);
    bake.links.tint = toVector(v.tint);
    bake.links.offset = toVector(v.offset);
    bake.links.spreadShare = toVector(v.spreadShare);
    bake.surfelSky = toVector(v.surfelSky);
    bake.cacheSky = toVector(v.cacheSky);
    return bake;
}

}  // namespace

Result<void> writeBakeFile(const std::string& path, const BakeData& bake) {
    const std::string what = fmt::format("cannot write bake file {}", path);
    if (auto ok = checkParams(bake.params, ErrorCode::InvalidInput, what); !ok) return ok;
    const BakeView view = viewOf(bake);
    if (auto ok = checkContents(view, bake.params, view.caches.size(), ErrorCode::InvalidInput, what);
        !ok)
        return ok;
    PIC_TRY_ASSIGN(const std::string params, paramsJson(bake.params, bake.defaults, what));
    return writeSections(path, kBakeKind, bake.sceneHash, sectionBytesOf(view, params), what);
}

Result<BakeData> readBakeFile(const std::string& path) {
    PIC_TRY_ASSIGN(const DecodedBake decoded, decodeBakeFile(path, kBakeKind));
    return bakeOf(decoded);
}

Result<void> writeBakePart(const std::string& path, const BakePart& part) {
    const std::string what = fmt::format("cannot write bake part {}", path);
    const BakeData& bake = part.bake;
    const uint64_t nC = bake.caches.size();
    if (part.count == 0 || part.index >= part.count)
        return fail(ErrorCode::InvalidInput, "{}: shard {} of {}", what, part.index, part.count);
    if (part.cacheBegin > part.cacheEnd || part.cacheEnd > nC)
        return fail(ErrorCode::InvalidInput, "{}: caches [{}, {}) of {}", what, part.cacheBegin,
                    part.cacheEnd, nC);
    if (part.seesSurfel.size() != part.cacheEnd - part.cacheBegin ||
        std::ranges::any_of(part.seesSurfel, [](uint8_t x) { return x > 1; }))
        return fail(ErrorCode::InvalidInput, "{}: {} seesSurfel flags (0 or 1) for {} caches", what,
                    part.seesSurfel.size(), part.cacheEnd - part.cacheBegin);
    if (auto ok = checkParams(bake.params, ErrorCode::InvalidInput, what); !ok) return ok;
    const BakeView view = viewOf(bake);
    if (auto ok = checkContents(view, bake.params, part.cacheEnd - part.cacheBegin,
                                ErrorCode::InvalidInput, what);
        !ok)
        return ok;
    PIC_TRY_ASSIGN(const std::string params, paramsJson(bake.params, bake.defaults, what));
    const ShardRecord shard{part.index, part.count, part.cacheBegin, part.cacheEnd};
    const auto bakeSections = sectionBytesOf(view, params);
    std::array<std::span<const std::byte>, kPartSectionNames.size()> sections;
    std::ranges::copy(bakeSections, sections.begin());
    sections[kSectionCount] = bytesOf(shard);
    sections[kSectionCount + 1] = std::as_bytes(std::span(part.seesSurfel));
    return writeSections(path, kPartKind, bake.sceneHash, sections, what);
}

Result<BakePart> readBakePart(const std::string& path) {
    PIC_TRY_ASSIGN(const DecodedBake decoded, decodeBakeFile(path, kPartKind));
    BakePart part;
    part.index = decoded.shard.index;
    part.count = decoded.shard.count;
    part.cacheBegin = decoded.shard.cacheBegin;
    part.cacheEnd = decoded.shard.cacheEnd;
    part.seesSurfel = toVector(decoded.sees);
    part.bake = bakeOf(decoded);
    return part;
}

Result<BakeFileInfo> inspectBakeFile(const std::string& path) {
    PIC_TRY_ASSIGN(const DecodedBake decoded, decodeBakeFile(path, kBakeKind));
    const BakeView& v = decoded.view;
    const auto holdsCache = [](uint32_t index) { return index != kNoCache; };
    BakeFileInfo info;
    info.path = path;
    info.formatVersion = decoded.header.formatVersion;
    info.sceneHash = decoded.header.sceneHash;
    info.fileSize = decoded.header.fileSize;
    info.sectionBytes = decoded.sectionBytes;
    info.params = decoded.params.params;
    info.defaults = decoded.params.defaults;
    info.surfels = v.surfels.size();
    info.nodes = v.nodes.size();
    info.caches = v.caches.size();
    info.gridCaches = std::ranges::count_if(v.gridIndex, holdsCache);
    info.lightmapCaches = std::ranges::count_if(v.lightmapIndex, holdsCache);
    info.linksPerCache = v.links.linksPerCache;
    return info;
}

Result<void> checkSceneMatches(const BakeFileInfo& info, uint64_t sceneHash,
                               const std::string& scenePath) {
    if (info.sceneHash != sceneHash)
        return fail(ErrorCode::Corrupt,
                    "bake {} was made for a different scene (hash {:016x}, scene {} has hash "
                    "{:016x})",
                    info.path, info.sceneHash, scenePath, sceneHash);
    return {};
}

}  // namespace pic
