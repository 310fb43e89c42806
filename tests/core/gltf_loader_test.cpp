#include "core/gltf_loader.h"

#include <unistd.h>

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <stb/stb_image_write.h>
#include <nlohmann/json.hpp>

namespace pic {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr int kFloat = 5126;
constexpr int kUnsignedByte = 5121;
constexpr int kUnsignedShort = 5123;
constexpr int kUnsignedInt = 5125;

int componentsOf(const std::string& type) {
    return type == "SCALAR" ? 1 : type == "VEC2" ? 2 : type == "VEC3" ? 3 : 4;
}

void writeBytes(const fs::path& path, const void* data, size_t size) {
    std::ofstream out(path, std::ios::binary);
    out.write(static_cast<const char*>(data), std::streamsize(size));
    ASSERT_TRUE(out.good()) << path;
}

/// Builds a small glTF document in memory and writes it as .gltf + .bin or as .glb.
class GltfBuilder {
public:
    GltfBuilder() { doc["asset"] = {{"version", "2.0"}}; }

    /// Appends bytes to the binary buffer (4-byte aligned) as a new buffer view.
    int view(const void* data, size_t size, size_t stride = 0) {
        while (mBin.size() % 4 != 0) mBin.push_back(0);
        json v = {{"buffer", 0}, {"byteOffset", mBin.size()}, {"byteLength", size}};
        if (stride != 0) v["byteStride"] = stride;
        const auto* bytes = static_cast<const unsigned char*>(data);
        mBin.insert(mBin.end(), bytes, bytes + size);
        return append("bufferViews", v);
    }

    int accessor(int view, int componentType, size_t count, const std::string& type,
                 size_t byteOffset = 0, bool normalized = false) {
        json a = {{"bufferView", view},
                  {"componentType", componentType},
                  {"count", count},
                  {"type", type},
                  {"byteOffset", byteOffset}};
        if (normalized) a["normalized"] = true;
        return append("accessors", a);
    }

    /// A tightly packed accessor over `values`, `type` giving the components per element.
    template <class T>
    int data(const std::vector<T>& values, int componentType, const std::string& type,
             bool normalized = false) {
        int v = view(values.data(), values.size() * sizeof(T));
        return accessor(v, componentType, values.size() / size_t(componentsOf(type)), type, 0,
                        normalized);
    }
    int floats(const std::vector<float>& values, const std::string& type) {
        return data(values, kFloat, type);
    }

    int append(const std::string& array, json value) {
        doc[array].push_back(std::move(value));
        return int(doc[array].size()) - 1;
    }

    /// Makes `roots` the default scene.
    void scene(const std::vector<int>& roots) {
        doc["scenes"] = json::array({{{"nodes", roots}}});
        doc["scene"] = 0;
    }

    void writeGltf(const fs::path& path) const {
        json d = doc;
        if (!mBin.empty()) {
            fs::path bin = path;
            bin.replace_extension(".bin");
            writeBytes(bin, mBin.data(), mBin.size());
            d["buffers"] =
                json::array({{{"uri", bin.filename().string()}, {"byteLength", mBin.size()}}});
        }
        std::string text = d.dump(2);
        writeBytes(path, text.data(), text.size());
    }

    void writeGlb(const fs::path& path) const {
        json d = doc;
        std::vector<unsigned char> bin = mBin;
        while (bin.size() % 4 != 0) bin.push_back(0);
        if (!bin.empty()) d["buffers"] = json::array({{{"byteLength", mBin.size()}}});
        std::string text = d.dump();
        while (text.size() % 4 != 0) text.push_back(' ');
        std::vector<unsigned char> out;
        auto u32 = [&](uint32_t v) {
            for (int i = 0; i < 4; ++i) out.push_back(uint8_t(v >> (8 * i)));
        };
        size_t total = 12 + 8 + text.size() + (bin.empty() ? 0 : 8 + bin.size());
        out.insert(out.end(), {'g', 'l', 'T', 'F'});
        u32(2);
        u32(uint32_t(total));
        u32(uint32_t(text.size()));
        u32(0x4E4F534A);  // "JSON"
        out.insert(out.end(), text.begin(), text.end());
        if (!bin.empty()) {
            u32(uint32_t(bin.size()));
            u32(0x004E4942);  // "BIN\0"
            out.insert(out.end(), bin.begin(), bin.end());
        }
        writeBytes(path, out.data(), out.size());
    }

    json doc;

private:
    std::vector<unsigned char> mBin;
};

/// The unit quad in the z = 0 plane facing +z, UVs equal to x and y; returns the mesh index.
int addQuadMesh(GltfBuilder& b, const std::string& name, int material = -1) {
    json primitive = {
        {"attributes",
         {{"POSITION", b.floats({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}, "VEC3")},
          {"NORMAL", b.floats({0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1}, "VEC3")},
          {"TEXCOORD_0", b.floats({0, 0, 1, 0, 1, 1, 0, 1}, "VEC2")}}},
        {"indices", b.data(std::vector<uint16_t>{0, 1, 2, 0, 2, 3}, kUnsignedShort, "SCALAR")}};
    if (material >= 0) primitive["material"] = material;
    return b.append("meshes", {{"name", name}, {"primitives", json::array({primitive})}});
}

/// A unit quad under a node translated by (1, 2, 3), turned 90° about +y and scaled (2, 3, 4).
GltfBuilder transformedQuad() {
    GltfBuilder b;
    int mesh = addQuadMesh(b, "Quad");
    double s = std::sqrt(0.5);
    int node = b.append("nodes", {{"mesh", mesh},
                                  {"translation", {1.0, 2.0, 3.0}},
                                  {"rotation", {0.0, s, 0.0, s}},
                                  {"scale", {2.0, 3.0, 4.0}}});
    b.scene({node});
    return b;
}

double srgbToLinear(double c) {
    return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

void expectVecNear(const glm::vec3& a, const glm::vec3& b, float tolerance) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], tolerance) << "component " << c;
}

