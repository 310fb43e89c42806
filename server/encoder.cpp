#include "server/encoder.h"

#include "core/color.h"

namespace pic {

HalfFrame halfFrameOf(const CacheTextures& textures) {
    HalfFrame frame;
    for (int ch = 0; ch < 3; ++ch) {
        const std::vector<float>* sources[2] = {&textures.grid[ch], &textures.lightmap[ch]};
        for (int kind = 0; kind < 2; ++kind) {
            std::vector<uint16_t>& plane = frame.planes[3 * kind + ch];
            plane.resize(sources[kind]->size());
            for (size_t i = 0; i < plane.size(); ++i) plane[i] = floatToHalfClamped((*sources[kind])[i]);
        }
    }
    return frame;
}

size_t frameValues(const HalfFrame& frame) {
    size_t values = 0;
    for (const auto& plane : frame.planes) values += plane.size();
    return values;
}

}  // namespace pic
