#include "core/texture.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace pic {

namespace {

/// Maps a texel coordinate (in texel units, centres at i + 0.5) to the index of the texel at or
/// left of it, and the next one, under the wrap mode; `fraction` is the weight of the second.
struct TexelPair {
    int i0;
    int i1;
    float fraction;
};

TexelPair texelPair(float coord, int size, bool repeat) {
    // Reduce before scaling so huge or negative coordinates never overflow the int conversion;
    // a non-finite coordinate reads texel 0 rather than spreading NaN into lighting.
    if (!std::isfinite(coord)) coord = 0.0f;
    coord = repeat ? coord - std::floor(coord) : std::fmin(std::fmax(coord, 0.0f), 1.0f);
    float x = coord * static_cast<float>(size) - 0.5f;
    float base = std::floor(x);
    int i0 = static_cast<int>(base);
    int i1 = i0 + 1;
    if (repeat) {
        if (i0 < 0) i0 += size;
        if (i1 >= size) i1 -= size;
    } else {
        i0 = i0 < 0 ? 0 : i0;
        i1 = i1 >= size ? size - 1 : i1;
    }
    return {i0, i1, x - base};
}

/// Bilinear lookup of a width × height level under the wrap modes.
glm::vec4 bilinear(const glm::vec4* texels, int width, int height, glm::vec2 uv, bool repeatS,
                   bool repeatT) {
    TexelPair s = texelPair(uv.x, width, repeatS);
    TexelPair t = texelPair(uv.y, height, repeatT);
    auto at = [&](int x, int y) { return texels[size_t(y) * size_t(width) + size_t(x)]; };
    glm::vec4 top = glm::mix(at(s.i0, t.i0), at(s.i1, t.i0), s.fraction);
    glm::vec4 bottom = glm::mix(at(s.i0, t.i1), at(s.i1, t.i1), s.fraction);
    return glm::mix(top, bottom, t.fraction);
}

/// One finer texel's share of a coarser texel along one axis.
struct Share {
    int index;
    float weight;
};

/// For each of the `target` texels along an axis, the `source` texels its interval
/// [i·s/t, (i + 1)·s/t] overlaps and their overlap ÷ the interval's length (summing to 1).
std::vector<std::vector<Share>> axisShares(int source, int target) {
    std::vector<std::vector<Share>> shares(static_cast<size_t>(target));
    const double ratio = double(source) / double(target);
    for (int i = 0; i < target; ++i) {
        const double begin = i * ratio;
        const double end = (i + 1) * ratio;
        for (int j = int(std::floor(begin)); j < std::min(source, int(std::ceil(end))); ++j) {
            const double overlap = std::min(end, double(j + 1)) - std::max(begin, double(j));
            if (overlap > 0.0) shares[size_t(i)].push_back({j, float(overlap / ratio)});
        }
    }
    return shares;
}

/// The next level of a width × height level: the area-weighted box average, x then y.
MipLevel downsample(const glm::vec4* texels, int width, int height) {
    MipLevel next;
    next.width = std::max(1, width / 2);
    next.height = std::max(1, height / 2);
    const auto sharesX = axisShares(width, next.width);
    const auto sharesY = axisShares(height, next.height);
    // Rows first: next.width × height.
    std::vector<glm::vec4> rows(size_t(next.width) * size_t(height), glm::vec4(0.0f));
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < next.width; ++x) {
            glm::vec4 sum(0.0f);
            for (const Share& s : sharesX[size_t(x)])
                sum += s.weight * texels[size_t(y) * size_t(width) + size_t(s.index)];
            rows[size_t(y) * size_t(next.width) + size_t(x)] = sum;
        }
    next.texels.assign(size_t(next.width) * size_t(next.height), glm::vec4(0.0f));
    for (int y = 0; y < next.height; ++y)
        for (int x = 0; x < next.width; ++x) {
            glm::vec4 sum(0.0f);
            for (const Share& s : sharesY[size_t(y)])
                sum += s.weight * rows[size_t(s.index) * size_t(next.width) + size_t(x)];
            next.texels[size_t(y) * size_t(next.width) + size_t(x)] = sum;
        }
    return next;
}

}  // namespace

