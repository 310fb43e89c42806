#include "bench/light_propagation_volume.h"

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <utility>

#include "core/color.h"
#include "core/geometry.h"
#include "core/parallel.h"
#include "core/sh.h"

namespace pic {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr float kInfinity = std::numeric_limits<float>::infinity();
/// y_0^0 = 1/(2√π), and the factor of band 1: y_1^m = √(3/(4π))·(y, z, x).
const float kY00 = float(0.5 / std::sqrt(kPi));
const float kY1 = float(std::sqrt(3.0 / (4.0 * kPi)));
/// The re-emission of flux Φ as the lobe Φ/π·max(0, n·ω): coefficients Φ·(kReemit0, kReemit1·n)
/// with kReemit0 = (√π/2)/π = y_0^0 and kReemit1 = √(π/3)/π = 1/√(3π).
const float kReemit0 = kY00;
const float kReemit1 = float(1.0 / std::sqrt(3.0 * kPi));
/// Index of the band-1 coefficient of each axis: y_1^m = √(3/(4π))·(y, z, x) at 1, 2, 3.
constexpr int kAxisCoefficient[3] = {3, 1, 2};

/// Spots wider than this (half-angle) use the six faces of a point light: a square map over a
/// wide cone would spend its texels unevenly.
constexpr float kMaxPerspectiveSpot = float(kPi / 3.0);

/// Largest settings create accepts.
constexpr uint32_t kMaxResolution = 256;
constexpr uint32_t kMaxIterations = 4096;
constexpr uint32_t kMaxRsmSize = 4096;

double millisecondsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
        .count();
}

/// Solid angle of the rectangle [0, u] × [0, v] of the plane at distance 1, seen from the
/// origin, with the sign of u·v (the corner term of a cube-map texel's solid angle).
double cornerSolidAngle(double u, double v) {
    return std::atan2(u * v, std::sqrt(1.0 + u * u + v * v));
}

/// Solid angle of the rectangle [u0, u1] × [v0, v1] of the plane at distance 1.
double rectangleSolidAngle(double u0, double u1, double v0, double v1) {
    return cornerSolidAngle(u1, v1) - cornerSolidAngle(u0, v1) - cornerSolidAngle(u1, v0) +
           cornerSolidAngle(u0, v0);
}

/// The view of a shadow map (a cube face, a spot's cone, the sun's box): the axis it looks
/// along and two unit axes across it.
struct MapFace {
    glm::vec3 forward{0.0f};
    glm::vec3 right{0.0f};
    glm::vec3 up{0.0f};
};

MapFace mapFace(const glm::vec3& forward) {
    MapFace face;
    face.forward = glm::normalize(forward);
    orthonormalBasis(face.forward, face.right, face.up);
    return face;
}

float maxComponent(const glm::vec3& v) {
    return std::max(v.x, std::max(v.y, v.z));
}

/// Index along one axis of a position in cells (clamped; NaN → 0).
uint32_t clampedCell(float coordinate, uint32_t count) {
    if (!(coordinate >= 0.0f)) return 0;
    if (!(coordinate < float(count))) return count - 1;
    return std::min(uint32_t(coordinate), count - 1);
}

}  // namespace

