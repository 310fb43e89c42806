#pragma once
/// Assembles a glTF 2.0 document (JSON plus one binary buffer) from world-space mesh primitives,
/// Lambertian materials, KHR_lights_punctual lights and perspective cameras.

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "core/error.h"
#include "core/scene.h"

namespace pic::testscenes {

/// glTF primitive topologies the generator writes (values are the glTF `mode` numbers).
enum class PrimitiveMode : uint32_t { Points = 0, Triangles = 4 };

/// One mesh primitive in world space; each attribute array is empty or has one entry per position.
struct PrimitiveData {
    uint32_t material = 0;
    PrimitiveMode mode = PrimitiveMode::Triangles;
    std::vector<glm::vec3> positions;  ///< metres
    std::vector<glm::vec3> normals;    ///< unit
    std::vector<glm::vec2> uv0;        ///< TEXCOORD_0
    std::vector<glm::vec2> uv1;        ///< TEXCOORD_1 (needs TEXCOORD_0, as glTF requires)
    std::vector<uint32_t> indices;     ///< empty for a non-indexed primitive
};

/// A Lambertian material: metallic 0, roughness 1, optional emission and base-colour texture.
struct MaterialDesc {
    std::string name;
    glm::dvec3 baseColor{1.0};  ///< linear albedo
    glm::dvec3 emissiveFactor{0.0};
    double emissiveStrength = 1.0;  ///< KHR_materials_emissive_strength; written when ≠ 1
    int baseColorTexture = -1;      ///< index returned by addPngTexture, -1 for none
    int baseColorTexCoord = 0;      ///< which TEXCOORD_n the texture reads
};

/// A KHR_lights_punctual light placed on its own node.
struct LightDesc {
    std::string name;
    LightType type = LightType::Point;
    glm::dvec3 position{0.0};              ///< metres (point, spot)
    glm::dvec3 direction{0.0, -1.0, 0.0};  ///< direction light travels (spot, directional)
    glm::dvec3 color{1.0};
    double intensity = 1.0;                      ///< W/sr (point, spot) or W/m² (directional)
    double innerConeAngle = 0.0;                 ///< radians, half-angle (spot)
    double outerConeAngle = 0.7853981633974483;  ///< radians, half-angle (spot)
};

/// A perspective camera on its own node, looking from `eye` towards `target`.
struct CameraDesc {
    std::string name;
    glm::dvec3 eye{0.0};
    glm::dvec3 target{0.0, 0.0, -1.0};
    glm::dvec3 up{0.0, 1.0, 0.0};
    double yfovDegrees = 60.0;
    double aspectRatio = 1.0;
};

/// Collects the parts of one glTF scene and writes them as NAME.gltf (+ NAME.bin).
class GltfBuilder {
public:
    /// Adds a material and returns its index.
    uint32_t addMaterial(const MaterialDesc& material);
    /// Adds a PNG image embedded as a data URI with nearest filtering and repeat wrapping;
    /// returns its texture index.
    uint32_t addPngTexture(const std::string& name, std::vector<uint8_t> png);
    /// Adds a mesh of world-space primitives under its own untransformed node.
    void addMesh(const std::string& name, std::vector<PrimitiveData> primitives);
    /// Adds a light node whose −Z axis is the light's direction.
    void addLight(const LightDesc& light);
    /// Adds a camera node whose −Z axis looks at the target.
    void addCamera(const CameraDesc& camera);

    /// Triangles over all TRIANGLES primitives added so far.
    uint64_t triangleCount() const;

    /// Writes OUTDIR/NAME.gltf and, when there is geometry, OUTDIR/NAME.bin; returns the paths.
    Result<std::vector<std::string>> write(const std::string& outDir,
                                           const std::string& name) const;

private:
    struct Mesh {
        std::string name;
        std::vector<PrimitiveData> primitives;
    };
    struct Texture {
        std::string name;
        std::vector<uint8_t> png;
    };

    std::vector<Mesh> mMeshes;
    std::vector<MaterialDesc> mMaterials;
    std::vector<Texture> mTextures;
    std::vector<LightDesc> mLights;
    std::vector<CameraDesc> mCameras;
};

}  // namespace pic::testscenes
