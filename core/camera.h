#pragma once
/// Pinhole cameras from the command line (`--camera ex,ey,ez,tx,ty,tz,ux,uy,uz,fovy`) or the
/// scene (`--scene-camera N`), and their primary rays.

#include <cstdint>
#include <string>

#include <glm/glm.hpp>

#include "core/error.h"
#include "core/scene.h"

namespace pic {

/// Parses the 10 comma-separated numbers of --camera; InvalidInput names the text when there
/// are not 10 finite numbers, eye == target, up is parallel to the view direction or fovy is
/// outside (0, 180).
Result<Camera> parseCamera(const std::string& text);

/// InvalidInput naming the camera when a number is not finite, eye == target, up is zero or
/// parallel to the view direction, or fovy is outside (0, 180): what parseCamera checks, for
/// cameras that did not come through it.
Result<void> checkCamera(const Camera& camera);

/// The scene's N-th camera (0-based); InvalidInput if it has fewer.
Result<Camera> sceneCamera(const Scene& scene, int index);

/// Offset of subsample s of n inside a pixel, in [0, 1)² from its top-left corner: the pixel
/// centre for n = 1, else a Hammersley set shifted by half a stratum, the same in every pixel
/// so that images depend on nothing but their inputs. Both the thin client's renderer and its
/// CPU counterpart (`picref shade --spp`) average a pixel over these. s < n.
glm::vec2 subsampleOffset(uint32_t s, uint32_t n);

/// A pixel's footprint on a surface: the hit point's changes per pixel along x and along y.
struct PixelFootprint {
    glm::vec3 dPdx{0.0f};  ///< metres per pixel along image x
    glm::vec3 dPdy{0.0f};  ///< metres per pixel along image y (downward)
};

/// Primary rays of a camera for an image of width × height pixels (square pixels,
/// vertical field of view fovy).
class CameraRays {
public:
    CameraRays(const Camera& camera, uint32_t width, uint32_t height);
    /// Unit direction through image point (x, y) in pixels, (0,0) the top-left corner of the
    /// top-left pixel; pixel centres are at +0.5.
    glm::vec3 direction(float x, float y) const;
    const glm::vec3& origin() const { return mEye; }
    /// Unit view direction (the image centre's).
    const glm::vec3& forward() const { return mForward; }
    /// How the unnormalised direction forward + … through image point (x, y), whose component
    /// along forward is 1, changes per pixel along x and along y (constant for a pinhole).
    glm::vec3 directionPerPixelX() const;
    glm::vec3 directionPerPixelY() const;
    /// The sides of a pixel's footprint on the plane through `hit` with normal `normal` (any
    /// sign): how the point where this camera's rays meet that plane moves per pixel along x
    /// and y, in metres (ray differentials). Infinite or NaN when the ray through `hit` runs
    /// along the plane.
    PixelFootprint footprintOnPlane(const glm::vec3& hit, const glm::vec3& normal) const;

private:
    glm::vec3 mEye, mForward, mRight, mUp;
    float mTanHalfFovy, mAspect;
    uint32_t mWidth, mHeight;
};

}  // namespace pic
