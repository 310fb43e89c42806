#include "core/camera.h"

#include <cmath>
#include <string>

#include <gtest/gtest.h>

namespace pic {
namespace {

void expectVecNear(const glm::vec3& a, const glm::vec3& b, float tolerance) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], tolerance) << "component " << c;
}

void expectInvalid(const std::string& text, const std::string& expectedPart) {
    auto camera = parseCamera(text);
    ASSERT_FALSE(camera) << "parsed: " << text;
    EXPECT_EQ(camera.error().code, ErrorCode::InvalidInput);
    EXPECT_NE(camera.error().message.find(expectedPart), std::string::npos)
        << "message \"" << camera.error().message << "\" lacks \"" << expectedPart << "\"";
    // Every message quotes the text it refused.
    EXPECT_NE(camera.error().message.find(text), std::string::npos) << camera.error().message;
}

TEST(CameraParse, ReadsTenNumbers) {
    auto camera = parseCamera("0,0.5,2.5, 0,0.5,0, 0,1,0, 45");
    ASSERT_TRUE(camera) << camera.error().message;
    expectVecNear(camera->eye, {0.0f, 0.5f, 2.5f}, 0.0f);
    expectVecNear(camera->target, {0.0f, 0.5f, 0.0f}, 0.0f);
    expectVecNear(camera->up, {0.0f, 1.0f, 0.0f}, 0.0f);
    EXPECT_EQ(camera->fovyDegrees, 45.0f);
    auto scientific = parseCamera("-1e-1,2,3,4,5,6,0,0,1,1.5e1");
    ASSERT_TRUE(scientific) << scientific.error().message;
    EXPECT_FLOAT_EQ(scientific->eye.x, -0.1f);
    EXPECT_EQ(scientific->fovyDegrees, 15.0f);
}

TEST(CameraParse, RejectsBadText) {
    expectInvalid("", "10 finite numbers");
    expectInvalid("0,0,1,0,0,0,0,1,0", "got 9");
    expectInvalid("0,0,1,0,0,0,0,1,0,45,3", "got more");
    expectInvalid("0,0,1,0,0,0,0,1,0,4five", "field 10 is \"4five\"");
    expectInvalid("0,0,1,,0,0,0,1,0,45", "field 4 is \"\"");
    expectInvalid("0,0,nan,0,0,0,0,1,0,45", "field 3 is \"nan\"");
    expectInvalid("0,0,1,0,0,0,0,1,0,inf", "field 10");
    expectInvalid("0,0,1e39,0,0,0,0,1,0,45", "field 3");
}

TEST(CameraParse, RejectsDegenerateGeometry) {
    expectInvalid("1,2,3,1,2,3,0,1,0,45", "eye and target are the same point");
    expectInvalid("0,0,1,0,0,0,0,0,-2,45", "parallel to the view direction");
    expectInvalid("0,0,1,0,0,0,0,0,0,45", "up vector is zero");
    expectInvalid("0,0,1,0,0,0,0,1,0,0", "fovy must be in (0, 180)");
    expectInvalid("0,0,1,0,0,0,0,1,0,180", "fovy must be in (0, 180)");
    expectInvalid("0,0,1,0,0,0,0,1,0,-30", "fovy must be in (0, 180)");
}

TEST(CameraCheck, RefusesWhatParseCameraRefusesNamingTheCamera) {
    Camera camera;
    camera.name = "Overview";
    camera.eye = {0.0f, 0.0f, 1.0f};
    camera.up = {0.0f, 1.0f, 0.0f};
    camera.fovyDegrees = 45.0f;
    EXPECT_TRUE(checkCamera(camera));
    auto expectRefused = [](const Camera& bad, const std::string& part) {
        auto checked = checkCamera(bad);
        ASSERT_FALSE(checked) << part;
        EXPECT_EQ(checked.error().code, ErrorCode::InvalidInput);
        EXPECT_NE(checked.error().message.find("camera \"Overview\": " + part), std::string::npos)
            << checked.error().message;
    };
    Camera bad = camera;
    bad.eye.x = std::nanf("");
    expectRefused(bad, "a number is not finite");
    bad = camera;
    bad.target = bad.eye;
    expectRefused(bad, "eye and target are the same point");
    bad = camera;
    bad.up = {0.0f, 0.0f, 2.0f};
    expectRefused(bad, "up vector is zero or parallel");
    bad = camera;
    bad.fovyDegrees = 180.0f;
    expectRefused(bad, "fovy must be in (0, 180) degrees, got 180");
}