void buildMipChain(Texture& texture) {
    PIC_CHECK(texture.width > 0 && texture.height > 0);
    PIC_CHECK_EQ(texture.texels.size(), size_t(texture.width) * size_t(texture.height));
    texture.mips.clear();
    const glm::vec4* texels = texture.texels.data();
    int width = texture.width;
    int height = texture.height;
    while (width > 1 || height > 1) {
        texture.mips.push_back(downsample(texels, width, height));
        const MipLevel& level = texture.mips.back();
        texels = level.texels.data();
        width = level.width;
        height = level.height;
    }
}

glm::vec4 Texture::sample(glm::vec2 uv) const {
    return sampleLevel(uv, 0);
}

glm::vec4 Texture::sampleLevel(glm::vec2 uv, int level) const {
    PIC_DCHECK(width > 0 && height > 0 && texels.size() == size_t(width) * size_t(height));
    level = std::clamp(level, 0, int(mips.size()));
    if (level == 0) return bilinear(texels.data(), width, height, uv, repeatS, repeatT);
    const MipLevel& m = mips[size_t(level - 1)];
    return bilinear(m.texels.data(), m.width, m.height, uv, repeatS, repeatT);
}

glm::vec4 Texture::sampleTrilinear(glm::vec2 uv, float lod) const {
    // Written so that NaN reads the last level, like the footprint of a grazing ray.
    if (!(lod > 0.0f)) return std::isnan(lod) ? sampleLevel(uv, int(mips.size())) : sample(uv);
    const float last = float(mips.size());
    if (lod >= last) return sampleLevel(uv, int(mips.size()));
    const float base = std::floor(lod);
    const float fraction = lod - base;
    const glm::vec4 fine = sampleLevel(uv, int(base));
    if (fraction == 0.0f) return fine;
    return glm::mix(fine, sampleLevel(uv, int(base) + 1), fraction);
}

glm::vec4 Texture::sampleFootprint(glm::vec2 uv, glm::vec2 dUvdx, glm::vec2 dUvdy) const {
    const TextureFootprint footprint = textureFootprint(dUvdx, dUvdy, width, height, levelCount());
    // Each tap is trilinear between the same two levels; the taps are summed per level and
    // blended once (the G-buffer shader's order: it reads each level's record once).
    const float last = float(mips.size());
    const float base = std::fmin(std::floor(footprint.lod), last);
    const float fraction = footprint.lod - base;  // 0 at the last level
    const int fine = int(base);
    const int coarse = std::min(fine + 1, int(mips.size()));
    const float taps = float(footprint.taps);
    glm::vec4 sumFine(0.0f), sumCoarse(0.0f);
    for (int i = 0; i < footprint.taps; ++i) {
        const glm::vec2 at = uv + footprint.axis * ((float(i) + 0.5f) / taps - 0.5f);
        sumFine += sampleLevel(at, fine);
        if (fraction > 0.0f) sumCoarse += sampleLevel(at, coarse);
    }
    return glm::mix(sumFine, sumCoarse, fraction) / taps;
}

TextureFootprint textureFootprint(glm::vec2 dUvdx, glm::vec2 dUvdy, int width, int height,
                                  int levels) {
    const glm::vec2 size = {float(width), float(height)};
    const float lengthX = glm::length(dUvdx * size);
    const float lengthY = glm::length(dUvdy * size);
    const float major = std::fmax(lengthX, lengthY);
    const float minor = std::fmin(lengthX, lengthY);
    TextureFootprint footprint;
    // A ray grazing its plane spreads over the whole texture: its mean is the last level.
    if (!std::isfinite(lengthX) || !std::isfinite(lengthY)) {
        footprint.lod = float(levels - 1);
        return footprint;
    }
    if (!(major > 0.0f)) return footprint;
    // Hardware's anisotropic rule (EXT_texture_filter_anisotropic): as many taps as the
    // footprint is longer than wide, each one covering major / taps texels; never more taps
    // than texels along the major side, so magnified footprints stay one bilinear lookup.
    const float ratio = minor > 0.0f ? major / minor : float(kMaxAnisotropy);
    const float taps = std::fmax(
        1.0f, std::fmin(std::ceil(std::fmin(ratio, float(kMaxAnisotropy))), std::ceil(major)));
    footprint.taps = int(taps);
    footprint.lod = std::clamp(std::log2(major / taps), 0.0f, float(levels - 1));
    if (footprint.taps > 1) footprint.axis = lengthX >= lengthY ? dUvdx : dUvdy;
    return footprint;
}

}  // namespace pic
