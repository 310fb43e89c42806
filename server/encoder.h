#pragma once
/// The server's side of the stream (ARCHITECTURE §1 step 6): one update's cache textures as
/// the half-float planes the frame codec (core/frame_codec.h) compresses.

#include "core/frame_codec.h"
#include "server/cpu/lightmap_copy.h"

namespace pic {

/// The textures' six coefficient planes (grid Y, Co, Cg, light map Y, Co, Cg; coverage is
/// part of the scene's assets, not of a frame) as half floats, saturated to ±65504 so that
/// no infinity reaches a client. The GPU writes halves already, so this loses nothing there.
HalfFrame halfFrameOf(const CacheTextures& textures);

/// Values over all six planes: lY² + 2·lC² SH coefficients per grid vertex and light-map
/// texel.
size_t frameValues(const HalfFrame& frame);

}  // namespace pic
