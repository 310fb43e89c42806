#pragma once
/// Textures in linear RGBA float with their mip chains, and their filtered lookups: bilinear at
/// a point (what the path tracer and the bake read) and mip-mapped, anisotropic over a pixel's
/// footprint (what the thin client and the CPU shading read; shaders/gbuffer.frag is the GPU
/// twin of textureFootprint and Texture::sampleFootprint).

#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace pic {

/// Most trilinear taps one footprint lookup takes along its major axis (hardware's 16×).
inline constexpr int kMaxAnisotropy = 16;

/// One level of a mip chain: linear RGBA texels, row-major, row 0 at v = 0.
struct MipLevel {
    int width = 0;
    int height = 0;
    std::vector<glm::vec4> texels;
};

/// A decoded texture in linear RGBA float (sRGB textures are linearised at load).
struct Texture {
    std::string name;
    int width = 0;
    int height = 0;
    std::vector<glm::vec4> texels;  ///< level 0: row-major, row 0 at v = 0
    bool repeatS = true;            ///< wrap mode along u: repeat, else clamp
    bool repeatT = true;            ///< wrap mode along v: repeat, else clamp
    /// Levels 1, 2, … down to 1×1 (buildMipChain; the glTF loader builds them). While it is
    /// empty every lookup reads level 0.
    std::vector<MipLevel> mips;

    /// Levels in the chain, level 0 included.
    int levelCount() const { return 1 + int(mips.size()); }
    /// Bilinear lookup of level 0 with the texture's wrap modes.
    glm::vec4 sample(glm::vec2 uv) const;
    /// Bilinear lookup of `level` (clamped to the chain) with the texture's wrap modes.
    glm::vec4 sampleLevel(glm::vec2 uv, int level) const;
    /// Trilinear lookup: levels ⌊lod⌋ and ⌊lod⌋ + 1 blended by the fraction; lod ≤ 0 is
    /// level 0 bilinear, lod ≥ levelCount() − 1 the last level.
    glm::vec4 sampleTrilinear(glm::vec2 uv, float lod) const;
    /// The average over the pixel footprint whose centre is at `uv` and whose sides are the
    /// UV changes per pixel `dUvdx`, `dUvdy`: textureFootprint's taps, each trilinear, spread
    /// evenly along the major side, averaged. A footprint under one texel is sample(uv).
    glm::vec4 sampleFootprint(glm::vec2 uv, glm::vec2 dUvdx, glm::vec2 dUvdy) const;
};

/// Replaces texture.mips with the chain of its level-0 texels: each level max(1, ⌊side/2⌋) of
/// the one before per side, down to 1×1; each texel the area-weighted average of the finer
/// texels its rectangle covers (a 2×2 box for even sides, weights ⅓ ⅓ ⅓ / ½ … at odd ones), in
/// linear RGBA, so that every level keeps level 0's mean. Rectangles never cross the edge, so
/// the chain does not depend on the wrap modes; lookups apply them at every level.
void buildMipChain(Texture& texture);

/// What a footprint lookup reads (core/texture.cpp derives it; shaders/gbuffer.frag repeats
/// it): with a = dUvdx·(w, h), b = dUvdy·(w, h) in level-0 texels per pixel, major = max(|a|,
/// |b|), minor = min(|a|, |b|): taps = min(⌈major / minor⌉, ⌈major⌉, kMaxAnisotropy) (at
/// least 1), lod = log2(major / taps) clamped to [0, levels − 1]. A non-finite footprint
/// (a ray grazing its plane) reads the last level.
struct TextureFootprint {
    float lod = 0.0f;
    int taps = 1;
    glm::vec2 axis{0.0f};  ///< the major side in UV: taps at uv + axis·((i + ½)/taps − ½)
};

/// The footprint of a width × height texture with `levels` mip levels seen through UV
/// derivatives per pixel dUvdx, dUvdy.
TextureFootprint textureFootprint(glm::vec2 dUvdx, glm::vec2 dUvdy, int width, int height,
                                  int levels);

}  // namespace pic
