// Dynamic objects placed into a scene (core/scene_objects.h): the transform flag's parsing and
// errors, and the placed copy's geometry, materials, indices and hash.

#include "core/scene_objects.h"

#include <cmath>
#include <string>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "core/gltf_loader.h"

namespace pic {
namespace {

std::string scenePath(const std::string& name) {
    return std::string(PIC_TEST_SCENE_DIR) + "/" + name + ".gltf";
}

std::string refusal(const std::string& transform) {
    auto parsed = parseObjectPlacement("box.glb", transform);
    if (parsed) return "";
    EXPECT_EQ(parsed.error().code, ErrorCode::InvalidInput);
    return parsed.error().message;
}

TEST(ObjectPlacement, ParsesSevenNumbers) {
    auto parsed = parseObjectPlacement("box.glb", "1, 2,3,0,90,-45, 0.5");
    ASSERT_TRUE(parsed) << parsed.error().message;
    EXPECT_EQ(parsed->path, "box.glb");
    EXPECT_EQ(parsed->translation, glm::vec3(1, 2, 3));
    EXPECT_EQ(parsed->rotationDegrees, glm::vec3(0, 90, -45));
    EXPECT_EQ(parsed->scale, 0.5f);
    EXPECT_NE(refusal("1,2,3,0,0,0").find("got 6"), std::string::npos);
    EXPECT_NE(refusal("1,2,3,0,0,0,1,1").find("got more"), std::string::npos);
    EXPECT_NE(refusal("1,2,x,0,0,0,1").find("field 3 is \"x\""), std::string::npos);
    EXPECT_NE(refusal("1,2,3,0,0,inf,1").find("field 6"), std::string::npos);
    EXPECT_NE(refusal("1,2,3,0,0,0,0").find("scale s must be > 0, got 0"), std::string::npos);
    auto unpaired = parseObjectFlags({"a.glb", "b.glb"}, {"0,0,0,0,0,0,1"});
    ASSERT_FALSE(unpaired);
    EXPECT_NE(unpaired.error().message.find("2 objects, 1 transforms"), std::string::npos);
}

TEST(PlaceObjects, AppendsTheTransformedObjectAfterTheScene) {
    auto base = loadScene(scenePath("cornell"));
    ASSERT_TRUE(base) << base.error().message;
    auto box = loadScene(scenePath("object_box"));
    ASSERT_TRUE(box) << box.error().message;
    // Nothing placed: the same scene, hash included (finishScene is the loader's last step).
    auto same = placeObjects(*base, {});
    ASSERT_TRUE(same);
    EXPECT_EQ(same->hash, base->hash);

    ObjectPlacement placement;
    placement.path = scenePath("object_box");
    placement.translation = {0.1f, 0.4f, -0.2f};
    placement.rotationDegrees = {0.0f, 90.0f, 0.0f};
    placement.scale = 0.2f;
    auto placed = placeObjects(*base, {placement});
    ASSERT_TRUE(placed) << placed.error().message;
    ASSERT_EQ(placed->triangles.size(), base->triangles.size() + box->triangles.size());
    ASSERT_EQ(placed->materials.size(), base->materials.size() + box->materials.size());
    EXPECT_EQ(placed->materials.back().name, "object_box/box");
    EXPECT_NE(placed->hash, base->hash);
    // The scene's own triangles are untouched; the object's follow, re-indexed.
    for (size_t t = 0; t < base->triangles.size(); ++t)
        ASSERT_EQ(placed->triangles[t].material, base->triangles[t].material);
    for (size_t t = base->triangles.size(); t < placed->triangles.size(); ++t) {
        const Triangle& tri = placed->triangles[t];
        EXPECT_GE(tri.material, base->materials.size());
        for (uint32_t v : tri.v) EXPECT_GE(v, base->vertices.size());
    }
    // The unit cube about the origin becomes a 0.2 m cube about the translation; turning it
    // 90° about y takes its +x face's normal to −z.
    Aabb objectBounds;
    for (size_t v = base->vertices.size(); v < placed->vertices.size(); ++v) {
        objectBounds.extend(placed->vertices[v].position);
        const glm::vec3 model = box->vertices[v - base->vertices.size()].normal;
        const glm::vec3 turned = placed->vertices[v].normal;
        if (model.x > 0.99f) {
            EXPECT_NEAR(turned.z, -1.0f, 1e-5f) << v;
        }
    }
    for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(objectBounds.min[a], placement.translation[a] - 0.1f, 1e-5f) << a;
        EXPECT_NEAR(objectBounds.max[a], placement.translation[a] + 0.1f, 1e-5f) << a;
    }
    EXPECT_NEAR(placed->totalArea, base->totalArea + 6.0 * 0.04, 1e-4);

    placement.path = "/nonexistent/object.glb";
    auto missing = placeObjects(*base, {placement});
    ASSERT_FALSE(missing);
    EXPECT_NE(missing.error().message.find("--object /nonexistent/object.glb"), std::string::npos);
}

}  // namespace
}  // namespace pic
