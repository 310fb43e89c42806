#pragma once
/// The CPU twin of every runtime pass (paper 000 Figure 2): the oracle the GPU passes are
/// tested against and the fallback backend. Multithreaded over both cores.

#include <memory>

#include "rays/embree_scene.h"
#include "render/runtime.h"

namespace pic {

/// Creates the CPU backend. `scene`, `rays` and `bake` must outlive it; the bake must have
/// been made for this scene (same hash).
Result<std::unique_ptr<Runtime>> createCpuRuntime(const Scene& scene, const EmbreeScene& rays,
                                                  const BakeData& bake, const BounceParams& bounces);

}  // namespace pic