/// Barycentrics (b1, b2) at which triangle t's TEXCOORD_0 equals uv.
std::pair<float, float> barycentricsOfUv(const Scene& scene, uint32_t t, glm::vec2 uv) {
    const Triangle& tri = scene.triangles[t];
    glm::vec2 a = scene.vertices[tri.v[0]].uv0;
    glm::mat2 m(scene.vertices[tri.v[1]].uv0 - a, scene.vertices[tri.v[2]].uv0 - a);
    glm::vec2 b = glm::inverse(m) * (uv - a);
    return {b.x, b.y};
}

class GltfLoader : public ::testing::Test {
protected:
    void SetUp() override {
        mDir = fs::temp_directory_path() /
               fmt::format("pic_gltf_loader_{}_{}", getpid(),
                           ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(mDir);
        fs::create_directories(mDir);
    }
    void TearDown() override { fs::remove_all(mDir); }

    fs::path path(const std::string& name) const { return mDir / name; }

    /// Writes `b` as name.gltf and loads it.
    Result<Scene> writeAndLoad(const GltfBuilder& b, const std::string& name = "scene",
                               const LoadOptions& options = {}) {
        fs::path file = path(name + ".gltf");
        b.writeGltf(file);
        return loadScene(file.string(), options);
    }

    fs::path mDir;
};

TEST_F(GltfLoader, QuadUnderTransformedNodeIsInWorldSpace) {
    Result<Scene> scene = writeAndLoad(transformedQuad());
    ASSERT_TRUE(scene) << scene.error().message;
    ASSERT_EQ(scene->triangles.size(), 2u);
    ASSERT_EQ(scene->vertices.size(), 4u);
    // p = T + R_y(90°)(S p_local): (x, y, 0) → (1, 2 + 3y, 3 − 2x).
    for (const Vertex& v : scene->vertices) {
        glm::vec2 local = v.uv0;  // UVs carry the local (x, y) of each corner
        expectVecNear(v.position, {1.0f, 2.0f + 3.0f * local.y, 3.0f - 2.0f * local.x}, 1e-5f);
        // Normals go through the inverse transpose: +z → R S⁻¹ (0, 0, 1) ∝ +x.
        expectVecNear(v.normal, {1.0f, 0.0f, 0.0f}, 1e-6f);
    }
    for (uint32_t t = 0; t < 2; ++t) {
        EXPECT_NEAR(scene->triangleArea(t), 3.0f, 1e-5f);
        expectVecNear(scene->triangleNormal(t), {1.0f, 0.0f, 0.0f}, 1e-6f);
    }
    EXPECT_NEAR(scene->totalArea, 6.0, 1e-5);
    expectVecNear(scene->bounds.min, {1.0f, 2.0f, 1.0f}, 1e-5f);
    expectVecNear(scene->bounds.max, {1.0f, 5.0f, 3.0f}, 1e-5f);
    ASSERT_EQ(scene->primitives.size(), 1u);
    EXPECT_EQ(scene->primitives[0].name, "Quad/0");
    EXPECT_EQ(scene->primitives[0].triangleCount, 2u);
    ASSERT_EQ(scene->materials.size(), 1u);  // the default white material
    EXPECT_EQ(scene->materials[0].baseColorFactor, glm::vec4(1.0f));
    EXPECT_EQ(scene->droppedDegenerate, 0u);
}

TEST_F(GltfLoader, NestedNodesComposeAndInstanceMeshes) {
    GltfBuilder b;
    int mesh = addQuadMesh(b, "Quad");
    // The child's matrix (column-major) scales by 2; the parent translates by (10, 0, 0).
    int child = b.append(
        "nodes", {{"mesh", mesh}, {"matrix", {2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1}}});
    int parent =
        b.append("nodes", {{"mesh", mesh}, {"translation", {10, 0, 0}}, {"children", {child}}});
    b.scene({parent});
    Result<Scene> scene = writeAndLoad(b);
    ASSERT_TRUE(scene) << scene.error().message;
    ASSERT_EQ(scene->primitives.size(), 2u);
    EXPECT_EQ(scene->triangles.size(), 4u);
    EXPECT_NEAR(scene->totalArea, 1.0 + 4.0, 1e-5);
    expectVecNear(scene->bounds.min, {10.0f, 0.0f, 0.0f}, 1e-6f);
    expectVecNear(scene->bounds.max, {12.0f, 2.0f, 0.0f}, 1e-6f);
    // Pre-order: the parent's instance comes first.
    EXPECT_NEAR(scene->triangleArea(scene->primitives[0].firstTriangle), 0.5f, 1e-6f);
    EXPECT_NEAR(scene->triangleArea(scene->primitives[1].firstTriangle), 2.0f, 1e-6f);
}

TEST_F(GltfLoader, NormalsTransformByTheInverseTranspose) {
    // A triangle in the plane y + z = 1 with its true normal, stretched by 2 along y: the
    // stretched plane's normal is ∝ (0, 1, 2), not the stretched normal's (0, 2, 1).
    GltfBuilder b;
    float n = float(std::sqrt(0.5));
    int positions = b.floats({0, 1, 0, 0, 0, 1, 1, 1, 0}, "VEC3");
    int normals = b.floats({0, n, n, 0, n, n, 0, n, n}, "VEC3");
    int mesh = b.append(
        "meshes",
        {{"primitives",
          json::array({{{"attributes", {{"POSITION", positions}, {"NORMAL", normals}}}}})}});
    b.scene({b.append("nodes", {{"mesh", mesh}, {"scale", {1, 2, 1}}})});
    Result<Scene> scene = writeAndLoad(b);
    ASSERT_TRUE(scene) << scene.error().message;
    ASSERT_EQ(scene->triangles.size(), 1u);
    glm::vec3 expected = glm::normalize(glm::vec3(0.0f, 1.0f, 2.0f));
    expectVecNear(scene->triangleNormal(0), expected, 1e-6f);
    for (const Vertex& v : scene->vertices) expectVecNear(v.normal, expected, 1e-6f);
}

TEST_F(GltfLoader, GlbLoadsTheSameAsGltf) {
    GltfBuilder b = transformedQuad();
    Result<Scene> text = writeAndLoad(b);
    b.writeGlb(path("scene.glb"));
    Result<Scene> binary = loadScene(path("scene.glb").string());
    // The magic, not the extension, identifies a binary file.
    b.writeGlb(path("scene.data"));
    Result<Scene> sniffed = loadScene(path("scene.data").string());
    ASSERT_TRUE(text) << text.error().message;
    ASSERT_TRUE(binary) << binary.error().message;
    ASSERT_TRUE(sniffed) << sniffed.error().message;
    for (const Result<Scene>* other : {&binary, &sniffed}) {
        ASSERT_EQ((*other)->vertices.size(), text->vertices.size());
        for (size_t i = 0; i < text->vertices.size(); ++i) {
            EXPECT_EQ((*other)->vertices[i].position, text->vertices[i].position);
            EXPECT_EQ((*other)->vertices[i].normal, text->vertices[i].normal);
        }
        EXPECT_EQ((*other)->triangles.size(), text->triangles.size());
        EXPECT_EQ((*other)->hash, text->hash);
    }
    EXPECT_EQ(binary->sourcePath, path("scene.glb").string());
}

TEST_F(GltfLoader, PointsAndLinesAreUnsupported) {
    for (auto [mode, name] : {std::pair{0, "POINTS"}, {1, "LINES"}, {3, "LINE_STRIP"}}) {
        GltfBuilder b;
        int positions = b.floats({0, 0, 0, 1, 0, 0, 0, 1, 0}, "VEC3");
        int mesh = b.append(
            "meshes",
            {{"name", "Foo"},
             {"primitives",
              json::array({{{"attributes", {{"POSITION", positions}}}, {"mode", mode}}})}});
        b.scene({b.append("nodes", {{"mesh", mesh}})});
        Result<Scene> scene = writeAndLoad(b);
        ASSERT_FALSE(scene);
        EXPECT_EQ(scene.error().code, ErrorCode::Unsupported);
        EXPECT_EQ(scene.error().message,
                  fmt::format("mesh 'Foo' primitive 0 has mode {} ({}); only triangles are "
                              "supported",
                              name, mode));
    }
}

TEST_F(GltfLoader, StripsAndFansBecomeFrontFacingTriangles) {
    for (int mode : {5, 6}) {
        GltfBuilder b;
        // Strip order zig-zags across the quad; fan order walks around it from corner 0.
        std::vector<float> strip = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
        std::vector<float> fan = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
        int positions = b.floats(mode == 5 ? strip : fan, "VEC3");
        int mesh = b.append(
            "meshes",
            {{"primitives",
              json::array({{{"attributes", {{"POSITION", positions}}}, {"mode", mode}}})}});
        b.scene({b.append("nodes", {{"mesh", mesh}})});
        Result<Scene> scene = writeAndLoad(b);
        ASSERT_TRUE(scene) << scene.error().message;
        ASSERT_EQ(scene->triangles.size(), 2u) << "mode " << mode;
        EXPECT_NEAR(scene->totalArea, 1.0, 1e-6);
        for (uint32_t t = 0; t < 2; ++t)
            expectVecNear(scene->triangleNormal(t), {0.0f, 0.0f, 1.0f}, 1e-6f);
    }
}

TEST_F(GltfLoader, FileWithoutMeshesHasNoGeometry) {
    GltfBuilder b;
    b.scene({b.append("nodes", {{"name", "empty"}})});
    Result<Scene> scene = writeAndLoad(b);
    ASSERT_FALSE(scene);
    EXPECT_EQ(scene.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(scene.error().message.find("contains no triangle geometry"), std::string::npos)
        << scene.error().message;
    Result<Scene> allowed = writeAndLoad(b, "scene", LoadOptions{.requireGeometry = false});
    ASSERT_TRUE(allowed) << allowed.error().message;
    EXPECT_TRUE(allowed->triangles.empty());
}

TEST_F(GltfLoader, MissingFileIsNotFound) {
    std::string missing = path("does_not_exist.glb").string();
    Result<Scene> scene = loadScene(missing);
    ASSERT_FALSE(scene);
    EXPECT_EQ(scene.error().code, ErrorCode::NotFound);
    EXPECT_NE(scene.error().message.find(missing), std::string::npos) << scene.error().message;
}

TEST_F(GltfLoader, MalformedFilesAreCorrupt) {
    std::string text = "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [";
    writeBytes(path("broken.gltf"), text.data(), text.size());
    Result<Scene> scene = loadScene(path("broken.gltf").string());
    ASSERT_FALSE(scene);
    EXPECT_EQ(scene.error().code, ErrorCode::Corrupt);

    // A truncated .glb: the header promises more bytes than the file has.
    transformedQuad().writeGlb(path("whole.glb"));
    std::ifstream in(path("whole.glb"), std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(in)), {});
    writeBytes(path("truncated.glb"), bytes.data(), bytes.size() / 2);
    Result<Scene> truncated = loadScene(path("truncated.glb").string());
    ASSERT_FALSE(truncated);
    EXPECT_EQ(truncated.error().code, ErrorCode::Corrupt);
}

TEST_F(GltfLoader, IndicesOutOfRangeAreCorrupt) {
    GltfBuilder b;
    int positions = b.floats({0, 0, 0, 1, 0, 0, 0, 1, 0}, "VEC3");
    int indices = b.data(std::vector<uint32_t>{0, 1, 3}, kUnsignedInt, "SCALAR");
    int mesh =
        b.append("meshes", {{"name", "Bad"},
                            {"primitives", json::array({{{"attributes", {{"POSITION", positions}}},
                                                         {"indices", indices}}})}});
    b.scene({b.append("nodes", {{"mesh", mesh}})});
    Result<Scene> scene = writeAndLoad(b);
    ASSERT_FALSE(scene);
    EXPECT_EQ(scene.error().code, ErrorCode::Corrupt);
    EXPECT_NE(scene.error().message.find("mesh 'Bad'"), std::string::npos);
}

TEST_F(GltfLoader, NonFinitePositionIsInvalidInput) {
    GltfBuilder b;
    float nan = std::numeric_limits<float>::quiet_NaN();
    int positions = b.floats({0, 0, 0, 1, nan, 0, 0, 1, 0}, "VEC3");
    int mesh = b.append(
        "meshes", {{"name", "Broken"},
                   {"primitives", json::array({{{"attributes", {{"POSITION", positions}}}}})}});
    b.scene({b.append("nodes", {{"mesh", mesh}})});
    Result<Scene> scene = writeAndLoad(b);
    ASSERT_FALSE(scene);
    EXPECT_EQ(scene.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(scene.error().message.find("mesh 'Broken'"), std::string::npos)
        << scene.error().message;
}

/// Adds KHR_lights_punctual lights to the document.
void addLights(GltfBuilder& b, const json& lights) {
    b.doc["extensionsUsed"] = {"KHR_lights_punctual"};
    b.doc["extensions"]["KHR_lights_punctual"]["lights"] = lights;
}

TEST_F(GltfLoader, PunctualLightsTakeTheirNodesTransform) {
    GltfBuilder b;
    int mesh = addQuadMesh(b, "Floor");
    addLights(b, json::array({
                     {{"name", "bulb"},
                      {"type", "point"},
                      {"color", {1.0, 0.5, 0.25}},
                      {"intensity", 5.0},
                      {"range", 10.0}},
                     {{"name", "torch"},
                      {"type", "spot"},
                      {"intensity", 2.0},
                      {"spot", {{"innerConeAngle", 0.2}, {"outerConeAngle", 0.5}}}},
                     {{"type", "directional"}, {"intensity", 3.0}},
                     {{"name", "plain"}, {"type", "spot"}, {"spot", json::object()}},
                 }));
    double s = std::sqrt(0.5);
    auto lightNode = [&](int light, json node) {
        node["extensions"] = {{"KHR_lights_punctual", {{"light", light}}}};
        return b.append("nodes", node);
    };
    int point = lightNode(0, {{"translation", {1, 2, 3}}});
    // −90° about +x turns the node's −z into −y: the spot shines straight down.
    int spot = lightNode(1, {{"translation", {0, 4, 0}}, {"rotation", {-s, 0, 0, s}}});
    int sun = lightNode(2, json::object());
    int plain = lightNode(3, json::object());
    int secondBulb = lightNode(0, {{"translation", {5, 5, 5}}});
    b.scene({b.append("nodes", {{"mesh", mesh}}), point, spot, sun, plain, secondBulb});

    Result<Scene> scene = writeAndLoad(b);
    ASSERT_TRUE(scene) << scene.error().message;
    ASSERT_EQ(scene->lights.size(), 5u);
    const Light& bulb = scene->lights[0];
    EXPECT_EQ(bulb.id, "bulb");
    EXPECT_EQ(bulb.type, LightType::Point);
    expectVecNear(bulb.position, {1, 2, 3}, 1e-6f);
    expectVecNear(bulb.color, {1.0f, 0.5f, 0.25f}, 0.0f);
    EXPECT_EQ(bulb.intensity, 5.0f);
    EXPECT_EQ(bulb.range, 10.0f);

    const Light& torch = scene->lights[1];
    EXPECT_EQ(torch.id, "torch");
    EXPECT_EQ(torch.type, LightType::Spot);
    expectVecNear(torch.position, {0, 4, 0}, 1e-6f);
    expectVecNear(torch.direction, {0, -1, 0}, 1e-6f);
    EXPECT_NEAR(torch.innerConeAngle, 0.2f, 1e-7f);
    EXPECT_NEAR(torch.outerConeAngle, 0.5f, 1e-7f);
    EXPECT_TRUE(std::isinf(torch.range));

    const Light& sunLight = scene->lights[2];
    EXPECT_EQ(sunLight.id, "light_2");
    EXPECT_EQ(sunLight.type, LightType::Directional);
    expectVecNear(sunLight.direction, {0, 0, -1}, 0.0f);
    EXPECT_EQ(sunLight.intensity, 3.0f);

    const Light& defaults = scene->lights[3];
    EXPECT_EQ(defaults.innerConeAngle, 0.0f);
    EXPECT_NEAR(defaults.outerConeAngle, std::numbers::pi / 4.0, 1e-7);
    EXPECT_EQ(defaults.intensity, 1.0f);

    // A light instanced twice gets a second, distinct id.
    EXPECT_EQ(scene->lights[4].id, "bulb#2");
    expectVecNear(scene->lights[4].position, {5, 5, 5}, 1e-6f);
}

TEST_F(GltfLoader, NegativeLightIntensityIsInvalidInput) {
    GltfBuilder b;
    int mesh = addQuadMesh(b, "Floor");
    addLights(b, json::array({{{"name", "antilight"}, {"type", "point"}, {"intensity", -1.0}}}));
    int light = b.append("nodes", {{"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
    b.scene({b.append("nodes", {{"mesh", mesh}}), light});
    Result<Scene> scene = writeAndLoad(b);
    ASSERT_FALSE(scene);
    EXPECT_EQ(scene.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(scene.error().message.find("antilight"), std::string::npos) << scene.error().message;
}

TEST_F(GltfLoader, PerspectiveCamerasFollowTheirNodes) {
    GltfBuilder b;
    int mesh = addQuadMesh(b, "Floor");
    b.append("cameras", {{"name", "eye"},
                         {"type", "perspective"},
                         {"perspective", {{"yfov", 0.8}, {"znear", 0.1}}}});
    b.append("cameras", {{"type", "orthographic"},
                         {"orthographic", {{"xmag", 1}, {"ymag", 1}, {"znear", 0}, {"zfar", 9}}}});
    double s = std::sqrt(0.5);
    // +90° about +y turns the camera's −z view direction into −x.
    int viewer =
        b.append("nodes", {{"camera", 0}, {"translation", {0, 1, 5}}, {"rotation", {0, s, 0, s}}});
    int ortho = b.append("nodes", {{"camera", 1}});
    b.scene({b.append("nodes", {{"mesh", mesh}}), viewer, ortho});
    Result<Scene> scene = writeAndLoad(b);
    ASSERT_TRUE(scene) << scene.error().message;
    ASSERT_EQ(scene->cameras.size(), 1u);  // the orthographic camera is skipped
    const Camera& camera = scene->cameras[0];
    EXPECT_EQ(camera.name, "eye");
    expectVecNear(camera.eye, {0, 1, 5}, 1e-6f);
    expectVecNear(camera.target, {-1, 1, 5}, 1e-6f);
    expectVecNear(camera.up, {0, 1, 0}, 1e-6f);
    EXPECT_NEAR(camera.fovyDegrees, 0.8 * 180.0 / std::numbers::pi, 1e-4);
}

TEST_F(GltfLoader, EmissiveStrengthMultipliesEmissiveFactor) {
    GltfBuilder b;
    b.doc["extensionsUsed"] = {"KHR_materials_emissive_strength"};
    b.append("materials",
             {{"name", "glow"},
              {"emissiveFactor", {1.0, 0.5, 0.25}},
              {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 4.0}}}}}});
    b.append("materials", {{"name", "dim"}, {"emissiveFactor", {1.0, 0.5, 0.25}}});
    int glowing = addQuadMesh(b, "Glowing", 0);
    int dim = addQuadMesh(b, "Dim", 1);
    b.scene({b.append("nodes", {{"mesh", glowing}}), b.append("nodes", {{"mesh", dim}})});
    Result<Scene> scene = writeAndLoad(b);
    ASSERT_TRUE(scene) << scene.error().message;
    ASSERT_EQ(scene->materials.size(), 2u);
    EXPECT_EQ(scene->materials[0].name, "glow");
    expectVecNear(scene->materials[0].emission, {4.0f, 2.0f, 1.0f}, 0.0f);
    expectVecNear(scene->materials[1].emission, {1.0f, 0.5f, 0.25f}, 0.0f);
    uint32_t t = scene->primitives[0].firstTriangle;
    expectVecNear(scene->emissionAt(t, 0.3f, 0.3f), {4.0f, 2.0f, 1.0f}, 0.0f);
}

/// PNG bytes of an 8-bit RGBA image, written by stb_image_write.
std::vector<unsigned char> png8(int width, int height, const std::vector<uint8_t>& rgba) {
    std::vector<unsigned char> out;
    auto append = [](void* context, void* data, int size) {
        auto* bytes = static_cast<unsigned char*>(data);
        static_cast<std::vector<unsigned char>*>(context)->insert(
            static_cast<std::vector<unsigned char>*>(context)->end(), bytes, bytes + size);
    };
    stbi_write_png_to_func(append, &out, width, height, 4, rgba.data(), 4 * width);
    return out;
}

/// PNG bytes of a 16-bit RGBA image: stb_image_write writes 8 bits only, so this one stores
/// the rows in an uncompressed deflate block (RFC 1950/1951) inside IDAT.
std::vector<unsigned char> png16(int width, int height, const std::vector<uint16_t>& rgba) {
    auto crc32 = [](const unsigned char* p, size_t n) {
        uint32_t crc = 0xFFFFFFFFu;
        for (size_t i = 0; i < n; ++i) {
            crc ^= p[i];
            for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
        }
        return ~crc;
    };
    auto be32 = [](std::vector<unsigned char>& out, uint32_t v) {
        for (int i = 3; i >= 0; --i) out.push_back(uint8_t(v >> (8 * i)));
    };
    std::vector<unsigned char> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    auto chunk = [&](const char* type, const std::vector<unsigned char>& data) {
        be32(png, uint32_t(data.size()));
        std::vector<unsigned char> body(type, type + 4);
        body.insert(body.end(), data.begin(), data.end());
        png.insert(png.end(), body.begin(), body.end());
        be32(png, crc32(body.data(), body.size()));
    };
    std::vector<unsigned char> header;
    be32(header, uint32_t(width));
    be32(header, uint32_t(height));
    header.insert(header.end(), {16, 6, 0, 0, 0});  // 16 bits, RGBA, deflate, no filter/interlace
    chunk("IHDR", header);

    std::vector<unsigned char> raw;
    for (int y = 0; y < height; ++y) {
        raw.push_back(0);  // filter type None
        for (int i = 0; i < 4 * width; ++i) {
            uint16_t v = rgba[size_t(y * 4 * width + i)];
            raw.push_back(uint8_t(v >> 8));  // PNG samples are big-endian
            raw.push_back(uint8_t(v & 0xFF));
        }
    }
    std::vector<unsigned char> zlib = {0x78, 0x01, 0x01};  // zlib header; final stored block
    uint16_t length = uint16_t(raw.size());
    zlib.insert(zlib.end(), {uint8_t(length), uint8_t(length >> 8), uint8_t(~length),
                             uint8_t(uint16_t(~length) >> 8)});
    zlib.insert(zlib.end(), raw.begin(), raw.end());
    uint32_t a = 1, b = 0;
    for (unsigned char c : raw) {
        a = (a + c) % 65521;
        b = (b + a) % 65521;
    }
    be32(zlib, (b << 16) | a);
    chunk("IDAT", zlib);
    chunk("IEND", {});
    return png;
}

TEST_F(GltfLoader, TextureIsLinearisedFromSrgbAndSampledBilinearly) {
    // Row 0: A, B; row 1: C, D (8-bit sRGB codes).
    std::vector<uint8_t> codes = {0,  64, 128, 255, 255, 191, 32, 255,
                                  10, 20, 30,  255, 200, 100, 50, 128};
    std::vector<unsigned char> png = png8(2, 2, codes);
    writeBytes(path("albedo.png"), png.data(), png.size());

    GltfBuilder b;
    b.append("images", {{"uri", "albedo.png"}});
    b.append("samplers", {{"wrapS", 33071}, {"wrapT", 33071}});
    b.append("textures", {{"source", 0}, {"sampler", 0}});
    b.append("materials",
             {{"name", "painted"},
              {"pbrMetallicRoughness",
               {{"baseColorFactor", {1.0, 0.5, 1.0, 1.0}}, {"baseColorTexture", {{"index", 0}}}}},
              {"emissiveFactor", {1.0, 1.0, 1.0}},
              {"emissiveTexture", {{"index", 0}}}});
    int mesh = addQuadMesh(b, "Canvas", 0);
    b.scene({b.append("nodes", {{"mesh", mesh}})});
    Result<Scene> scene = writeAndLoad(b);
    ASSERT_TRUE(scene) << scene.error().message;
    ASSERT_EQ(scene->textures.size(), 1u);
    const Texture& texture = scene->textures[0];
    ASSERT_EQ(texture.width, 2);
    ASSERT_EQ(texture.height, 2);
    EXPECT_FALSE(texture.repeatS);
    EXPECT_FALSE(texture.repeatT);
    std::vector<glm::vec3> linear;
    for (size_t i = 0; i < 4; ++i) {
        glm::vec3 expected(srgbToLinear(codes[4 * i] / 255.0),
                           srgbToLinear(codes[4 * i + 1] / 255.0),
                           srgbToLinear(codes[4 * i + 2] / 255.0));
        expectVecNear(glm::vec3(texture.texels[i]), expected, 1e-6f);
        EXPECT_NEAR(texture.texels[i].a, codes[4 * i + 3] / 255.0, 1e-6);  // alpha stays linear
        linear.push_back(expected);
    }

    const glm::vec3 factor(1.0f, 0.5f, 1.0f);
    struct Probe {
        glm::vec2 uv;
        glm::vec3 texel;
    };
    // Between texel centres (0.25 and 0.75) the linear values are interpolated.
    const Probe probes[] = {
        {{0.25f, 0.25f}, linear[0]},
        {{0.5f, 0.25f}, 0.5f * (linear[0] + linear[1])},
        {{0.5f, 0.5f}, 0.25f * (linear[0] + linear[1] + linear[2] + linear[3])},
        {{0.375f, 0.625f},
         0.75f * 0.25f * linear[0] + 0.25f * 0.25f * linear[1] + 0.75f * 0.75f * linear[2] +
             0.25f * 0.75f * linear[3]},
        {{0.95f, 0.1f}, linear[1]},  // clamped beyond the last centre
    };
    for (const Probe& probe : probes) {
        uint32_t t = 0;
        auto [b1, b2] = barycentricsOfUv(*scene, t, probe.uv);
        if (b1 < 0.0f || b2 < 0.0f || b1 + b2 > 1.0f) {
            t = 1;
            std::tie(b1, b2) = barycentricsOfUv(*scene, t, probe.uv);
        }
        expectVecNear(scene->albedoAt(t, b1, b2), factor * probe.texel, 1e-5f);
        expectVecNear(scene->emissionAt(t, b1, b2), probe.texel, 1e-5f);
    }

    // The loader builds the mip chain from the linear values: its 1×1 top is their mean, not
    // the mean of the sRGB codes.
    ASSERT_EQ(texture.levelCount(), 2);
    ASSERT_EQ(texture.mips[0].texels.size(), 1u);
    expectVecNear(glm::vec3(texture.mips[0].texels[0]),
                  0.25f * (linear[0] + linear[1] + linear[2] + linear[3]), 1e-6f);
}

TEST_F(GltfLoader, SixteenBitTexturesKeepTheirPrecision) {
    std::vector<uint16_t> codes = {1000, 30000, 65535, 65535};
    std::vector<unsigned char> png = png16(1, 1, codes);
    GltfBuilder b;
    int view = b.view(png.data(), png.size());
    b.append("images", {{"bufferView", view}, {"mimeType", "image/png"}, {"name", "deep"}});
    b.append("textures", {{"source", 0}});
    b.append("materials", {{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}});
    int mesh = addQuadMesh(b, "Canvas", 0);
    b.scene({b.append("nodes", {{"mesh", mesh}})});
    b.writeGlb(path("deep.glb"));
    Result<Scene> scene = loadScene(path("deep.glb").string());
    ASSERT_TRUE(scene) << scene.error().message;
    ASSERT_EQ(scene->textures.size(), 1u);
    EXPECT_EQ(scene->materials[0].name, "material_0");
    glm::vec4 texel = scene->textures[0].texels.at(0);
    // 1000/65535 has no 8-bit code: an 8-bit decode would be off by far more than 1e-6.
    EXPECT_NEAR(texel.r, srgbToLinear(1000 / 65535.0), 1e-6);
    EXPECT_NEAR(texel.g, srgbToLinear(30000 / 65535.0), 1e-6);
    EXPECT_NEAR(texel.b, 1.0, 1e-6);
    EXPECT_TRUE(scene->textures[0].repeatS);
}

TEST_F(GltfLoader, UnreadableImagesAreReported) {
    GltfBuilder b;
    b.append("images", {{"uri", "missing.png"}});
    b.append("images", {{"uri", "garbage.png"}, {"name", "noise"}});
    b.append("textures", {{"source", 0}});
    b.append("textures", {{"source", 1}});
    b.append("materials", {{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}});
    b.append("materials", {{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 1}}}}}});
    std::string garbage = "definitely not a PNG";
    writeBytes(path("garbage.png"), garbage.data(), garbage.size());

    for (int material : {0, 1}) {
        GltfBuilder one = b;
        int mesh = addQuadMesh(one, "Canvas", material);
        one.scene({one.append("nodes", {{"mesh", mesh}})});
        Result<Scene> scene = writeAndLoad(one);
        ASSERT_FALSE(scene);
        if (material == 0) {
            EXPECT_EQ(scene.error().code, ErrorCode::NotFound);
            EXPECT_NE(scene.error().message.find("missing.png"), std::string::npos)
                << scene.error().message;
        } else {
            EXPECT_EQ(scene.error().code, ErrorCode::Corrupt);
            EXPECT_NE(scene.error().message.find("noise"), std::string::npos)
                << scene.error().message;
        }
    }
}

