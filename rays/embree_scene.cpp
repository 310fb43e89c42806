#include "rays/embree_scene.h"

#include <cmath>
#include <limits>

#include <embree3/rtcore.h>

namespace pic {

struct EmbreeScene::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    std::vector<glm::vec3> triangleNormals;  // unit, counter-clockwise, per scene triangle

    ~Impl() {
        if (scene) rtcReleaseScene(scene);
        if (device) rtcReleaseDevice(device);
    }
};

namespace {

const char* embreeErrorName(RTCError error) {
    switch (error) {
    case RTC_ERROR_NONE: return "RTC_ERROR_NONE";
    case RTC_ERROR_UNKNOWN: return "RTC_ERROR_UNKNOWN";
    case RTC_ERROR_INVALID_ARGUMENT: return "RTC_ERROR_INVALID_ARGUMENT";
    case RTC_ERROR_INVALID_OPERATION: return "RTC_ERROR_INVALID_OPERATION";
    case RTC_ERROR_OUT_OF_MEMORY: return "RTC_ERROR_OUT_OF_MEMORY";
    case RTC_ERROR_UNSUPPORTED_CPU: return "RTC_ERROR_UNSUPPORTED_CPU";
    case RTC_ERROR_CANCELLED: return "RTC_ERROR_CANCELLED";
    }
    return "RTC_ERROR_?";
}

/// An Embree ray over (tNear, tFar) that every geometry mask accepts.
RTCRay makeRay(const glm::vec3& origin, const glm::vec3& direction, float tNear, float tFar) {
    RTCRay ray;
    ray.org_x = origin.x;
    ray.org_y = origin.y;
    ray.org_z = origin.z;
    ray.tnear = tNear;
    ray.dir_x = direction.x;
    ray.dir_y = direction.y;
    ray.dir_z = direction.z;
    ray.time = 0.0f;
    ray.tfar = tFar;
    ray.mask = 0xFFFFFFFFu;
    ray.id = 0;
    ray.flags = 0;
    return ray;
}

/// Distance from p to the nearest point of triangle abc (Ericson, Real-Time Collision
/// Detection §5.1.5: the Voronoi region of p among the corners, edges and face), in double:
/// in float, long thin triangles (merged strips) lose tens of micrometres to cancellation.
double distanceToTriangle(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b,
                          const glm::dvec3& c) {
    const glm::dvec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) return glm::length(ap);
    const glm::dvec3 bp = p - b;
    const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return glm::length(bp);
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return glm::length(p - (a + ab * (d1 / (d1 - d3))));
    const glm::dvec3 cp = p - c;
    const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return glm::length(cp);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return glm::length(p - (a + ac * (d2 / (d2 - d6))));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0)
        return glm::length(p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))));
    const double denominator = va + vb + vc;
    if (!(denominator > 0.0)) return glm::length(ap);  // degenerate: the edges decided above
    return glm::length(p - (a + ab * (vb / denominator) + ac * (vc / denominator)));
}

/// Point-query callback: shrinks the query radius to the distance of the nearest triangle of
/// the Scene behind userPtr.
bool nearerTriangle(RTCPointQueryFunctionArguments* args) {
    const Scene& scene = *static_cast<const Scene*>(args->userPtr);
    const Triangle& t = scene.triangles[args->primID];
    const glm::dvec3 p(args->query->x, args->query->y, args->query->z);
    const float d = float(distanceToTriangle(p, scene.vertices[t.v[0]].position,
                                             scene.vertices[t.v[1]].position,
                                             scene.vertices[t.v[2]].position));
    if (!(d < args->query->radius)) return false;
    args->query->radius = d;
    return true;
}

}  // namespace

EmbreeScene::~EmbreeScene() = default;

