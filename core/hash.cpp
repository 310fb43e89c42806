#include "core/hash.h"

#include <cstring>

namespace pic {

namespace {
inline uint64_t mix(uint64_t h, uint64_t k) {
    // One round of a multiply-xorshift mixer (after MurmurHash3's fmix64 constants).
    k *= 0xff51afd7ed558ccdull;
    k ^= k >> 33;
    h ^= k;
    h *= 0xc4ceb9fe1a85ec53ull;
    return h ^ (h >> 29);
}
}  // namespace

uint64_t hashBytes(const void* data, size_t size, uint64_t seed) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    uint64_t h = seed ^ (size * 0x9E3779B97F4A7C15ull);
    size_t i = 0;
    // Four independent lanes keep the multiplier pipeline busy on large sections.
    uint64_t lanes[4] = {h, h ^ 1, h ^ 2, h ^ 3};
    for (; i + 32 <= size; i += 32) {
        for (int l = 0; l < 4; ++l) {
            uint64_t k;
            std::memcpy(&k, bytes + i + 8 * l, 8);
            lanes[l] = mix(lanes[l], k);
        }
    }
    h = mix(mix(mix(mix(h, lanes[0]), lanes[1]), lanes[2]), lanes[3]);
    for (; i + 8 <= size; i += 8) {
        uint64_t k;
        std::memcpy(&k, bytes + i, 8);
        h = mix(h, k);
    }
    uint64_t tail = 0;
    if (i < size) {
        std::memcpy(&tail, bytes + i, size - i);
        h = mix(h, tail ^ 0xA5A5A5A5A5A5A5A5ull);
    }
    return mix(h, size);
}

}  // namespace pic