// Before: a buffer or image URI of ../../../../etc/passwd was opened as given.
TEST_F(GltfLoader, UrisOutsideTheScenesFolderAreRefusedBeforeTheyAreOpened) {
    std::string outside = "outside the scene's folder";
    writeBytes(path("outside.png"), outside.data(), outside.size());
    fs::create_directories(path("scene"));
    for (const std::string uri : {"../outside.png", "textures/../../outside.png", "%2E%2E/outside.png",
                                  "/etc/passwd", "../../../../../../etc/passwd", "file:///etc/passwd"}) {
        SCOPED_TRACE(uri);
        GltfBuilder b;
        b.append("images", {{"uri", uri}});
        b.append("textures", {{"source", 0}});
        b.append("materials", {{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}});
        int mesh = addQuadMesh(b, "Canvas", 0);
        b.scene({b.append("nodes", {{"mesh", mesh}})});
        for (const std::string kind : {"gltf", "glb"}) {
            const fs::path file = path("scene") / ("scene." + kind);
            kind == "gltf" ? b.writeGltf(file) : b.writeGlb(file);
            Result<Scene> scene = loadScene(file.string());
            ASSERT_FALSE(scene) << kind;
            EXPECT_EQ(scene.error().code, ErrorCode::InvalidInput) << scene.error().message;
            EXPECT_NE(scene.error().message.find("leaves the scene's folder"), std::string::npos)
                << scene.error().message;
            EXPECT_FALSE(sceneFiles(file.string())) << kind;
        }
    }
}

