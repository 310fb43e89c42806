#include "core/camera.h"

#include <array>
#include <charconv>
#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>

#include "core/sampling.h"

namespace pic {

namespace {

/// Text without leading and trailing spaces and tabs.
std::string_view trimmed(std::string_view text) {
    size_t begin = text.find_first_not_of(" \t");
    if (begin == std::string_view::npos) return {};
    size_t end = text.find_last_not_of(" \t");
    return text.substr(begin, end - begin + 1);
}

bool finite(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// Why `camera` cannot render, or nothing when it can.
std::optional<std::string> cameraProblem(const Camera& camera) {
    if (!finite(camera.eye) || !finite(camera.target) || !finite(camera.up) ||
        !std::isfinite(camera.fovyDegrees))
        return "a number is not finite";
    const glm::vec3 view = camera.target - camera.eye;
    if (!(glm::length(view) > 0.0f)) return "eye and target are the same point";
    // Relative test, so that scenes in millimetres or kilometres behave alike.
    const float upLength = glm::length(camera.up);
    if (!(upLength > 0.0f) ||
        glm::length(glm::cross(view / glm::length(view), camera.up / upLength)) < 1e-4f)
        return "up vector is zero or parallel to the view direction";
    if (!(camera.fovyDegrees > 0.0f && camera.fovyDegrees < 180.0f))
        return fmt::format("fovy must be in (0, 180) degrees, got {}", camera.fovyDegrees);
    return std::nullopt;
}

}  // namespace

Result<void> checkCamera(const Camera& camera) {
    if (auto problem = cameraProblem(camera))
        return fail(ErrorCode::InvalidInput, "camera \"{}\": {}", camera.name, *problem);
    return {};
}

Result<Camera> parseCamera(const std::string& text) {
    constexpr const char* kUsage = "ex,ey,ez,tx,ty,tz,ux,uy,uz,fovy";
    std::array<float, 10> values{};
    size_t count = 0;
    std::string_view rest = text;
    while (true) {
        size_t comma = rest.find(',');
        std::string_view field = trimmed(rest.substr(0, comma));
        if (count == values.size())
            return fail(ErrorCode::InvalidInput, "--camera needs 10 numbers {}, got more in \"{}\"",
                        kUsage, text);
        float& value = values[count++];
        auto [end, ec] = std::from_chars(field.data(), field.data() + field.size(), value);
        if (field.empty() || ec != std::errc() || end != field.data() + field.size() ||
            !std::isfinite(value))
            return fail(ErrorCode::InvalidInput,
                        "--camera needs 10 finite numbers {}, field {} is \"{}\" in \"{}\"", kUsage,
                        count, field, text);
        if (comma == std::string_view::npos) break;
        rest.remove_prefix(comma + 1);
    }
    if (count != values.size())
        return fail(ErrorCode::InvalidInput, "--camera needs 10 numbers {}, got {} in \"{}\"",
                    kUsage, count, text);

    Camera camera;
    camera.name = "--camera";
    camera.eye = {values[0], values[1], values[2]};
    camera.target = {values[3], values[4], values[5]};
    camera.up = {values[6], values[7], values[8]};
    camera.fovyDegrees = values[9];

    if (auto problem = cameraProblem(camera))
        return fail(ErrorCode::InvalidInput, "--camera {} in \"{}\"", *problem, text);
    return camera;
}

Result<Camera> sceneCamera(const Scene& scene, int index) {
    if (index < 0 || size_t(index) >= scene.cameras.size())
        return fail(ErrorCode::InvalidInput, "--scene-camera {} does not exist: {} has {} camera{}",
                    index, scene.sourcePath.empty() ? "the scene" : scene.sourcePath,
                    scene.cameras.size(), scene.cameras.size() == 1 ? "" : "s");
    return scene.cameras[size_t(index)];
}

CameraRays::CameraRays(const Camera& camera, uint32_t width, uint32_t height)
    : mEye(camera.eye),
      mTanHalfFovy(std::tan(glm::radians(camera.fovyDegrees) * 0.5f)),
      mAspect(float(width) / float(height)),
      mWidth(width),
      mHeight(height) {
    PIC_CHECK(width > 0 && height > 0);
    // Right-handed: right = forward × up, and the given up is only a hint, re-orthogonalised.
    mForward = glm::normalize(camera.target - camera.eye);
    mRight = glm::normalize(glm::cross(mForward, camera.up));
    mUp = glm::cross(mRight, mForward);
    PIC_CHECK(std::isfinite(mRight.x + mRight.y + mRight.z) && std::isfinite(mTanHalfFovy));
}

glm::vec2 subsampleOffset(uint32_t s, uint32_t n) {
    const float shifted = float(radicalInverse(2, s)) + 0.5f / float(n);
    return {(float(s) + 0.5f) / float(n), shifted - std::floor(shifted)};
}

glm::vec3 CameraRays::direction(float x, float y) const {
    // Normalised device coordinates in [-1, 1]; image y grows downward, camera up is +1.
    float ndcX = 2.0f * x / float(mWidth) - 1.0f;
    float ndcY = 1.0f - 2.0f * y / float(mHeight);
    return glm::normalize(mForward + (ndcX * mAspect * mTanHalfFovy) * mRight +
                          (ndcY * mTanHalfFovy) * mUp);
}

glm::vec3 CameraRays::directionPerPixelX() const {
    // d/dx of ndcX·aspect·tan·right with ndcX = 2x/width − 1; aspect/width = 1/height.
    return (2.0f * mTanHalfFovy / float(mHeight)) * mRight;
}

glm::vec3 CameraRays::directionPerPixelY() const {
    return (-2.0f * mTanHalfFovy / float(mHeight)) * mUp;
}

PixelFootprint CameraRays::footprintOnPlane(const glm::vec3& hit, const glm::vec3& normal) const {
    // The ray eye + t·D (D·forward = 1) meets the plane at t = depth = (hit − eye)·forward.
    // Differentiating n·(eye + t·D − hit) = 0 gives dP = t·dD − (hit − eye)·(n·t·dD)/(n·(hit −
    // eye)) for a change dD of the direction: the change of t·dD projected along the ray
    // onto the plane.
    const glm::vec3 toHit = hit - mEye;
    const float depth = glm::dot(toHit, mForward);
    const float along = glm::dot(normal, toHit);
    const auto onPlane = [&](const glm::vec3& dDirection) {
        const glm::vec3 s = depth * dDirection;
        return s - toHit * (glm::dot(normal, s) / along);
    };
    return {onPlane(directionPerPixelX()), onPlane(directionPerPixelY())};
}

}  // namespace pic