Result<std::unique_ptr<EmbreeScene>> EmbreeScene::create(const Scene& scene) {
    if (scene.triangles.empty())
        return fail(ErrorCode::InvalidInput, "scene '{}' has no triangles to trace", scene.sourcePath);
    std::unique_ptr<EmbreeScene> result(new EmbreeScene());
    result->mScene = &scene;
    result->mEpsilon = std::max(1e-6f, 1e-5f * scene.bounds.diagonal());
    result->mImpl = std::make_unique<Impl>();
    Impl& impl = *result->mImpl;

    impl.device = rtcNewDevice(nullptr);
    if (!impl.device)
        return fail(ErrorCode::Internal, "Embree device creation failed: {}",
                    embreeErrorName(rtcGetDeviceError(nullptr)));
    impl.scene = rtcNewScene(impl.device);
    rtcSetSceneBuildQuality(impl.scene, RTC_BUILD_QUALITY_HIGH);

    RTCGeometry geometry = rtcNewGeometry(impl.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    // Embree reads vertices as 16-byte vectors, so the last position needs 4 readable bytes
    // past it: a separate padded copy keeps that guarantee independent of Vertex's layout.
    auto* positions = static_cast<float*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
        scene.vertices.size()));
    auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t),
        scene.triangles.size()));
    if (!positions || !indices) {
        rtcReleaseGeometry(geometry);
        return fail(ErrorCode::Internal, "Embree buffer allocation failed: {}",
                    embreeErrorName(rtcGetDeviceError(impl.device)));
    }
    for (size_t i = 0; i < scene.vertices.size(); ++i) {
        positions[3 * i + 0] = scene.vertices[i].position.x;
        positions[3 * i + 1] = scene.vertices[i].position.y;
        positions[3 * i + 2] = scene.vertices[i].position.z;
    }
    impl.triangleNormals.resize(scene.triangles.size());
    for (size_t t = 0; t < scene.triangles.size(); ++t) {
        const Triangle& tri = scene.triangles[t];
        for (int k = 0; k < 3; ++k) indices[3 * t + k] = tri.v[k];
        const glm::vec3& a = scene.vertices[tri.v[0]].position;
        const glm::vec3& b = scene.vertices[tri.v[1]].position;
        const glm::vec3& c = scene.vertices[tri.v[2]].position;
        glm::vec3 n = glm::cross(b - a, c - a);
        float len = glm::length(n);
        impl.triangleNormals[t] = len > 0.0f ? n / len : glm::vec3(0.0f, 1.0f, 0.0f);
    }
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(impl.scene, geometry);
    rtcReleaseGeometry(geometry);
    rtcCommitScene(impl.scene);
    if (RTCError error = rtcGetDeviceError(impl.device); error != RTC_ERROR_NONE)
        return fail(ErrorCode::Internal, "Embree scene build failed: {}", embreeErrorName(error));
    return result;
}

bool EmbreeScene::occluded(const glm::vec3& origin, const glm::vec3& direction, float tNear,
                           float tFar) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay ray = makeRay(origin, direction, tNear, tFar);
    rtcOccluded1(mImpl->scene, &context, &ray);
    // Embree marks an occluded ray by setting tfar to -inf.
    return ray.tfar < 0.0f;
}

std::optional<RayHit> EmbreeScene::intersect(const glm::vec3& origin, const glm::vec3& direction,
                                             float tNear, float tFar) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rayHit;
    rayHit.ray = makeRay(origin, direction, tNear, tFar);
    const RTCRay& ray = rayHit.ray;
    rayHit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rayHit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(mImpl->scene, &context, &rayHit);
    if (rayHit.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
    RayHit hit;
    hit.t = ray.tfar;
    hit.triangle = rayHit.hit.primID;
    hit.b1 = rayHit.hit.u;
    hit.b2 = rayHit.hit.v;
    hit.geometricNormal = mImpl->triangleNormals[hit.triangle];
    hit.backFace = glm::dot(hit.geometricNormal, direction) > 0.0f;
    return hit;
}

float EmbreeScene::nearestDistance(const glm::vec3& point, float limit) const {
    RTCPointQuery query{point.x, point.y, point.z, 0.0f, limit};
    RTCPointQueryContext context;
    rtcInitPointQueryContext(&context);
    rtcPointQuery(mImpl->scene, &query, &context, nearerTriangle, const_cast<Scene*>(mScene));
    return query.radius < limit ? query.radius : std::numeric_limits<float>::infinity();
}

}  // namespace pic