namespace lpv {

std::array<float, kCoefficients> clampedCosineLobe(const glm::vec3& normal) {
    // Funk-Hecke: max(0, n·ω) projects to K_l·y_l^m(n), K_0 = π, K_1 = 2π/3 (core/sh.h).
    const float k0 = float(kPi) * kY00;
    const float k1 = float(2.0 * kPi / 3.0) * kY1;
    return {k0, k1 * normal.y, k1 * normal.z, k1 * normal.x};
}

double polygonSolidAngle(std::span<const glm::dvec3> corners) {
    // Fan of triangles from corner 0, each by Van Oosterom & Strackee:
    // tan(Ω/2) = a·(b×c) / (|a||b||c| + (a·b)|c| + (a·c)|b| + (b·c)|a|), signed by orientation.
    double total = 0.0;
    for (size_t i = 1; i + 1 < corners.size(); ++i) {
        const glm::dvec3 &a = corners[0], &b = corners[i], &c = corners[i + 1];
        const double la = glm::length(a), lb = glm::length(b), lc = glm::length(c);
        const double numerator = glm::dot(a, glm::cross(b, c));
        const double denominator =
            la * lb * lc + glm::dot(a, b) * lc + glm::dot(a, c) * lb + glm::dot(b, c) * la;
        total += 2.0 * std::atan2(numerator, denominator);
    }
    return std::abs(total);
}

glm::dvec3 polygonDirectionIntegral(std::span<const glm::dvec3> corners) {
    // Arvo's irradiance vector: ∫ ω dω = ½ Σ_edges Θ_e·Γ_e, Θ_e the angle the edge subtends at
    // the origin and Γ_e the unit normal of the plane through the origin and the edge; the
    // sign of the sum follows the corners' order, so it is turned to face the polygon.
    glm::dvec3 sum(0.0), centre(0.0);
    for (size_t i = 0; i < corners.size(); ++i) {
        const glm::dvec3 a = glm::normalize(corners[i]);
        const glm::dvec3 b = glm::normalize(corners[(i + 1) % corners.size()]);
        const glm::dvec3 normal = glm::cross(a, b);
        const double sine = glm::length(normal);
        if (!(sine > 0.0)) continue;
        sum += std::atan2(sine, glm::dot(a, b)) * (normal / sine);
        centre += corners[i];
    }
    sum *= 0.5;
    return glm::dot(sum, centre) < 0.0 ? -sum : sum;
}

const std::array<std::array<Face, 5>, 6>& propagationFaces() {
    static const std::array<std::array<Face, 5>, 6> faces = [] {
        std::array<std::array<Face, 5>, 6> all{};
        for (int k = 0; k < 6; ++k) {
            const int a = k / 2;
            glm::dvec3 d(0.0), eb(0.0), ec(0.0);
            d[a] = k % 2 == 0 ? 1.0 : -1.0;
            eb[(a + 1) % 3] = 1.0;
            ec[(a + 2) % 3] = 1.0;
            // The destination spans [0.5, 1.5] along d and [−0.5, 0.5] across: face 0 is
            // its far side (distance 1.5), faces 1-4 its sides (distance 0.5 across).
            struct Quad {
                glm::dvec3 corners[4];
                glm::dvec3 normal;
            };
            Quad quads[5];
            quads[0] = {{1.5 * d - 0.5 * eb - 0.5 * ec, 1.5 * d + 0.5 * eb - 0.5 * ec,
                         1.5 * d + 0.5 * eb + 0.5 * ec, 1.5 * d - 0.5 * eb + 0.5 * ec},
                        d};
            const glm::dvec3 sides[4][2] = {{eb, ec}, {-eb, ec}, {ec, eb}, {-ec, eb}};
            for (int s = 0; s < 4; ++s) {
                const glm::dvec3 l = sides[s][0], m = sides[s][1];
                quads[1 + s] = {{0.5 * d + 0.5 * l - 0.5 * m, 1.5 * d + 0.5 * l - 0.5 * m,
                                 1.5 * d + 0.5 * l + 0.5 * m, 0.5 * d + 0.5 * l + 0.5 * m},
                                l};
            }
            for (int f = 0; f < 5; ++f) {
                Face& face = all[k][f];
                const std::span<const glm::dvec3> corners(quads[f].corners, 4);
                const glm::dvec3 centre = 0.25 * (corners[0] + corners[1] + corners[2] + corners[3]);
                face.direction = glm::vec3(glm::normalize(centre));
                face.normal = glm::vec3(quads[f].normal);
                face.solidAngle = polygonSolidAngle(corners);
                const glm::dvec3 v = polygonDirectionIntegral(corners);
                face.basisIntegral = {float(face.solidAngle * kY00), kY1 * float(v.y),
                                      kY1 * float(v.z), kY1 * float(v.x)};
                shEvaluate(2, face.direction, face.directionBasis.data());
            }
        }
        return all;
    }();
    return faces;
}

Volume::Volume(const glm::vec3& origin, float cellSize, const glm::uvec3& dims)
    : mOrigin(origin), mCellSize(cellSize), mDims(dims) {
    PIC_CHECK(dims.x >= 1 && dims.y >= 1 && dims.z >= 1 && cellSize > 0.0f);
    mCurrent.assign(cellCount() * kCellFloats, 0.0f);
    mNext.assign(cellCount() * kCellFloats, 0.0f);
    mAccumulated.assign(cellCount() * kCellFloats, 0.0f);
}

uint32_t Volume::cellOf(const glm::vec3& position) const {
    const glm::vec3 u = (position - mOrigin) / mCellSize;
    return uint32_t(cellIndex(clampedCell(u.x, mDims.x), clampedCell(u.y, mDims.y),
                              clampedCell(u.z, mDims.z)));
}

void Volume::setBlockers(std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
                         std::span<const float> areas) {
    PIC_CHECK(positions.size() == normals.size() && positions.size() == areas.size());
    // The geometry volume's cells are centred on the light volume's corners (dims + 1 per
    // axis), so that the mean of the 4 around a face is the blocking between the two cells
    // that share it. Serial: the sum's order is fixed.
    const glm::uvec3 g = mDims + 1u;
    std::vector<float> corners(size_t(g.x) * g.y * g.z * kCoefficients, 0.0f);
    const float perArea = 1.0f / (mCellSize * mCellSize);
    for (size_t i = 0; i < positions.size(); ++i) {
        const glm::vec3 u = (positions[i] - mOrigin) / mCellSize + 0.5f;
        const size_t index = clampedCell(u.x, g.x) +
                             size_t(g.x) * (clampedCell(u.y, g.y) + size_t(g.y) * clampedCell(u.z, g.z));
        // Light travelling along ω into the front of the surface is blocked with the
        // probability of hitting it, A·max(0, −n·ω)/s² (its projected area over the cell's).
        const auto lobe = clampedCosineLobe(-normals[i]);
        for (int j = 0; j < kCoefficients; ++j)
            corners[index * kCoefficients + j] += areas[i] * perArea * lobe[j];
    }
    mFaceBlocking.assign(cellCount() * 3 * kCoefficients, 0.0f);
    parallelFor(0, cellCount(), [&](size_t cell) {
        const uint32_t x = uint32_t(cell % mDims.x);
        const uint32_t y = uint32_t((cell / mDims.x) % mDims.y);
        const uint32_t z = uint32_t(cell / (size_t(mDims.x) * mDims.y));
        const glm::uvec3 c(x, y, z);
        for (int a = 0; a < 3; ++a) {
            // The lower face along a lies at corner index c[a]; across it spans c and c + 1.
            const int b = (a + 1) % 3, e = (a + 2) % 3;
            float* out = &mFaceBlocking[(cell * 3 + size_t(a)) * kCoefficients];
            for (uint32_t i = 0; i < 2; ++i)
                for (uint32_t j = 0; j < 2; ++j) {
                    glm::uvec3 corner = c;
                    corner[b] += i;
                    corner[e] += j;
                    const size_t index = corner.x + size_t(g.x) * (corner.y + size_t(g.y) * corner.z);
                    for (int k = 0; k < kCoefficients; ++k)
                        out[k] += 0.25f * corners[index * kCoefficients + k];
                }
        }
    }, 256);
}

void Volume::clearLight() {
    std::fill(mCurrent.begin(), mCurrent.end(), 0.0f);
}

void Volume::inject(std::span<const Vpl> vpls) {
    // Serial in the VPLs' order, so that sums do not depend on the thread count; cheap against
    // the shadow maps and the propagation (12 additions per VPL).
    for (const Vpl& vpl : vpls) {
        if (!(maxComponent(vpl.flux) > 0.0f)) continue;
        PIC_CHECK(vpl.cell < cellCount());
        // I(ω) = Φ/π·max(0, n·ω): ∫ I dω = Φ.
        const auto lobe = clampedCosineLobe(vpl.normal);
        float* cell = &mCurrent[size_t(vpl.cell) * kCellFloats];
        for (int c = 0; c < 3; ++c) {
            const float scale = vpl.flux[c] / float(kPi);
            for (int j = 0; j < kCoefficients; ++j) cell[c * kCoefficients + j] += scale * lobe[j];
        }
    }
}

glm::dvec3 Volume::totalFlux() const {
    // ∫ y_0^0 dω = 4π·y_0^0 = 2√π; band 1 integrates to zero.
    glm::dvec3 total(0.0);
    for (size_t cell = 0; cell < cellCount(); ++cell)
        for (int c = 0; c < 3; ++c)
            total[c] += double(mCurrent[cell * kCellFloats + size_t(c) * kCoefficients]);
    return total * (2.0 * std::sqrt(kPi));
}

void Volume::propagate(uint32_t iterations, bool occlusion) {
    const auto& faces = propagationFaces();
    // The transfers of every direction are those of +x turned: by symmetry the far face's
    // ∫y_1 lies along the travel (F1) and a side face's along the travel (Sd) and towards
    // the side (Sl); the other components are zero.
    const auto& far = faces[0][0].basisIntegral;
    const auto& side = faces[0][1].basisIntegral;  // the side towards +y
    const float f0 = far[0], f1 = far[3];
    const float s0 = side[0], sd = side[3], sl = side[1];
    mAccumulated = mCurrent;
    const glm::uvec3 n = mDims;
    const size_t stride[3] = {1, size_t(n.x), size_t(n.x) * n.y};
    for (uint32_t step = 1; step <= iterations; ++step) {
        // The first step leaves the VPLs unblocked: they lie on the surfaces that block.
        const bool blocked = occlusion && step > 1 && !mFaceBlocking.empty();
        // Every cell gathers from its 6 neighbours: the light a neighbour sends towards it
        // leaves through the 5 faces that are not shared, each part re-emitted from this
        // cell's centre as a cosine lobe about the face's normal. Each cell writes only its own
        // values, so the result is the same for any thread count.
        parallelFor(
            0, size_t(n.y) * n.z,
            [&](size_t row) {
                const uint32_t y = uint32_t(row % n.y), z = uint32_t(row / n.y);
                for (uint32_t x = 0; x < n.x; ++x) {
                    const glm::uvec3 c(x, y, z);
                    const size_t cell = cellIndex(x, y, z);
                    float out[kCellFloats] = {};
                    for (int k = 0; k < 6; ++k) {
                        const int a = k / 2, b = (a + 1) % 3, e = (a + 2) % 3;
                        const bool positive = k % 2 == 0;
                        // The source lies one cell against the direction of travel.
                        if (positive ? c[a] == 0 : c[a] + 1 == n[a]) continue;
                        const size_t source = positive ? cell - stride[a] : cell + stride[a];
                        const float* in = &mCurrent[source * kCellFloats];
                        // The faces' shares that pass the blocking on the face the two cells
                        // share (the lower face of the upper cell), in the faces' order: far,
                        // +b, −b, +e, −e.
                        float pass[5] = {1.0f, 1.0f, 1.0f, 1.0f, 1.0f};
                        if (blocked) {
                            const float* blocking =
                                &mFaceBlocking[((positive ? cell : source) * 3 + size_t(a)) *
                                               kCoefficients];
                            for (int f = 0; f < 5; ++f) {
                                const auto& basis = faces[size_t(k)][size_t(f)].directionBasis;
                                const float block = blocking[0] * basis[0] + blocking[1] * basis[1] +
                                                    blocking[2] * basis[2] + blocking[3] * basis[3];
                                pass[f] = std::clamp(1.0f - block, 0.0f, 1.0f);
                            }
                        }
                        const float sign = positive ? 1.0f : -1.0f;
                        const int ia = kAxisCoefficient[a], ib = kAxisCoefficient[b],
                                  ie = kAxisCoefficient[e];
                        for (int ch = 0; ch < 3; ++ch) {
                            const float* sh = in + ch * kCoefficients;
                            float* o = out + ch * kCoefficients;
                            // Flux through each face, ∫_face I(ω) dω of the 2-band I (with
                            // the band-1 component along the travel taken signed).
                            const float along = sign * sh[ia];
                            const float fluxFar = pass[0] * (f0 * sh[0] + f1 * along);
                            const float base = s0 * sh[0] + sd * along;
                            const float fluxPb = pass[1] * (base + sl * sh[ib]);
                            const float fluxMb = pass[2] * (base - sl * sh[ib]);
                            const float fluxPe = pass[3] * (base + sl * sh[ie]);
                            const float fluxMe = pass[4] * (base - sl * sh[ie]);
                            // Re-emitted as Φ/π·max(0, n_face·ω) from this cell's centre.
                            o[0] += kReemit0 * (fluxFar + fluxPb + fluxMb + fluxPe + fluxMe);
                            o[ia] += kReemit1 * sign * fluxFar;
                            o[ib] += kReemit1 * (fluxPb - fluxMb);
                            o[ie] += kReemit1 * (fluxPe - fluxMe);
                        }
                    }
                    float* next = &mNext[cell * kCellFloats];
                    float* sum = &mAccumulated[cell * kCellFloats];
                    for (int j = 0; j < kCellFloats; ++j) {
                        next[j] = out[j];
                        sum[j] += out[j];
                    }
                }
            },
            4);
        std::swap(mCurrent, mNext);
    }
}

void Volume::sampleRadiance(const glm::vec3& position, float rgb[3][kCoefficients]) const {
    // Cell centres at (i + ½)·s: trilinear weights between the 8 around the point, clamped
    // to the outermost centres.
    const glm::vec3 u = (position - mOrigin) / mCellSize - 0.5f;
    uint32_t lo[3], hi[3];
    float t[3];
    for (int a = 0; a < 3; ++a) {
        const float maxCoordinate = float(mDims[a] - 1);
        const float v = u[a] >= 0.0f ? std::min(u[a], maxCoordinate) : 0.0f;  // NaN → 0
        lo[a] = std::min(uint32_t(v), mDims[a] - 1);
        hi[a] = std::min(lo[a] + 1, mDims[a] - 1);
        t[a] = v - float(lo[a]);
    }
    float sum[kCellFloats] = {};
    for (int corner = 0; corner < 8; ++corner) {
        float weight = 1.0f;
        uint32_t index[3];
        for (int a = 0; a < 3; ++a) {
            const bool upper = (corner >> a) & 1;
            index[a] = upper ? hi[a] : lo[a];
            weight *= upper ? t[a] : 1.0f - t[a];
        }
        if (weight == 0.0f) continue;
        const float* cell = &mAccumulated[cellIndex(index[0], index[1], index[2]) * kCellFloats];
        for (int j = 0; j < kCellFloats; ++j) sum[j] += weight * cell[j];
    }
    // Radiance = accumulated intensity / s² (header); the direction light comes from is minus
    // the one it travels, which flips the odd band.
    const float perArea = 1.0f / (mCellSize * mCellSize);
    for (int c = 0; c < 3; ++c)
        for (int j = 0; j < kCoefficients; ++j)
            rgb[c][j] = (j == 0 ? perArea : -perArea) * sum[c * kCoefficients + j];
}

uint64_t Volume::memoryBytes() const {
    return uint64_t(mCurrent.capacity() + mNext.capacity() + mAccumulated.capacity() +
                    mFaceBlocking.capacity()) *
           sizeof(float);
}

}  // namespace lpv

