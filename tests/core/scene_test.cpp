#include "core/scene.h"

#include <cmath>

#include <gtest/gtest.h>

namespace pic {
namespace {

void expectVecNear(const glm::vec4& a, const glm::vec4& b, float tolerance) {
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(a[c], b[c], tolerance) << "component " << c;
}

void expectVecNear(const glm::vec3& a, const glm::vec3& b, float tolerance) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], tolerance) << "component " << c;
}

/// A 3 × 2 texture whose texel (x, y) holds (x, y, 10x + y, 1).
Texture gradientTexture(bool repeatS, bool repeatT) {
    Texture t;
    t.width = 3;
    t.height = 2;
    t.repeatS = repeatS;
    t.repeatT = repeatT;
    for (int y = 0; y < t.height; ++y)
        for (int x = 0; x < t.width; ++x)
            t.texels.push_back({float(x), float(y), float(10 * x + y), 1.0f});
    return t;
}

glm::vec4 texel(const Texture& t, int x, int y) {
    return t.texels[size_t(y * t.width + x)];
}

TEST(TextureSample, TexelCentresReturnTexelsExactly) {
    Texture t = gradientTexture(true, true);
    for (int y = 0; y < t.height; ++y)
        for (int x = 0; x < t.width; ++x) {
            glm::vec2 uv((x + 0.5f) / float(t.width), (y + 0.5f) / float(t.height));
            expectVecNear(t.sample(uv), texel(t, x, y), 1e-6f);
        }
}

TEST(TextureSample, BilinearWeightsBetweenCentres) {
    Texture t = gradientTexture(false, false);
    // A quarter of the way from the centre of texel (0, 0) to the centres of (1, 0) and (0, 1).
    glm::vec2 uv((0.5f + 0.25f) / 3.0f, (0.5f + 0.75f) / 2.0f);
    glm::vec4 expected = 0.75f * 0.25f * texel(t, 0, 0) + 0.25f * 0.25f * texel(t, 1, 0) +
                         0.75f * 0.75f * texel(t, 0, 1) + 0.25f * 0.75f * texel(t, 1, 1);
    expectVecNear(t.sample(uv), expected, 1e-5f);
}

TEST(TextureSample, RepeatWrapsAcrossTheEdge) {
    Texture t = gradientTexture(true, true);
    // u = 0 lies halfway between the last texel of the row and the first.
    glm::vec4 edge = t.sample({0.0f, 0.25f});
    expectVecNear(edge, 0.5f * (texel(t, 2, 0) + texel(t, 0, 0)), 1e-5f);
    // Whole tiles and negative coordinates read the same place.
    glm::vec2 uv(0.3f, 0.6f);
    expectVecNear(t.sample(uv + glm::vec2(2.0f, -3.0f)), t.sample(uv), 1e-4f);
    expectVecNear(t.sample(uv - glm::vec2(1.0f, 1.0f)), t.sample(uv), 1e-4f);
}

TEST(TextureSample, ClampHoldsEdgeTexels) {
    Texture t = gradientTexture(false, false);
    expectVecNear(t.sample({0.0f, 0.25f}), texel(t, 0, 0), 1e-6f);
    expectVecNear(t.sample({-5.0f, -5.0f}), texel(t, 0, 0), 1e-6f);
    expectVecNear(t.sample({7.0f, 9.0f}), texel(t, 2, 1), 1e-6f);
    // Wrap modes are independent per axis: clamp along u, repeat along v.
    Texture mixed = gradientTexture(false, true);
    expectVecNear(mixed.sample({1.5f, 0.0f}), 0.5f * (texel(t, 2, 0) + texel(t, 2, 1)), 1e-5f);
}

TEST(TextureSample, NonFiniteUvGivesFiniteTexel) {
    Texture t = gradientTexture(true, false);
    float nan = std::numeric_limits<float>::quiet_NaN();
    float inf = std::numeric_limits<float>::infinity();
    for (glm::vec2 uv : {glm::vec2(nan, 0.5f), glm::vec2(inf, -inf), glm::vec2(1e30f, -1e30f)}) {
        glm::vec4 v = t.sample(uv);
        for (int c = 0; c < 4; ++c) EXPECT_TRUE(std::isfinite(v[c]));
    }
}

/// One triangle with legs 3 and 4 in a tilted plane, spanned by orthonormal e1, e2.
Scene rightTriangleScene() {
    glm::vec3 e1 = glm::normalize(glm::vec3(1.0f, 1.0f, 0.0f));
    glm::vec3 e2 = glm::normalize(glm::vec3(-1.0f, 1.0f, 1.0f));
    e2 = glm::normalize(e2 - glm::dot(e2, e1) * e1);
    glm::vec3 origin(0.5f, -2.0f, 3.0f);
    Scene scene;
    scene.vertices.resize(3);
    scene.vertices[0].position = origin;
    scene.vertices[1].position = origin + 3.0f * e1;
    scene.vertices[2].position = origin + 4.0f * e2;
    scene.triangles.push_back(Triangle{{0, 1, 2}, 0, 0});
    scene.materials.push_back(Material{});
    return scene;
}