TEST_F(GltfLoader, InterleavedNormalizedAttributes) {
    // One vertex: position float×3, TEXCOORD_0 unorm16×2, COLOR_0 unorm8×4 (20 bytes).
    struct Packed {
        float position[3];
        uint16_t uv[2];
        uint8_t color[4];
    };
    static_assert(sizeof(Packed) == 20);
    std::vector<Packed> vertices = {{{0, 0, 0}, {0, 65535}, {255, 128, 0, 255}},
                                    {{1, 0, 0}, {32768, 0}, {0, 255, 51, 255}},
                                    {{0, 1, 0}, {65535, 13107}, {102, 0, 255, 128}}};
    GltfBuilder b;
    int view = b.view(vertices.data(), vertices.size() * sizeof(Packed), sizeof(Packed));
    int positions = b.accessor(view, kFloat, 3, "VEC3", 0);
    int uvs = b.accessor(view, kUnsignedShort, 3, "VEC2", 12, true);
    int colors = b.accessor(view, kUnsignedByte, 3, "VEC4", 16, true);
    int indices = b.data(std::vector<uint8_t>{0, 1, 2}, kUnsignedByte, "SCALAR");
    b.append("materials", {{"pbrMetallicRoughness", {{"baseColorFactor", {0.5, 1.0, 1.0, 1.0}}}}});
    int mesh = b.append(
        "meshes",
        {{"primitives",
          json::array(
              {{{"attributes", {{"POSITION", positions}, {"TEXCOORD_0", uvs}, {"COLOR_0", colors}}},
                {"indices", indices},
                {"material", 0}}})}});
    b.scene({b.append("nodes", {{"mesh", mesh}})});
    Result<Scene> scene = writeAndLoad(b);
    ASSERT_TRUE(scene) << scene.error().message;
    ASSERT_EQ(scene->vertices.size(), 3u);
    for (size_t i = 0; i < 3; ++i) {
        const Vertex& v = scene->vertices[i];
        const Packed& p = vertices[i];
        expectVecNear(v.position, {p.position[0], p.position[1], p.position[2]}, 0.0f);
        EXPECT_NEAR(v.uv0.x, p.uv[0] / 65535.0, 1e-7);
        EXPECT_NEAR(v.uv0.y, p.uv[1] / 65535.0, 1e-7);
        for (int c = 0; c < 4; ++c) EXPECT_NEAR(v.color[c], p.color[c] / 255.0, 1e-7);
        // No NORMAL: the flat face normal.
        expectVecNear(v.normal, {0, 0, 1}, 0.0f);
    }
    // Albedo at a corner is baseColorFactor × COLOR_0 there.
    expectVecNear(scene->albedoAt(0, 1.0f, 0.0f), {0.0f, 1.0f, 0.2f}, 1e-6f);
}