TEST(SceneCamera, PicksTheNthCameraOrNamesTheCount) {
    Scene scene;
    scene.sourcePath = "room.gltf";
    scene.cameras.resize(2);
    scene.cameras[1].name = "second";
    auto camera = sceneCamera(scene, 1);
    ASSERT_TRUE(camera) << camera.error().message;
    EXPECT_EQ(camera->name, "second");
    for (int index : {2, -1}) {
        auto missing = sceneCamera(scene, index);
        ASSERT_FALSE(missing);
        EXPECT_EQ(missing.error().code, ErrorCode::InvalidInput);
        EXPECT_NE(missing.error().message.find("room.gltf has 2 cameras"), std::string::npos)
            << missing.error().message;
    }
}

TEST(CameraRays, CentreLooksAlongTheViewDirection) {
    Camera camera;
    camera.eye = {1.0f, 2.0f, 3.0f};
    camera.target = {4.0f, 2.0f, -1.0f};
    camera.up = {0.0f, 1.0f, 0.0f};
    // Odd and even sizes: the image centre is a pixel centre or a pixel corner.
    for (auto [width, height] : {std::pair{64u, 48u}, std::pair{63u, 47u}}) {
        CameraRays rays(camera, width, height);
        expectVecNear(rays.direction(0.5f * float(width), 0.5f * float(height)),
                      glm::vec3(0.6f, 0.0f, -0.8f), 1e-6f);
        expectVecNear(rays.origin(), camera.eye, 0.0f);
    }
}

TEST(CameraRays, CornersMatchFieldOfViewAndAspect) {
    // Looking down -z from the origin with +y up: right is +x (right-handed).
    Camera camera;
    camera.eye = glm::vec3(0.0f);
    camera.target = {0.0f, 0.0f, -5.0f};
    // A tilted up vector is orthogonalised against the view direction.
    camera.up = {0.0f, 1.0f, 0.7f};
    camera.fovyDegrees = 60.0f;
    CameraRays rays(camera, 200, 100);
    float t = std::tan(glm::radians(30.0f));
    float aspect = 2.0f;
    auto expected = [&](float sx, float sy) { return glm::normalize(glm::vec3(sx, sy, -1.0f)); };
    expectVecNear(rays.direction(0.0f, 0.0f), expected(-aspect * t, t), 1e-6f);
    expectVecNear(rays.direction(200.0f, 0.0f), expected(aspect * t, t), 1e-6f);
    expectVecNear(rays.direction(0.0f, 100.0f), expected(-aspect * t, -t), 1e-6f);
    expectVecNear(rays.direction(200.0f, 100.0f), expected(aspect * t, -t), 1e-6f);
    // The top edge centre sits fovy/2 above the forward direction.
    glm::vec3 top = rays.direction(100.0f, 0.0f);
    EXPECT_NEAR(std::acos(glm::dot(top, glm::vec3(0.0f, 0.0f, -1.0f))), glm::radians(30.0f), 1e-6f);
    EXPECT_GT(top.y, 0.0f);
    // Pixel centres step evenly in the image plane: the first one is half a pixel in.
    glm::vec3 first = rays.direction(0.5f, 0.5f);
    glm::vec3 plane = first / -first.z;
    EXPECT_NEAR(plane.x, -aspect * t + aspect * t / 200.0f, 1e-6f);
    EXPECT_NEAR(plane.y, t - t / 100.0f, 1e-6f);
}

}  // namespace
}  // namespace pic
