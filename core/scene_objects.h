#pragma once
/// Dynamic objects (paper 000 §5.1, ARCHITECTURE.md §5 `--object FILE.glb --transform
/// tx,ty,tz,rx,ry,rz,s`): glTF models that are not in the bake, placed into a copy of the
/// scene for one view. Renderers shade them from the grid caches (their triangles are not
/// light-mapped; bakes made with `--grid-caches space` hold caches wherever they may go) with
/// direct light and shadows; they add nothing to the caches, so they cast no indirect shadows
/// and reflect no light onto the static scene.

#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "core/error.h"
#include "core/scene.h"

namespace pic {

/// One object and where it goes: p_world = translation + R·(scale·p_model), R turning about
/// x by rotationDegrees.x, then about y, then about z (R = Rz·Ry·Rx), normals turned by R.
struct ObjectPlacement {
    std::string path;                     ///< .gltf or .glb
    glm::vec3 translation{0.0f};          ///< metres
    glm::vec3 rotationDegrees{0.0f};      ///< about x, y, z, applied in that order
    float scale = 1.0f;                   ///< uniform, > 0
};

/// Parses `--transform tx,ty,tz,rx,ry,rz,s` for the object at `path`: seven finite numbers,
/// s > 0. InvalidInput naming the field and the text otherwise.
Result<ObjectPlacement> parseObjectPlacement(const std::string& path, const std::string& transform);

/// Pairs the repeated --object and --transform flags in order; InvalidInput when their counts
/// differ or a transform does not parse.
Result<std::vector<ObjectPlacement>> parseObjectFlags(const std::vector<std::string>& objects,
                                                     const std::vector<std::string>& transforms);

/// A copy of `base` with every object loaded (loadScene), transformed and appended: its
/// triangles, materials (named "<file stem>/<material>") and textures after the scene's own,
/// so that the scene's triangle and material indices stay; the objects' lights and cameras are
/// left out. Bounds, area and hash are the new scene's. Errors as loadScene's, naming the file.
Result<Scene> placeObjects(const Scene& base, const std::vector<ObjectPlacement>& objects);

/// The fraction of `scene`'s vertices from `firstVertex` on (the placed objects') whose grid
/// cell has a cache at one of its 8 corners at least: where an object finds grid light. The
/// grid: vertex (0, 0, 0) at `origin`, `cellSize` metres apart, `dims` vertices per axis,
/// `cacheIndex` per vertex x + dims.x·(y + dims.y·z) (kNoCache: none). 1 without vertices.
double gridCoverage(const Scene& scene, size_t firstVertex, const glm::vec3& origin,
                    float cellSize, const glm::uvec3& dims, const std::vector<uint32_t>& cacheIndex);

/// What a program warns when the objects find a grid cache around fewer than 90 % of their
/// vertices (`coverage` from gridCoverage), naming the bake mode that fills the grid; empty
/// when they find enough.
std::string gridCoverageWarning(double coverage);

}  // namespace pic
