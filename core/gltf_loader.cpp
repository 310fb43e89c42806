#include "core/gltf_loader.h"

#include "core/light_set.h"

#include <algorithm>
#include <cctype>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <new>
#include <set>
#include <stdexcept>
#include <string_view>
#include <vector>

#include <tiny_gltf.h>
#include <nlohmann/json.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "core/hash.h"
#include "core/light_set.h"
#include "core/parallel.h"
#include "core/progress.h"

namespace pic {

namespace {

namespace fs = std::filesystem;

/// Extensions whose data the loader reads; any other required extension refuses the file.
constexpr std::array<std::string_view, 3> kUnderstoodExtensions = {
    "KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_mesh_quantization"};

bool isUnderstood(const std::string& extension) {
    return std::ranges::find(kUnderstoodExtensions, extension) != kUnderstoodExtensions.end();
}

constexpr std::array<char, 4> kGlbMagic = {'g', 'l', 'T', 'F'};

// ---------------------------------------------------------------------------------------------
// Small helpers

const char* modeName(int mode) {
    switch (mode) {
    case TINYGLTF_MODE_POINTS:
        return "POINTS";
    case TINYGLTF_MODE_LINE:
        return "LINES";
    case TINYGLTF_MODE_LINE_LOOP:
        return "LINE_LOOP";
    case TINYGLTF_MODE_LINE_STRIP:
        return "LINE_STRIP";
    case TINYGLTF_MODE_TRIANGLES:
        return "TRIANGLES";
    case TINYGLTF_MODE_TRIANGLE_STRIP:
        return "TRIANGLE_STRIP";
    case TINYGLTF_MODE_TRIANGLE_FAN:
        return "TRIANGLE_FAN";
    default:
        return "unknown";
    }
}

bool isFinite(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// The exact sRGB electro-optical transfer function (IEC 61966-2-1), encoded → linear.
float srgbToLinear(float c) {
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

/// Linear values of the 256 8-bit sRGB codes.
const std::array<float, 256>& srgb8ToLinear() {
    static const std::array<float, 256> table = [] {
        std::array<float, 256> t{};
        for (int i = 0; i < 256; ++i) t[size_t(i)] = srgbToLinear(float(i) / 255.0f);
        return t;
    }();
    return table;
}

/// tinygltf image callback that keeps the encoded bytes: only images that used materials
/// reference are decoded afterwards, in parallel.
bool keepEncodedImage(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                      const unsigned char* bytes, int size, void*) {
    image->image.assign(bytes, bytes + size);
    image->as_is = true;
    return true;
}

/// The world-from-local matrix of a node: its matrix, or translation × rotation × scale.
Result<glm::dmat4> localTransform(const tinygltf::Node& node, int index) {
    if (node.matrix.size() == 16) return glm::make_mat4(node.matrix.data());
    if (!node.matrix.empty())
        return fail(ErrorCode::Corrupt, "node {} has a matrix of {} values, expected 16", index,
                    node.matrix.size());
    glm::dmat4 m(1.0);
    if (!node.translation.empty()) {
        if (node.translation.size() != 3)
            return fail(ErrorCode::Corrupt, "node {} has a translation of {} values, expected 3",
                        index, node.translation.size());
        m = glm::translate(m, glm::make_vec3(node.translation.data()));
    }
    if (!node.rotation.empty()) {
        if (node.rotation.size() != 4)
            return fail(ErrorCode::Corrupt, "node {} has a rotation of {} values, expected 4",
                        index, node.rotation.size());
        // glTF stores quaternions as (x, y, z, w); glm's constructor takes w first.
        glm::dquat q(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
        double length = glm::length(q);
        if (!(length > 0.0) || !std::isfinite(length))
            return fail(ErrorCode::InvalidInput,
                        "node {} has rotation ({}, {}, {}, {}), which is not a unit quaternion",
                        index, q.x, q.y, q.z, q.w);
        m *= glm::mat4_cast(q / length);
    }
    if (!node.scale.empty()) {
        if (node.scale.size() != 3)
            return fail(ErrorCode::Corrupt, "node {} has a scale of {} values, expected 3", index,
                        node.scale.size());
        m = glm::scale(m, glm::make_vec3(node.scale.data()));
    }
    return m;
}

// ---------------------------------------------------------------------------------------------
// Accessors

/// A validated, strided view of one accessor's elements.
struct AccessorView {
    const unsigned char* data = nullptr;  ///< first element
    size_t stride = 0;
    size_t count = 0;
    int components = 0;
    int componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    bool normalized = false;

    /// Component c of element i as float, normalised integers mapped to [0, 1] or [-1, 1].
    float component(size_t i, int c) const {
        const unsigned char* p = data + i * stride;
        switch (componentType) {
        case TINYGLTF_COMPONENT_TYPE_BYTE: {
            auto v = static_cast<int8_t>(p[c]);
            return normalized ? std::max(float(v) / 127.0f, -1.0f) : float(v);
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
            return normalized ? float(p[c]) / 255.0f : float(p[c]);
        case TINYGLTF_COMPONENT_TYPE_SHORT: {
            int16_t v;
            std::memcpy(&v, p + 2 * c, 2);
            return normalized ? std::max(float(v) / 32767.0f, -1.0f) : float(v);
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
            uint16_t v;
            std::memcpy(&v, p + 2 * c, 2);
            return normalized ? float(v) / 65535.0f : float(v);
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
            uint32_t v;
            std::memcpy(&v, p + 4 * c, 4);
            return normalized ? float(double(v) / 4294967295.0) : float(v);
        }
        default: {
            float v;
            std::memcpy(&v, p + 4 * c, 4);
            return v;
        }
        }
    }

    /// Element i with its missing trailing components taken from `fallback`.
    glm::vec4 element(size_t i, glm::vec4 fallback) const {
        for (int c = 0; c < components; ++c) fallback[c] = component(i, c);
        return fallback;
    }

    /// Element i of an index accessor (unsigned integer scalars).
    uint32_t index(size_t i) const {
        const unsigned char* p = data + i * stride;
        switch (componentType) {
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
            return p[0];
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
            uint16_t v;
            std::memcpy(&v, p, 2);
            return v;
        }
        default: {
            uint32_t v;
            std::memcpy(&v, p, 4);
            return v;
        }
        }
    }
};

/// Checks accessor `index` against its buffer view and buffer and returns a view of it; `what`
/// names its use ("POSITION of mesh 'Foo' primitive 0") and `allowedComponents` its shapes.
Result<AccessorView> viewAccessor(const tinygltf::Model& model, int index, const std::string& what,
                                  std::initializer_list<int> allowedComponents) {
    if (index < 0 || size_t(index) >= model.accessors.size())
        return fail(ErrorCode::Corrupt, "{} refers to accessor {}, but the file has {} accessors",
                    what, index, model.accessors.size());
    const tinygltf::Accessor& accessor = model.accessors[size_t(index)];
    if (accessor.sparse.isSparse)
        return fail(ErrorCode::Unsupported,
                    "{} uses sparse accessor {}; sparse accessors are not supported", what, index);
    int componentSize = tinygltf::GetComponentSizeInBytes(uint32_t(accessor.componentType));
    int components = tinygltf::GetNumComponentsInType(uint32_t(accessor.type));
    if (accessor.componentType == TINYGLTF_COMPONENT_TYPE_INT || componentSize <= 0 ||
        accessor.componentType == TINYGLTF_COMPONENT_TYPE_DOUBLE)
        return fail(ErrorCode::Corrupt, "{}: accessor {} has invalid componentType {}", what, index,
                    accessor.componentType);
    if (std::find(allowedComponents.begin(), allowedComponents.end(), components) ==
        allowedComponents.end())
        return fail(ErrorCode::Corrupt, "{}: accessor {} has {} components per element", what,
                    index, components);

    // Without a bufferView glTF reads an accessor as zeros, which only sparse accessors
    // (refused above) put to use.
    if (accessor.bufferView < 0)
        return fail(ErrorCode::Unsupported, "{}: accessor {} has no bufferView (all zeros)", what,
                    index);
    if (size_t(accessor.bufferView) >= model.bufferViews.size())
        return fail(ErrorCode::Corrupt, "{}: accessor {} refers to missing bufferView {}", what,
                    index, accessor.bufferView);
    const tinygltf::BufferView& bufferView = model.bufferViews[size_t(accessor.bufferView)];
    if (bufferView.buffer < 0 || size_t(bufferView.buffer) >= model.buffers.size())
        return fail(ErrorCode::Corrupt, "{}: bufferView {} refers to missing buffer {}", what,
                    accessor.bufferView, bufferView.buffer);
    const tinygltf::Buffer& buffer = model.buffers[size_t(bufferView.buffer)];
    if (bufferView.byteOffset > buffer.data.size() ||
        bufferView.byteLength > buffer.data.size() - bufferView.byteOffset)
        return fail(ErrorCode::Corrupt,
                    "{}: bufferView {} (offset {}, length {}) overruns buffer {} of {} bytes", what,
                    accessor.bufferView, bufferView.byteOffset, bufferView.byteLength,
                    bufferView.buffer, buffer.data.size());
    int stride = accessor.ByteStride(bufferView);
    if (stride <= 0)
        return fail(ErrorCode::Corrupt, "{}: bufferView {} has invalid byteStride {}", what,
                    accessor.bufferView, bufferView.byteStride);
    // The last element must end inside the view; written so that no product can overflow.
    size_t elementSize = size_t(componentSize) * size_t(components);
    size_t length = bufferView.byteLength;
    if (accessor.count > 0 &&
        (accessor.byteOffset > length || elementSize > length - accessor.byteOffset ||
         accessor.count - 1 > (length - accessor.byteOffset - elementSize) / size_t(stride)))
        return fail(ErrorCode::Corrupt,
                    "{}: accessor {} (offset {}, {} elements, stride {}) overruns bufferView {} of "
                    "{} bytes",
                    what, index, accessor.byteOffset, accessor.count, stride, accessor.bufferView,
                    length);

    AccessorView view;
    view.count = accessor.count;
    view.components = components;
    view.componentType = accessor.componentType;
    view.normalized = accessor.normalized;
    view.data = buffer.data.data() + bufferView.byteOffset + accessor.byteOffset;
    view.stride = size_t(stride);
    return view;
}

// ---------------------------------------------------------------------------------------------
// Images

/// A decoded image in linear RGBA.
struct DecodedImage {
    int width = 0;
    int height = 0;
    std::vector<glm::vec4> texels;
};

/// "image 3 'name'" (or its URI, or its buffer view) for messages.
std::string imageLabel(const tinygltf::Image& image, int index) {
    if (!image.name.empty()) return fmt::format("image {} '{}'", index, image.name);
    if (!image.uri.empty()) return fmt::format("image {} '{}'", index, image.uri);
    return fmt::format("image {} (bufferView {}, {})", index, image.bufferView, image.mimeType);
}

/// Decodes glTF image `index`, sRGB-encoded and kept by keepEncodedImage, into linear RGBA.
Result<DecodedImage> decodeSrgbImage(const tinygltf::Image& encoded, int index,
                                     const std::string& baseDir) {
    std::string label = imageLabel(encoded, index);
    if (!encoded.as_is)
        return fail(ErrorCode::NotFound, "{} ('{}' relative to '{}') could not be read", label,
                    encoded.uri, baseDir);
    // tinygltf's stb-based decoder expands every image to RGBA, 8 or 16 bits per channel.
    tinygltf::Image image;
    image.name = encoded.name;
    std::string err;
    std::string warn;
    if (!tinygltf::LoadImageData(&image, index, &err, &warn, 0, 0, encoded.image.data(),
                                 int(encoded.image.size()), nullptr)) {
        while (!err.empty() && err.back() == '\n') err.pop_back();
        return fail(ErrorCode::Corrupt, "{} could not be decoded: {}", label, err);
    }
    if (image.component != 4 || (image.bits != 8 && image.bits != 16))
        return fail(ErrorCode::Unsupported, "{} decoded to {} channels of {} bits", label,
                    image.component, image.bits);

    DecodedImage decoded;
    decoded.width = image.width;
    decoded.height = image.height;
    size_t count = size_t(image.width) * size_t(image.height);
    decoded.texels.resize(count);
    if (image.bits == 8) {
        const auto& table = srgb8ToLinear();
        const unsigned char* p = image.image.data();
        for (size_t i = 0; i < count; ++i, p += 4)
            decoded.texels[i] = {table[p[0]], table[p[1]], table[p[2]], float(p[3]) / 255.0f};
    } else {
        for (size_t i = 0; i < count; ++i) {
            uint16_t c[4];
            std::memcpy(c, image.image.data() + 8 * i, 8);
            decoded.texels[i] = {srgbToLinear(float(c[0]) / 65535.0f),
                                 srgbToLinear(float(c[1]) / 65535.0f),
                                 srgbToLinear(float(c[2]) / 65535.0f), float(c[3]) / 65535.0f};
        }
    }
    return decoded;
}

// ---------------------------------------------------------------------------------------------
// Scene building

/// Converts a parsed tinygltf model into a Scene, instancing the node hierarchy.
class SceneBuilder {
public:
    SceneBuilder(const tinygltf::Model& model, std::string path, std::string baseDir)
        : mModel(model),
          mPath(std::move(path)),
          mBaseDir(std::move(baseDir)),
          mSceneMaterialOf(model.materials.size(), -1),
          mSceneTextureOf(model.textures.size(), -1) {
        mScene.sourcePath = mPath;
    }

    Result<Scene> build(const LoadOptions& options) {
        if (auto checked = checkExtensions(); !checked) return std::unexpected(checked.error());
        PIC_TRY_ASSIGN(std::vector<int> roots, rootNodes());
        if (auto traversed = traverse(roots); !traversed) return std::unexpected(traversed.error());
        if (options.requireGeometry && mScene.triangles.empty())
            return fail(ErrorCode::InvalidInput,
                        "'{}' contains no triangle geometry ({} degenerate triangles dropped)",
                        mPath, mScene.droppedDegenerate);
        if (auto decoded = decodeTextures(); !decoded) return std::unexpected(decoded.error());
        if (mIgnoredMorphTargets)
            fmt::print(stderr, "note: '{}': morph targets are ignored (base shapes loaded)\n",
                       mPath);
        if (!mModel.skins.empty())
            fmt::print(stderr, "note: '{}': skins are ignored (meshes loaded in bind pose)\n",
                       mPath);
        if (mScene.rewound)
            fmt::print(stderr,
                       "note: '{}': {} triangles wound clockwise about their vertex normals were "
                       "turned to face them\n",
                       mPath, mScene.rewound);
        finishScene(mScene);
        return std::move(mScene);
    }

private:
    Result<void> checkExtensions() const {
        for (const std::string& name : mModel.extensionsRequired)
            if (!isUnderstood(name))
                return fail(ErrorCode::Unsupported,
                            "'{}' requires glTF extension {}, which pic does not support", mPath,
                            name);
        std::string ignored;
        for (const std::string& name : mModel.extensionsUsed)
            if (!isUnderstood(name)) ignored += (ignored.empty() ? "" : ", ") + name;
        if (!ignored.empty())
            fmt::print(stderr, "note: '{}': ignoring glTF extensions {}\n", mPath, ignored);
        return {};
    }

    /// The default scene's root nodes, else scene 0's, else every node that is nobody's child.
    Result<std::vector<int>> rootNodes() const {
        if (!mModel.scenes.empty()) {
            int scene = mModel.defaultScene >= 0 ? mModel.defaultScene : 0;
            if (size_t(scene) >= mModel.scenes.size())
                return fail(ErrorCode::Corrupt, "'{}' has default scene {} but only {} scenes",
                            mPath, scene, mModel.scenes.size());
            return mModel.scenes[size_t(scene)].nodes;
        }
        std::vector<char> isChild(mModel.nodes.size(), 0);
        for (const tinygltf::Node& node : mModel.nodes)
            for (int child : node.children)
                if (child >= 0 && size_t(child) < isChild.size()) isChild[size_t(child)] = 1;
        std::vector<int> roots;
        for (size_t i = 0; i < mModel.nodes.size(); ++i)
            if (!isChild[i]) roots.push_back(int(i));
        return roots;
    }

    /// Depth-first, pre-order walk (children in file order) instancing meshes, lights, cameras.
    Result<void> traverse(const std::vector<int>& roots) {
        struct Pending {
            int node;
            glm::dmat4 worldFromParent;
        };
        std::vector<Pending> stack;
        for (auto it = roots.rbegin(); it != roots.rend(); ++it)
            stack.push_back({*it, glm::dmat4(1.0)});
        // The node hierarchy is a forest (glTF 2.0 §3.5.3): each node is reached at most once,
        // which also rules out cycles.
        std::vector<char> visited(mModel.nodes.size(), 0);
        while (!stack.empty()) {
            Pending item = stack.back();
            stack.pop_back();
            if (item.node < 0 || size_t(item.node) >= mModel.nodes.size())
                return fail(ErrorCode::Corrupt, "'{}' refers to node {}, but it has {} nodes",
                            mPath, item.node, mModel.nodes.size());
            if (visited[size_t(item.node)])
                return fail(ErrorCode::Corrupt,
                            "node {} is reached twice; the node hierarchy must be a forest",
                            item.node);
            visited[size_t(item.node)] = 1;
            const tinygltf::Node& node = mModel.nodes[size_t(item.node)];
            PIC_TRY_ASSIGN(glm::dmat4 local, localTransform(node, item.node));
            glm::dmat4 worldFromNode = item.worldFromParent * local;

            if (node.mesh >= 0) {
                if (size_t(node.mesh) >= mModel.meshes.size())
                    return fail(ErrorCode::Corrupt,
                                "node {} refers to mesh {}, but the file has {}", item.node,
                                node.mesh, mModel.meshes.size());
                const tinygltf::Mesh& mesh = mModel.meshes[size_t(node.mesh)];
                for (size_t p = 0; p < mesh.primitives.size(); ++p)
                    if (auto added = addPrimitive(node.mesh, int(p), worldFromNode); !added)
                        return std::unexpected(added.error());
            }
            if (node.camera >= 0)
                if (auto added = addCamera(node.camera, item.node, worldFromNode); !added)
                    return std::unexpected(added.error());
            if (auto it = node.extensions.find("KHR_lights_punctual"); it != node.extensions.end())
                if (auto added = addLight(it->second, item.node, worldFromNode); !added)
                    return std::unexpected(added.error());

            for (auto child = node.children.rbegin(); child != node.children.rend(); ++child)
                stack.push_back({*child, worldFromNode});
        }
        return {};
    }

    Result<void> addPrimitive(int meshIndex, int primitiveIndex, const glm::dmat4& worldFromMesh) {
        const tinygltf::Mesh& mesh = mModel.meshes[size_t(meshIndex)];
        const tinygltf::Primitive& primitive = mesh.primitives[size_t(primitiveIndex)];
        std::string meshName = mesh.name.empty() ? fmt::format("mesh_{}", meshIndex) : mesh.name;
        std::string label = fmt::format("mesh '{}' primitive {}", meshName, primitiveIndex);

        int mode = primitive.mode < 0 ? TINYGLTF_MODE_TRIANGLES : primitive.mode;
        if (mode < TINYGLTF_MODE_POINTS || mode > TINYGLTF_MODE_TRIANGLE_FAN)
            return fail(ErrorCode::Corrupt, "{} has invalid mode {}", label, mode);
        if (mode < TINYGLTF_MODE_TRIANGLES)
            return fail(ErrorCode::Unsupported, "{} has mode {} ({}); only triangles are supported",
                        label, modeName(mode), mode);
        if (!primitive.targets.empty()) mIgnoredMorphTargets = true;

        auto attribute = [&](const char* name) {
            auto it = primitive.attributes.find(name);
            return it == primitive.attributes.end() ? -1 : it->second;
        };
        int positionAccessor = attribute("POSITION");
        if (positionAccessor < 0) return fail(ErrorCode::Corrupt, "{} has no POSITION", label);
        PIC_TRY_ASSIGN(AccessorView positions,
                       viewAccessor(mModel, positionAccessor, "POSITION of " + label, {3}));
        size_t vertexCount = positions.count;
        auto optionalView = [&](const char* name,
                                std::initializer_list<int> shapes) -> Result<AccessorView> {
            int accessor = attribute(name);
            if (accessor < 0) return AccessorView{};
            PIC_TRY_ASSIGN(
                AccessorView view,
                viewAccessor(mModel, accessor, fmt::format("{} of {}", name, label), shapes));
            if (view.count != vertexCount)
                return fail(ErrorCode::Corrupt, "{} of {} has {} elements but POSITION has {}",
                            name, label, view.count, vertexCount);
            return view;
        };
        PIC_TRY_ASSIGN(AccessorView normals, optionalView("NORMAL", {3}));
        PIC_TRY_ASSIGN(AccessorView uv0s, optionalView("TEXCOORD_0", {2}));
        PIC_TRY_ASSIGN(AccessorView uv1s, optionalView("TEXCOORD_1", {2}));
        PIC_TRY_ASSIGN(AccessorView colors, optionalView("COLOR_0", {3, 4}));
        bool hasNormals = attribute("NORMAL") >= 0;
        bool hasUv0 = attribute("TEXCOORD_0") >= 0;
        bool hasUv1 = attribute("TEXCOORD_1") >= 0;

        PIC_TRY_ASSIGN(std::vector<uint32_t> corners,
                       triangleCorners(primitive, mode, vertexCount, label));
        // A mirroring transform turns counter-clockwise into clockwise: swap two corners so the
        // front face (and the geometric normal) stays on the outside.
        glm::dmat3 linear(worldFromMesh);
        if (glm::determinant(linear) < 0.0)
            for (size_t c = 0; c < corners.size(); c += 3)
                std::swap(corners[c + 1], corners[c + 2]);

        // Vertices come from the accessors one to one, or once per corner when face normals
        // must be flat (no NORMAL attribute).
        std::vector<uint32_t> sourceVertex;
        if (hasNormals) {
            sourceVertex.resize(vertexCount);
            for (size_t i = 0; i < vertexCount; ++i) sourceVertex[i] = uint32_t(i);
        } else {
            sourceVertex = corners;
        }
        size_t base = mScene.vertices.size();
        if (base + sourceVertex.size() > std::numeric_limits<uint32_t>::max())
            return fail(ErrorCode::Unsupported, "{} takes the scene past 2^32 vertices", label);

        glm::dmat3 normalFromMesh = glm::transpose(glm::inverse(linear));
        mScene.vertices.resize(base + sourceVertex.size());
        for (size_t i = 0; i < sourceVertex.size(); ++i) {
            uint32_t s = sourceVertex[i];
            Vertex& v = mScene.vertices[base + i];
            glm::dvec3 local = glm::dvec3(positions.element(s, glm::vec4(0.0f)));
            v.position = glm::vec3(glm::dvec3(worldFromMesh * glm::dvec4(local, 1.0)));
            if (!isFinite(v.position))
                return fail(ErrorCode::InvalidInput,
                            "{} vertex {} has non-finite world position ({}, {}, {})", label, s,
                            v.position.x, v.position.y, v.position.z);
            if (hasNormals)
                v.normal = glm::vec3(glm::normalize(
                    normalFromMesh * glm::dvec3(normals.element(s, glm::vec4(0.0f)))));
            if (hasUv0) v.uv0 = glm::vec2(uv0s.element(s, glm::vec4(0.0f)));
            if (hasUv1) v.uv1 = glm::vec2(uv1s.element(s, glm::vec4(0.0f)));
            if (colors.components > 0) v.color = colors.element(s, glm::vec4(1.0f));
        }

        // Keep triangles of non-zero area, using Scene's own area so every kept triangle has a
        // finite unit normal.
        uint32_t primitiveId = uint32_t(mScene.primitives.size());
        uint32_t firstTriangle = uint32_t(mScene.triangles.size());
        for (size_t c = 0; c < corners.size(); c += 3) {
            Triangle t;
            for (int k = 0; k < 3; ++k)
                t.v[k] = uint32_t(base + (hasNormals ? corners[c + size_t(k)] : c + size_t(k)));
            t.primitive = primitiveId;
            mScene.triangles.push_back(t);
            const uint32_t index = uint32_t(mScene.triangles.size() - 1);
            float area = mScene.triangleArea(index);
            if (!(area > 0.0f) || !std::isfinite(area)) {
                mScene.triangles.pop_back();
                ++mScene.droppedDegenerate;
            } else if (hasNormals && windsAgainstItsNormals(index)) {
                std::swap(mScene.triangles.back().v[1], mScene.triangles.back().v[2]);
                ++mScene.rewound;
            }
        }
        uint32_t triangleCount = uint32_t(mScene.triangles.size()) - firstTriangle;
        fixNormals(base, firstTriangle, hasNormals);
        compactVertices(base, firstTriangle);
        if (triangleCount == 0) return {};

        PIC_TRY_ASSIGN(uint32_t material, useMaterial(primitive.material));
        const Material& m = mScene.materials[material];
        if (m.baseColorTexture >= 0 && !(m.baseColorTexCoord == 0 ? hasUv0 : hasUv1))
            return fail(ErrorCode::InvalidInput,
                        "material '{}' samples its base colour texture with TEXCOORD_{}, which {} "
                        "lacks",
                        m.name, m.baseColorTexCoord, label);
        if (m.emissiveTexture >= 0 && !hasUv0)
            return fail(ErrorCode::InvalidInput,
                        "material '{}' has an emissive texture but {} lacks TEXCOORD_0", m.name,
                        label);
        for (uint32_t t = firstTriangle; t < firstTriangle + triangleCount; ++t)
            mScene.triangles[t].material = material;
        mScene.primitives.push_back(
            {fmt::format("{}/{}", meshName, primitiveIndex), firstTriangle, triangleCount, hasUv1});
        return {};
    }

    /// Vertex indices, three per triangle, of a TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN
    /// primitive (glTF 2.0 §3.7.2.1), all checked against the vertex count.
    Result<std::vector<uint32_t>> triangleCorners(const tinygltf::Primitive& primitive, int mode,
                                                  size_t vertexCount,
                                                  const std::string& label) const {
        std::vector<uint32_t> indices;
        if (primitive.indices >= 0) {
            PIC_TRY_ASSIGN(AccessorView view,
                           viewAccessor(mModel, primitive.indices, "indices of " + label, {1}));
            if (view.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                view.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
                view.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
                return fail(ErrorCode::Corrupt, "indices of {} have componentType {}", label,
                            view.componentType);
            indices.resize(view.count);
            for (size_t i = 0; i < view.count; ++i) {
                indices[i] = view.index(i);
                if (indices[i] >= vertexCount)
                    return fail(ErrorCode::Corrupt,
                                "{} index {} (at {}) is out of range for {} vertices", label,
                                indices[i], i, vertexCount);
            }
        } else {
            indices.resize(vertexCount);
            for (size_t i = 0; i < vertexCount; ++i) indices[i] = uint32_t(i);
        }

        std::vector<uint32_t> corners;
        if (mode == TINYGLTF_MODE_TRIANGLES) {
            if (indices.size() % 3 != 0)
                return fail(ErrorCode::Corrupt, "{} has {} indices, not a multiple of 3", label,
                            indices.size());
            corners = std::move(indices);
        } else if (indices.size() >= 3) {
            corners.reserve(3 * (indices.size() - 2));
            for (size_t i = 0; i + 2 < indices.size(); ++i) {
                if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
                    // Every other strip triangle is reversed to keep a consistent winding.
                    corners.insert(corners.end(),
                                   {indices[i], indices[i + 1 + i % 2], indices[i + 2 - i % 2]});
                } else {
                    corners.insert(corners.end(), {indices[i + 1], indices[i + 2], indices[0]});
                }
            }
        }
        return corners;
    }

    /// Whether triangle t winds clockwise about its vertex normals: the front face of glTF is
    /// the counter-clockwise one, but files from other tools often disagree with their own
    /// normals, and the normals are what their authors saw shaded. Surfels, light-map caches
    /// and the inside tests all face the geometric normal, so a triangle wound against its
    /// normals would be lit, and would light, from behind. Non-finite normals have no say.
    bool windsAgainstItsNormals(uint32_t t) const {
        glm::vec3 sum(0.0f);
        for (uint32_t v : mScene.triangles[t].v)
            if (isFinite(mScene.vertices[v].normal)) sum += mScene.vertices[v].normal;
        return glm::dot(sum, mScene.triangleNormal(t)) < 0.0f;
    }

    /// Gives flat-shaded vertices their triangle's normal, and shared vertices whose NORMAL was
    /// zero or non-finite the area-weighted normal of the kept triangles around them.
    void fixNormals(size_t base, uint32_t firstTriangle, bool hasNormals) {
        std::vector<glm::vec3> sums;
        if (hasNormals) sums.assign(mScene.vertices.size() - base, glm::vec3(0.0f));
        for (uint32_t t = firstTriangle; t < mScene.triangles.size(); ++t) {
            glm::vec3 n = mScene.triangleNormal(t);
            for (uint32_t v : mScene.triangles[t].v) {
                if (!hasNormals)
                    mScene.vertices[v].normal = n;
                else if (!isFinite(mScene.vertices[v].normal))
                    sums[v - base] += mScene.triangleArea(t) * n;
            }
        }
        if (!hasNormals) return;
        for (size_t i = 0; i < sums.size(); ++i) {
            Vertex& v = mScene.vertices[base + i];
            if (isFinite(v.normal)) continue;
            float length = glm::length(sums[i]);
            // Opposite faces can cancel; any unit vector is then as good as another.
            v.normal = length > 0.0f ? sums[i] / length : glm::vec3(0.0f, 1.0f, 0.0f);
        }
    }

    /// Removes the vertices from `base` on that no kept triangle uses, renumbering triangles
    /// so vertices appear in the order of their first use.
    void compactVertices(size_t base, uint32_t firstTriangle) {
        constexpr uint32_t kUnused = std::numeric_limits<uint32_t>::max();
        std::vector<uint32_t> remap(mScene.vertices.size() - base, kUnused);
        std::vector<Vertex> kept;
        kept.reserve(remap.size());
        for (uint32_t t = firstTriangle; t < mScene.triangles.size(); ++t) {
            for (uint32_t& v : mScene.triangles[t].v) {
                uint32_t& slot = remap[v - base];
                if (slot == kUnused) {
                    slot = uint32_t(base + kept.size());
                    kept.push_back(mScene.vertices[v]);
                }
                v = slot;
            }
        }
        mScene.vertices.resize(base);
        mScene.vertices.insert(mScene.vertices.end(), kept.begin(), kept.end());
    }

    /// Index in Scene::materials of glTF material `index` (-1: the default white material).
    Result<uint32_t> useMaterial(int index) {
        if (index < 0) {
            if (mDefaultMaterial < 0) {
                mDefaultMaterial = int(mScene.materials.size());
                mScene.materials.push_back(Material{.name = "default"});
            }
            return uint32_t(mDefaultMaterial);
        }
        if (size_t(index) >= mModel.materials.size())
            return fail(ErrorCode::Corrupt, "'{}' refers to material {}, but it has {}", mPath,
                        index, mModel.materials.size());
        if (mSceneMaterialOf[size_t(index)] >= 0) return uint32_t(mSceneMaterialOf[size_t(index)]);

        const tinygltf::Material& source = mModel.materials[size_t(index)];
        Material material;
        material.name = source.name.empty() ? fmt::format("material_{}", index) : source.name;
        material.doubleSided = source.doubleSided;

        const std::vector<double>& base = source.pbrMetallicRoughness.baseColorFactor;
        if (base.size() != 4)
            return fail(ErrorCode::Corrupt, "material '{}' baseColorFactor has {} values",
                        material.name, base.size());
        for (double c : base)
            if (!(c >= 0.0 && c <= 1.0))
                return fail(ErrorCode::InvalidInput,
                            "material '{}' baseColorFactor ({}, {}, {}, {}) is outside [0, 1]",
                            material.name, base[0], base[1], base[2], base[3]);
        material.baseColorFactor = glm::vec4(glm::make_vec4(base.data()));

        const std::vector<double>& emissive = source.emissiveFactor;
        if (emissive.size() != 3)
            return fail(ErrorCode::Corrupt, "material '{}' emissiveFactor has {} values",
                        material.name, emissive.size());
        double strength = 1.0;
        if (auto it = source.extensions.find("KHR_materials_emissive_strength");
            it != source.extensions.end() && it->second.Has("emissiveStrength")) {
            const tinygltf::Value& value = it->second.Get("emissiveStrength");
            if (!value.IsNumber())
                return fail(ErrorCode::InvalidInput,
                            "material '{}' emissiveStrength is not a number", material.name);
            strength = value.GetNumberAsDouble();
        }
        glm::dvec3 emission = glm::make_vec3(emissive.data()) * strength;
        if (!(strength >= 0.0) || !std::isfinite(strength) ||
            !(emission.x >= 0.0 && emission.y >= 0.0 && emission.z >= 0.0) ||
            !isFinite(glm::vec3(emission)))
            return fail(ErrorCode::InvalidInput,
                        "material '{}' emission ({}, {}, {}) × strength {} must be finite and "
                        "non-negative",
                        material.name, emissive[0], emissive[1], emissive[2], strength);
        material.emission = glm::vec3(emission);

        const tinygltf::TextureInfo& baseTexture = source.pbrMetallicRoughness.baseColorTexture;
        if (baseTexture.index >= 0) {
            if (baseTexture.texCoord < 0 || baseTexture.texCoord > 1)
                return fail(ErrorCode::Unsupported,
                            "material '{}' base colour texture uses TEXCOORD_{}; only TEXCOORD_0 "
                            "and TEXCOORD_1 are supported",
                            material.name, baseTexture.texCoord);
            PIC_TRY_ASSIGN(material.baseColorTexture, useTexture(baseTexture.index, material.name));
            material.baseColorTexCoord = baseTexture.texCoord;
        }
        const tinygltf::TextureInfo& emissiveTexture = source.emissiveTexture;
        if (emissiveTexture.index >= 0) {
            if (emissiveTexture.texCoord != 0)
                return fail(ErrorCode::Unsupported,
                            "material '{}' emissive texture uses TEXCOORD_{}; only TEXCOORD_0 is "
                            "supported",
                            material.name, emissiveTexture.texCoord);
            PIC_TRY_ASSIGN(material.emissiveTexture,
                           useTexture(emissiveTexture.index, material.name));
        }

        mSceneMaterialOf[size_t(index)] = int(mScene.materials.size());
        mScene.materials.push_back(std::move(material));
        return uint32_t(mScene.materials.size() - 1);
    }

    /// Index in Scene::textures of glTF texture `index`; its texels are decoded later.
    Result<int> useTexture(int index, const std::string& materialName) {
        if (size_t(index) >= mModel.textures.size())
            return fail(ErrorCode::Corrupt,
                        "material '{}' refers to texture {}, but the file has {}", materialName,
                        index, mModel.textures.size());
        if (mSceneTextureOf[size_t(index)] >= 0) return mSceneTextureOf[size_t(index)];
        const tinygltf::Texture& source = mModel.textures[size_t(index)];
        if (source.source < 0 || size_t(source.source) >= mModel.images.size())
            return fail(ErrorCode::Unsupported,
                        "texture {} of material '{}' has no PNG/JPEG image source (image {})",
                        index, materialName, source.source);
        Texture texture;
        const tinygltf::Image& image = mModel.images[size_t(source.source)];
        texture.name = !source.name.empty()  ? source.name
                       : !image.name.empty() ? image.name
                       : !image.uri.empty()  ? image.uri
                                             : fmt::format("texture_{}", index);
        if (source.sampler >= 0) {
            if (size_t(source.sampler) >= mModel.samplers.size())
                return fail(ErrorCode::Corrupt,
                            "texture {} refers to sampler {}, but the file has {}", index,
                            source.sampler, mModel.samplers.size());
            const tinygltf::Sampler& sampler = mModel.samplers[size_t(source.sampler)];
            // MIRRORED_REPEAT is read as REPEAT: the Texture model knows repeat and clamp only.
            // Both agree inside [0, 1] except within half a texel of its edges.
            texture.repeatS = sampler.wrapS != TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE;
            texture.repeatT = sampler.wrapT != TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE;
        }
        mSceneTextureOf[size_t(index)] = int(mScene.textures.size());
        mScene.textures.push_back(std::move(texture));
        mTextureImage.push_back(source.source);
        return mSceneTextureOf[size_t(index)];
    }

    /// Decodes each image the used textures refer to once, in parallel, all as sRGB (base
    /// colour and emissive textures are sRGB-encoded by the glTF specification), and builds
    /// each texture's mip chain in linear RGBA.
    Result<void> decodeTextures() {
        std::vector<int> images = mTextureImage;
        std::sort(images.begin(), images.end());
        images.erase(std::unique(images.begin(), images.end()), images.end());
        std::vector<Result<DecodedImage>> decoded(images.size(), std::unexpected(Error{}));
        Progress progress("decoding textures", images.size());
        parallelFor(
            0, images.size(),
            [&](size_t i) {
                decoded[i] = decodeSrgbImage(mModel.images[size_t(images[i])], images[i], mBaseDir);
                progress.advance();
            },
            1);
        progress.finish();
        for (const Result<DecodedImage>& image : decoded)
            if (!image) return std::unexpected(image.error());
        for (size_t t = 0; t < mScene.textures.size(); ++t) {
            size_t slot = size_t(std::lower_bound(images.begin(), images.end(), mTextureImage[t]) -
                                 images.begin());
            const DecodedImage& image = *decoded[slot];
            Texture& texture = mScene.textures[t];
            texture.width = image.width;
            texture.height = image.height;
            texture.texels = image.texels;
        }
        // The mip chains every footprint lookup reads, built once here (core/texture.h).
        parallelFor(
            0, mScene.textures.size(), [&](size_t t) { buildMipChain(mScene.textures[t]); }, 1);
        return {};
    }

    Result<void> addLight(const tinygltf::Value& extension, int nodeIndex,
                          const glm::dmat4& worldFromNode) {
        const tinygltf::Value& ref = extension.Get("light");
        if (!ref.IsNumber())
            return fail(ErrorCode::Corrupt, "node {} has KHR_lights_punctual without a light",
                        nodeIndex);
        int index = ref.GetNumberAsInt();
        if (index < 0 || size_t(index) >= mModel.lights.size())
            return fail(ErrorCode::Corrupt, "node {} refers to light {}, but the file has {}",
                        nodeIndex, index, mModel.lights.size());
        const tinygltf::Light& source = mModel.lights[size_t(index)];

        Light light;
        // A name that cannot be a light id (too long, with room for uniqueLightId's "#k", or
        // with control characters) is not used.
        const bool named = isLightId(source.name) && source.name.size() + 8 <= kMaxLightIdBytes;
        light.id = uniqueLightId(named ? source.name : fmt::format("light_{}", index));
        if (source.type == "point")
            light.type = LightType::Point;
        else if (source.type == "spot")
            light.type = LightType::Spot;
        else if (source.type == "directional")
            light.type = LightType::Directional;
        else
            return fail(ErrorCode::InvalidInput, "light '{}' has unknown type '{}'", light.id,
                        source.type);
        light.position = glm::vec3(glm::dvec3(worldFromNode * glm::dvec4(0.0, 0.0, 0.0, 1.0)));
        light.direction =
            glm::vec3(glm::normalize(glm::dvec3(worldFromNode * glm::dvec4(0.0, 0.0, -1.0, 0.0))));
        if (!isFinite(light.position) || !isFinite(light.direction))
            return fail(ErrorCode::InvalidInput,
                        "light '{}' on node {} has a degenerate or non-finite transform", light.id,
                        nodeIndex);

        if (!source.color.empty()) {
            if (source.color.size() != 3)
                return fail(ErrorCode::InvalidInput, "light '{}' colour has {} values", light.id,
                            source.color.size());
            light.color = glm::vec3(glm::make_vec3(source.color.data()));
        }
        if (!isFinite(light.color) || glm::any(glm::lessThan(light.color, glm::vec3(0.0f))))
            return fail(ErrorCode::InvalidInput,
                        "light '{}' colour ({}, {}, {}) must be finite and non-negative", light.id,
                        light.color.x, light.color.y, light.color.z);
        if (!(source.intensity >= 0.0) || !std::isfinite(source.intensity))
            return fail(ErrorCode::InvalidInput,
                        "light '{}' intensity {} must be finite and non-negative", light.id,
                        source.intensity);
        light.intensity = float(source.intensity);
        // tinygltf reports an absent range as 0; the extension requires range > 0 when present.
        if (!(source.range >= 0.0))
            return fail(ErrorCode::InvalidInput, "light '{}' range {} must be positive", light.id,
                        source.range);
        if (source.range > 0.0) light.range = float(source.range);

        if (light.type == LightType::Spot) {
            double inner = source.spot.innerConeAngle;
            double outer = source.spot.outerConeAngle;
            if (!(inner >= 0.0 && inner <= outer && outer > 0.0 && outer <= glm::half_pi<double>()))
                return fail(ErrorCode::InvalidInput,
                            "light '{}' cone angles inner {} outer {} must satisfy 0 <= inner <= "
                            "outer <= pi/2, outer > 0",
                            light.id, inner, outer);
            light.innerConeAngle = float(inner);
            light.outerConeAngle = float(outer);
        }
        mScene.lights.push_back(std::move(light));
        return {};
    }

    /// `id`, or `id#k` with the smallest k ≥ 2 not taken, so every light has its own id
    /// (a light used by several nodes, or several lights sharing a name).
    std::string uniqueLightId(const std::string& id) {
        std::string unique = id;
        for (int k = 2; mLightIds.contains(unique); ++k) unique = fmt::format("{}#{}", id, k);
        mLightIds.insert(unique);
        return unique;
    }

    Result<void> addCamera(int index, int nodeIndex, const glm::dmat4& worldFromNode) {
        if (size_t(index) >= mModel.cameras.size())
            return fail(ErrorCode::Corrupt, "node {} refers to camera {}, but the file has {}",
                        nodeIndex, index, mModel.cameras.size());
        const tinygltf::Camera& source = mModel.cameras[size_t(index)];
        std::string name = source.name.empty() ? fmt::format("camera_{}", index) : source.name;
        if (source.type != "perspective") {
            fmt::print(stderr, "note: '{}': skipping {} camera '{}' (only perspective cameras)\n",
                       mPath, source.type, name);
            return {};
        }
        double yfov = source.perspective.yfov;
        if (!(yfov > 0.0 && yfov < glm::pi<double>()))
            return fail(ErrorCode::InvalidInput, "camera '{}' yfov {} rad must be in (0, pi)", name,
                        yfov);
        Camera camera;
        camera.name = name;
        camera.eye = glm::vec3(glm::dvec3(worldFromNode * glm::dvec4(0.0, 0.0, 0.0, 1.0)));
        glm::vec3 forward =
            glm::vec3(glm::normalize(glm::dvec3(worldFromNode * glm::dvec4(0.0, 0.0, -1.0, 0.0))));
        camera.target = camera.eye + forward;
        camera.up =
            glm::vec3(glm::normalize(glm::dvec3(worldFromNode * glm::dvec4(0.0, 1.0, 0.0, 0.0))));
        camera.fovyDegrees = float(glm::degrees(yfov));
        if (!isFinite(camera.eye) || !isFinite(camera.target) || !isFinite(camera.up))
            return fail(ErrorCode::InvalidInput,
                        "camera '{}' on node {} has a degenerate or non-finite transform", name,
                        nodeIndex);
        mScene.cameras.push_back(std::move(camera));
        return {};
    }

    const tinygltf::Model& mModel;
    std::string mPath;
    std::string mBaseDir;
    Scene mScene;
    std::vector<int> mSceneMaterialOf;  ///< glTF material → Scene::materials index, -1 unused
    std::vector<int> mSceneTextureOf;   ///< glTF texture → Scene::textures index, -1 unused
    std::vector<int> mTextureImage;     ///< Scene::textures index → glTF image
    std::set<std::string> mLightIds;    ///< ids given to Scene::lights so far
    int mDefaultMaterial = -1;
    bool mIgnoredMorphTargets = false;
};

/// The JSON text of a glTF file's bytes: all of a .gltf, the first chunk of a .glb.
Result<std::string_view> gltfJsonOf(std::string_view bytes, const std::string& path) {
    if (bytes.size() < kGlbMagic.size() ||
        !std::equal(kGlbMagic.begin(), kGlbMagic.end(), bytes.begin()))
        return bytes;
    // GLB: 12-byte header, then chunk 0 = u32 length, u32 type "JSON", the JSON text.
    constexpr size_t kChunkData = 20;
    uint32_t length = 0;
    uint32_t type = 0;
    if (bytes.size() >= kChunkData) {
        std::memcpy(&length, bytes.data() + 12, 4);
        std::memcpy(&type, bytes.data() + 16, 4);
    }
    constexpr uint32_t kJsonChunk = 0x4E4F534Au;
    if (bytes.size() < kChunkData || type != kJsonChunk || length > bytes.size() - kChunkData)
        return fail(ErrorCode::Corrupt, "'{}' is not a valid GLB file (no JSON chunk)", path);
    return bytes.substr(kChunkData, length);
}

std::string percentDecoded(const std::string& uri) {
    std::string out;
    for (size_t i = 0; i < uri.size(); ++i) {
        if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit((unsigned char)uri[i + 1]) &&
            std::isxdigit((unsigned char)uri[i + 2])) {
            out += char(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
            i += 2;
        } else {
            out += uri[i];
        }
    }
    return out;
}

/// The files a glTF's JSON references (buffers and images, not data: URIs), relative to its
/// folder, each once. InvalidInput for one outside the folder: an absolute path, a ".." part
/// or a URL; a scene may read only what lies beside it.
Result<std::vector<std::string>> referencedFiles(std::string_view json, const std::string& path) {
    nlohmann::json root = nlohmann::json::parse(json, nullptr, /*allow_exceptions=*/false);
    if (!root.is_object())
        return fail(ErrorCode::Corrupt, "'{}' is not glTF: its JSON does not parse to an object",
                    path);
    std::vector<std::string> files;
    for (const char* list : {"buffers", "images"}) {
        auto entries = root.find(list);
        if (entries == root.end() || !entries->is_array()) continue;
        for (const auto& entry : *entries) {
            if (!entry.is_object() || !entry.contains("uri") || !entry["uri"].is_string()) continue;
            std::string uri = entry["uri"].get<std::string>();
            if (uri.starts_with("data:")) continue;
            std::string file = percentDecoded(uri);
            fs::path relative(file);
            bool escapes = relative.is_absolute() || file.find("://") != std::string::npos ||
                           file.find('\0') != std::string::npos;
            for (const auto& part : relative) escapes = escapes || part == "..";
            if (escapes)
                return fail(ErrorCode::InvalidInput,
                            "'{}': {} URI \"{}\" leaves the scene's folder: a scene may only "
                            "reference files beside it or below",
                            path, list, uri.substr(0, 256));
            if (std::find(files.begin(), files.end(), file) == files.end()) files.push_back(file);
        }
    }
    return files;
}

/// loadScene without the exception guard.
Result<Scene> loadSceneUnguarded(const std::string& path, const LoadOptions& options) {
    std::error_code ec;
    fs::file_status status = fs::status(path, ec);
    if (!fs::exists(status)) return fail(ErrorCode::NotFound, "scene file '{}' not found", path);
    if (!fs::is_regular_file(status))
        return fail(ErrorCode::InvalidInput, "scene path '{}' is not a regular file", path);

    std::ifstream file(path, std::ios::binary);
    std::vector<unsigned char> bytes;
    if (file) {
        file.seekg(0, std::ios::end);
        std::streamoff size = file.tellg();
        file.seekg(0, std::ios::beg);
        if (size > std::streamoff(std::numeric_limits<unsigned int>::max()))
            return fail(ErrorCode::Unsupported, "scene file '{}' is {} bytes; the limit is 4 GiB",
                        path, size);
        bytes.resize(size_t(size));
        file.read(reinterpret_cast<char*>(bytes.data()), size);
    }
    if (!file) return fail(ErrorCode::Io, "could not read scene file '{}'", path);

    // Before tinygltf opens anything a URI names: none may leave the scene's folder. A file
    // that is no glTF at all is left to tinygltf, whose message says what is wrong with it.
    if (auto json = gltfJsonOf({reinterpret_cast<const char*>(bytes.data()), bytes.size()}, path)) {
        if (auto files = referencedFiles(*json, path); !files && files.error().code == ErrorCode::InvalidInput)
            return std::unexpected(files.error());
    }

    std::string extension = fs::path(path).extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    bool hasMagic = bytes.size() >= kGlbMagic.size() &&
                    std::equal(kGlbMagic.begin(), kGlbMagic.end(), bytes.begin());
    bool binary = hasMagic || extension == ".glb";

    fs::path parent = fs::path(path).parent_path();
    std::string baseDir = parent.empty() ? std::string(".") : parent.string();
    tinygltf::TinyGLTF parser;
    parser.SetImageLoader(&keepEncodedImage, nullptr);
    tinygltf::Model model;
    std::string err;
    std::string warn;
    bool parsed = binary ? parser.LoadBinaryFromMemory(&model, &err, &warn, bytes.data(),
                                                       unsigned(bytes.size()), baseDir)
                         : parser.LoadASCIIFromString(&model, &err, &warn,
                                                      reinterpret_cast<const char*>(bytes.data()),
                                                      unsigned(bytes.size()), baseDir);
    bytes = {};
    if (!parsed) {
        while (!err.empty() && err.back() == '\n') err.pop_back();
        return fail(ErrorCode::Corrupt, "could not parse glTF '{}': {}", path, err);
    }
    while (!warn.empty() && warn.back() == '\n') warn.pop_back();
    if (!warn.empty()) fmt::print(stderr, "note: '{}': {}\n", path, warn);

    return SceneBuilder(model, path, baseDir).build(options);
}

}  // namespace

Result<std::vector<std::string>> sceneFiles(const std::string& path) {
    std::ifstream file(path, std::ios::binary);
    if (!file) return fail(ErrorCode::NotFound, "cannot open scene file '{}'", path);
    const std::string bytes{std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
    if (file.bad()) return fail(ErrorCode::Io, "could not read scene file '{}'", path);
    PIC_TRY_ASSIGN(const std::string_view json, gltfJsonOf(bytes, path));
    PIC_TRY_ASSIGN(std::vector<std::string> files, referencedFiles(json, path));
    files.insert(files.begin(), fs::path(path).filename().string());
    return files;
}

Result<Scene> loadScene(const std::string& path, const LoadOptions& options) {
    // Allocation failures and container limits surface as exceptions (in tinygltf, its JSON
    // parser and the standard library); none may cross the module boundary (STYLE.md 18).
    try {
        return loadSceneUnguarded(path, options);
    } catch (const std::bad_alloc&) {
        return fail(ErrorCode::Internal, "out of memory while loading '{}'", path);
    } catch (const std::exception& e) {
        return fail(ErrorCode::Internal, "loading '{}' failed: {}", path, e.what());
    }
}

}  // namespace pic
