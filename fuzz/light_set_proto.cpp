// Light sets as SetLights carries them (proto/pic.proto LightSet), from any client.

#include "fuzz/fuzz.h"
#include "proto/wire.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace pic;
    v1::LightSet wire;
    if (!wire.ParseFromArray(data, int(size))) return 0;
    const auto lights = wire::fromProto(wire);
    if (!lights) return 0;
    // Accepted once, accepted again as the server sends it back (JoinSession).
    const auto again = wire::fromProto(wire::toProto(*lights));
    PIC_CHECK(again);
    PIC_CHECK(toJson(*again) == toJson(*lights));
    return 0;
}