TEST(SceneGeometry, AreaAndNormalOfATiltedRightTriangle) {
    Scene scene = rightTriangleScene();
    EXPECT_NEAR(scene.triangleArea(0), 6.0f, 1e-5f);
    glm::vec3 e1 = glm::normalize(scene.vertices[1].position - scene.vertices[0].position);
    glm::vec3 e2 = glm::normalize(scene.vertices[2].position - scene.vertices[0].position);
    glm::vec3 n = scene.triangleNormal(0);
    expectVecNear(n, glm::cross(e1, e2), 1e-6f);
    EXPECT_NEAR(glm::length(n), 1.0f, 1e-6f);
    // Clockwise order flips the normal.
    std::swap(scene.triangles[0].v[1], scene.triangles[0].v[2]);
    expectVecNear(scene.triangleNormal(0), -n, 1e-6f);
    EXPECT_NEAR(scene.triangleArea(0), 6.0f, 1e-5f);
}

TEST(SceneShading, AlbedoIsFactorTimesTextureTimesVertexColour) {
    Scene scene = rightTriangleScene();
    scene.textures.push_back(gradientTexture(true, true));
    for (glm::vec4& texel : scene.textures[0].texels)
        texel = glm::vec4(glm::vec3(texel) / 25.0f, 1.0f);
    scene.materials[0].baseColorFactor = {0.5f, 0.8f, 1.0f, 1.0f};
    scene.materials[0].baseColorTexture = 0;
    const glm::vec2 uvs[3] = {{0.1f, 0.2f}, {0.9f, 0.3f}, {0.4f, 0.7f}};
    const glm::vec4 colors[3] = {
        {1.0f, 0.5f, 0.2f, 1.0f}, {0.3f, 1.0f, 0.6f, 1.0f}, {0.7f, 0.9f, 1.0f, 1.0f}};
    for (int i = 0; i < 3; ++i) {
        scene.vertices[size_t(i)].uv0 = uvs[i];
        scene.vertices[size_t(i)].color = colors[i];
    }
    for (auto [b1, b2] : {std::pair{0.0f, 0.0f}, {1.0f, 0.0f}, {0.2f, 0.3f}, {0.6f, 0.25f}}) {
        float b0 = 1.0f - b1 - b2;
        glm::vec2 uv = b0 * uvs[0] + b1 * uvs[1] + b2 * uvs[2];
        glm::vec3 color = glm::vec3(b0 * colors[0] + b1 * colors[1] + b2 * colors[2]);
        glm::vec3 expected = glm::vec3(scene.materials[0].baseColorFactor) * color *
                             glm::vec3(scene.textures[0].sample(uv));
        expectVecNear(scene.albedoAt(0, b1, b2), expected, 1e-6f);
    }
}

TEST(SceneShading, AlbedoReadsTheMaterialsUvSet) {
    Scene scene = rightTriangleScene();
    scene.textures.push_back(gradientTexture(false, false));
    scene.materials[0].baseColorTexture = 0;
    scene.materials[0].baseColorTexCoord = 1;
    for (Vertex& v : scene.vertices) {
        v.uv0 = {0.1f, 0.1f};
        v.uv1 = {0.9f, 0.9f};
    }
    expectVecNear(scene.albedoAt(0, 0.3f, 0.3f), glm::vec3(texel(scene.textures[0], 2, 1)), 1e-6f);
    scene.materials[0].baseColorTexCoord = 0;
    expectVecNear(scene.albedoAt(0, 0.3f, 0.3f), glm::vec3(texel(scene.textures[0], 0, 0)), 1e-6f);
}

TEST(SceneShading, EmissionIsScaledByTheEmissiveTexture) {
    Scene scene = rightTriangleScene();
    scene.materials[0].emission = {2.0f, 4.0f, 8.0f};
    expectVecNear(scene.emissionAt(0, 0.2f, 0.2f), glm::vec3(2.0f, 4.0f, 8.0f), 0.0f);
    scene.textures.push_back(gradientTexture(false, false));
    scene.materials[0].emissiveTexture = 0;
    for (Vertex& v : scene.vertices) v.uv0 = {0.5f, 0.75f};  // centre of texel (1, 1)
    expectVecNear(scene.emissionAt(0, 0.2f, 0.2f),
                  glm::vec3(2.0f, 4.0f, 8.0f) * glm::vec3(1, 1, 11), 1e-5f);
}

}  // namespace
}  // namespace pic
