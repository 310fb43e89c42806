#pragma once
/// The frame codec: one version's caches, as half floats, compressed for the stream (paper
/// 001's YCoCg split: Y with lY² coefficients per cache, Co and Cg with lC²). Lossless:
/// decoding reproduces the encoder's half-float input bit for bit.
///
/// A frame holds the unique caches, not the textures renderers sample: the thin client
/// writes them into its textures through the index maps it downloaded with the scene
/// (core/cache_textures.h), which hold most caches more than once. Each of the three
/// planes (Y, Co, Cg) is coefficient-major, coefficient k of cache c at k·nC + c, so that
/// neighbouring values are the same coefficient of neighbouring caches; each is coded on
/// its own:
///   1. each half's bit pattern h becomes its rank o(h) in float order (negative values
///      reversed), so that nearby values have nearby ranks across zero;
///   2. key planes take the difference from the previous value in the plane (caches placed
///      one after another are mostly near each other), delta planes the difference from the
///      same value in the base version (a light change moves most values a little);
///      differences wrap mod 2¹⁶;
///   3. differences are zigzagged (small negatives become small positives) and split into
///      a plane of low bytes followed by a plane of high bytes, mostly zero;
///   4. zstd.
/// A delta frame applies only to the exact base version it was made from; a receiver that
/// holds another version needs a key frame.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/cache_values.h"
#include "core/error.h"

namespace pic {

/// The planes of a frame, in wire order: the caches' Y, Co and Cg coefficients.
enum class FramePlane : uint8_t { CacheY, CacheCo, CacheCg };
inline constexpr int kFramePlanes = 3;

/// "cache_y", "cache_co", "cache_cg" for logs and messages.
const char* framePlaneName(int plane);

/// Every plane of one version as half-float bit patterns: what the encoder takes and the
/// decoder reproduces.
struct HalfFrame {
    std::array<std::vector<uint16_t>, kFramePlanes> planes;

    bool operator==(const HalfFrame&) const = default;
};

enum class PlaneEncoding : uint8_t {
    Key = 1,    ///< the plane alone
    Delta = 2,  ///< the difference from the base version's plane
};

struct EncodedPlane {
    PlaneEncoding encoding = PlaneEncoding::Key;
    uint32_t values = 0;        ///< halves in the decoded plane
    std::vector<uint8_t> bytes; ///< one zstd frame of 2·values bytes
};

struct EncodedFrame {
    std::array<EncodedPlane, kFramePlanes> planes;

    /// Compressed bytes over all planes.
    size_t bytes() const;
    /// Whether every plane is a key plane (decodable without a base).
    bool key() const;
};

/// zstd level of the stream. `picbench codec` on the atrium and the living room: levels 3 to
/// 9 code the caches at most 2.4 % smaller than level 1 does, for 1.4–4.5 times its encode
/// time.
inline constexpr int kDefaultZstdLevel = 1;

/// Encodes `frame` as a key frame (`base` null) or as the difference from `base`, whose
/// planes must have the same sizes (InvalidInput naming the plane otherwise).
Result<EncodedFrame> encodeFrame(const HalfFrame& frame, const HalfFrame* base,
                                 int zstdLevel = kDefaultZstdLevel);

/// The caches' three coefficient planes (Y, Co, Cg; layout above) as half floats, saturated
/// to ±65504 so that no infinity reaches a client. The GPU writes halves already, so this
/// loses nothing there.
HalfFrame halfFrameOf(const CacheValues& values);

/// The caches again from the planes, halves widened to floats: what a client holds.
/// InvalidInput naming the plane when a plane does not hold `caches` × its coefficients.
Result<CacheValues> cacheValuesOf(const HalfFrame& frame, size_t caches, uint32_t bandsY,
                                  uint32_t bandsC);

/// Values over all three planes: lY² + 2·lC² SH coefficients per cache.
size_t frameValues(const HalfFrame& frame);

/// Decodes `encoded` into `frame`, whose planes already have their sizes (from the scene's
/// layout): a key plane replaces its plane, a delta plane applies to it, which must hold the
/// base version. Corrupt input, a size that does not match or a zstd failure gives Corrupt
/// naming the plane, and leaves `frame` unchanged.
Result<void> decodeFrame(const EncodedFrame& encoded, HalfFrame& frame);

}  // namespace pic
