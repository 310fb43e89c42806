#include "core/frame_codec.h"

#include <memory>

#include <zstd.h>

#include "core/color.h"
#include "core/sh.h"

namespace pic {
namespace {

/// Rank of a half's bit pattern in float order: negative values (sign set) reversed below
/// the positives, so that −0 and +0 are neighbours and so are −ε and +ε.
uint16_t orderOf(uint16_t h) { return (h & 0x8000u) ? uint16_t(~h) : uint16_t(h | 0x8000u); }
uint16_t halfOfOrder(uint16_t o) { return (o & 0x8000u) ? uint16_t(o & 0x7fffu) : uint16_t(~o); }

/// int16 differences as small unsigned numbers: 0, −1, 1, −2, … → 0, 1, 2, 3, …
uint16_t zigzag(uint16_t d) {
    const auto s = int16_t(d);
    return uint16_t((uint16_t(s) << 1) ^ uint16_t(s >> 15));
}
uint16_t unzigzag(uint16_t z) { return uint16_t((z >> 1) ^ uint16_t(-(z & 1))); }

/// The plane's differences (steps 1–3 of the header), low bytes then high bytes.
std::vector<uint8_t> transform(std::span<const uint16_t> plane, const uint16_t* base) {
    const size_t n = plane.size();
    std::vector<uint8_t> bytes(2 * n);
    uint16_t previous = orderOf(0);
    for (size_t i = 0; i < n; ++i) {
        const uint16_t o = orderOf(plane[i]);
        const uint16_t reference = base ? orderOf(base[i]) : previous;
        const uint16_t z = zigzag(uint16_t(o - reference));
        bytes[i] = uint8_t(z & 0xffu);
        bytes[n + i] = uint8_t(z >> 8);
        previous = o;
    }
    return bytes;
}

/// Inverse of transform, in place over `plane` (which holds the base for delta planes).
void untransform(std::span<const uint8_t> bytes, bool delta, std::span<uint16_t> plane) {
    const size_t n = plane.size();
    uint16_t previous = orderOf(0);
    for (size_t i = 0; i < n; ++i) {
        const uint16_t z = uint16_t(bytes[i] | (uint16_t(bytes[n + i]) << 8));
        const uint16_t reference = delta ? orderOf(plane[i]) : previous;
        const uint16_t o = uint16_t(reference + unzigzag(z));
        plane[i] = halfOfOrder(o);
        previous = o;
    }
}

}  // namespace

const char* framePlaneName(int plane) {
    static const char* const kNames[kFramePlanes] = {"cache_y", "cache_co", "cache_cg"};
    return plane >= 0 && plane < kFramePlanes ? kNames[plane] : "unknown";
}

size_t EncodedFrame::bytes() const {
    size_t total = 0;
    for (const EncodedPlane& p : planes) total += p.bytes.size();
    return total;
}

bool EncodedFrame::key() const {
    for (const EncodedPlane& p : planes)
        if (p.encoding != PlaneEncoding::Key) return false;
    return true;
}

Result<EncodedFrame> encodeFrame(const HalfFrame& frame, const HalfFrame* base, int zstdLevel) {
    // One context per frame; zstd's content checksum lets the decoder refuse damaged bytes.
    std::unique_ptr<ZSTD_CCtx, size_t (*)(ZSTD_CCtx*)> context(ZSTD_createCCtx(), ZSTD_freeCCtx);
    if (!context ||
        ZSTD_isError(ZSTD_CCtx_setParameter(context.get(), ZSTD_c_compressionLevel, zstdLevel)) ||
        ZSTD_isError(ZSTD_CCtx_setParameter(context.get(), ZSTD_c_checksumFlag, 1)))
        return fail(ErrorCode::Internal, "zstd: could not set up compression at level {}", zstdLevel);
    EncodedFrame encoded;
    for (int t = 0; t < kFramePlanes; ++t) {
        const std::vector<uint16_t>& plane = frame.planes[t];
        if (plane.size() > UINT32_MAX / 2)
            return fail(ErrorCode::InvalidInput, "frame plane {} has {} values, too many",
                        framePlaneName(t), plane.size());
        if (base && base->planes[t].size() != plane.size())
            return fail(ErrorCode::InvalidInput, "frame plane {} has {} values but its base has {}",
                        framePlaneName(t), plane.size(), base->planes[t].size());
        const std::vector<uint8_t> raw = transform(plane, base ? base->planes[t].data() : nullptr);
        EncodedPlane& out = encoded.planes[t];
        out.encoding = base ? PlaneEncoding::Delta : PlaneEncoding::Key;
        out.values = uint32_t(plane.size());
        out.bytes.resize(ZSTD_compressBound(raw.size()));
        const size_t size = ZSTD_compress2(context.get(), out.bytes.data(), out.bytes.size(),
                                           raw.data(), raw.size());
        if (ZSTD_isError(size))
            return fail(ErrorCode::Internal, "zstd could not compress plane {}: {}",
                        framePlaneName(t), ZSTD_getErrorName(size));
        out.bytes.resize(size);
    }
    return encoded;
}

Result<void> decodeFrame(const EncodedFrame& encoded, HalfFrame& frame) {
    // Decompress and check every plane before touching `frame`, so that a bad frame leaves
    // the receiver's state as it was.
    std::array<std::vector<uint8_t>, kFramePlanes> raw;
    for (int t = 0; t < kFramePlanes; ++t) {
        const EncodedPlane& plane = encoded.planes[t];
        const char* name = framePlaneName(t);
        if (plane.encoding != PlaneEncoding::Key && plane.encoding != PlaneEncoding::Delta)
            return fail(ErrorCode::Corrupt, "frame plane {}: unknown encoding {}", name,
                        int(plane.encoding));
        if (plane.values != frame.planes[t].size())
            return fail(ErrorCode::Corrupt, "frame plane {} has {} values, the scene's layout {}",
                        name, plane.values, frame.planes[t].size());
        const size_t expected = 2 * size_t{plane.values};
        const unsigned long long content = ZSTD_getFrameContentSize(plane.bytes.data(), plane.bytes.size());
        if (content == ZSTD_CONTENTSIZE_ERROR || content == ZSTD_CONTENTSIZE_UNKNOWN)
            return fail(ErrorCode::Corrupt, "frame plane {}: not a zstd frame ({} bytes)", name,
                        plane.bytes.size());
        if (content != expected)
            return fail(ErrorCode::Corrupt, "frame plane {}: zstd frame holds {} bytes, expected {}",
                        name, content, expected);
        raw[t].resize(expected);
        const size_t size = ZSTD_decompress(raw[t].data(), expected, plane.bytes.data(), plane.bytes.size());
        if (ZSTD_isError(size))
            return fail(ErrorCode::Corrupt, "frame plane {}: zstd: {}", name, ZSTD_getErrorName(size));
        if (size != expected)
            return fail(ErrorCode::Corrupt, "frame plane {}: decompressed {} bytes, expected {}",
                        name, size, expected);
    }
    for (int t = 0; t < kFramePlanes; ++t)
        untransform(raw[t], encoded.planes[t].encoding == PlaneEncoding::Delta, frame.planes[t]);
    return {};
}

HalfFrame halfFrameOf(const CacheValues& values) {
    HalfFrame frame;
    const size_t caches = values.cacheCount();
    const std::array<const std::vector<float>*, kFramePlanes> channels = {&values.y, &values.co,
                                                                          &values.cg};
    for (int ch = 0; ch < kFramePlanes; ++ch) {
        // Cache-major in, coefficient-major out.
        const std::vector<float>& source = *channels[size_t(ch)];
        const size_t count = caches ? source.size() / caches : 0;
        std::vector<uint16_t>& plane = frame.planes[size_t(ch)];
        plane.resize(source.size());
        for (size_t c = 0; c < caches; ++c)
            for (size_t k = 0; k < count; ++k)
                plane[k * caches + c] = floatToHalfClamped(source[c * count + k]);
    }
    return frame;
}

Result<CacheValues> cacheValuesOf(const HalfFrame& frame, size_t caches, uint32_t bandsY,
                                  uint32_t bandsC) {
    if (bandsY < 1 || bandsY > uint32_t(kMaxShBands) || bandsC > bandsY)
        return fail(ErrorCode::InvalidInput, "frame: {} luma and {} chroma bands are out of range",
                    bandsY, bandsC);
    const auto countOf = [&](int ch) {
        return ch == 0 ? size_t{bandsY} * bandsY : size_t{bandsC} * bandsC;
    };
    // Sizes first, so that nothing is allocated for a count the frame does not hold.
    for (int ch = 0; ch < kFramePlanes; ++ch)
        if (frame.planes[size_t(ch)].size() != caches * countOf(ch))
            return fail(ErrorCode::InvalidInput,
                        "frame plane {} holds {} values; {} caches × {} coefficients need {}",
                        framePlaneName(ch), frame.planes[size_t(ch)].size(), caches, countOf(ch),
                        caches * countOf(ch));
    CacheValues values = CacheValues::zeros(caches, bandsY, bandsC);
    std::array<std::vector<float>*, kFramePlanes> channels = {&values.y, &values.co, &values.cg};
    for (int ch = 0; ch < kFramePlanes; ++ch) {
        std::vector<float>& target = *channels[size_t(ch)];
        const std::vector<uint16_t>& plane = frame.planes[size_t(ch)];
        const size_t count = countOf(ch);
        for (size_t c = 0; c < caches; ++c)
            for (size_t k = 0; k < count; ++k)
                target[c * count + k] = halfToFloat(plane[k * caches + c]);
    }
    return values;
}

size_t frameValues(const HalfFrame& frame) {
    size_t values = 0;
    for (const auto& plane : frame.planes) values += plane.size();
    return values;
}

}  // namespace pic