LightPropagationVolume::LightPropagationVolume(const Scene& scene, const EmbreeScene& rays,
                                               const BakeData& bake, const LpvParams& params,
                                               lpv::Volume volume)
    : mScene(&scene), mRays(&rays), mBake(&bake), mParams(params), mVolume(std::move(volume)) {}

Result<std::unique_ptr<LightPropagationVolume>> LightPropagationVolume::create(
    const Scene& scene, const EmbreeScene& rays, const BakeData& bake, const LpvParams& params) {
    if (params.resolution < 2 || params.resolution > kMaxResolution)
        return fail(ErrorCode::InvalidInput, "LPV resolution must be in [2, {}], got {}",
                    kMaxResolution, params.resolution);
    if (params.iterations == 0 || params.iterations > kMaxIterations)
        return fail(ErrorCode::InvalidInput, "LPV iterations must be in [1, {}], got {}",
                    kMaxIterations, params.iterations);
    if (params.rsmSize == 0 || params.rsmSize > kMaxRsmSize)
        return fail(ErrorCode::InvalidInput, "LPV rsmSize must be in [1, {}], got {}", kMaxRsmSize,
                    params.rsmSize);
    if (bake.sceneHash != scene.hash)
        return fail(ErrorCode::InvalidInput,
                    "the bake was made for scene hash {:016x}, scene '{}' has hash {:016x}",
                    bake.sceneHash, scene.sourcePath, scene.hash);
    const glm::vec3 extent = scene.bounds.extent();
    const float longest = std::max(extent.x, std::max(extent.y, extent.z));
    if (scene.bounds.empty() || !(longest > 0.0f) || !std::isfinite(longest))
        return fail(ErrorCode::InvalidInput, "scene '{}' has no extent for an LPV",
                    scene.sourcePath);
    if (bake.params.bandsY < 1 || bake.params.bandsC > bake.params.bandsY ||
        bake.params.bandsY > uint32_t(kMaxShBands))
        return fail(ErrorCode::InvalidInput, "bake band counts y {} c {} are invalid",
                    bake.params.bandsY, bake.params.bandsC);

    // Cubic cells, `resolution` along the longest axis; the other axes take as many as cover
    // the bounds (a thousandth of a cell of rounding spare), centred on them.
    const float cell = longest / float(params.resolution);
    glm::uvec3 dims;
    for (int a = 0; a < 3; ++a)
        dims[a] = std::max(1u, uint32_t(std::ceil(extent[a] / cell - 1e-3f)));
    const glm::vec3 origin = scene.bounds.center() - 0.5f * glm::vec3(dims) * cell;
    lpv::Volume volume(origin, cell, dims);

    // The geometry volume from the bake's surfels: they sample every surface of the scene
    // with its area, which the VPLs do only where the lights see. The scene is static, so it
    // is made once; a dynamic scene would rebuild it per update from its surfaces (one pass
    // over the surfels and one over the cells, O(nS + cells): all of create() takes 9 ms on
    // cornell's default bake, 26k surfels into 32³ cells, on two cores).
    if (params.occlusion) {
        std::vector<glm::vec3> positions, normals;
        std::vector<float> areas;
        positions.reserve(bake.surfels.size());
        normals.reserve(bake.surfels.size());
        areas.reserve(bake.surfels.size());
        for (const Surfel& s : bake.surfels) {
            positions.push_back(s.position);
            normals.push_back(s.normal);
            areas.push_back(s.area);
        }
        volume.setBlockers(positions, normals, areas);
    }

    auto lpv = std::unique_ptr<LightPropagationVolume>(
        new LightPropagationVolume(scene, rays, bake, params, std::move(volume)));
    lpv->mValues = CacheValues::zeros(bake.caches.size(), bake.params.bandsY, bake.params.bandsC);
    return lpv;
}

