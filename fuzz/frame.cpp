// Frames as a thin client receives them from a server (proto/pic.proto Frame): the planes
// read from the wire, then decoded into the layout of a scene of 64 caches, lY 3 and lC 2, as
// the client's FrameDecoder does (its size check first, then a key frame into a copy).

#include "core/frame_codec.h"
#include "fuzz/fuzz.h"
#include "proto/wire.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace pic;
    v1::Frame wire;
    if (!wire.ParseFromArray(data, int(size))) return 0;
    auto encoded = wire::planesFromProto(wire);
    if (!encoded) return 0;
    constexpr uint32_t kCaches = 64;
    const uint32_t expected[kFramePlanes] = {kCaches * 9, kCaches * 4, kCaches * 4};
    for (int t = 0; t < kFramePlanes; ++t)
        if (encoded->planes[size_t(t)].values != expected[t]) return 0;
    // A held version to apply deltas to, and a copy to see that a failure changes nothing.
    HalfFrame frame;
    for (int t = 0; t < kFramePlanes; ++t) frame.planes[size_t(t)].assign(expected[t], uint16_t(0x3C00));
    const HalfFrame before = frame;
    if (!decodeFrame(*encoded, frame)) {
        PIC_CHECK(frame == before);
        return 0;
    }
    for (int t = 0; t < kFramePlanes; ++t) PIC_CHECK(frame.planes[size_t(t)].size() == expected[t]);
    return 0;
}
