// Bake files and parts of sharded bakes: what picserver, picref and picbake merge map and
// index without bounds checks once the reader has passed them.

#include "core/bake_file.h"
#include "fuzz/fuzz.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace pic;
    const std::string& path = fuzz::scratchFile(fuzz::text(data, size), ".pic");
    const auto bake = readBakeFile(path);
    const auto info = inspectBakeFile(path);
    // The summary validates exactly what the reader validates.
    PIC_CHECK(bool(bake) == bool(info));
    if (bake) {
        PIC_CHECK(info->caches == bake->caches.size() && info->surfels == bake->surfels.size());
        // What the reader accepts, the writer writes again (the same checks both ways).
        const std::string copy = path + ".copy";
        PIC_CHECK(writeBakeFile(copy, *bake));
        PIC_CHECK(readBakeFile(copy));
    }
    if (const auto part = readBakePart(path)) {
        PIC_CHECK(!bake);  // a file is a bake or a part, never both
        PIC_CHECK(part->cacheBegin <= part->cacheEnd && part->cacheEnd <= part->bake.caches.size());
        PIC_CHECK(part->seesSurfel.size() == part->cacheEnd - part->cacheBegin);
    }
    return 0;
}