size_t LightPropagationVolume::shadowMapTexels(const Light& light) const {
    const size_t face = size_t(mParams.rsmSize) * mParams.rsmSize;
    const bool cube = light.type == LightType::Point ||
                      (light.type == LightType::Spot && light.outerConeAngle > kMaxPerspectiveSpot);
    return cube ? 6 * face : face;
}

size_t LightPropagationVolume::renderShadowMap(const Light& light, size_t first) {
    const size_t texels = shadowMapTexels(light);
    // A light that emits nothing leaves its texels empty without tracing them.
    if (!(light.intensity > 0.0f) || !(maxComponent(light.color) > 0.0f)) {
        std::fill_n(mVpls.begin() + ptrdiff_t(first), texels, lpv::Vpl{});
        return texels;
    }
    const uint32_t size = mParams.rsmSize;
    const size_t perFace = size_t(size) * size;
    const float halfCell = 0.5f * mVolume.cellSize();

    // The views: a perspective map over the spot's cone, six cube faces for a point light
    // (or a wide spot), an orthographic map over the scene's bounds for a directional light.
    MapFace faces[6];
    double halfExtent = 1.0;  // of the image plane at distance 1 (perspective)
    glm::vec2 orthoMin(0.0f), orthoMax(0.0f);
    float orthoStart = 0.0f;
    if (texels == 6 * perFace) {
        for (int f = 0; f < 6; ++f) {
            glm::vec3 axis(0.0f);
            axis[f / 2] = f % 2 == 0 ? 1.0f : -1.0f;
            faces[f] = mapFace(axis);
        }
    } else if (light.type == LightType::Spot) {
        faces[0] = mapFace(light.direction);
        halfExtent = std::tan(double(light.outerConeAngle));
    } else {
        faces[0] = mapFace(light.direction);
        // The bounds' corners in the light's frame (right, up, forward) give the map's extent
        // and the plane the rays start from, a little outside.
        const Aabb& b = mScene->bounds;
        glm::vec3 lo(kInfinity), hi(-kInfinity);
        for (int i = 0; i < 8; ++i) {
            const glm::vec3 p((i & 1) ? b.max.x : b.min.x, (i & 2) ? b.max.y : b.min.y,
                              (i & 4) ? b.max.z : b.min.z);
            const glm::vec3 q(glm::dot(p, faces[0].right), glm::dot(p, faces[0].up),
                              glm::dot(p, faces[0].forward));
            lo = glm::min(lo, q);
            hi = glm::max(hi, q);
        }
        const float margin = 1e-3f * b.diagonal();
        orthoMin = glm::vec2(lo) - margin;
        orthoMax = glm::vec2(hi) + margin;
        orthoStart = lo.z - margin;
    }
    const glm::vec2 orthoTexel = (orthoMax - orthoMin) / float(size);
    const float orthoArea = orthoTexel.x * orthoTexel.y;

    parallelFor(
        0, texels,
        [&](size_t texel) {
            lpv::Vpl& vpl = mVpls[first + texel];
            vpl = lpv::Vpl{};
            const MapFace& face = faces[texel / perFace];
            const uint32_t i = uint32_t(texel % perFace % size);
            const uint32_t j = uint32_t(texel % perFace / size);
            glm::vec3 origin, direction;
            double solidAngle = 0.0;
            if (light.type == LightType::Directional) {
                const glm::vec2 uv = orthoMin + (glm::vec2(float(i), float(j)) + 0.5f) * orthoTexel;
                origin = uv.x * face.right + uv.y * face.up + orthoStart * face.forward;
                direction = face.forward;
            } else {
                // The texel's solid angle exactly, from the corner terms of its rectangle on
                // the image plane at distance 1; its ray through the rectangle's centre.
                const double step = 2.0 * halfExtent / double(size);
                const double u0 = -halfExtent + step * i, v0 = -halfExtent + step * j;
                solidAngle = rectangleSolidAngle(u0, u0 + step, v0, v0 + step);
                origin = light.position;
                direction = glm::normalize(face.forward + float(u0 + 0.5 * step) * face.right +
                                           float(v0 + 0.5 * step) * face.up);
            }
            const std::optional<RayHit> hit = mRays->intersect(origin, direction, 0.0f, kInfinity);
            if (!hit) return;
            const glm::vec3 position = origin + hit->t * direction;
            // The side the light sees reflects it (two-sided, as the path tracer).
            const glm::vec3 normal = hit->backFace ? -hit->geometricNormal : hit->geometricNormal;
            const float cosine = -glm::dot(normal, direction);
            if (!(cosine > 1e-6f)) return;
            glm::vec3 toLight;
            float distance = 0.0f;
            const glm::vec3 irradiance = lightIrradiance(light, position, normal, toLight, distance);
            // The texel's footprint on the surface: its solid angle times d²/cosθ, or its
            // orthographic area over cosθ.
            const float area = light.type == LightType::Directional
                                   ? orthoArea / cosine
                                   : float(solidAngle) * hit->t * hit->t / cosine;
            const glm::vec3 albedo = mScene->albedoAt(hit->triangle, hit->b1, hit->b2);
            const glm::vec3 flux = albedo * irradiance * area;
            if (!(maxComponent(flux) > 0.0f) || !std::isfinite(flux.x + flux.y + flux.z)) return;
            // Half a cell along the normal (Kaplanyan): the VPL lights the cells in front of
            // its surface, not its own.
            vpl.cell = mVolume.cellOf(position + halfCell * normal);
            vpl.normal = normal;
            vpl.flux = flux;
        },
        256);
    return texels;
}

