// Vertex positions on the sub-pixel grid every rasteriser can represent.

/// `clip` with its framebuffer x and y (viewport `viewport` pixels, origin 0) moved to the
/// nearest 1/16 pixel, the coarsest grid Vulkan (subPixelPrecisionBits ≥ 4) and WebGL 2
/// (SUBPIXEL_BITS ≥ 4) allow. Rasterisers snap vertices to their own grid, lavapipe to 1/256
/// and SwiftShader (the browser tests' WebGL) to 1/16, so that a caster edge within 1/32 texel
/// of a texel centre covers it in one and not in the other; on a receiver near the camera
/// that one texel is a block of pixels lit in one client's image and shadowed in the other's.
/// On the shared grid both cover the same texels. The position moves by at most 1/32 pixel,
/// plus 1/1024 up, so that rounding in the rasteriser's (x·w)/w cannot land a truncating
/// rasteriser one step low. Positions behind the eye (w ≤ 0) are left to clipping.
///
/// The G-buffer does not snap: its interpolated position and light-map UV would leave the
/// pixel's camera ray, which the CPU twin follows exactly.
vec4 snapToSubpixels(vec4 clip, vec2 viewport) {
    if (!(clip.w > 0.0)) return clip;
    const vec2 pixels = (clip.xy / clip.w * 0.5 + 0.5) * viewport;
    const vec2 snapped = (floor(pixels * 16.0 + 0.5) + 1.0 / 64.0) / 16.0;
    return vec4((snapped / viewport * 2.0 - 1.0) * clip.w, clip.zw);
}