TEST_F(GltfLoader, MirroringNodeKeepsNormalsOutward) {
    // A tetrahedron without NORMAL (flat normals) and a quad with NORMAL, both mirrored in x.
    GltfBuilder b;
    glm::vec3 p[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    int faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};  // counter-clockwise outside
    std::vector<float> corners;
    for (auto& face : faces)
        for (int k : face) corners.insert(corners.end(), {p[k].x, p[k].y, p[k].z});
    int tetra = b.append(
        "meshes", {{"name", "Tetra"},
                   {"primitives",
                    json::array({{{"attributes", {{"POSITION", b.floats(corners, "VEC3")}}}}})}});
    int quad = addQuadMesh(b, "Quad");
    b.scene({b.append("nodes", {{"mesh", tetra}, {"scale", {-1, 1, 1}}}),
             b.append("nodes", {{"mesh", quad}, {"scale", {1, 1, -2}}})});
    Result<Scene> scene = writeAndLoad(b);
    ASSERT_TRUE(scene) << scene.error().message;
    ASSERT_EQ(scene->primitives.size(), 2u);

    const Primitive& tetraPrim = scene->primitives[0];
    ASSERT_EQ(tetraPrim.triangleCount, 4u);
    glm::vec3 centroid(-0.25f, 0.25f, 0.25f);
    for (uint32_t t = tetraPrim.firstTriangle; t < tetraPrim.firstTriangle + 4; ++t) {
        const Triangle& tri = scene->triangles[t];
        glm::vec3 faceCentre =
            (scene->vertices[tri.v[0]].position + scene->vertices[tri.v[1]].position +
             scene->vertices[tri.v[2]].position) /
            3.0f;
        glm::vec3 n = scene->triangleNormal(t);
        EXPECT_GT(glm::dot(n, faceCentre - centroid), 0.0f) << "face " << t;
        for (uint32_t v : tri.v) expectVecNear(scene->vertices[v].normal, n, 1e-6f);
    }

    // The quad's +z side maps to −z: vertex normals and winding agree on it.
    const Primitive& quadPrim = scene->primitives[1];
    for (uint32_t t = quadPrim.firstTriangle; t < quadPrim.firstTriangle + 2; ++t) {
        expectVecNear(scene->triangleNormal(t), {0, 0, -1}, 1e-6f);
        for (uint32_t v : scene->triangles[t].v)
            expectVecNear(scene->vertices[v].normal, {0, 0, -1}, 1e-6f);
    }
    EXPECT_NEAR(scene->totalArea, 1.5 + std::sqrt(3.0) / 2.0 + 1.0, 1e-5);
}