Result<const CacheValues*> LightPropagationVolume::update(const LightSet& lights) {
    if (lights.lights.size() > kMaxLights)
        return fail(ErrorCode::InvalidInput, "a light set holds at most {} lights, got {}",
                    kMaxLights, lights.lights.size());
    mStats = LpvStats{};
    auto start = std::chrono::steady_clock::now();

    // 1. A reflective shadow map per light, then the emissive surfels: their flux π·L_e·A.
    size_t total = 0;
    for (const Light& light : lights.lights) total += shadowMapTexels(light);
    std::vector<float> emissiveScale(mScene->materials.size());
    for (size_t m = 0; m < emissiveScale.size(); ++m)
        emissiveScale[m] = lights.emissiveScaleOf(mScene->materials[m].name);
    size_t emitters = 0;
    for (const Surfel& s : mBake->surfels)
        if (maxComponent(s.emission) > 0.0f) ++emitters;
    mVpls.resize(total + emitters);
    size_t next = 0;
    for (const Light& light : lights.lights) next += renderShadowMap(light, next);
    const float halfCell = 0.5f * mVolume.cellSize();
    for (const Surfel& s : mBake->surfels) {
        if (!(maxComponent(s.emission) > 0.0f)) continue;
        const float scale = s.material < emissiveScale.size() ? emissiveScale[s.material] : 1.0f;
        mVpls[next++] = {mVolume.cellOf(s.position + halfCell * s.normal), s.normal,
                         float(kPi) * s.emission * s.area * scale};
    }
    for (const lpv::Vpl& vpl : mVpls)
        if (maxComponent(vpl.flux) > 0.0f) {
            ++mStats.vpls;
            mStats.vplFlux += glm::dvec3(vpl.flux);
        }
    mStats.rsmMs = millisecondsSince(start);

    // 2. Injection.
    start = std::chrono::steady_clock::now();
    mVolume.clearLight();
    mVolume.inject(mVpls);
    mStats.injectedFlux = mVolume.totalFlux();
    mStats.injectMs = millisecondsSince(start);

    // 3-4. Propagation through the geometry volume made in create().
    start = std::chrono::steady_clock::now();
    mVolume.propagate(mParams.iterations, mParams.occlusion);
    mStats.propagateMs = millisecondsSince(start);

    // 5. Radiance at every cache; light-map caches half a cell out along their normal, as
    // the VPLs were injected.
    start = std::chrono::steady_clock::now();
    const uint32_t bandsY = mValues.bandsY, bandsC = mValues.bandsC;
    const size_t countY = size_t(bandsY) * bandsY, countC = size_t(bandsC) * bandsC;
    const size_t usedY = std::min<size_t>(countY, lpv::kCoefficients);
    const size_t usedC = std::min<size_t>(countC, lpv::kCoefficients);
    parallelFor(0, mBake->caches.size(), [&](size_t c) {
        const Cache& cache = mBake->caches[c];
        glm::vec3 position = cache.position;
        if (cache.kind == gpu::kCacheKindLightmap) position += halfCell * cache.normal;
        float rgb[3][lpv::kCoefficients];
        mVolume.sampleRadiance(position, rgb);
        // Bands above 1 stay zero; YCoCg is linear, so each coefficient converts alone.
        for (size_t j = 0; j < lpv::kCoefficients; ++j) {
            const glm::vec3 yCoCg = rgbToYCoCg(glm::vec3(rgb[0][j], rgb[1][j], rgb[2][j]));
            if (j < usedY) mValues.y[c * countY + j] = yCoCg.x;
            if (j < usedC) {
                mValues.co[c * countC + j] = yCoCg.y;
                mValues.cg[c * countC + j] = yCoCg.z;
            }
        }
    });
    mStats.sampleMs = millisecondsSince(start);
    return &mValues;
}

uint64_t LightPropagationVolume::memoryBytes() const {
    return mVolume.memoryBytes() + uint64_t(mVpls.capacity()) * sizeof(lpv::Vpl) +
           uint64_t(mValues.y.capacity() + mValues.co.capacity() + mValues.cg.capacity()) *
               sizeof(float) +
           uint64_t(mValues.irradiance.capacity()) * sizeof(glm::vec3);
}

}  // namespace pic
