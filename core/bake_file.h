#pragma once
/// The bake file (ARCHITECTURE.md §6): writes a BakeData atomically, reads it back through
/// one read-only mmap, and refuses files whose format, version, checksums or counts are wrong.
///
/// Layout (version kBakeFormatVersion). Little-endian, fixed-width types, no implicit padding; every byte the
/// writer emits is determined by the BakeData, so identical bakes give identical files.
///
///   offset  size  field
///   0       8     magic "PICBAKE\0"
///   8       4     u32 format version (kBakeFormatVersion)
///   12      4     u32 section count n
///   16      8     u64 scene hash (BakeData::sceneHash)
///   24      8     u64 file size in bytes
///   32      8     u64 hashBytes of the section table
///   40      8     u64 hashBytes of bytes [0, 40): the header checksum
///   48      48·n  section table, one entry per section:
///                   24  name, NUL-padded ASCII
///                    8  u64 offset from the start of the file, a multiple of 64
///                    8  u64 size in bytes
///                    8  u64 hashBytes of the section's bytes
///   …             sections in table order, each starting at the next multiple of 64 so that
///                 an mmap'ed file can be used in place; zero bytes between them; the file
///                 ends with the last section.
///
/// Sections (all present, possibly empty; nS surfels, nC caches, nL links per cache):
///   params           JSON object: every BakeParams field (link_mode "sh"|"rtp", hierarchy
///                    "agglomerative"|"kdtree") and "defaults" {parameter: how it was chosen}
///   surfels          nS × gpu::Surfel (64 bytes)
///   surfel_weights   nS × f32 flux weight, finite and positive (BakeData::surfelWeights)
///   nodes            (2·nS − 1) × gpu::Node (64 bytes); empty when nS = 0
///   levels           u32 level offsets, non-decreasing, ≤ node count
///   caches           nC × gpu::Cache (32 bytes)
///   grid             f32 origin[3], f32 cell size, u32 dims[3], u32 zero
///   grid_index       dims.x·dims.y·dims.z × u32 cache index (kNoCache: none)
///   lightmap         u32 width, u32 height, f32 texel size, u32 chart count
///   lightmap_index   width·height × u32 cache index (kNoCache: none)
///   lightmap_uvs     3 per scene triangle × f32[2]
///   links            u32 link mode, u32 nL, u32 SH bands per link, u32 zero
///   links_rtp        RTP mode: nC·nL × gpu::RtpLink (16 bytes); SH mode: empty
///   links_sh_nodes   SH mode: nC·nL × u32 node index (padding: node 0 with zero coefficients)
///   links_sh_coeffs  SH mode: nC·nL·bands² × u16 half float; RTP mode: empty
///   links_tint       nC·nL × u32 link tint (core/color.h encodeLinkTint), both modes
///   links_offset     nC·nL·3 × u16 finite half float, metres (LinkSet::offset), both modes
///   links_spread_share nC·nL × u8 code ≤ 63 (LinkSet::spreadShare, encodeSpreadShare), both modes
///   surfel_sky       nS·9 × f32 sky transfer (BakeData::surfelSky); empty when sky_rays is 0
///   cache_sky        nC·skyVisibilityBands(lY)² × f32 sky visibility (BakeData::cacheSky);
///                    empty when sky_rays is 0
///
/// A part of a sharded bake (BakePart) has the same layout with magic "PICPART\0", the links of
/// its cache range only (cacheEnd − cacheBegin caches in every links_* section and in cache_sky) and two more
/// sections after cache_sky:
///   shard            u32 index I, u32 count N, u64 cacheBegin, u64 cacheEnd
///   shard_sees       (cacheEnd − cacheBegin) × u8: 1 where the cache's links see a surfel, else 0
///
/// Both directions check that the counts agree and that every node and cache index is in range
/// (kNoNode / kNoCache aside; RTP padding links have factor 0), so the runtime can index the
/// arrays without bounds checks.

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/bake_data.h"
#include "core/error.h"

namespace pic {

/// Format version written into, and required of, every bake file.
inline constexpr uint32_t kBakeFormatVersion = 7;
/// Bytes of the header including its trailing checksum; the section table follows.
inline constexpr uint64_t kBakeHeaderBytes = 48;
/// Bytes of one section table entry.
inline constexpr uint64_t kBakeSectionEntryBytes = 48;
/// Every section starts at a multiple of this many bytes.
inline constexpr uint64_t kBakeSectionAlignment = 64;

/// Writes `bake` to `path` atomically (temp file in the same directory, fsync, rename);
/// InvalidInput if the bake's arrays are inconsistent, Io naming the path on any failure.
Result<void> writeBakeFile(const std::string& path, const BakeData& bake);

/// Reads and fully validates a bake file: NotFound if missing, Corrupt naming what is wrong (a
/// part of a sharded bake given as a bake, too).
Result<BakeData> readBakeFile(const std::string& path);

/// One part of a sharded bake (`picbake bake --shard I/N`): the bake as it stands before the
/// caches that see no surfel are dropped, every cache present, with the links of the caches
/// [cacheBegin, cacheEnd) only. `picbake merge` joins the parts (bake/bake.h BakeJoiner).
struct BakePart {
    uint32_t index = 0;                ///< I, from 0
    uint32_t count = 1;                ///< N
    uint64_t cacheBegin = 0;
    uint64_t cacheEnd = 0;
    std::vector<uint8_t> seesSurfel;   ///< per cache of the range: 1 when its links see a surfel or it sees the sky
    BakeData bake;                     ///< links: (cacheEnd − cacheBegin)·nL entries
};

/// Writes a part atomically, as writeBakeFile writes a bake.
Result<void> writeBakePart(const std::string& path, const BakePart& part);

/// Reads and fully validates a part: NotFound if missing, Corrupt naming what is wrong (a whole
/// bake given as a part, too).
Result<BakePart> readBakePart(const std::string& path);

/// A summary of a validated bake file, for `picbake info`.
struct BakeFileInfo {
    std::string path;
    uint32_t formatVersion = 0;
    uint64_t sceneHash = 0;
    uint64_t fileSize = 0;
    std::vector<std::pair<std::string, uint64_t>> sectionBytes;  ///< in file order
    BakeParams params;
    std::map<std::string, std::string> defaults;
    uint64_t surfels = 0;         ///< nS
    uint64_t nodes = 0;           ///< 2·nS − 1
    uint64_t caches = 0;          ///< nC unique caches
    uint64_t gridCaches = 0;      ///< grid vertices holding a cache index
    uint64_t lightmapCaches = 0;  ///< light-map texels holding a cache index
    uint64_t linksPerCache = 0;   ///< nL
};

/// Validates a bake file exactly as readBakeFile does (all checksums) and summarises it
/// without copying its arrays.
Result<BakeFileInfo> inspectBakeFile(const std::string& path);

/// Corrupt if the bake was made for a scene whose hash differs from `sceneHash`.
Result<void> checkSceneMatches(const BakeFileInfo& info, uint64_t sceneHash,
                               const std::string& scenePath);

}  // namespace pic