TEST_F(GltfLoader, TrianglesWoundAgainstTheirNormalsAreTurned) {
    // The same quad three times: wound counter-clockwise about its +z normals, wound clockwise
    // about them (one triangle), and without normals wound clockwise (flat normals follow the
    // winding, so nothing disagrees).
    GltfBuilder b;
    int positions = b.floats({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}, "VEC3");
    int normals = b.floats({0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1}, "VEC3");
    auto quad = [&](std::vector<uint16_t> indices, bool withNormals) {
        json attributes = {{"POSITION", positions}};
        if (withNormals) attributes["NORMAL"] = normals;
        return b.append(
            "meshes",
            {{"primitives",
              json::array({{{"attributes", attributes},
                            {"indices", b.data(indices, kUnsignedShort, "SCALAR")}}})}});
    };
    int agreeing = quad({0, 1, 2, 0, 2, 3}, true);
    int halfTurned = quad({0, 2, 1, 0, 2, 3}, true);
    int flat = quad({0, 2, 1, 0, 3, 2}, false);
    b.scene({b.append("nodes", {{"mesh", agreeing}}), b.append("nodes", {{"mesh", halfTurned}}),
             b.append("nodes", {{"mesh", flat}})});
    Result<Scene> scene = writeAndLoad(b);
    ASSERT_TRUE(scene) << scene.error().message;
    ASSERT_EQ(scene->triangles.size(), 6u);
    EXPECT_EQ(scene->rewound, 1u);
    for (uint32_t t = 0; t < 4; ++t) {
        expectVecNear(scene->triangleNormal(t), {0, 0, 1}, 1e-6f);
        for (uint32_t v : scene->triangles[t].v)
            expectVecNear(scene->vertices[v].normal, {0, 0, 1}, 1e-6f);
    }
    for (uint32_t t = 4; t < 6; ++t) expectVecNear(scene->triangleNormal(t), {0, 0, -1}, 1e-6f);
    EXPECT_NEAR(scene->totalArea, 3.0, 1e-6);
}

