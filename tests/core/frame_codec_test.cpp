// The frame codec: lossless for every half pattern, key and delta; compact on smooth data;
// corrupt or mismatched frames refused without touching the receiver's state.

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/color.h"
#include "core/frame_codec.h"

namespace pic {
namespace {

/// A frame of smooth radiance-like planes (a few lit blobs over dark texels, zeros where
/// there is no cache), `shift` moving the light a little.
HalfFrame smoothFrame(uint32_t values, float shift) {
    HalfFrame frame;
    for (int t = 0; t < kFramePlanes; ++t) {
        std::vector<uint16_t>& plane = frame.planes[t];
        plane.resize(values + 17 * t);
        for (size_t i = 0; i < plane.size(); ++i) {
            const float x = float(i % 64) / 64.0f, y = float(i / 64 % 64) / 64.0f;
            const float lit = std::exp(-30.0f * ((x - 0.4f - shift) * (x - 0.4f - shift) + (y - 0.5f) * (y - 0.5f)));
            const float value = (i % 11 == 0) ? 0.0f : (t % 3 == 0 ? 2.0f : 0.3f) * lit - (t % 3 == 2 ? 0.05f : 0.0f);
            plane[i] = floatToHalf(value);
        }
    }
    return frame;
}

/// A frame of the same sizes as `like`, zero everywhere (what a receiver starts from).
HalfFrame zerosLike(const HalfFrame& like) {
    HalfFrame frame;
    for (int t = 0; t < kFramePlanes; ++t) frame.planes[t].assign(like.planes[t].size(), 0);
    return frame;
}

TEST(FrameCodec, KeyAndDeltaAreLosslessForEveryHalfPattern) {
    // Every one of the 65,536 patterns (NaNs, infinities, denormals, ±0) in every plane, in a
    // shuffled order, then a delta to another shuffle.
    HalfFrame a, b;
    std::mt19937 rng(7);
    for (int t = 0; t < kFramePlanes; ++t) {
        for (uint32_t h = 0; h < 65536; ++h) a.planes[t].push_back(uint16_t(h));
        b.planes[t] = a.planes[t];
        std::shuffle(a.planes[t].begin(), a.planes[t].end(), rng);
        std::shuffle(b.planes[t].begin(), b.planes[t].end(), rng);
    }
    auto key = encodeFrame(a, nullptr);
    ASSERT_TRUE(key) << key.error().message;
    EXPECT_TRUE(key->key());
    HalfFrame received = zerosLike(a);
    ASSERT_TRUE(decodeFrame(*key, received));
    EXPECT_TRUE(received == a);

    auto delta = encodeFrame(b, &a);
    ASSERT_TRUE(delta) << delta.error().message;
    EXPECT_FALSE(delta->key());
    ASSERT_TRUE(decodeFrame(*delta, received));
    EXPECT_TRUE(received == b);
}

TEST(FrameCodec, SmoothFramesAreCompact) {
    const HalfFrame first = smoothFrame(64 * 64 * 4, 0.0f);
    const HalfFrame second = smoothFrame(64 * 64 * 4, 0.01f);
    size_t values = 0;
    for (const auto& plane : first.planes) values += plane.size();

    auto key = encodeFrame(second, nullptr);
    auto delta = encodeFrame(second, &first);
    ASSERT_TRUE(key && delta);
    const double keyBits = 8.0 * double(key->bytes()) / double(values);
    const double deltaBits = 8.0 * double(delta->bytes()) / double(values);
    RecordProperty("key_bits_per_value", std::to_string(keyBits));
    RecordProperty("delta_bits_per_value", std::to_string(deltaBits));
    // Raw halves are 16 bits; smooth planes must compress well below that, and a small
    // light move must cost less as a delta than as a key frame.
    EXPECT_LT(keyBits, 8.0);
    EXPECT_LT(deltaBits, keyBits);
    // An unchanged frame costs almost nothing as a delta.
    auto same = encodeFrame(second, &second);
    ASSERT_TRUE(same);
    EXPECT_LT(8.0 * double(same->bytes()) / double(values), 0.1);

    HalfFrame received = zerosLike(first);
    ASSERT_TRUE(decodeFrame(*encodeFrame(first, nullptr), received));
    ASSERT_TRUE(decodeFrame(*delta, received));
    EXPECT_TRUE(received == second);
}

TEST(FrameCodec, MismatchedSizesAreRefused) {
    const HalfFrame a = smoothFrame(100, 0.0f);
    HalfFrame shorter = a;
    shorter.planes[1].pop_back();
    auto bad = encodeFrame(a, &shorter);
    ASSERT_FALSE(bad);
    EXPECT_NE(bad.error().message.find("cache_co"), std::string::npos) << bad.error().message;

    // A receiver whose layout differs refuses the frame and keeps its state.
    auto key = encodeFrame(a, nullptr);
    ASSERT_TRUE(key);
    HalfFrame received = zerosLike(shorter);
    const HalfFrame before = received;
    auto decoded = decodeFrame(*key, received);
    ASSERT_FALSE(decoded);
    EXPECT_EQ(decoded.error().code, ErrorCode::Corrupt);
    EXPECT_NE(decoded.error().message.find("cache_co"), std::string::npos)
        << decoded.error().message;
    EXPECT_TRUE(received == before);
}

TEST(FrameCodec, CorruptFramesAreRefusedWithoutTouchingTheState) {
    const HalfFrame a = smoothFrame(5000, 0.0f);
    auto key = encodeFrame(a, nullptr);
    ASSERT_TRUE(key);
    const HalfFrame start = zerosLike(a);
    std::mt19937 rng(3);
    int refused = 0;
    for (int trial = 0; trial < 200; ++trial) {
        EncodedFrame broken = *key;
        EncodedPlane& plane = broken.planes[trial % kFramePlanes];
        switch (trial % 4) {
        case 0: plane.bytes.resize(plane.bytes.size() / 2); break;          // truncated
        case 1: plane.bytes[rng() % plane.bytes.size()] ^= uint8_t(1 + rng() % 255); break;  // flipped
        case 2: plane.values += 1; break;                                   // wrong count
        case 3: plane.encoding = PlaneEncoding(9); break;                   // unknown encoding
        }
        HalfFrame received = start;
        auto decoded = decodeFrame(broken, received);
        if (!decoded) {
            ++refused;
            EXPECT_TRUE(received == start) << "trial " << trial;
        }
    }
    EXPECT_EQ(refused, 200);  // flipped bits too: every plane carries zstd's checksum
}

TEST(FrameCodec, CachePlanesAreCoefficientMajorAndGiveTheValuesBack) {
    // Three caches, lY 2 (4 luma coefficients), lC 1; every value a distinct half.
    CacheValues values = CacheValues::zeros(3, 2, 1);
    for (size_t i = 0; i < values.y.size(); ++i) values.y[i] = 0.25f * float(i) - 1.0f;
    for (size_t c = 0; c < 3; ++c) {
        values.co[c] = 10.0f + float(c);
        values.cg[c] = -20.0f - float(c);
    }
    values.y[5] = 1e6f;  // beyond half range: saturated, never infinite
    const HalfFrame frame = halfFrameOf(values);
    EXPECT_EQ(frameValues(frame), 3u * (4 + 1 + 1));
    // Coefficient k of cache c at k·nC + c.
    EXPECT_EQ(frame.planes[0][1 * 3 + 2], floatToHalf(values.y[2 * 4 + 1]));
    EXPECT_EQ(frame.planes[2][1], floatToHalf(-21.0f));
    EXPECT_EQ(halfToFloat(frame.planes[0][1 * 3 + 1]), 65504.0f);

    auto back = cacheValuesOf(frame, 3, 2, 1);
    ASSERT_TRUE(back) << back.error().message;
    values.y[5] = 65504.0f;
    EXPECT_EQ(back->y, values.y);
    EXPECT_EQ(back->co, values.co);
    EXPECT_EQ(back->cg, values.cg);

    // A plane that does not hold the caches × coefficients is refused, naming it, and so are
    // band counts no frame can have.
    auto refused = cacheValuesOf(frame, 4, 2, 1);
    ASSERT_FALSE(refused);
    EXPECT_NE(refused.error().message.find("cache_y"), std::string::npos)
        << refused.error().message;
    EXPECT_FALSE(cacheValuesOf(frame, 3, 1, 2));
    EXPECT_FALSE(cacheValuesOf(frame, 3, 0, 0));
}

}  // namespace
}  // namespace pic
