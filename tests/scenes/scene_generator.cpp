#include "tests/scenes/scene_generator.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include <stb/stb_image_write.h>

#include "tests/scenes/gltf_builder.h"
#include "tests/scenes/mesh_builder.h"

namespace pic::testscenes {

namespace {

constexpr double kDegrees = std::numbers::pi / 180.0;

// ---------------------------------------------------------------------------------------------
// Shared helpers

/// Cells of about `cellSize` metres along `length`; a cell size of 0 means one cell.
uint32_t cellsAlong(float length, float cellSize) {
    if (cellSize <= 0.0f) return 1;
    return std::max(1u, uint32_t(std::ceil(double(length) / double(cellSize))));
}

/// Per-axis cells of a box of the given size.
glm::uvec3 boxCells(const glm::vec3& size, float cellSize) {
    return {cellsAlong(size.x, cellSize), cellsAlong(size.y, cellSize),
            cellsAlong(size.z, cellSize)};
}

/// Triangles of a box split into n cells per axis.
uint64_t boxTriangles(const glm::uvec3& n) {
    return 4ull * (uint64_t(n.x) * n.y + uint64_t(n.y) * n.z + uint64_t(n.z) * n.x);
}

/// The six walls of an axis-aligned room.
enum class RoomSide { Floor, Ceiling, NegX, PosX, NegZ, PosZ };

/// Where a room wall lies and how its quad is spanned.
struct SideFrame {
    int axis;    ///< axis the wall is perpendicular to
    bool atMax;  ///< wall lies on the room's max plane of that axis
    int u, v;    ///< in-plane axes with cross(e_u, e_v) pointing into the room
};

SideFrame sideFrame(RoomSide side) {
    // Cyclic axes (a+1, a+2) give cross(e_u, e_v) = +e_a; swapping them flips the facing.
    const auto frame = [](int axis, bool atMax) {
        const int u = (axis + 1) % 3;
        const int v = (axis + 2) % 3;
        return atMax ? SideFrame{axis, true, v, u} : SideFrame{axis, false, u, v};
    };
    switch (side) {
    case RoomSide::Floor:
        return frame(1, false);
    case RoomSide::Ceiling:
        return frame(1, true);
    case RoomSide::NegX:
        return frame(0, false);
    case RoomSide::PosX:
        return frame(0, true);
    case RoomSide::NegZ:
        return frame(2, false);
    case RoomSide::PosZ:
        return frame(2, true);
    }
    return frame(1, false);
}

/// Cells of the wall on `side` of room [lo, hi] at about `cellSize` metres (0: one cell).
glm::uvec2 roomSideCells(const glm::vec3& lo, const glm::vec3& hi, RoomSide side, float cellSize) {
    const SideFrame f = sideFrame(side);
    return {cellsAlong(hi[f.u] - lo[f.u], cellSize), cellsAlong(hi[f.v] - lo[f.v], cellSize)};
}

/// Single-sided wall on `side` of room [lo, hi], facing into the room.
void addRoomSide(MeshBuilder& mesh, const glm::vec3& lo, const glm::vec3& hi, RoomSide side,
                 float cellSize = 0.0f) {
    const SideFrame f = sideFrame(side);
    const auto corner = [&](bool uMax, bool vMax) {
        glm::vec3 p;
        p[f.axis] = f.atMax ? hi[f.axis] : lo[f.axis];
        p[f.u] = uMax ? hi[f.u] : lo[f.u];
        p[f.v] = vMax ? hi[f.v] : lo[f.v];
        return p;
    };
    const glm::uvec2 cells = roomSideCells(lo, hi, side, cellSize);
    mesh.addQuad(corner(false, false), corner(true, false), corner(true, true), corner(false, true),
                 cells.x, cells.y);
}

/// Adds a mesh named `name` built by `build` with every face in `material`.
template <class Build>
void addMesh(GltfBuilder& gltf, const std::string& name, uint32_t material, Build&& build) {
    MeshBuilder mesh;
    mesh.setMaterial(material);
    build(mesh);
    gltf.addMesh(name, mesh.takePrimitives());
}

/// Inward walls of room [lo, hi] on the given sides as one mesh.
void addRoom(GltfBuilder& gltf, const std::string& name, uint32_t material, const glm::vec3& lo,
             const glm::vec3& hi, std::initializer_list<RoomSide> sides) {
    addMesh(gltf, name, material, [&](MeshBuilder& mesh) {
        for (RoomSide side : sides) addRoomSide(mesh, lo, hi, side);
    });
}

constexpr std::initializer_list<RoomSide> kAllSides = {RoomSide::Floor, RoomSide::Ceiling,
                                                       RoomSide::NegX,  RoomSide::PosX,
                                                       RoomSide::NegZ,  RoomSide::PosZ};

/// The Cornell box's white, used by every plain room.
uint32_t addWhite(GltfBuilder& gltf) {
    return gltf.addMaterial({.name = "white", .baseColor = {0.725, 0.71, 0.68}});
}

// ---------------------------------------------------------------------------------------------
// Cornell box: interior [-0.5, 0.5] x [0, 1] x [-0.5, 0.5], open at z = +0.5.

constexpr glm::vec3 kCornellLo(-0.5f, 0.0f, -0.5f);
constexpr glm::vec3 kCornellHi(0.5f, 1.0f, 0.5f);

/// The Cornell box walls (red left, green right), its two closed boxes and its camera.
void addCornellBox(GltfBuilder& gltf) {
    const uint32_t white = addWhite(gltf);
    const uint32_t red = gltf.addMaterial({.name = "red", .baseColor = {0.63, 0.065, 0.05}});
    const uint32_t green = gltf.addMaterial({.name = "green", .baseColor = {0.14, 0.45, 0.091}});
    const auto wall = [&](const char* name, uint32_t material, RoomSide side) {
        addMesh(gltf, name, material,
                [&](MeshBuilder& mesh) { addRoomSide(mesh, kCornellLo, kCornellHi, side); });
    };
    wall("floor", white, RoomSide::Floor);
    wall("ceiling", white, RoomSide::Ceiling);
    wall("back_wall", white, RoomSide::NegZ);
    wall("left_wall", red, RoomSide::NegX);
    wall("right_wall", green, RoomSide::PosX);
    addMesh(gltf, "tall_box", white, [](MeshBuilder& mesh) {
        mesh.addBox({-0.19f, 0.3f, -0.16f}, {0.15f, 0.3f, 0.15f}, float(17.0 * kDegrees));
    });
    addMesh(gltf, "short_box", white, [](MeshBuilder& mesh) {
        mesh.addBox({0.19f, 0.15f, 0.19f}, {0.15f, 0.15f, 0.15f}, float(-17.0 * kDegrees));
    });
    gltf.addCamera({.name = "camera",
                    .eye = {0.0, 0.5, 1.9},
                    .target = {0.0, 0.5, 0.0},
                    .yfovDegrees = 39.3,
                    .aspectRatio = 1.0});
}

/// `cornell`: the box lit by a 1 W/sr point light just under the ceiling.
Result<void> buildCornell(GltfBuilder& gltf, const SceneOptions&) {
    addCornellBox(gltf);
    // 1 W/sr at 0.95 m above the floor: E = 1 / 0.95² ≈ 1.108 W/m² at the floor centre.
    gltf.addLight({.name = "ceiling_lamp",
                   .type = LightType::Point,
                   .position = {0.0, 0.95, 0.0},
                   .intensity = 1.0});
    return {};
}

/// `cornell_area`: the box lit only by an emissive ceiling panel of radiance 10 W/(m²·sr).
Result<void> buildCornellArea(GltfBuilder& gltf, const SceneOptions&) {
    addCornellBox(gltf);
    const uint32_t emitter = gltf.addMaterial({.name = "light",
                                               .baseColor = {0.78, 0.78, 0.78},
                                               .emissiveFactor = {1.0, 1.0, 1.0},
                                               .emissiveStrength = 10.0});
    // A 0.25 m square panel 1 mm below the ceiling, facing down.
    addMesh(gltf, "light_panel", emitter, [](MeshBuilder& mesh) {
        addRoomSide(mesh, {-0.125f, 0.0f, -0.125f}, {0.125f, 0.999f, 0.125f}, RoomSide::Ceiling);
    });
    return {};
}

// ---------------------------------------------------------------------------------------------
// Small rooms.

/// `two_floors`: two 4 × 2.5 × 4 m rooms split by a closed slab; only the lower one has a light.
Result<void> buildTwoFloors(GltfBuilder& gltf, const SceneOptions&) {
    const uint32_t white = addWhite(gltf);
    constexpr float kHalf = 2.0f;
    constexpr float kRoomHeight = 2.5f;
    constexpr float kSlabThickness = 0.02f;
    constexpr float kUpperFloor = kRoomHeight + kSlabThickness;
    addRoom(gltf, "lower_room", white, {-kHalf, 0.0f, -kHalf}, {kHalf, kRoomHeight, kHalf},
            {RoomSide::Floor, RoomSide::NegX, RoomSide::PosX, RoomSide::NegZ, RoomSide::PosZ});
    // The slab reaches 5 cm past the walls, so the seams where walls meet it cannot leak.
    addMesh(gltf, "slab", white, [&](MeshBuilder& mesh) {
        mesh.addBox({0.0f, kRoomHeight + 0.5f * kSlabThickness, 0.0f},
                    {kHalf + 0.05f, 0.5f * kSlabThickness, kHalf + 0.05f});
    });
    addRoom(gltf, "upper_room", white, {-kHalf, kUpperFloor, -kHalf},
            {kHalf, kUpperFloor + kRoomHeight, kHalf},
            {RoomSide::Ceiling, RoomSide::NegX, RoomSide::PosX, RoomSide::NegZ, RoomSide::PosZ});
    gltf.addLight({.name = "lower_lamp",
                   .type = LightType::Point,
                   .position = {0.0, 1.8, 0.0},
                   .intensity = 5.0});
    gltf.addCamera({.name = "upper_camera",
                    .eye = {1.6, 4.2, 1.6},
                    .target = {-1.0, 2.9, -1.0},
                    .yfovDegrees = 60.0,
                    .aspectRatio = 16.0 / 9.0});
    return {};
}

/// `opposite_colors`: a 10 × 3 × 3 m room with a red lamp near one end and a green one near the
/// other.
Result<void> buildOppositeColors(GltfBuilder& gltf, const SceneOptions&) {
    const uint32_t white = addWhite(gltf);
    addRoom(gltf, "room", white, {-5.0f, 0.0f, -1.5f}, {5.0f, 3.0f, 1.5f}, kAllSides);
    gltf.addLight({.name = "red_lamp",
                   .type = LightType::Point,
                   .position = {-4.0, 1.5, 0.0},
                   .color = {1.0, 0.0, 0.0},
                   .intensity = 5.0});
    gltf.addLight({.name = "green_lamp",
                   .type = LightType::Point,
                   .position = {4.0, 1.5, 0.0},
                   .color = {0.0, 1.0, 0.0},
                   .intensity = 5.0});
    gltf.addCamera({.name = "camera",
                    .eye = {-4.7, 1.7, 0.0},
                    .target = {5.0, 1.3, 0.0},
                    .yfovDegrees = 60.0,
                    .aspectRatio = 16.0 / 9.0});
    return {};
}

/// `small_spot`: a 5 × 3 × 5 m room lit by one narrow spotlight pointing at the floor.
Result<void> buildSmallSpot(GltfBuilder& gltf, const SceneOptions&) {
    const uint32_t white = addWhite(gltf);
    addRoom(gltf, "room", white, {-2.5f, 0.0f, -2.5f}, {2.5f, 3.0f, 2.5f}, kAllSides);
    // 20 W/sr from 2.9 m: E ≈ 2.38 W/m² in a spot of radius 2.9·tan 8° ≈ 0.41 m on the floor.
    gltf.addLight({.name = "spot",
                   .type = LightType::Spot,
                   .position = {0.0, 2.9, 0.0},
                   .direction = {0.0, -1.0, 0.0},
                   .intensity = 20.0,
                   .innerConeAngle = 6.0 * kDegrees,
                   .outerConeAngle = 8.0 * kDegrees});
    gltf.addCamera({.name = "camera",
                    .eye = {2.2, 2.2, 2.2},
                    .target = {0.0, 0.0, 0.0},
                    .yfovDegrees = 60.0,
                    .aspectRatio = 16.0 / 9.0});
    return {};
}

/// `open_plane`: a 4 × 4 m floor of albedo 0.5 open to the sky, nothing else: the sky's furnace
/// (under a constant sky of radiance L the floor receives π·L and reflects ρ·L) and no lights.
Result<void> buildOpenPlane(GltfBuilder& gltf, const SceneOptions&) {
    const uint32_t grey = gltf.addMaterial({.name = "grey", .baseColor = {0.5, 0.5, 0.5}});
    addMesh(gltf, "floor", grey, [](MeshBuilder& mesh) {
        mesh.addQuad({-2.0f, 0.0f, -2.0f}, {-2.0f, 0.0f, 2.0f}, {2.0f, 0.0f, 2.0f},
                     {2.0f, 0.0f, -2.0f}, 4, 4);
    });
    gltf.addCamera({.name = "camera",
                    .eye = {0.0, 3.0, 4.0},
                    .target = {0.0, 0.0, 0.0},
                    .yfovDegrees = 60.0,
                    .aspectRatio = 16.0 / 9.0});
    return {};
}

/// `object_box`: a lone 1 m cube centred on the origin, in a light grey: a dynamic object to
/// place into other scenes (`--object FILE --transform …`); no lights, no camera.
Result<void> buildObjectBox(GltfBuilder& gltf, const SceneOptions&) {
    const uint32_t grey = gltf.addMaterial({.name = "box", .baseColor = {0.6, 0.6, 0.6}});
    addMesh(gltf, "box", grey,
            [](MeshBuilder& mesh) { mesh.addBox({0.0f, 0.0f, 0.0f}, {0.5f, 0.5f, 0.5f}); });
    return {};
}

/// `closed_box`: a sealed 1 m room with a point light at its centre.
Result<void> buildClosedBox(GltfBuilder& gltf, const SceneOptions&) {
    const uint32_t white = addWhite(gltf);
    addRoom(gltf, "room", white, {-0.5f, 0.0f, -0.5f}, {0.5f, 1.0f, 0.5f}, kAllSides);
    gltf.addLight({.name = "centre_lamp",
                   .type = LightType::Point,
                   .position = {0.0, 0.5, 0.0},
                   .intensity = 1.0});
    gltf.addCamera({.name = "camera",
                    .eye = {0.0, 0.5, 0.45},
                    .target = {0.0, 0.5, -0.5},
                    .yfovDegrees = 90.0,
                    .aspectRatio = 1.0});
    return {};
}

/// `thin_wall`: a 6 × 2.5 × 4 m room split at x = 0 by a 2 cm partition; only the left (−x) half
/// has a light (paper 000 §5.2: caches next to a thin wall, clusters straddling it).
Result<void> buildThinWall(GltfBuilder& gltf, const SceneOptions&) {
    const uint32_t white = addWhite(gltf);
    constexpr float kThickness = 0.02f;
    addRoom(gltf, "room", white, {-3.0f, 0.0f, -2.0f}, {3.0f, 2.5f, 2.0f}, kAllSides);
    // The partition reaches 5 cm past the floor, ceiling and walls, so no seam can leak.
    addMesh(gltf, "partition", white, [&](MeshBuilder& mesh) {
        mesh.addBox({0.0f, 1.25f, 0.0f}, {0.5f * kThickness, 1.3f, 2.05f});
    });
    gltf.addLight({.name = "lit_side_lamp",
                   .type = LightType::Point,
                   .position = {-1.5, 1.8, 0.0},
                   .intensity = 5.0});
    // Camera 0 looks at the partition from the dark side, camera 1 from the lit side.
    gltf.addCamera({.name = "dark_side",
                    .eye = {2.8, 1.6, 1.8},
                    .target = {0.0, 1.0, -0.6},
                    .yfovDegrees = 70.0,
                    .aspectRatio = 4.0 / 3.0});
    gltf.addCamera({.name = "lit_side",
                    .eye = {-2.8, 1.6, 1.8},
                    .target = {0.0, 1.0, -0.6},
                    .yfovDegrees = 70.0,
                    .aspectRatio = 4.0 / 3.0});
    return {};
}

// ---------------------------------------------------------------------------------------------
// Furnished rooms: real-sized rooms with furniture that hides surfaces, a window the sun comes
// through, white and coloured diffuse materials and lamps of every kind.

namespace furnished {

/// The wall on `side` of room [lo, hi] with a rectangular opening: `openLo`, `openHi` give the
/// opening's corners (only their coordinates along the wall's two in-plane axes are read).
void addWallWithOpening(MeshBuilder& mesh, const glm::vec3& lo, const glm::vec3& hi, RoomSide side,
                        const glm::vec3& openLo, const glm::vec3& openHi) {
    const SideFrame f = sideFrame(side);
    PIC_CHECK(lo[f.u] < openLo[f.u] && openLo[f.u] < openHi[f.u] && openHi[f.u] < hi[f.u]);
    PIC_CHECK(lo[f.v] < openLo[f.v] && openLo[f.v] < openHi[f.v] && openHi[f.v] < hi[f.v]);
    // Four pieces around the opening: below and above it over the full width, beside it.
    const auto piece = [&](float u0, float u1, float v0, float v1) {
        glm::vec3 a = lo, b = hi;
        a[f.u] = u0;
        b[f.u] = u1;
        a[f.v] = v0;
        b[f.v] = v1;
        addRoomSide(mesh, a, b, side);
    };
    piece(lo[f.u], hi[f.u], lo[f.v], openLo[f.v]);
    piece(lo[f.u], hi[f.u], openHi[f.v], hi[f.v]);
    piece(lo[f.u], openLo[f.u], openLo[f.v], openHi[f.v]);
    piece(openHi[f.u], hi[f.u], openLo[f.v], openHi[f.v]);
}

/// A box given by its min and max corners.
void addSlab(MeshBuilder& mesh, const glm::vec3& lo, const glm::vec3& hi) {
    mesh.addBox(0.5f * (lo + hi), 0.5f * (hi - lo));
}

/// A table of top [x0, x1] × [z0, z1] at `height`, 4 cm thick, on four 5 cm legs.
void addTable(MeshBuilder& mesh, float x0, float x1, float z0, float z1, float height) {
    constexpr float kTop = 0.04f, kLeg = 0.05f;
    addSlab(mesh, {x0, height - kTop, z0}, {x1, height, z1});
    for (float x : {x0 + 0.03f, x1 - 0.03f - kLeg})
        for (float z : {z0 + 0.03f, z1 - 0.03f - kLeg})
            addSlab(mesh, {x, 0.0f, z}, {x + kLeg, height - kTop, z + kLeg});
}

/// An open bookcase over [lo, hi]: a back on the low-x side (`backAtLowX`) or the high-x side,
/// open towards the other, two sides and `boards` shelves (bottom and top included), all 2 cm
/// thick.
void addBookcase(MeshBuilder& mesh, const glm::vec3& lo, const glm::vec3& hi, bool backAtLowX,
                 int boards) {
    constexpr float kBoard = 0.02f;
    const float backX0 = backAtLowX ? lo.x : hi.x - kBoard;
    addSlab(mesh, {backX0, lo.y, lo.z}, {backX0 + kBoard, hi.y, hi.z});
    addSlab(mesh, {lo.x, lo.y, lo.z}, {hi.x, hi.y, lo.z + kBoard});
    addSlab(mesh, {lo.x, lo.y, hi.z - kBoard}, {hi.x, hi.y, hi.z});
    const float innerX0 = backAtLowX ? lo.x + kBoard : lo.x;
    const float innerX1 = backAtLowX ? hi.x : hi.x - kBoard;
    for (int k = 0; k < boards; ++k) {
        const float y = lo.y + (hi.y - lo.y - kBoard) * float(k) / float(boards - 1);
        addSlab(mesh, {innerX0, y, lo.z + kBoard}, {innerX1, y + kBoard, hi.z - kBoard});
    }
}

}  // namespace furnished

/// `furnished_room`: a 4 × 2.7 × 5 m living room (x ∈ [−2, 2], z ∈ [−2.5, 2.5]) with a window in
/// the +x wall, a table, a bookcase, a sofa, boxes against the walls; a sun through the window,
/// a ceiling lamp and a narrow spot on the table.
Result<void> buildFurnishedRoom(GltfBuilder& gltf, const SceneOptions&) {
    using namespace furnished;
    const glm::vec3 lo(-2.0f, 0.0f, -2.5f), hi(2.0f, 2.7f, 2.5f);
    const uint32_t white = addWhite(gltf);
    const uint32_t floor = gltf.addMaterial({.name = "oak_floor", .baseColor = {0.5, 0.34, 0.2}});
    const uint32_t wood = gltf.addMaterial({.name = "walnut", .baseColor = {0.35, 0.22, 0.13}});
    const uint32_t fabric =
        gltf.addMaterial({.name = "blue_fabric", .baseColor = {0.12, 0.2, 0.5}});
    const uint32_t red = gltf.addMaterial({.name = "red_box", .baseColor = {0.63, 0.065, 0.05}});
    const uint32_t green =
        gltf.addMaterial({.name = "green_box", .baseColor = {0.14, 0.45, 0.091}});
    addMesh(gltf, "floor", floor,
            [&](MeshBuilder& mesh) { addRoomSide(mesh, lo, hi, RoomSide::Floor); });
    addMesh(gltf, "walls", white, [&](MeshBuilder& mesh) {
        for (RoomSide side : {RoomSide::Ceiling, RoomSide::NegX, RoomSide::NegZ, RoomSide::PosZ})
            addRoomSide(mesh, lo, hi, side);
        // The window: 1.6 m wide, 1.2 m high, its sill at 0.9 m.
        addWallWithOpening(mesh, lo, hi, RoomSide::PosX, {0.0f, 0.9f, -0.8f}, {0.0f, 2.1f, 0.8f});
    });
    addMesh(gltf, "table", wood,
            [](MeshBuilder& mesh) { addTable(mesh, -0.2f, 1.2f, 0.6f, 1.4f, 0.75f); });
    addMesh(gltf, "bookcase", wood, [&](MeshBuilder& mesh) {
        addBookcase(mesh, {-2.0f, 0.0f, -1.2f}, {-1.65f, 1.9f, 0.4f}, true, 5);
    });
    // The sofa against the −z wall: seat, back rest and two arms, closed boxes on the floor.
    addMesh(gltf, "sofa", fabric, [](MeshBuilder& mesh) {
        addSlab(mesh, {-1.0f, 0.0f, -2.5f}, {1.0f, 0.45f, -1.6f});
        addSlab(mesh, {-1.0f, 0.45f, -2.5f}, {1.0f, 0.85f, -2.25f});
        addSlab(mesh, {-1.2f, 0.0f, -2.5f}, {-1.0f, 0.65f, -1.6f});
        addSlab(mesh, {1.0f, 0.0f, -2.5f}, {1.2f, 0.65f, -1.6f});
    });
    // Boxes standing against the walls hide the floor and wall behind them.
    addMesh(gltf, "boxes", red, [&](MeshBuilder& mesh) {
        addSlab(mesh, {1.45f, 0.0f, 1.95f}, {2.0f, 0.55f, 2.5f});
        mesh.setMaterial(green);
        addSlab(mesh, {-2.0f, 0.0f, 1.9f}, {-1.4f, 0.4f, 2.5f});
        addSlab(mesh, {-1.9f, 0.4f, 2.0f}, {-1.5f, 0.8f, 2.4f});
    });
    gltf.addLight({.name = "sun",
                   .type = LightType::Directional,
                   .direction = glm::normalize(glm::dvec3(-0.7, -0.55, -0.25)),
                   .color = {1.0, 0.95, 0.85},
                   .intensity = 4.0});
    gltf.addLight({.name = "ceiling_lamp",
                   .type = LightType::Point,
                   .position = {0.0, 2.55, 0.0},
                   .color = {1.0, 0.9, 0.75},
                   .intensity = 3.0});
    // 12 W/sr from 1.85 m above the table: a 10° cone lights a disc of radius ≈ 0.33 m.
    gltf.addLight({.name = "table_spot",
                   .type = LightType::Spot,
                   .position = {0.5, 2.6, 1.0},
                   .direction = {0.0, -1.0, 0.0},
                   .intensity = 12.0,
                   .innerConeAngle = 7.0 * kDegrees,
                   .outerConeAngle = 10.0 * kDegrees});
    gltf.addCamera({.name = "camera",
                    .eye = {-1.7, 1.6, 2.2},
                    .target = {0.8, 0.8, -1.2},
                    .yfovDegrees = 70.0,
                    .aspectRatio = 4.0 / 3.0});
    return {};
}

/// `furnished_study`: a 3.5 × 2.6 × 4.5 m study (x ∈ [−1.75, 1.75], z ∈ [−2.25, 2.25]) with a
/// window in the −z wall, a green accent wall, a desk and chair, two bookcases, a cabinet and
/// stacked boxes in a corner; a low sun through the window, a ceiling lamp and a desk spot.
Result<void> buildFurnishedStudy(GltfBuilder& gltf, const SceneOptions&) {
    using namespace furnished;
    const glm::vec3 lo(-1.75f, 0.0f, -2.25f), hi(1.75f, 2.6f, 2.25f);
    const uint32_t white = addWhite(gltf);
    const uint32_t accent = gltf.addMaterial({.name = "sage_wall", .baseColor = {0.35, 0.5, 0.3}});
    const uint32_t floor = gltf.addMaterial({.name = "grey_carpet", .baseColor = {0.3, 0.3, 0.32}});
    const uint32_t wood = gltf.addMaterial({.name = "pine", .baseColor = {0.65, 0.5, 0.3}});
    const uint32_t leather =
        gltf.addMaterial({.name = "red_leather", .baseColor = {0.45, 0.08, 0.05}});
    const uint32_t cardboard =
        gltf.addMaterial({.name = "cardboard", .baseColor = {0.55, 0.42, 0.26}});
    addMesh(gltf, "floor", floor,
            [&](MeshBuilder& mesh) { addRoomSide(mesh, lo, hi, RoomSide::Floor); });
    addMesh(gltf, "walls", white, [&](MeshBuilder& mesh) {
        for (RoomSide side : {RoomSide::Ceiling, RoomSide::NegX, RoomSide::PosZ})
            addRoomSide(mesh, lo, hi, side);
        // The window: 1.4 m wide, 1.3 m high, its sill at 0.8 m, left of the wall's centre.
        addWallWithOpening(mesh, lo, hi, RoomSide::NegZ, {-0.9f, 0.8f, 0.0f}, {0.5f, 2.1f, 0.0f});
        mesh.setMaterial(accent);
        addRoomSide(mesh, lo, hi, RoomSide::PosX);
    });
    // The desk under the window and the chair in front of it.
    addMesh(gltf, "desk", wood,
            [](MeshBuilder& mesh) { addTable(mesh, -1.0f, 0.6f, -2.25f, -1.55f, 0.74f); });
    addMesh(gltf, "chair", leather, [](MeshBuilder& mesh) {
        addSlab(mesh, {-0.45f, 0.0f, -1.35f}, {0.05f, 0.46f, -0.85f});
        addSlab(mesh, {-0.45f, 0.46f, -0.9f}, {0.05f, 1.0f, -0.8f});
    });
    // Two bookcases along the green wall, their backs against it, and a cabinet on the −x wall.
    addMesh(gltf, "bookcases", wood, [](MeshBuilder& mesh) {
        addBookcase(mesh, {1.4f, 0.0f, -1.6f}, {1.75f, 2.0f, -0.4f}, false, 6);
        addBookcase(mesh, {1.4f, 0.0f, -0.2f}, {1.75f, 2.0f, 1.0f}, false, 6);
        addSlab(mesh, {-1.75f, 0.0f, 0.2f}, {-1.3f, 0.9f, 1.6f});
    });
    // Boxes stacked in the far corner hide the corner and each other's faces.
    addMesh(gltf, "boxes", cardboard, [](MeshBuilder& mesh) {
        addSlab(mesh, {0.95f, 0.0f, 1.65f}, {1.75f, 0.5f, 2.25f});
        addSlab(mesh, {1.05f, 0.5f, 1.75f}, {1.65f, 0.9f, 2.25f});
        addSlab(mesh, {0.3f, 0.0f, 1.85f}, {0.9f, 0.35f, 2.25f});
    });
    gltf.addLight({.name = "low_sun",
                   .type = LightType::Directional,
                   .direction = glm::normalize(glm::dvec3(0.3, -0.45, 0.85)),
                   .color = {1.0, 0.85, 0.65},
                   .intensity = 5.0});
    gltf.addLight({.name = "ceiling_lamp",
                   .type = LightType::Point,
                   .position = {0.0, 2.45, 0.5},
                   .color = {0.95, 0.95, 1.0},
                   .intensity = 2.5});
    // 8 W/sr from 1.0 m above the desk: an 8° cone lights a disc of radius ≈ 0.14 m.
    gltf.addLight({.name = "desk_spot",
                   .type = LightType::Spot,
                   .position = {-0.2, 1.74, -1.9},
                   .direction = {0.0, -1.0, 0.0},
                   .color = {1.0, 0.9, 0.7},
                   .intensity = 8.0,
                   .innerConeAngle = 5.0 * kDegrees,
                   .outerConeAngle = 8.0 * kDegrees});
    gltf.addCamera({.name = "camera",
                    .eye = {-1.4, 1.6, 2.0},
                    .target = {0.6, 0.8, -1.6},
                    .yfovDegrees = 70.0,
                    .aspectRatio = 4.0 / 3.0});
    return {};
}

// ---------------------------------------------------------------------------------------------
// Error cases and textures.

/// `bad_points`: valid glTF whose only primitive is POINTS, which pic rejects.
Result<void> buildBadPoints(GltfBuilder& gltf, const SceneOptions&) {
    const uint32_t white = addWhite(gltf);
    PrimitiveData points{.material = white,
                         .mode = PrimitiveMode::Points,
                         .positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
    gltf.addMesh("points", {std::move(points)});
    gltf.addCamera({.name = "camera", .eye = {2.0, 2.0, 2.0}, .target = {0.0, 0.0, 0.0}});
    return {};
}

/// `bad_empty`: valid glTF with a camera and no mesh at all.
Result<void> buildBadEmpty(GltfBuilder& gltf, const SceneOptions&) {
    gltf.addCamera({.name = "camera", .eye = {0.0, 1.0, 3.0}, .target = {0.0, 1.0, 0.0}});
    return {};
}

/// The kCheckerSize² checkerboard as an RGB PNG.
std::vector<uint8_t> checkerPng() {
    std::vector<uint8_t> texels;
    for (int row = 0; row < kCheckerSize; ++row)
        for (int column = 0; column < kCheckerSize; ++column) {
            const auto& color = (row + column) % 2 == 0 ? kCheckerSrgbA : kCheckerSrgbB;
            texels.insert(texels.end(), color.begin(), color.end());
        }
    std::vector<uint8_t> png;
    const auto append = [](void* context, void* data, int size) {
        const auto* bytes = static_cast<const uint8_t*>(data);
        static_cast<std::vector<uint8_t>*>(context)->insert(
            static_cast<std::vector<uint8_t>*>(context)->end(), bytes, bytes + size);
    };
    const int ok = stbi_write_png_to_func(append, &png, kCheckerSize, kCheckerSize, 3,
                                          texels.data(), kCheckerSize * 3);
    PIC_CHECK(ok != 0);
    return png;
}

/// Two-triangle quad primitive with its own normal and per-corner UVs.
PrimitiveData texturedQuad(uint32_t material, const std::array<glm::vec3, 4>& corners,
                           const glm::vec3& normal, const std::array<glm::vec2, 4>& uv0) {
    return {.material = material,
            .positions = {corners.begin(), corners.end()},
            .normals = std::vector<glm::vec3>(4, normal),
            .uv0 = {uv0.begin(), uv0.end()},
            .indices = {0, 1, 2, 0, 2, 3}};
}

/// `textured_quad`: a checkerboard floor read through TEXCOORD_0 and a wall with TEXCOORD_1.
Result<void> buildTexturedQuad(GltfBuilder& gltf, const SceneOptions&) {
    const uint32_t checker = gltf.addPngTexture("checker", checkerPng());
    const uint32_t floorMaterial = gltf.addMaterial(
        {.name = "checker", .baseColorTexture = int(checker), .baseColorTexCoord = 0});
    const uint32_t wallMaterial = gltf.addMaterial(
        {.name = "checker_uv1", .baseColorTexture = int(checker), .baseColorTexCoord = 1});

    // Floor y = 0 over [-0.5, 0.5]², u along +x, v along +z; counter-clockwise seen from above.
    PrimitiveData floor = texturedQuad(
        floorMaterial,
        {{{-0.5f, 0.0f, -0.5f}, {-0.5f, 0.0f, 0.5f}, {0.5f, 0.0f, 0.5f}, {0.5f, 0.0f, -0.5f}}},
        {0.0f, 1.0f, 0.0f}, {{{0.0f, 0.0f}, {0.0f, 1.0f}, {1.0f, 1.0f}, {1.0f, 0.0f}}});
    // Back wall z = -0.5 facing +z, u along +x, v down from the top edge; its texture reads
    // TEXCOORD_1 = TEXCOORD_0 / 2, i.e. the 4 × 4 texel corner [0, 0.5]² of the checkerboard.
    PrimitiveData wall = texturedQuad(
        wallMaterial,
        {{{-0.5f, 0.0f, -0.5f}, {0.5f, 0.0f, -0.5f}, {0.5f, 1.0f, -0.5f}, {-0.5f, 1.0f, -0.5f}}},
        {0.0f, 0.0f, 1.0f}, {{{0.0f, 1.0f}, {1.0f, 1.0f}, {1.0f, 0.0f}, {0.0f, 0.0f}}});
    for (const glm::vec2& uv : wall.uv0) wall.uv1.push_back(0.5f * uv);
    gltf.addMesh("textured_quad", {std::move(floor), std::move(wall)});

    gltf.addLight(
        {.name = "lamp", .type = LightType::Point, .position = {0.0, 0.8, 0.3}, .intensity = 1.0});
    gltf.addCamera({.name = "camera",
                    .eye = {0.0, 0.9, 1.3},
                    .target = {0.0, 0.2, -0.2},
                    .yfovDegrees = 50.0,
                    .aspectRatio = 1.0});
    return {};
}

// ---------------------------------------------------------------------------------------------
// Atrium: a Sponza-like courtyard, 30 m (x) by 15 m (z), walls 13 m high, open to the sky, with
// two storeys of arcades along both long sides.

namespace atrium {

constexpr glm::vec3 kLo(-15.0f, 0.0f, -7.5f);
constexpr glm::vec3 kHi(15.0f, 13.0f, 7.5f);
constexpr float kColonnadeZ = 4.5f;    ///< |z| of the column axes
constexpr float kColumnRadius = 0.3f;  ///< also the half-depth of the arcade bands
constexpr uint32_t kBays = 10;         ///< arches per side and storey (3 m bays)
constexpr float kSlabThickness = 0.3f;

/// One storey of arcades: columns from `base` to `spring`, arcade band up to `top`, then a slab.
struct Storey {
    float base;
    float spring;
    float top;
};
constexpr Storey kStoreys[] = {{0.0f, 4.0f, 6.0f}, {6.3f, 9.8f, 11.6f}};

constexpr uint32_t kMinSegments = 8;
constexpr uint32_t kMaxSegments = 96;
/// Share of the triangle budget the curved details may take before flat subdivision fills the rest.
constexpr double kDetailShare = 0.3;
constexpr uint32_t kMaxTriangles = 10'000'000;

constexpr std::initializer_list<RoomSide> kWallSides = {RoomSide::NegX, RoomSide::PosX,
                                                        RoomSide::NegZ, RoomSide::PosZ};

/// Material indices of the atrium.
struct Materials {
    uint32_t stone;
    uint32_t floor;
    uint32_t curtains[3];
    uint32_t banners[2];
};

/// Adds the atrium's materials.
Materials addMaterials(GltfBuilder& gltf) {
    Materials m;
    m.stone = gltf.addMaterial({.name = "stone", .baseColor = {0.7, 0.65, 0.55}});
    m.floor = gltf.addMaterial({.name = "floor", .baseColor = {0.5, 0.48, 0.45}});
    m.curtains[0] = gltf.addMaterial({.name = "curtain_red", .baseColor = {0.75, 0.08, 0.06}});
    m.curtains[1] = gltf.addMaterial({.name = "curtain_green", .baseColor = {0.08, 0.55, 0.1}});
    m.curtains[2] = gltf.addMaterial({.name = "curtain_blue", .baseColor = {0.06, 0.12, 0.7}});
    m.banners[0] = gltf.addMaterial({.name = "banner_yellow", .baseColor = {0.8, 0.62, 0.08}});
    m.banners[1] = gltf.addMaterial({.name = "banner_purple", .baseColor = {0.45, 0.1, 0.5}});
    return m;
}

/// Bounds of the slab over `storey` on the side whose z has sign `side`: it spans the arcade from
/// the courtyard face of the band to the outer wall.
std::pair<glm::vec3, glm::vec3> slabBounds(const Storey& storey, float side) {
    const float z0 = kColonnadeZ - kColumnRadius;
    const float y0 = storey.top;
    const float y1 = storey.top + kSlabThickness;
    const glm::vec3 a(kLo.x, y0, side * z0);
    const glm::vec3 b(kHi.x, y1, side * kHi.z);
    return {glm::min(a, b), glm::max(a, b)};
}

/// Signs of z for the two arcaded sides (also of x for the two ends).
constexpr float kSides[] = {-1.0f, 1.0f};

/// Triangles of the flat parts (floor, outer walls, slabs) at `cellSize`.
uint64_t flatTriangles(float cellSize) {
    uint64_t count = 0;
    const glm::uvec2 floor = roomSideCells(kLo, kHi, RoomSide::Floor, cellSize);
    count += 2ull * floor.x * floor.y;
    for (RoomSide side : kWallSides) {
        const glm::uvec2 n = roomSideCells(kLo, kHi, side, cellSize);
        count += 2ull * n.x * n.y;
    }
    for (const Storey& storey : kStoreys)
        for (float side : kSides) {
            const auto [lo, hi] = slabBounds(storey, side);
            count += boxTriangles(boxCells(hi - lo, cellSize));
        }
    return count;
}

/// Floor, outer walls and slabs, subdivided into cells of about `cellSize` metres.
void addFlatParts(GltfBuilder& gltf, const Materials& m, float cellSize) {
    addMesh(gltf, "floor", m.floor,
            [&](MeshBuilder& mesh) { addRoomSide(mesh, kLo, kHi, RoomSide::Floor, cellSize); });
    addMesh(gltf, "walls", m.stone, [&](MeshBuilder& mesh) {
        for (RoomSide side : kWallSides) addRoomSide(mesh, kLo, kHi, side, cellSize);
    });
    addMesh(gltf, "slabs", m.stone, [&](MeshBuilder& mesh) {
        for (const Storey& storey : kStoreys)
            for (float side : kSides) {
                const auto [lo, hi] = slabBounds(storey, side);
                mesh.addBox(0.5f * (lo + hi), 0.5f * (hi - lo), 0.0f, boxCells(hi - lo, cellSize));
            }
    });
}

/// Closed wall band over a row of `bays` round arches between x0 and x1: each arch has radius
/// bay/2 − footHalfWidth, springs at ySpring and is cut through the band's depth [z0, z1]; the band
/// is solid up to yTop. `segments` (even) facets approximate each semicircle.
void addArcadeBand(MeshBuilder& mesh, float x0, float x1, uint32_t bays, float footHalfWidth,
                   float ySpring, float yTop, float z0, float z1, uint32_t segments) {
    PIC_CHECK(segments >= 2 && segments % 2 == 0);
    const float bay = (x1 - x0) / float(bays);
    const float radius = 0.5f * bay - footHalfWidth;
    PIC_CHECK(radius > 0.0f && ySpring + radius < yTop);

    std::vector<float> columnsX(bays + 1);
    for (uint32_t k = 0; k <= bays; ++k) columnsX[k] = k == bays ? x1 : x0 + bay * float(k);
    // arcs[k][i]: (x, y) of arch k at angle π − π·i/segments, from its left to its right springing.
    std::vector<std::vector<glm::vec2>> arcs(bays);
    for (uint32_t k = 0; k < bays; ++k) {
        const float centerX = 0.5f * (columnsX[k] + columnsX[k + 1]);
        arcs[k].resize(segments + 1);
        for (uint32_t i = 0; i <= segments; ++i) {
            const double phi = std::numbers::pi * (1.0 - double(i) / double(segments));
            arcs[k][i] = i == 0          ? glm::vec2(centerX - radius, ySpring)
                         : i == segments ? glm::vec2(centerX + radius, ySpring)
                                         : glm::vec2(centerX + float(radius * std::cos(phi)),
                                                     ySpring + float(radius * std::sin(phi)));
        }
    }
    const auto at = [](const glm::vec2& p, float z) { return glm::vec3(p.x, p.y, z); };
    const uint32_t half = segments / 2;

    // Front (+z) and back (−z) faces: per bay, the rectangle minus its half disc, fanned from the
    // two top corners (each sees its quarter of the arc) plus the foot triangles.
    for (const auto& [z, normal] : {std::pair{z1, 1.0f}, std::pair{z0, -1.0f}}) {
        mesh.beginFace({0.0f, 0.0f, normal});
        std::vector<uint32_t> foot(bays + 1);
        std::vector<uint32_t> corner(bays + 1);
        for (uint32_t k = 0; k <= bays; ++k) {
            foot[k] = mesh.addVertex({columnsX[k], ySpring, z});
            corner[k] = mesh.addVertex({columnsX[k], yTop, z});
        }
        for (uint32_t k = 0; k < bays; ++k) {
            std::vector<uint32_t> arc(segments + 1);
            for (uint32_t i = 0; i <= segments; ++i) arc[i] = mesh.addVertex(at(arcs[k][i], z));
            mesh.addTriangle(foot[k], arc[0], corner[k]);
            for (uint32_t i = 0; i < half; ++i) mesh.addTriangle(corner[k], arc[i], arc[i + 1]);
            mesh.addTriangle(corner[k], arc[half], corner[k + 1]);
            for (uint32_t i = half; i < segments; ++i)
                mesh.addTriangle(corner[k + 1], arc[i], arc[i + 1]);
            mesh.addTriangle(arc[segments], foot[k + 1], corner[k + 1]);
        }
    }
    // Top face, one quad per bay so its edges match the front and back faces.
    mesh.beginFace({0.0f, 1.0f, 0.0f});
    for (uint32_t k = 0; k < bays; ++k) {
        const uint32_t a = mesh.addVertex({columnsX[k], yTop, z0});
        const uint32_t b = mesh.addVertex({columnsX[k + 1], yTop, z0});
        const uint32_t c = mesh.addVertex({columnsX[k + 1], yTop, z1});
        const uint32_t d = mesh.addVertex({columnsX[k], yTop, z1});
        mesh.addTriangle(a, b, c);
        mesh.addTriangle(a, c, d);
    }
    // End faces at x0 and x1.
    for (const auto& [x, normal] : {std::pair{x0, -1.0f}, std::pair{x1, 1.0f}}) {
        mesh.beginFace({normal, 0.0f, 0.0f});
        const uint32_t a = mesh.addVertex({x, ySpring, z0});
        const uint32_t b = mesh.addVertex({x, ySpring, z1});
        const uint32_t c = mesh.addVertex({x, yTop, z1});
        const uint32_t d = mesh.addVertex({x, yTop, z0});
        mesh.addTriangle(a, b, c);
        mesh.addTriangle(a, c, d);
    }
    // Feet (the band's underside between arches), split at each column axis to match the faces.
    mesh.beginFace({0.0f, -1.0f, 0.0f});
    const auto footStrip = [&](float xa, float xb) {
        const uint32_t a = mesh.addVertex({xa, ySpring, z0});
        const uint32_t b = mesh.addVertex({xb, ySpring, z0});
        const uint32_t c = mesh.addVertex({xb, ySpring, z1});
        const uint32_t d = mesh.addVertex({xa, ySpring, z1});
        mesh.addTriangle(a, b, c);
        mesh.addTriangle(a, c, d);
    };
    for (uint32_t k = 0; k <= bays; ++k) {
        if (k > 0) footStrip(arcs[k - 1][segments].x, columnsX[k]);
        if (k < bays) footStrip(columnsX[k], arcs[k][0].x);
    }
    // Intrados: one flat facet per arc segment, facing the arch's centre.
    for (uint32_t k = 0; k < bays; ++k) {
        for (uint32_t i = 0; i < segments; ++i) {
            const double mid = std::numbers::pi * (1.0 - (double(i) + 0.5) / double(segments));
            mesh.beginFace({-float(std::cos(mid)), -float(std::sin(mid)), 0.0f});
            const uint32_t a = mesh.addVertex(at(arcs[k][i], z0));
            const uint32_t b = mesh.addVertex(at(arcs[k][i + 1], z0));
            const uint32_t c = mesh.addVertex(at(arcs[k][i + 1], z1));
            const uint32_t d = mesh.addVertex(at(arcs[k][i], z1));
            mesh.addTriangle(a, b, c);
            mesh.addTriangle(a, c, d);
        }
    }
}

/// Columns, arcade bands, pilasters, curtains and banners; `segments` facets per circle and arch.
void addDetails(GltfBuilder& gltf, const Materials& m, uint32_t segments) {
    const float bay = (kHi.x - kLo.x) / float(kBays);
    addMesh(gltf, "columns", m.stone, [&](MeshBuilder& mesh) {
        for (const Storey& storey : kStoreys)
            for (float side : kSides)
                for (uint32_t k = 1; k < kBays; ++k)
                    mesh.addCylinder({kLo.x + bay * float(k), storey.base, side * kColonnadeZ},
                                     kColumnRadius, storey.spring - storey.base, segments);
    });
    addMesh(gltf, "arcades", m.stone, [&](MeshBuilder& mesh) {
        for (const Storey& storey : kStoreys)
            for (float side : kSides)
                addArcadeBand(mesh, kLo.x, kHi.x, kBays, kColumnRadius, storey.spring, storey.top,
                              side * kColonnadeZ - kColumnRadius,
                              side * kColonnadeZ + kColumnRadius, segments);
    });
    // Half-width pilasters carry the arcades' ends against the end walls.
    addMesh(gltf, "pilasters", m.stone, [&](MeshBuilder& mesh) {
        for (const Storey& storey : kStoreys)
            for (float side : kSides)
                for (float end : kSides) {
                    const float halfHeight = 0.5f * (storey.spring - storey.base);
                    mesh.addBox({end * (kHi.x - 0.5f * kColumnRadius), storey.base + halfHeight,
                                 side * kColonnadeZ},
                                {0.5f * kColumnRadius, halfHeight, kColumnRadius});
                }
    });
    // Curtains hang in the upper gallery just behind three arches per side.
    addMesh(gltf, "curtains", m.curtains[0], [&](MeshBuilder& mesh) {
        const Storey& upper = kStoreys[1];
        uint32_t colour = 0;
        for (float side : kSides)
            for (uint32_t k : {1u, 4u, 7u}) {
                mesh.setMaterial(m.curtains[colour++ % 3]);
                const float centerX = kLo.x + bay * (float(k) + 0.5f);
                const float bottom = upper.base + 1.0f;
                const float top = upper.spring + 1.0f;
                mesh.addBox({centerX, 0.5f * (bottom + top), side * (kColonnadeZ + 0.36f)},
                            {1.1f, 0.5f * (top - bottom), 0.01f});
            }
    });
    // Banners hang 1 cm in front of the end walls, facing into the courtyard.
    addMesh(gltf, "banners", m.banners[0], [&](MeshBuilder& mesh) {
        for (uint32_t e = 0; e < 2; ++e) {
            mesh.setMaterial(m.banners[e]);
            const RoomSide wall = e == 0 ? RoomSide::NegX : RoomSide::PosX;
            const float x = e == 0 ? kLo.x + 0.01f : kHi.x - 0.01f;
            for (float side : kSides) {
                const float z = side * 2.0f;
                addRoomSide(mesh, {x, 5.0f, z - 0.8f}, {x, 11.0f, z + 0.8f}, wall);
            }
        }
    });
}

/// Triangles of the details at `segments`, counted on a scratch document.
uint64_t detailTriangles(uint32_t segments) {
    GltfBuilder scratch;
    addDetails(scratch, addMaterials(scratch), segments);
    return scratch.triangleCount();
}

}  // namespace atrium

/// `atrium`: the courtyard tessellated to options.atriumTriangles (±5 %), sun and gallery lamp.
Result<void> buildAtrium(GltfBuilder& gltf, const SceneOptions& options) {
    using namespace atrium;
    const uint64_t target = options.atriumTriangles;
    const uint64_t smallest = detailTriangles(kMinSegments) + flatTriangles(0.0f);
    if (target * 105 < smallest * 100 || target > kMaxTriangles)
        return fail(ErrorCode::InvalidInput,
                    "atrium triangle target {} is out of range: the layout needs at least {} and "
                    "at most {} triangles",
                    target, (smallest * 100 + 104) / 105, kMaxTriangles);

    // Segments: the largest even count whose details stay within kDetailShare of the target.
    uint32_t lo = kMinSegments / 2;
    uint32_t hi = kMaxSegments / 2;
    while (lo < hi) {
        const uint32_t mid = (lo + hi + 1) / 2;
        if (double(detailTriangles(2 * mid)) <= kDetailShare * double(target))
            lo = mid;
        else
            hi = mid - 1;
    }
    const uint32_t segments = 2 * lo;
    const uint64_t details = detailTriangles(segments);

    // Cell size: bisect (in log scale) for the step of flatTriangles that straddles the budget,
    // then take whichever side lands closer to the target.
    const double budget = double(target) - double(details);
    double small = 0.005;
    double large = 100.0;
    for (int step = 0; step < 64; ++step) {
        const double mid = std::sqrt(small * large);
        if (double(flatTriangles(float(mid))) >= budget)
            small = mid;
        else
            large = mid;
    }
    const auto error = [&](double cell) {
        return std::abs(double(flatTriangles(float(cell))) - budget);
    };
    const float cellSize = float(error(small) <= error(large) ? small : large);
    const uint64_t total = details + flatTriangles(cellSize);
    if (std::abs(double(total) - double(target)) > 0.05 * double(target))
        return fail(ErrorCode::InvalidInput,
                    "atrium cannot meet the triangle target {} within 5 % (closest: {})", target,
                    total);

    const Materials materials = addMaterials(gltf);
    addFlatParts(gltf, materials, cellSize);
    addDetails(gltf, materials, segments);
    PIC_CHECK_EQ(gltf.triangleCount(), total);

    gltf.addLight({.name = "sun",
                   .type = LightType::Directional,
                   .direction = glm::normalize(glm::dvec3(0.35, -0.85, 0.4)),
                   .color = {1.0, 0.96, 0.9},
                   .intensity = 5.0});
    gltf.addLight({.name = "gallery_lamp",
                   .type = LightType::Point,
                   .position = {6.0, 3.0, -6.2},
                   .color = {1.0, 0.85, 0.65},
                   .intensity = 40.0});
    gltf.addCamera({.name = "courtyard_camera",
                    .eye = {-12.5, 1.7, -1.5},
                    .target = {6.0, 5.0, 1.0},
                    .yfovDegrees = 60.0,
                    .aspectRatio = 16.0 / 9.0});
    return {};
}

// ---------------------------------------------------------------------------------------------
// The scene table.

/// A scene's name and the function that fills a document with it.
struct SceneEntry {
    const char* name;
    Result<void> (*build)(GltfBuilder&, const SceneOptions&);
};

constexpr SceneEntry kScenes[] = {
    {"cornell", buildCornell},
    {"cornell_area", buildCornellArea},
    {"two_floors", buildTwoFloors},
    {"opposite_colors", buildOppositeColors},
    {"small_spot", buildSmallSpot},
    {"atrium", buildAtrium},
    {"closed_box", buildClosedBox},
    {"object_box", buildObjectBox},
    {"open_plane", buildOpenPlane},
    {"bad_points", buildBadPoints},
    {"bad_empty", buildBadEmpty},
    {"textured_quad", buildTexturedQuad},
    {"thin_wall", buildThinWall},
    {"furnished_room", buildFurnishedRoom},
    {"furnished_study", buildFurnishedStudy},
};

}  // namespace

std::vector<std::string> testSceneNames() {
    std::vector<std::string> names;
    for (const SceneEntry& entry : kScenes) names.emplace_back(entry.name);
    return names;
}

Result<WrittenScene> generateTestScene(const std::string& name, const std::string& outDir,
                                       const SceneOptions& options) {
    const auto entry = std::find_if(std::begin(kScenes), std::end(kScenes),
                                    [&](const SceneEntry& e) { return name == e.name; });
    if (entry == std::end(kScenes))
        return fail(ErrorCode::InvalidInput, "unknown test scene '{}' (known: {})", name,
                    fmt::join(testSceneNames(), ", "));
    GltfBuilder gltf;
    if (auto built = entry->build(gltf, options); !built) return std::unexpected(built.error());
    PIC_TRY_ASSIGN(std::vector<std::string> files, gltf.write(outDir, name));
    return WrittenScene{std::move(files), gltf.triangleCount()};
}

Result<void> writeTestScene(const std::string& name, const std::string& outDir,
                            const SceneOptions& options) {
    const Result<WrittenScene> written = generateTestScene(name, outDir, options);
    if (!written) return std::unexpected(written.error());
    return {};
}

}  // namespace pic::testscenes