TEST_F(GltfLoader, DegenerateTrianglesAreDroppedAndCounted) {
    GltfBuilder b;
    int positions = b.floats({0, 0, 0, 1, 0, 0, 0, 1, 0, 2, 0, 0}, "VEC3");
    // A good triangle, one with a repeated index and one along a line.
    int indices =
        b.data(std::vector<uint16_t>{0, 1, 2, 0, 1, 1, 0, 1, 3}, kUnsignedShort, "SCALAR");
    int mesh =
        b.append("meshes", {{"primitives", json::array({{{"attributes", {{"POSITION", positions}}},
                                                         {"indices", indices}}})}});
    b.scene({b.append("nodes", {{"mesh", mesh}})});
    Result<Scene> scene = writeAndLoad(b);
    ASSERT_TRUE(scene) << scene.error().message;
    EXPECT_EQ(scene->droppedDegenerate, 2u);
    ASSERT_EQ(scene->triangles.size(), 1u);
    EXPECT_EQ(scene->vertices.size(), 3u);  // vertex 3 is used by no kept triangle
    EXPECT_NEAR(scene->totalArea, 0.5, 1e-7);
    expectVecNear(scene->bounds.max, {1, 1, 0}, 0.0f);
}

TEST_F(GltfLoader, SceneHashIsStableAndSeesChanges) {
    auto build = [](float corner, double red) {
        GltfBuilder b;
        b.append("materials", {{"pbrMetallicRoughness", {{"baseColorFactor", {red, 1, 1, 1}}}}});
        int positions = b.floats({0, 0, 0, corner, 0, 0, 0, 1, 0}, "VEC3");
        int mesh = b.append(
            "meshes",
            {{"primitives",
              json::array({{{"attributes", {{"POSITION", positions}}}, {"material", 0}}})}});
        b.scene({b.append("nodes", {{"mesh", mesh}})});
        return b;
    };
    Result<Scene> first = writeAndLoad(build(1.0f, 0.5), "a");
    Result<Scene> again = loadScene(path("a.gltf").string());
    Result<Scene> moved = writeAndLoad(build(1.001f, 0.5), "b");
    Result<Scene> recoloured = writeAndLoad(build(1.0f, 0.6), "c");
    for (const Result<Scene>* s : {&first, &again, &moved, &recoloured})
        ASSERT_TRUE(*s) << s->error().message;
    EXPECT_EQ(first->hash, again->hash);
    EXPECT_NE(first->hash, moved->hash);
    EXPECT_NE(first->hash, recoloured->hash);
    EXPECT_NE(moved->hash, recoloured->hash);
}

}  // namespace
}  // namespace pic
