// The Vulkan renderer, offscreen on whatever device there is (lavapipe in CI) with the Khronos
// validation layer on: every test ends with zero validation messages. Each property is measured on the
// picture: silhouettes against their analytic projection, colours against the material table, the
// brush highlight against the brush's field, uploads and frees counted.
#include "mesher/Mesher.h"
#include "render/DrawnDepth.h"
#include "render/Framing.h"
#include "render/SceneChunks.h"
#include "render/ScenePicture.h"
#include "scene/SceneStore.h"
#include "scene/StoreLod.h"
#include "scene/StreamingScene.h"
#include "sculpt/StrokeScript.h"
#include "render/ImageFile.h"
#include "render/OffscreenTarget.h"
#include "render/Pipelines.h"
#include "render/Renderer.h"
#include "render/Thumbnail.h"
#include "render/VulkanContext.h"
#include "support/CliRun.h"
#include "support/Sculpt.h"
#include "support/TestUtil.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <random>
#include <thread>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <set>

#include <sys/stat.h>
#include <zlib.h>

using namespace vdbclay;
using namespace vdbclay::test;
using namespace vdbclay::render;

namespace {

std::unique_ptr<VulkanContext> validatedContext()
{
    ContextOptions options;
    options.validation = true;
    return std::make_unique<VulkanContext>(options);
}

MeshOptions cmsOptions()
{
    MeshOptions o;
    o.kind = MesherKind::CubicalMarchingSquares;
    return o;
}

/// Pixels whose depth says something was drawn.
std::vector<bool> coverage(const OffscreenTarget& target)
{
    const std::vector<float> depth = target.depth();
    std::vector<bool> covered(depth.size());
    for (std::size_t i = 0; i < depth.size(); ++i) covered[i] = depth[i] != kNothingDrawn;
    return covered;
}

double srgbToLinear(uint8_t v) { return std::pow(double(v) / 255.0, 2.2); }

/// A camera on the +z axis looking at the origin.
Camera frontCamera(double distance, double fov = 40.0)
{
    Camera c;
    c.eye = {0.0, 0.0, distance};
    c.target = {0.0, 0.0, 0.0};
    c.fovYDegrees = fov;
    c.nearPlane = distance * 0.05;
    return c;
}

/// Where the ray through a pixel's centre meets the plane z = planeZ (camera on +z looking at -z).
std::array<double, 2> onPlane(const Camera& c, int x, int y, int size, double planeZ)
{
    const double t = std::tan(c.fovYDegrees * M_PI / 360.0);
    const double nx = (x + 0.5) / size * 2.0 - 1.0, ny = 1.0 - (y + 0.5) / size * 2.0;
    const double d = c.eye[2] - planeZ;
    return {nx * t * d, ny * t * d};
}

/// The pixel size on the plane z = planeZ (world units).
double pixelOnPlane(const Camera& c, int size, double planeZ)
{
    return 2.0 * std::tan(c.fovYDegrees * M_PI / 360.0) * (c.eye[2] - planeZ) / size;
}

/// A slab whose +z face (z = 8) faces a front camera, 80 wide.
Volume slab()
{
    Volume v(1.0);
    apply(v, CsgMode::Add, box(Vec3d(40.0, 40.0, 8.0)), at(Vec3d(0.0)));
    return v;
}

/// A white material named `name` with `texture` (none when empty) defined in `volume` and painted over
/// the whole slab; returns the material.
Material paintSlab(Volume& volume, const std::string& name, const std::string& texture)
{
    Material m;
    m.name = name;
    m.color = {1.0f, 1.0f, 1.0f, 1.0f};
    m.texture = texture;
    apply(volume, CsgMode::Paint, box(Vec3d(50.0, 50.0, 20.0)), at(Vec3d(0.0)), volume.materials().define(m));
    return m;
}

void requireNoValidationMessages(const VulkanContext& context)
{
    INFO("validation messages go to stderr");
    CHECK(context.validationMessages() == 0);
}

} // namespace

TEST_CASE("render: a sphere's silhouette matches its analytic projection within a pixel", "[render]")
{
    auto context = validatedContext();
    Volume volume(1.0);
    const double radius = 20.0;
    apply(volume, CsgMode::Add, sphere(radius), at(Vec3d(0.0)));
    Renderer renderer(*context);
    renderer.setMaterials(volume.materials());
    renderer.setChunk(1, meshVolume(volume, cmsOptions()));

    const int size = 96;
    OffscreenTarget target(*context, size, size);
    RenderView view;
    view.target = &target;
    view.camera.eye = {0.0, 0.0, 80.0};
    view.camera.target = {0.0, 0.0, 0.0};
    view.camera.fovYDegrees = 40.0;
    view.camera.nearPlane = 1.0;
    const FrameStats stats = renderer.render({view});
    CHECK(stats.chunksUploaded == 1);
    CHECK(stats.triangles > 1000);

    // The silhouette of a sphere at distance d is a circle of angular radius asin(r / d).
    const double tanHalf = std::tan(20.0 * M_PI / 180.0);
    const double edgePixels = std::tan(std::asin(radius / 80.0)) / tanHalf * size * 0.5;
    const std::vector<bool> covered = coverage(target);
    int mismatches = 0, checked = 0;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const double r = std::hypot(x + 0.5 - size * 0.5, y + 0.5 - size * 0.5);
            if (std::fabs(r - edgePixels) <= 1.0) continue;
            ++checked;
            if (covered[std::size_t(y * size + x)] != (r < edgePixels)) ++mismatches;
        }
    CHECK(checked > size * size * 3 / 4);
    CHECK(mismatches == 0);

    // Front faces face the camera: the normals view shows +z at the centre.
    ShadingOptions normals;
    normals.mode = ViewMode::Normals;
    renderer.setShading(normals);
    renderer.render({view});
    const Image image = target.colour();
    const uint8_t* centre = image.pixel(size / 2, size / 2);
    CHECK(centre[2] > 240);
    CHECK(std::abs(int(centre[0]) - 128) < 12);
    CHECK(std::abs(int(centre[1]) - 128) < 12);

    // The clay look reads the form: the face turned to the viewer is lit, the rim turned away is darker.
    ShadingOptions clay;
    clay.mode = ViewMode::Clay;
    renderer.setShading(clay);
    renderer.render({view});
    const Image clayImage = target.colour();
    const auto brightness = [&](int x, int y) {
        const uint8_t* p = clayImage.pixel(x, y);
        return int(p[0]) + int(p[1]) + int(p[2]);
    };
    const int rim = int(size * 0.5 + edgePixels * 0.92);
    INFO("clay: centre " << brightness(size / 2, size / 2) << ", near the rim " << brightness(rim, size / 2));
    CHECK(brightness(size / 2, size / 2) > brightness(rim, size / 2) + 60);
    CHECK(context->validationMessages() == 0);
}

TEST_CASE("render: a frame's depth tiles hold the farthest surface drawn in each, and hide a box behind it from the next selection", "[render][occlusion]")
{
    // The slab's +z face (z = 8, x and y within 40) seen from straight ahead of its right edge: the left
    // half of the picture is the face, 52 along the view, the right half nothing.
    auto context = validatedContext();
    const Volume volume = slab();
    Renderer renderer(*context);
    renderer.setMaterials(volume.materials());
    renderer.setChunk(1, meshVolume(volume, cmsOptions()));
    const int width = 128, height = 72, tile = 8;
    OffscreenTarget target(*context, width, height);
    RenderView view;
    view.target = &target;
    view.camera.eye = {40.0, 0.0, 60.0};
    view.camera.target = {40.0, 0.0, 0.0};
    view.camera.fovYDegrees = 50.0;
    view.camera.nearPlane = 1.0;
    renderer.render({view});
    const OccluderDepth depth = occluderDepthOf(target.depth(), width, height, view.camera, tile);
    REQUIRE(depth.columns() == width / tile);
    REQUIRE(depth.rows() == height / tile);
    // Tiles wholly left of the edge's column hold the face's distance; wholly right of it, nothing.
    const std::vector<float> pixels = target.depth();
    int face = 0, empty = 0;
    for (int r = 0; r < depth.rows(); ++r)
        for (int c = 0; c < depth.columns(); ++c) {
            // What the tile holds, read back through a box that fills it at the face's distance +- a hair.
            const double tanY = std::tan(25.0 * M_PI / 180.0), tanX = tanY * width / height;
            const double x0 = (2.0 * c / depth.columns() - 1.0) * tanX, x1 = (2.0 * (c + 1) / depth.columns() - 1.0) * tanX;
            const double y0 = (1.0 - 2.0 * (r + 1) / depth.rows()) * tanY, y1 = (1.0 - 2.0 * r / depth.rows()) * tanY;
            const auto boxAt = [&](double distance) {
                // The tile's pyramid at `distance`, shrunk a little so that it stays inside the tile.
                const double s = 0.98, cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
                const double hx = 0.5 * (x1 - x0) * s, hy = 0.5 * (y1 - y0) * s;
                return std::make_pair(std::array<double, 3>{40.0 + (cx - hx) * distance, (cy - hy) * distance, 60.0 - distance - 0.1},
                                      std::array<double, 3>{40.0 + (cx + hx) * distance, (cy + hy) * distance, 60.0 - distance});
            };
            bool anyDrawn = false, allDrawn = true;
            for (int y = r * tile; y < (r + 1) * tile; ++y)
                for (int x = c * tile; x < (c + 1) * tile; ++x) {
                    const bool drawn = pixels[std::size_t(y * width + x)] != kNothingDrawn;
                    anyDrawn = anyDrawn || drawn;
                    allDrawn = allDrawn && drawn;
                }
            const auto [nearLo, nearHi] = boxAt(51.5);
            const auto [farLo, farHi] = boxAt(53.0);
            if (allDrawn) {
                ++face;
                CHECK(!depth.hides(nearLo, nearHi)); // before the face
                CHECK(depth.hides(farLo, farHi));    // behind it
            } else if (!anyDrawn) {
                ++empty;
                CHECK(!depth.hides(farLo, farHi));
            }
        }
    CHECK(face >= depth.columns() * depth.rows() * 2 / 5);
    CHECK(empty >= depth.columns() * depth.rows() * 2 / 5);
    // A box behind the slab where it is drawn is hidden; one beyond its edge, or partly in front, is not.
    CHECK(depth.hides({10.0, -5.0, -20.0}, {20.0, 5.0, -10.0}));
    CHECK(!depth.hides({45.0, -5.0, -20.0}, {55.0, 5.0, -10.0}));
    CHECK(!depth.hides({10.0, -5.0, -20.0}, {20.0, 5.0, 10.0}));
    CHECK_THROWS_AS(occluderDepthOf(pixels, width + 1, height, view.camera), std::invalid_argument);
    CHECK_THROWS_AS(occluderDepthOf(pixels, width, height, view.camera, 0), std::invalid_argument);

    // The device's reduction (a view that keeps its depth) gives the same tiles as the pixels read back,
    // for a whole target and for a view in part of one (its tiles start at its viewport's corner).
    CHECK(renderer.drawnDepth() == nullptr);
    const auto sameTiles = [](const OccluderDepth& a, const OccluderDepth& b) {
        REQUIRE(a.columns() == b.columns());
        REQUIRE(a.rows() == b.rows());
        int differing = 0;
        for (int r = 0; r < a.rows(); ++r)
            for (int c = 0; c < a.columns(); ++c) differing += a.farthest(c, r) != b.farthest(c, r);
        CHECK(differing == 0);
    };
    view.keepDepth = true;
    renderer.render({view});
    REQUIRE(renderer.drawnDepth() != nullptr);
    sameTiles(*renderer.drawnDepth(), occluderDepthOf(target.depth(), width, height, view.camera));
    RenderView part = view;
    part.viewport = {40, 16, 60, 44}; // not whole tiles: the last row and column are narrower
    renderer.render({part});
    const std::vector<float> all = target.depth();
    std::vector<float> cropped;
    for (int y = 16; y < 60; ++y)
        for (int x = 40; x < 100; ++x) cropped.push_back(all[std::size_t(y * width + x)]);
    sameTiles(*renderer.drawnDepth(), occluderDepthOf(cropped, 60, 44, part.camera));
    CHECK(renderer.drawnDepth()->columns() == 8);
    // Two views of one frame keep their depths (a headset's eyes): the tiles are the first's, and a box is
    // hidden only where both views hide it.
    RenderView left = view, right = view;
    left.keepDepth = right.keepDepth = true;
    left.viewport = {0, 0, 64, 72};
    right.viewport = {64, 0, 64, 72};
    right.camera.eye = {0.0, 0.0, 60.0}; // the slab's face fills this one
    right.camera.target = {0.0, 0.0, 0.0};
    renderer.render({left, right});
    const std::vector<float> pair = target.depth();
    std::vector<float> leftPixels, rightPixels;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) (x < 64 ? leftPixels : rightPixels).push_back(pair[std::size_t(y * width + x)]);
    const OccluderDepth leftDepth = occluderDepthOf(leftPixels, 64, 72, left.camera), rightDepth = occluderDepthOf(rightPixels, 64, 72, right.camera);
    sameTiles(*renderer.drawnDepth(), leftDepth);
    int boxes = 0, hiddenInBoth = 0;
    for (double x = -30.0; x <= 70.0; x += 10.0)
        for (double z : {-20.0, 30.0}) {
            const std::array<double, 3> lo{x, -4.0, z}, hi{x + 6.0, 4.0, z + 6.0};
            const bool both = leftDepth.hides(lo, hi) && rightDepth.hides(lo, hi);
            CHECK(renderer.drawnDepth()->hides(lo, hi) == both);
            ++boxes;
            hiddenInBoth += both;
        }
    CHECK(hiddenInBoth > 0);
    CHECK(hiddenInBoth < boxes);
    // A frame with no view keeping its depth leaves the last one.
    const OccluderDepth* kept = renderer.drawnDepth().get();
    renderer.render({view = RenderView{view.camera, &target, {}, false}});
    CHECK(renderer.drawnDepth().get() == kept);
    requireNoValidationMessages(*context);
}

TEST_CASE("render: a store drawn with its last frame's depth as occluders leaves what lies behind a wall coarse, and draws the same picture", "[render][occlusion]")
{
    // A wall over the left of the view (x <= 10, its face 92 from the eye) with a ball behind it, and a
    // ball in sight beside it; fine enough a tolerance that every brick in sight is shown at level 0.
    auto context = validatedContext();
    TempDir dir;
    Volume volume(1.0);
    apply(volume, CsgMode::Add, box(Vec3d(105.0, 150.0, 4.0)), at(Vec3d(-95.0, 0.0, 4.0)));
    apply(volume, CsgMode::Add, sphere(12.0), at(Vec3d(-40.0, 20.0, -90.0)));
    apply(volume, CsgMode::Add, sphere(12.0), at(Vec3d(40.0, 20.0, -90.0)));
    const std::string path = dir.file("walled.vdbclay");
    writeStoreFile(volume, path);
    {
        SceneStore store = SceneStore::open(path, StoreAccess::ReadWrite);
        buildStoreLod(store, 2);
    }
    StreamingOptions streaming;
    streaming.memoryBudgetBytes = 256ull << 20;
    streaming.pixelTolerance = 0.2;
    StreamingScene scene(path, streaming);
    const int size = 128;
    Camera camera;
    camera.eye = {0.0, 0.0, 100.0};
    camera.target = {0.0, 0.0, 0.0};
    camera.fovYDegrees = 45.0;
    camera.nearPlane = 1.0;
    Viewer viewer;
    viewer.position = camera.eye;
    viewer.target = camera.target;
    viewer.fovDegrees = camera.fovYDegrees;
    viewer.viewport = {size, size};
    Renderer renderer(*context);
    renderer.setMaterials(scene.materials());
    ShadingOptions shading;
    shading.ambientOcclusion = false; // occlusion near a brick's edge depends on what else is resident
    renderer.setShading(shading);
    StreamedSceneChunks chunks;
    OffscreenTarget target(*context, size, size);
    const RenderView view{camera, &target, {}, true};
    const auto drawSettled = [&](const OccluderDepth* drawn) {
        FrameReport report;
        for (int i = 0; i < 50 && !(report.settled && report.pending == 0); ++i) {
            report = scene.frame(viewer, drawn);
            scene.waitForLoads();
        }
        chunks.sync(scene, renderer);
        while (renderer.render({view}).chunksWaitingUpload > 0) {
        }
        return report;
    };
    const FrameReport open = drawSettled(nullptr);
    const Image openPicture = target.colour();
    const std::vector<BrickKey> openBricks = scene.shownBricks();
    CHECK(open.hidden == 0);
    for (const BrickKey& key : openBricks) CHECK(key.level == 0);
    const std::shared_ptr<const OccluderDepth> drawn = renderer.drawnDepth();
    REQUIRE(drawn);
    const FrameReport walled = drawSettled(drawn.get());
    CHECK(walled.hidden > 0);
    const std::vector<BrickKey> walledBricks = scene.shownBricks();
    CHECK(walledBricks.size() < openBricks.size());
    // The ball behind the wall is shown coarse; the one in sight and the wall's face as before.
    const auto levelAt = [&](const std::vector<BrickKey>& shown, const std::array<int32_t, 3>& voxel) {
        for (const BrickKey& key : shown) {
            const int32_t edge = int32_t(kBrickEdge) << key.level;
            bool inside = true;
            for (int a = 0; a < 3; ++a) inside = inside && voxel[std::size_t(a)] >= key.brick[std::size_t(a)] * edge && voxel[std::size_t(a)] < (key.brick[std::size_t(a)] + 1) * edge;
            if (inside) return key.level;
        }
        return -1;
    };
    CHECK(levelAt(walledBricks, {-40, 20, -90}) > 0);
    CHECK(levelAt(walledBricks, {40, 20, -90}) == 0);
    CHECK(levelAt(walledBricks, {-40, 20, 8}) == 0);
    const Image walledPicture = target.colour();
    int differing = 0;
    for (std::size_t i = 0; i < openPicture.rgba.size(); i += 4) {
        int d = 0;
        for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(int(openPicture.rgba[i + c]) - int(walledPicture.rgba[i + c])));
        differing += d > 2;
    }
    INFO("pixels differing: " << differing);
    CHECK(differing <= size * size / 500);
    requireNoValidationMessages(*context);
}

TEST_CASE("render: a painted region shows its material's colour, the rest the default's", "[render]")
{
    auto context = validatedContext();
    Volume volume = slab();
    const MaterialId red = defineMaterial(volume, "red", 0.9f, {0.8f, 0.1f, 0.1f, 1.0f});
    // Paint the left half of the face (x < 0).
    apply(volume, CsgMode::Paint, box(Vec3d(40.0, 40.0, 20.0)), at(Vec3d(-40.0, 0.0, 0.0)), red);
    Renderer renderer(*context);
    uploadVolume(renderer, volume, cmsOptions());
    const int size = 64;
    OffscreenTarget target(*context, size, size);
    RenderView view{frontCamera(120.0), &target, {}};
    renderer.render({view});
    const Image image = target.colour();
    const Material& grey = volume.materials().at(1);
    const Material& paint = volume.materials().at(red);
    int checked[2] = {0, 0};
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const auto p = onPlane(view.camera, x, y, size, 8.0);
            if (std::fabs(p[0]) < 7.0 || std::fabs(p[0]) > 36.0 || std::fabs(p[1]) > 36.0) continue; // edges, the seam (blended 2.5 voxels each side)
            const Material& expected = p[0] < 0.0 ? paint : grey;
            const uint8_t* px = image.pixel(x, y);
            // Light, occlusion and texture scale every channel alike: the chromaticity is the material's.
            const double r = srgbToLinear(px[0]), g = srgbToLinear(px[1]), b = srgbToLinear(px[2]);
            const double sum = r + g + b, expectedSum = expected.color[0] + expected.color[1] + expected.color[2];
            INFO("pixel " << x << "," << y << " rgb " << int(px[0]) << " " << int(px[1]) << " " << int(px[2]));
            REQUIRE(sum > 0.01);
            CHECK(std::fabs(r / sum - expected.color[0] / expectedSum) < 0.03);
            CHECK(std::fabs(g / sum - expected.color[1] / expectedSum) < 0.03);
            ++checked[p[0] < 0.0];
        }
    CHECK(checked[0] > 300);
    CHECK(checked[1] > 300);

    // The clay look shows the form alone: painted or not, the face is one colour.
    ShadingOptions clay;
    clay.mode = ViewMode::Clay;
    renderer.setShading(clay);
    renderer.render({view});
    const Image c = target.colour();
    for (int k = 0; k < 3; ++k) CHECK(std::abs(int(c.pixel(size / 4, size / 2)[k]) - int(c.pixel(3 * size / 4, size / 2)[k])) <= 3);

    // The toughness view: red (0.9) is nearer red than blue, the default (0.5) between.
    ShadingOptions toughness;
    toughness.mode = ViewMode::Toughness;
    renderer.setShading(toughness);
    renderer.render({view});
    const Image t = target.colour();
    const uint8_t* hard = t.pixel(size / 4, size / 2);
    const uint8_t* soft = t.pixel(3 * size / 4, size / 2);
    CHECK(hard[0] > hard[2]);
    CHECK(int(hard[0]) - int(hard[2]) > int(soft[0]) - int(soft[2]));
    requireNoValidationMessages(*context);
}

namespace {

/// The slab's face with red painted on by `paintOp`, drawn flat (no occlusion) from the front, 256 pixels
/// for 120 units; and how red a pixel is, as a share of the way from the default material to the paint.
struct PaintedFace {
    Image image;
    Camera camera;
    static constexpr int size = 256;
    double redShare = 0.0, greyShare = 0.0;

    static double share(double r, double g, double b) { return r / (r + g + b); }
    /// The red channel's share of the pixel's linear colour.
    double redness(int x, int y) const
    {
        const uint8_t* px = image.pixel(x, y);
        return share(srgbToLinear(px[0]), srgbToLinear(px[1]), srgbToLinear(px[2]));
    }
    double wayTowardsPaint(int x, int y) const { return (redness(x, y) - greyShare) / (redShare - greyShare); }
};

PaintedFace paintedFace(VulkanContext& context, const std::string& paintOp)
{
    Volume volume = slab();
    runStrokeScript(volume, parseStrokeScript(R"({"materials": [{"name": "red", "color": [0.8, 0.1, 0.1]}], "ops": [)" + paintOp + "]}"));
    Renderer renderer(context);
    uploadVolume(renderer, volume, cmsOptions());
    ShadingOptions flat;
    flat.ambientOcclusion = false;
    renderer.setShading(flat);
    OffscreenTarget target(context, PaintedFace::size, PaintedFace::size);
    PaintedFace out;
    out.camera = frontCamera(120.0);
    renderer.render({RenderView{out.camera, &target, {}}});
    out.image = target.colour();
    const Material& paint = volume.materials().at(*volume.materials().find("red"));
    const Material& grey = volume.materials().at(1);
    out.redShare = PaintedFace::share(paint.color[0], paint.color[1], paint.color[2]);
    out.greyShare = PaintedFace::share(grey.color[0], grey.color[1], grey.color[2]);
    return out;
}

} // namespace

TEST_CASE("render: paint's boundary colour changes continuously across a soft stroke's edge, not in one-voxel steps", "[render][paint]")
{
    auto context = validatedContext();
    const PaintedFace face = paintedFace(
        *context, R"({"mode": "paint", "material": "red", "falloff": [0, 0.5, 1, 1, 1], "brush": {"shape": "sphere", "radius": 30}, "at": [0, 0, 8]})");
    const int size = PaintedFace::size;
    // Redness along rows through the stroke's middle, from its centre out past its rim: it falls from the
    // paint's to the default's in steps no larger than a quarter of the way (pixels are a third of a voxel
    // apart; painted voxels drawn in their own colour step all the way).
    double largestStep = 0.0;
    int rows = 0;
    for (int y = size / 2 - 8; y <= size / 2 + 8; y += 4, ++rows) {
        std::vector<double> along;
        for (int x = size / 2; x < size; ++x) {
            if (onPlane(face.camera, x, y, size, 8.0)[0] > 36.0) break;
            along.push_back(face.wayTowardsPaint(x, y));
        }
        REQUIRE(along.size() > 60);
        INFO("row " << y << ": centre " << along.front() << ", end " << along.back() << " of the way from the default to the paint");
        CHECK(std::fabs(along.front() - 1.0) < 0.1);
        CHECK(std::fabs(along.back()) < 0.1);
        for (std::size_t i = 1; i < along.size(); ++i) largestStep = std::max(largestStep, std::fabs(along[i] - along[i - 1]));
    }
    INFO("largest step between neighbouring pixels: " << largestStep << " of the way");
    CHECK(largestStep < 0.25);
    requireNoValidationMessages(*context);
}

TEST_CASE("render: a hard paint edge's colour changes continuously along the edge, not in a one-voxel sawtooth", "[render][paint]")
{
    // A hard paint stroke (each voxel wholly one material) whose edge, a circle of radius 30 on the face,
    // crosses the lattice at every angle: voxels drawn in their own colour would show its staircase.
    auto context = validatedContext();
    const PaintedFace face = paintedFace(*context, R"({"mode": "paint", "material": "red", "brush": {"shape": "sphere", "radius": 30}, "at": [-10.3, 0.4, 8]})");
    const int size = PaintedFace::size;
    // Row by row (pixels half a voxel apart), the pixel on the edge's right half, where the circle's
    // tangent turns from 45 degrees through vertical and back: its redness, as a share of the way.
    std::vector<double> onEdge;
    for (int y = 0; y < size; ++y) {
        int best = -1;
        double nearest = 1e9;
        for (int x = size / 2; x < size; ++x) {
            const auto p = onPlane(face.camera, x, y, size, 8.0);
            const double off = std::fabs(std::hypot(p[0] + 10.3, p[1] - 0.4) - 30.0);
            if (std::fabs(p[1] - 0.4) < 21.0 && off < nearest) nearest = off, best = x;
        }
        if (best >= 0 && nearest <= 0.5) onEdge.push_back(face.wayTowardsPaint(best, y));
    }
    REQUIRE(onEdge.size() > 70);
    double largestStep = 0.0, lowest = 1.0, highest = 0.0;
    for (std::size_t i = 0; i < onEdge.size(); ++i) {
        lowest = std::min(lowest, onEdge[i]);
        highest = std::max(highest, onEdge[i]);
        if (i > 0) largestStep = std::max(largestStep, std::fabs(onEdge[i] - onEdge[i - 1]));
    }
    INFO("along the edge: from " << lowest << " to " << highest << " of the way from the default to the paint, steps up to " << largestStep);
    // Voxels in their own colour give 0 and 1 here, a step all the way; blended, about 0.19 to 0.47, in
    // steps up to 0.15.
    CHECK(lowest > 0.1);
    CHECK(highest < 0.9);
    CHECK(largestStep < 0.2);
    requireNoValidationMessages(*context);
}

TEST_CASE("render: the brush highlight covers exactly the surface inside the brush, the preview draws the brush", "[render]")
{
    auto context = validatedContext();
    const Volume volume = slab();
    Renderer renderer(*context);
    uploadVolume(renderer, volume, cmsOptions());
    const int size = 80;
    OffscreenTarget target(*context, size, size);
    RenderView view{frontCamera(100.0), &target, {}};
    renderer.render({view});
    const Image plain = target.colour();

    BrushOverlay brush;
    brush.shape = BrushOverlay::Shape::Sphere;
    const double radius = 14.0;
    const std::array<double, 3> centre{6.0, -4.0, 10.0}; // 2 above the face: a disc of radius sqrt(14^2 - 2^2)
    brush.params = {float(radius), 0, 0, 0};
    brush.worldToLocal = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -float(centre[0]), -float(centre[1]), -float(centre[2]), 1};
    brush.preview = false;
    renderer.setBrush(brush);
    renderer.render({view});
    const Image lit = target.colour();
    const double pixel = pixelOnPlane(view.camera, size, 8.0);
    const double disc = std::sqrt(radius * radius - 2.0 * 2.0);
    int inside = 0, mismatches = 0;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const auto p = onPlane(view.camera, x, y, size, 8.0);
            if (std::fabs(p[0]) > 38.0 || std::fabs(p[1]) > 38.0) continue;
            const double r = std::hypot(p[0] - centre[0], p[1] - centre[1]);
            if (std::fabs(r - disc) < 1.5 * pixel) continue;
            const uint8_t *a = plain.pixel(x, y), *b = lit.pixel(x, y);
            const bool highlighted = std::abs(int(a[0]) - int(b[0])) + std::abs(int(a[1]) - int(b[1])) + std::abs(int(a[2]) - int(b[2])) > 30;
            inside += r < disc;
            mismatches += highlighted != (r < disc);
        }
    CHECK(inside > 200);
    CHECK(mismatches == 0);

    // The preview: the brush's upper cap pokes out of the face, so pixels over the disc change again.
    brush.preview = true;
    brush.highlight = false;
    brush.worldBoundsMin = {float(centre[0] - radius), float(centre[1] - radius), float(centre[2] - radius), 0};
    brush.worldBoundsMax = {float(centre[0] + radius), float(centre[1] + radius), float(centre[2] + radius), 0};
    renderer.setBrush(brush);
    renderer.render({view});
    const Image previewed = target.colour();
    int changedInside = 0, changedOutside = 0;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const auto p = onPlane(view.camera, x, y, size, 8.0);
            const double r = std::hypot(p[0] - centre[0], p[1] - centre[1]);
            const uint8_t *a = plain.pixel(x, y), *b = previewed.pixel(x, y);
            const bool changed = std::abs(int(a[0]) - int(b[0])) + std::abs(int(a[1]) - int(b[1])) + std::abs(int(a[2]) - int(b[2])) > 12;
            if (r < disc - 2.0 * pixel) changedInside += changed;
            if (r > radius * 1.3) changedOutside += changed;
        }
    CHECK(changedInside > 150);
    CHECK(changedOutside == 0);

    // Up close, the near plane a millionth of the way to the face (as the editor fits it there): the
    // preview's rays leave the eye exactly, so its disc is the same pixel for pixel (rays made from two
    // points by the eye came out in blocks of pixels).
    const std::array<double, 2> over{23.7, -17.3}; // off the axis: the eye's own coordinates are large
    RenderView close{frontCamera(11.0), &target, {}};
    close.camera.eye = {over[0], over[1], 11.0};
    close.camera.target = {over[0], over[1], 0.0};
    close.camera.nearPlane = 3e-6;
    renderer.setBrush(std::nullopt);
    renderer.render({close});
    const Image closePlain = target.colour();
    const std::array<double, 3> nearCentre{over[0] + 0.2, over[1] - 0.1, 8.5};
    const double nearRadius = 1.0, nearDisc = std::sqrt(nearRadius * nearRadius - 0.5 * 0.5);
    brush.params = {float(nearRadius), 0, 0, 0};
    brush.worldToLocal = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -float(nearCentre[0]), -float(nearCentre[1]), -float(nearCentre[2]), 1};
    brush.worldBoundsMin = {float(nearCentre[0] - nearRadius), float(nearCentre[1] - nearRadius), float(nearCentre[2] - nearRadius), 0};
    brush.worldBoundsMax = {float(nearCentre[0] + nearRadius), float(nearCentre[1] + nearRadius), float(nearCentre[2] + nearRadius), 0};
    renderer.setBrush(brush);
    renderer.render({close});
    const Image closePreviewed = target.colour();
    const double closePixel = pixelOnPlane(close.camera, size, 8.0);
    int closeInside = 0, closeMissed = 0, closeStray = 0, closeOutside = 0;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const auto p = onPlane(close.camera, x, y, size, 8.0); // relative to the eye's x and y
            const double r = std::hypot(over[0] + p[0] - nearCentre[0], over[1] + p[1] - nearCentre[1]);
            const uint8_t *a = closePlain.pixel(x, y), *b = closePreviewed.pixel(x, y);
            const bool changed = std::abs(int(a[0]) - int(b[0])) + std::abs(int(a[1]) - int(b[1])) + std::abs(int(a[2]) - int(b[2])) > 12;
            if (r < nearDisc - 2.0 * closePixel) ++closeInside, closeMissed += !changed;
            // Beyond the sphere's silhouette seen from the eye: 2.5 away, it spans asin(1 / 2.5) around its
            // centre, 1.31 on the face.
            if (r > 1.4) closeStray += changed, ++closeOutside;
        }
    CHECK(closeInside > 1000);
    CHECK(closeMissed == 0);
    CHECK(closeStray == 0);
    CHECK(closeOutside > 20);
    requireNoValidationMessages(*context);
}

TEST_CASE("render: two views of one frame (stereo) each see the scene, a thumbnail frames a mesh", "[render]")
{
    auto context = validatedContext();
    Volume volume(1.0);
    apply(volume, CsgMode::Add, sphere(10.0), at(Vec3d(0.0)));
    const Mesh mesh = meshVolume(volume, cmsOptions());
    Renderer renderer(*context);
    renderer.setChunk(7, mesh);
    OffscreenTarget target(*context, 96, 48);
    RenderView left{frontCamera(60.0), &target, {0, 0, 48, 48}};
    RenderView right{frontCamera(60.0), &target, {48, 0, 48, 48}};
    left.camera.eye[0] = -3.0;
    right.camera.eye[0] = 3.0;
    const FrameStats stats = renderer.render({left, right});
    CHECK(stats.triangles == 2 * mesh.triangleCount());
    const std::vector<bool> covered = coverage(target);
    int coveredHalves[2] = {0, 0};
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 96; ++x) coveredHalves[x >= 48] += covered[std::size_t(y * 96 + x)];
    CHECK(coveredHalves[0] > 200);
    CHECK(std::abs(coveredHalves[0] - coveredHalves[1]) < coveredHalves[0] / 10);

    ThumbnailOptions options;
    options.size = 48;
    options.transparentBackground = true;
    const Image thumb = renderThumbnail(*context, mesh, volume.materials(), options);
    REQUIRE(thumb.width == 48);
    int opaque = 0, touchesEdge = 0;
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 48; ++x) {
            const bool drawn = thumb.pixel(x, y)[3] == 255;
            opaque += drawn;
            if (drawn && (x == 0 || y == 0 || x == 47 || y == 47)) ++touchesEdge;
        }
    // Framed: the sphere fills much of the square and is not cut by its edges.
    CHECK(opaque > 48 * 48 / 3);
    CHECK(touchesEdge == 0);
    CHECK_THROWS_AS(renderThumbnail(*context, Mesh{}, volume.materials(), options), std::invalid_argument);
    requireNoValidationMessages(*context);
}

TEST_CASE("render: uploads happen once per new or changed chunk, removed and over-budget chunks free their memory", "[render]")
{
    auto context = validatedContext();
    Volume volume(1.0);
    apply(volume, CsgMode::Add, sphere(12.0), at(Vec3d(0.0)));
    const std::vector<MeshChunk> chunks = meshVolumeChunks(volume, cmsOptions());
    RendererOptions options;
    options.stagingBytes = 1 << 20;
    Renderer renderer(*context, options);
    uint64_t ids = 0;
    for (const MeshChunk& c : chunks)
        if (!c.mesh.triangles.empty()) renderer.setChunk(++ids, c.mesh);
    OffscreenTarget target(*context, 32, 32);
    RenderView view{frontCamera(60.0), &target, {}};
    FrameStats first = renderer.render({view});
    CHECK(first.chunksUploaded == ids);
    const uint64_t allBytes = first.gpuMemoryBytes;
    CHECK(allBytes >= first.uploadBytes);
    FrameStats second = renderer.render({view});
    CHECK(second.chunksUploaded == 0);
    CHECK(second.uploadBytes == 0);
    // Replace one, remove two: one upload, two frees, and the memory follows.
    renderer.setChunk(1, chunks[0].mesh.triangles.empty() ? chunks[1].mesh : chunks[0].mesh);
    renderer.removeChunk(2);
    renderer.removeChunk(3);
    FrameStats third = renderer.render({view});
    CHECK(third.chunksUploaded == 1);
    CHECK(third.chunksFreed == 2);
    CHECK(third.residentChunks == ids - 2);
    CHECK(third.gpuMemoryBytes < allBytes);
    for (uint64_t id = 1; id <= ids; ++id) renderer.removeChunk(id);
    FrameStats emptied = renderer.render({view});
    CHECK(emptied.gpuMemoryBytes == 0);
    CHECK(emptied.residentChunks == 0);

    // Over the GPU budget, chunks not drawn this frame go first (a camera facing away draws none).
    RendererOptions tight;
    tight.gpuBudgetBytes = allBytes / 3;
    Renderer budgeted(*context, tight);
    ids = 0;
    for (const MeshChunk& c : chunks)
        if (!c.mesh.triangles.empty()) budgeted.setChunk(++ids, c.mesh);
    RenderView away{frontCamera(60.0), &target, {}};
    away.camera.target = {0.0, 0.0, 120.0};
    const FrameStats s = budgeted.render({away});
    CHECK(s.chunksDrawn == 0);
    CHECK(s.gpuMemoryBytes <= tight.gpuBudgetBytes);
    CHECK(budgeted.takeEvicted().size() == s.chunksFreed);
    CHECK(s.chunksFreed > 0);
    requireNoValidationMessages(*context);
}

namespace {

/// An offscreen image drawn as a window's swapchain image is: nothing reads it back, so frames run on
/// while the next ones are recorded.
class PresentedTarget : public RenderTarget {
public:
    explicit PresentedTarget(OffscreenTarget& image) : image_(image) {}
    int width() const override { return image_.width(); }
    int height() const override { return image_.height(); }
    VkRenderPass renderPass() const override { return image_.renderPass(); }
    VkFramebuffer framebuffer() const override { return image_.framebuffer(); }

private:
    OffscreenTarget& image_;
};

} // namespace

TEST_CASE("render: frames in flight keep a replaced chunk's memory until the frames that may draw it end, then draw the new one", "[render]")
{
    auto context = validatedContext();
    Volume small(1.0), large(1.0);
    apply(small, CsgMode::Add, sphere(6.0), at(Vec3d(0.0)));
    apply(large, CsgMode::Add, sphere(10.0), at(Vec3d(0.0)));
    const Mesh before = meshVolume(small, cmsOptions()), after = meshVolume(large, cmsOptions());
    Renderer renderer(*context);
    OffscreenTarget image(*context, 48, 48);
    PresentedTarget presented(image);
    const RenderView view{frontCamera(60.0), &presented, {}};
    renderer.setChunk(1, before);
    const FrameStats first = renderer.render({view});
    REQUIRE(first.chunksUploaded == 1);
    const uint64_t beforeBytes = first.gpuMemoryBytes;
    CHECK(first.gpuBytesAwaitingFree == 0);

    // Replaced: the new mesh is resident at once, the old one's memory waits for the frames in flight
    // (this one and the one before) and returns when this frame's slot comes round again.
    renderer.setChunk(1, after);
    const FrameStats replaced = renderer.render({view});
    CHECK(replaced.chunksUploaded == 1);
    CHECK(replaced.residentChunks == 1);
    CHECK(replaced.gpuMemoryBytes > beforeBytes);
    CHECK(replaced.gpuBytesAwaitingFree == beforeBytes);
    CHECK(renderer.gpuMemoryBytes() == replaced.gpuMemoryBytes);
    const FrameStats next = renderer.render({view});
    CHECK(next.gpuBytesAwaitingFree == beforeBytes);
    const FrameStats settled = renderer.render({view});
    CHECK(settled.gpuBytesAwaitingFree == 0);
    CHECK(settled.gpuMemoryBytes == replaced.gpuMemoryBytes);

    // Removed while frames run on, then a readback: the picture is the new sphere's alone, and an empty
    // scene draws nothing once its memory is back.
    RenderView readBack{frontCamera(60.0), &image, {}};
    renderer.render({readBack});
    const double pixel = pixelOnPlane(readBack.camera, 48, 0.0);
    std::size_t covered = 0;
    for (bool c : coverage(image)) covered += c;
    CHECK(std::fabs(double(covered) - M_PI * std::pow(10.0 / pixel, 2.0)) < 0.15 * M_PI * std::pow(10.0 / pixel, 2.0));
    renderer.removeChunk(1);
    for (int frame = 0; frame < 3; ++frame) renderer.render({view});
    const FrameStats empty = renderer.render({readBack});
    CHECK(empty.gpuMemoryBytes == 0);
    CHECK(empty.gpuBytesAwaitingFree == 0);
    for (bool c : coverage(image)) CHECK_FALSE(c);
    requireNoValidationMessages(*context);
}

TEST_CASE("render: a frame uploads within its budget, oldest queued first, and while uploads wait no removal opens a hole", "[render]")
{
    auto context = validatedContext();
    Volume volume(1.0);
    apply(volume, CsgMode::Add, sphere(12.0), at(Vec3d(0.0)));
    std::vector<Mesh> left, right; // by the chunks' leaves, either side of x = 0
    for (const MeshChunk& c : meshVolumeChunks(volume, cmsOptions()))
        if (!c.mesh.triangles.empty()) (c.leafOrigin[0] < 0 ? left : right).push_back(c.mesh);
    REQUIRE(left.size() > 2);
    REQUIRE(right.size() > 2);
    uint64_t leftBytes = 0, allBytes = 0;
    for (const Mesh& m : left) leftBytes += packChunk(m, 0, {}).bytes.size();
    allBytes = leftBytes;
    for (const Mesh& m : right) allBytes += packChunk(m, 0, {}).bytes.size();

    RendererOptions options;
    options.uploadBytesPerFrame = leftBytes; // the left half fits a frame exactly
    Renderer renderer(*context, options);
    ChunkId next = 0;
    for (const Mesh& m : left) renderer.setChunk(++next, m);
    for (const Mesh& m : right) renderer.setChunk(++next, m);
    const ChunkId count = next;
    OffscreenTarget target(*context, 64, 64);
    const RenderView view{frontCamera(60.0), &target, {}};

    // The first frame takes the chunks queued first, as many as its budget holds: the left half alone.
    const FrameStats first = renderer.render({view});
    CHECK(first.uploadBytes == leftBytes);
    CHECK(first.chunksUploaded == left.size());
    CHECK(first.chunksWaitingUpload == right.size());
    CHECK(renderer.uploadsWaiting() == right.size());
    const std::vector<bool> leftOnly = coverage(target);
    int drawnLeft = 0, drawnRight = 0;
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x)
            if (leftOnly[std::size_t(y * 64 + x)]) ++(x < 32 ? drawnLeft : drawnRight);
    CHECK(drawnLeft > 100);
    CHECK(drawnRight < drawnLeft / 10);
    const FrameStats second = renderer.render({view});
    CHECK(second.chunksUploaded == right.size());
    CHECK(second.chunksWaitingUpload == 0);
    const std::vector<bool> whole = coverage(target);

    // The sphere handed over to new chunks a third of it per frame: the old ones are drawn until the
    // uploads are done, so every frame covers the sphere whole, and then the old ones go.
    RendererOptions third = options;
    third.uploadBytesPerFrame = allBytes / 3 + 1;
    Renderer handover(*context, third);
    for (ChunkId id = 1; id <= count; ++id) handover.setChunk(id, id <= left.size() ? left[id - 1] : right[id - 1 - left.size()]);
    handover.render({view});
    while (handover.uploadsWaiting() > 0) handover.render({view});
    for (ChunkId id = 1; id <= count; ++id) {
        handover.removeChunk(id);
        handover.setChunk(count + id, id <= left.size() ? left[id - 1] : right[id - 1 - left.size()]);
    }
    int frames = 0;
    uint64_t uploaded = 0, freed = 0;
    for (; frames < 10 && (frames == 0 || handover.uploadsWaiting() > 0 || freed < count); ++frames) {
        const FrameStats s = handover.render({view});
        uploaded += s.chunksUploaded;
        freed += s.chunksFreed;
        CHECK(s.uploadBytes <= third.uploadBytesPerFrame);
        CHECK(coverage(target) == whole);
    }
    CHECK(uploaded == count);
    CHECK(freed == count);
    CHECK(frames >= 3);
    CHECK(handover.chunkCount() == count);
    requireNoValidationMessages(*context);
}

TEST_CASE("render: a store streamed under a small budget draws what the .vdb draws at level 0, an edit re-uploads only its bricks", "[render]")
{
    auto context = validatedContext();
    TempDir dir;
    Volume volume = multiBrickScene();
    const std::string path = dir.file("scene.vdbclay");
    writeStoreFile(volume, path);
    {
        SceneStore store = SceneStore::open(path, StoreAccess::ReadWrite);
        buildStoreLod(store, 2);
    }
    const int size = 64;
    PictureRequest request;
    request.width = request.height = size;
    Camera camera;
    camera.eye = {90.0, 60.0, 110.0};
    camera.target = {0.0, 0.0, 0.0};
    camera.fovYDegrees = 45.0;
    request.camera = camera;
    request.pixelTolerance = 1e-3; // level 0 everywhere
    request.memoryBudgetBytes = 24ull << 20;
    request.shading.ambientOcclusion = false; // occlusion near a brick's edge depends on what else is resident
    const Picture fromStore = renderStore(*context, path, request);
    const Picture fromVolume = renderVolume(*context, volume, request);
    REQUIRE(fromStore.refined);
    CHECK(fromStore.stats.levelsShown == std::vector<int>{0});
    int differing = 0;
    for (std::size_t i = 0; i < fromStore.image.rgba.size(); i += 4) {
        int d = 0;
        for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(int(fromStore.image.rgba[i + c]) - int(fromVolume.image.rgba[i + c])));
        differing += d > 2;
    }
    CHECK(differing <= size * size / 200);

    // Sculpt one small stamp: only the bricks it changed are meshed and uploaded again.
    StreamingOptions streaming;
    streaming.memoryBudgetBytes = 64ull << 20;
    streaming.pixelTolerance = 1e-3;
    streaming.access = StoreAccess::ReadWrite;
    StreamingScene scene(path, streaming);
    Viewer viewer;
    viewer.position = camera.eye;
    viewer.target = camera.target;
    viewer.fovDegrees = camera.fovYDegrees;
    viewer.viewport = {size, size};
    FrameReport report;
    for (int i = 0; i < 50 && !(report.settled && report.pending == 0); ++i) {
        report = scene.frame(viewer);
        scene.waitForLoads();
    }
    Renderer renderer(*context);
    renderer.setMaterials(scene.materials());
    StreamedSceneChunks chunks;
    const auto firstSync = chunks.sync(scene, renderer);
    OffscreenTarget target(*context, size, size);
    const RenderView view{camera, &target, {}};
    const FrameStats before = renderer.render({view});
    CHECK(before.chunksUploaded <= firstSync.meshed); // bricks whose mesh is empty upload nothing
    CHECK(before.chunksUploaded > 0);
    REQUIRE(firstSync.shown > 4);

    // The meshes of the shown bricks before the edit, to count the ones it changes.
    std::map<BrickKey, Mesh> meshesBefore;
    for (const BrickKey& key : scene.shownBricks()) meshesBefore[key] = scene.meshBrick(key)->mesh.decoded();
    const StrokeScript stamp = parseStrokeScript(R"({"ops": [{"mode": "add", "brush": {"shape": "sphere", "radius": 3}, "at": [43, 25, 50]}]})");
    const StreamingScene::EditReport edit = scene.sculpt(stamp);
    REQUIRE(edit.bricksChanged >= 1);
    scene.frame(viewer);
    uint64_t meshesChanged = 0;
    for (const BrickKey& key : scene.shownBricks()) {
        const Mesh now = scene.meshBrick(key)->mesh.decoded();
        const Mesh& was = meshesBefore.at(key);
        meshesChanged += now.positions != was.positions || now.triangles != was.triangles || now.materials != was.materials;
    }
    const auto secondSync = chunks.sync(scene, renderer);
    const FrameStats after = renderer.render({view});
    // Only the bricks the stamp reaches (and neighbours whose meshes read its voxels) change; exactly
    // those are uploaded again.
    CHECK(meshesChanged >= edit.bricksChanged);
    CHECK(secondSync.uploaded == meshesChanged);
    CHECK(after.chunksUploaded == meshesChanged);
    CHECK(after.chunksUploaded < before.chunksUploaded);
    requireNoValidationMessages(*context);
}

namespace {

/// The multi-brick scene in a store with two levels of detail, opened for editing (a 64 MB budget, half a
/// pixel of error), and a 64x64 view of it from (90, 60, 110).
struct EditableStore {
    TempDir dir;
    std::string path = dir.file("scene.vdbclay");
    std::unique_ptr<StreamingScene> scene;
    Viewer viewer;

    EditableStore()
    {
        writeStoreFile(multiBrickScene(), path);
        {
            SceneStore store = SceneStore::open(path, StoreAccess::ReadWrite);
            buildStoreLod(store, 2);
        }
        StreamingOptions streaming;
        streaming.memoryBudgetBytes = 64ull << 20;
        streaming.pixelTolerance = 0.5;
        streaming.access = StoreAccess::ReadWrite;
        scene = std::make_unique<StreamingScene>(path, streaming);
        viewer.position = {90.0, 60.0, 110.0};
        viewer.fovDegrees = 45.0;
        viewer.viewport = {64, 64};
    }
    /// Frames (waiting for the loads) until the view is settled and nothing is pending.
    void settle()
    {
        FrameReport report;
        for (int i = 0; i < 50 && !(report.settled && report.pending == 0); ++i) {
            report = scene->frame(viewer);
            scene->waitForLoads();
        }
    }
    /// The height of the surface where four bricks meet (x = y = 0), found along +z; 0 when none.
    double topAtOrigin() const
    {
        const Volume fine = scene->residentLevel0();
        for (int32_t k = 400; k > 0; --k)
            if (fine.materialAt({0, 0, k}) != kEmptyMaterial) return k * fine.voxelSize();
        return 0.0;
    }
};

/// Shown bricks whose drawn chunk is missing or older than the brick.
std::size_t staleChunks(const StreamingScene& scene, const StreamedSceneChunks& chunks)
{
    std::size_t n = 0;
    for (const BrickKey& key : scene.shownBricks()) n += chunks.versionOf(key) != scene.brickVersion(key);
    return n;
}

} // namespace

TEST_CASE("render: a sync within a meshing budget meshes a brick a call, draws edited bricks with their old meshes meanwhile, and never opens a hole", "[render]")
{
    auto context = validatedContext();
    EditableStore store;
    StreamingScene& scene = *store.scene;
    Viewer& viewer = store.viewer;
    store.settle();
    Renderer renderer(*context);
    renderer.setMaterials(scene.materials());
    StreamedSceneChunks chunks;
    // Every shown brick where something was drawn before is drawn: by its own mesh, or by drawn bricks
    // overlapping it (standing in). Regions coming into view for the first time have nothing to keep.
    const auto covered = [&](const std::vector<BrickKey>& drawnBefore) {
        const std::vector<BrickKey> drawn = chunks.drawnBricks();
        for (const BrickKey& key : scene.shownBricks()) {
            if (chunks.chunkOf(key)) continue;
            if (std::none_of(drawnBefore.begin(), drawnBefore.end(), [&](const BrickKey& d) { return bricksOverlap(key, d); })) continue;
            if (std::none_of(drawn.begin(), drawn.end(), [&](const BrickKey& d) { return bricksOverlap(key, d); })) return false;
        }
        return true;
    };
    const auto stale = [&] { return staleChunks(scene, chunks); };
    // A budget of nothing: one brick a call, until every shown brick has its mesh.
    const std::size_t shown = scene.shownBricks().size();
    REQUIRE(shown > 4);
    std::size_t calls = 0;
    for (StreamedSceneChunks::SyncReport r; calls == 0 || r.waiting > 0; ++calls) {
        r = chunks.sync(scene, renderer, 0.0);
        CHECK(r.meshed == 1);
        CHECK(r.waiting + calls + 1 == shown);
    }
    CHECK(stale() == 0);

    // An edit: the bricks it changed keep their old meshes, drawn, until their turn.
    // On the surface where four bricks meet (x = y = 0), found along +z.
    const double top = store.topAtOrigin();
    REQUIRE(top > 0.0);
    const StreamingScene::EditReport edit = scene.sculpt(parseStrokeScript(
        nlohmann::json{{"ops", {{{"mode", "add"}, {"brush", {{"shape", "sphere"}, {"radius", 5}}}, {"at", {0.2, 0.3, top}}}}}}.dump()));
    REQUIRE(edit.bricksChanged >= 2);
    store.settle(); // the loads the edit's frame asks for land first: a load makes the meshes beside it stale
    std::size_t before = stale();
    REQUIRE(before >= 2);
    const std::vector<BrickKey> drawnBeforeEdit = chunks.drawnBricks();
    while (before > 0) {
        chunks.sync(scene, renderer, 0.0);
        CHECK(covered(drawnBeforeEdit));
        const std::size_t now = stale();
        CHECK(now + 1 == before);
        before = now;
    }

    // The view moves far off: coarse bricks replace fine ones, and the fine stand in until their
    // replacements are meshed.
    const std::vector<BrickKey> drawnNear = chunks.drawnBricks();
    viewer.position = {900.0, 600.0, 1100.0};
    store.settle();
    REQUIRE(stale() > 1);
    const std::vector<BrickKey> farShown = scene.shownBricks();
    CHECK(std::any_of(farShown.begin(), farShown.end(), [](const BrickKey& k) { return k.level > 0; })); // coarse bricks replace fine ones
    CHECK(std::any_of(drawnNear.begin(), drawnNear.end(), [](const BrickKey& k) { return k.level == 0; }));
    for (int i = 0; i < 200 && stale() > 0; ++i) {
        chunks.sync(scene, renderer, 0.0);
        CHECK(covered(drawnNear));
    }
    CHECK(stale() == 0);
    // Then only the shown bricks are drawn, as an unlimited sync draws them.
    const std::vector<BrickKey> drawn = chunks.drawnBricks(), nowShown = scene.shownBricks();
    CHECK(std::set<BrickKey>(drawn.begin(), drawn.end()) == std::set<BrickKey>(nowShown.begin(), nowShown.end()));
    requireNoValidationMessages(*context);
}

TEST_CASE("render: chunks meshed on workers upload only what is finished, keep every view covered meanwhile, and settle to the shown bricks' meshes", "[render][worker]")
{
    auto context = validatedContext();
    EditableStore store;
    StreamingScene& scene = *store.scene;
    store.settle();
    Renderer renderer(*context);
    renderer.setMaterials(scene.materials());
    StreamedSceneChunks chunks(scene, 1);
    const auto stale = [&] { return staleChunks(scene, chunks); };
    // The first sync only asks: nothing is meshed on this thread.
    const std::size_t shown = scene.shownBricks().size();
    REQUIRE(shown > 4);
    StreamedSceneChunks::SyncReport first = chunks.sync(scene, renderer);
    CHECK(first.meshed == 0);
    CHECK(first.waiting == shown);
    const auto settleMeshes = [&](const std::vector<BrickKey>& drawnBefore) {
        for (int i = 0; i < 100; ++i) {
            chunks.waitForMeshes();
            const StreamedSceneChunks::SyncReport r = chunks.sync(scene, renderer);
            // Wherever something was drawn before, something is drawn still.
            const std::vector<BrickKey> drawn = chunks.drawnBricks();
            for (const BrickKey& key : scene.shownBricks())
                if (std::any_of(drawnBefore.begin(), drawnBefore.end(), [&](const BrickKey& d) { return bricksOverlap(key, d); }))
                    CHECK(std::any_of(drawn.begin(), drawn.end(), [&](const BrickKey& d) { return bricksOverlap(key, d); }));
            if (r.waiting == 0) return;
        }
    };
    settleMeshes({});
    CHECK(stale() == 0);
    CHECK(chunks.meshesInProgress() == 0);

    // An edit: the bricks it changed are meshed again on the workers, and drawn with their old meshes meanwhile.
    const double top = store.topAtOrigin(); // on the surface where four bricks meet
    REQUIRE(top > 0.0);
    const StreamingScene::EditReport edit = scene.sculpt(parseStrokeScript(
        nlohmann::json{{"ops", {{{"mode", "add"}, {"brush", {{"shape", "sphere"}, {"radius", 5}}}, {"at", {0.2, 0.3, top}}}}}}.dump()));
    REQUIRE(edit.bricksChanged >= 2);
    scene.frame(store.viewer);
    REQUIRE(stale() >= 1);
    settleMeshes(chunks.drawnBricks());
    CHECK(stale() == 0);

    // The view moves far off: coarse bricks replace fine ones, which stand in until those are meshed.
    store.viewer.position = {900.0, 600.0, 1100.0};
    const std::vector<BrickKey> drawnNear = chunks.drawnBricks();
    store.settle();
    settleMeshes(drawnNear);
    CHECK(stale() == 0);
    const std::vector<BrickKey> drawn = chunks.drawnBricks(), nowShown = scene.shownBricks();
    CHECK(std::set<BrickKey>(drawn.begin(), drawn.end()) == std::set<BrickKey>(nowShown.begin(), nowShown.end()));
    CHECK(chunks.takeMeshFailures().empty());
    // Another scene is refused.
    StreamingScene other(store.path, StreamingOptions{});
    CHECK_THROWS_AS(chunks.sync(other, renderer), std::logic_error);
    requireNoValidationMessages(*context);
}

TEST_CASE("cli: render writes the picture it is asked for, bad arguments and a missing device fail cleanly", "[render][cli]")
{
    TempDir dir;
    REQUIRE(runCli(dir, "new s.vdb --shape sphere --size 6").exitCode == 0);
    const nlohmann::json j = parseJsonOutput(runCli(dir, "render s.vdb -o s.png --size 40x30 --view normals --json"));
    for (const char* key : {"triangles", "chunks", "levels_shown", "gpu_memory_bytes", "cpu_ms", "gpu_ms", "device"}) CHECK(j.contains(key));
    CHECK(j["triangles"].get<int>() > 100);
    const Image image = readImage(dir.file("s.png"));
    CHECK(image.width == 40);
    CHECK(image.height == 30);

    for (const char* bad : {"render s.vdb -o t.png --size 0x10", "render s.vdb -o t.png --size 10", "render s.vdb -o t.png --camera 1,2,3",
                            "render s.vdb -o t.png --view fancy", "render s.vdb -o t.obj", "render s.vdb -o t.png --frame 2",
                            "render s.vdb -o t.png --camera 1,1,1,1,1,1"}) {
        INFO(bad);
        const CommandResult r = runCli(dir, bad);
        CHECK(r.exitCode == 2);
        checkCleanFailure(r);
        CHECK_FALSE(std::filesystem::exists(dir.file("t.png")));
    }
    // No Vulkan driver at all: one line, exit 1, nothing written.
    ::setenv("VK_DRIVER_FILES", "/nonexistent/icd.json", 1);
    ::setenv("VK_ICD_FILENAMES", "/nonexistent/icd.json", 1);
    const CommandResult missing = runCli(dir, "render s.vdb -o v.png");
    ::unsetenv("VK_DRIVER_FILES");
    ::unsetenv("VK_ICD_FILENAMES");
    CHECK(missing.exitCode == 1);
    checkCleanFailure(missing);
    CHECK(std::count(missing.err.begin(), missing.err.end(), '\n') == 1);
    CHECK(missing.err.find("Vulkan") != std::string::npos);
    CHECK_FALSE(std::filesystem::exists(dir.file("v.png")));
}

TEST_CASE("render: a store shown at several levels at once has no crack pixels inside its silhouette", "[render]")
{
    auto context = validatedContext();
    TempDir dir;
    Volume volume(1.0);
    apply(volume, CsgMode::Add, box(Vec3d(150.0, 40.0, 150.0)), at(Vec3d(0.0, -40.0, 0.0)));
    apply(volume, CsgMode::Add, sphere(60.0), at(Vec3d(30.0, 10.0, -20.0)));
    const std::string path = dir.file("slab.vdbclay");
    writeStoreFile(volume, path);
    {
        SceneStore store = SceneStore::open(path, StoreAccess::ReadWrite);
        buildStoreLod(store, 3);
    }
    const int size = 96;
    PictureRequest request;
    request.width = request.height = size;
    Camera camera;
    camera.eye = {-170.0, 90.0, -170.0}; // near one corner: fine bricks there, coarse ones far away
    camera.target = {60.0, -20.0, 60.0};
    camera.fovYDegrees = 60.0;
    request.camera = camera;
    request.pixelTolerance = 2.0;
    request.shading.mode = ViewMode::Lod;
    const Picture mixed = renderStore(*context, path, request);
    INFO("levels shown: " << mixed.stats.levelsShown.size());
    REQUIRE(mixed.stats.levelsShown.size() >= 2);
    // The scene fills the view's lower part: inside the silhouette of the level-0 picture (pixels whose
    // 5x5 neighbourhood it covers), the mixed picture covers every pixel: no background shows through.
    request.pixelTolerance = 1e-3;
    request.memoryBudgetBytes = 256ull << 20;
    const Picture fine = renderStore(*context, path, request);
    REQUIRE(fine.stats.levelsShown == std::vector<int>{0});
    const uint8_t* bg = fine.image.pixel(0, 0); // the top-left corner sees the sky
    auto background = [&](const Image& im, int x, int y) {
        const uint8_t* p = im.pixel(x, y);
        return p[0] == bg[0] && p[1] == bg[1] && p[2] == bg[2];
    };
    int interior = 0, cracks = 0;
    for (int y = 2; y < size - 2; ++y)
        for (int x = 2; x < size - 2; ++x) {
            bool inside = true;
            for (int dy = -2; dy <= 2 && inside; ++dy)
                for (int dx = -2; dx <= 2 && inside; ++dx) inside = !background(fine.image, x + dx, y + dy);
            if (!inside) continue;
            ++interior;
            cracks += background(mixed.image, x, y);
        }
    CHECK(interior > size * size / 4);
    CHECK(cracks == 0);
    requireNoValidationMessages(*context);
}

TEST_CASE("cli: render pictures of a flight with lod inspect --frames", "[render][cli]")
{
    TempDir dir;
    REQUIRE(runCli(dir, "synth csg-stack --extent 96 --seed 3 -o c.vdbclay").exitCode == 0);
    REQUIRE(runCli(dir, "lod build c.vdbclay").exitCode == 0);
    nlohmann::json frames = nlohmann::json::array();
    for (int i = 0; i < 10; ++i) frames.push_back({{"position", {-60.0 + 4.0 * i, 40.0, -60.0}}, {"target", {48.0, 8.0, 48.0}}});
    writeText(dir.file("path.json"), nlohmann::json{{"fov_degrees", 60}, {"viewport", {320, 180}}, {"frames", frames}}.dump());
    const CommandResult r = runCli(dir, "lod inspect c.vdbclay --camera-path path.json --memory-budget 64 --frames shots --every 4 --view lod");
    INFO(r.err);
    REQUIRE(r.exitCode == 0);
    // Frames 0, 4 and 8, and the view once settled: pictures of the viewport's size.
    for (const char* name : {"frame-00000.png", "frame-00004.png", "frame-00008.png", "settled.png"}) {
        INFO(name);
        const Image image = readImage(dir.file(std::string("shots/") + name));
        CHECK(image.width == 320);
        CHECK(image.height == 180);
    }
    CHECK_FALSE(std::filesystem::exists(dir.file("shots/frame-00001.png")));
    const Image settled = readImage(dir.file("shots/settled.png"));
    std::set<uint32_t> colours;
    for (std::size_t i = 0; i < settled.rgba.size(); i += 4)
        colours.insert(uint32_t(settled.rgba[i]) << 16 | uint32_t(settled.rgba[i + 1]) << 8 | settled.rgba[i + 2]);
    CHECK(colours.size() > 20); // the scene, lit, over the background
    // Options that need --frames, and a folder that is a file.
    CHECK(runCli(dir, "lod inspect c.vdbclay --camera-path path.json --memory-budget 64 --every 2").exitCode == 2);
    writeText(dir.file("afile"), "x");
    CHECK(runCli(dir, "lod inspect c.vdbclay --camera-path path.json --memory-budget 64 --frames afile").exitCode == 2);
}

TEST_CASE("render: a triangle shows its own material, whatever its corners carry", "[render]")
{
    auto context = validatedContext();
    MaterialTable table;
    Material red;
    red.name = "red";
    red.color = {0.9f, 0.05f, 0.05f, 1.0f};
    const MaterialId redId = table.define(red);
    // Two triangles facing +z over the view; every corner says "default", the second triangle says red.
    Mesh mesh;
    mesh.positions = {{-10, -10, 0}, {10, -10, 0}, {10, 10, 0}, {-10, 10, 0}};
    mesh.normals.assign(4, {0, 0, 1});
    mesh.materials.assign(4, 1);
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
    mesh.triangleMaterials = {1, redId};
    Renderer renderer(*context);
    renderer.setMaterials(table);
    renderer.setChunk(1, mesh);
    OffscreenTarget target(*context, 32, 32);
    renderer.render({RenderView{frontCamera(20.0, 60.0), &target, {}}});
    const Image image = target.colour();
    const uint8_t* lowerRight = image.pixel(26, 26); // first triangle: below the diagonal
    const uint8_t* upperLeft = image.pixel(5, 5);    // second triangle
    CHECK(upperLeft[0] > 3 * int(upperLeft[1]));
    CHECK(std::abs(int(lowerRight[0]) - int(lowerRight[1])) < 12);
    requireNoValidationMessages(*context);
}

TEST_CASE("render: a material's picture lands where the tri-planar projection puts it, an unreadable one is reported", "[render]")
{
    TempDir dir;
    // A checker of 8 x 8 squares, red and blue: one repetition covers 32 voxels, a square 4.
    Image checker;
    checker.width = checker.height = 64;
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x) {
            const bool red = ((x / 8) + (y / 8)) % 2 == 0;
            checker.rgba.insert(checker.rgba.end(), {uint8_t(red ? 230 : 30), 30, uint8_t(red ? 30 : 230), 255});
        }
    writePng(checker, dir.file("checker.png"));

    auto context = validatedContext();
    Volume volume = slab();
    const Material tiled = paintSlab(volume, "tiled", "checker.png"); // relative: from the scene's folder
    CHECK(MaterialTable::fromJson(volume.materials().toJson()) == volume.materials()); // saved with the scene

    Renderer renderer(*context);
    const VolumeUpload upload = uploadVolume(renderer, volume, cmsOptions(), materialLook(1.0, dir.path().string()));
    CHECK(upload.warnings.empty());
    const int size = 256;
    OffscreenTarget target(*context, size, size);
    const RenderView view{frontCamera(120.0), &target, {}};
    renderer.render({view});
    const Image image = target.colour();
    int checked = 0, reds = 0;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const auto p = onPlane(view.camera, x, y, size, 8.0);
            if (std::fabs(p[0]) > 36.0 || std::fabs(p[1]) > 36.0) continue;
            // The face looks along +z: the picture is projected on xy, texel (x, y) / 32 of a repetition.
            const double sx = p[0] / 4.0, sy = p[1] / 4.0;
            const double border = std::min(std::fabs(sx - std::round(sx)), std::fabs(sy - std::round(sy)));
            if (border < 0.3) continue; // filtering (trilinear, between mipmaps) blends across a square's border
            const bool red = (int64_t(std::floor(sx)) + int64_t(std::floor(sy))) % 2 == 0;
            const uint8_t* px = image.pixel(x, y);
            INFO("pixel " << x << "," << y << " at " << p[0] << "," << p[1] << " rgb " << int(px[0]) << " " << int(px[1]) << " " << int(px[2]));
            if (red) CHECK(px[0] > 2 * px[2]);
            else CHECK(px[2] > 2 * px[0]);
            ++checked;
            reds += red;
        }
    CHECK(checked > 4000);
    CHECK(reds > checked / 3);
    CHECK(reds < 2 * checked / 3);

    // A picture that cannot be read: one message naming it; the material keeps its procedural pattern.
    Material missing = tiled;
    missing.texture = "no-such-picture.png";
    volume.materials().define(missing);
    Renderer second(*context);
    const VolumeUpload without = uploadVolume(second, volume, cmsOptions(), materialLook(1.0, dir.path().string()));
    REQUIRE(without.warnings.size() == 1);
    CHECK(without.warnings[0].find("no-such-picture.png") != std::string::npos);
    second.render({view});
    const Image plain = target.colour();
    const uint8_t* centre = plain.pixel(size / 2, size / 2);
    CHECK(std::abs(int(centre[0]) - int(centre[2])) < 8); // white, not red or blue
    requireNoValidationMessages(*context);
}

namespace {

/// The picture's pixels that differ from its top-left corner (the background there), and whether any
/// of them lies on the picture's border (the scene cut off by the frame).
struct Foreground {
    int pixels = 0;
    bool touchesBorder = false;
};

Foreground foreground(const Image& image)
{
    const uint8_t* bg = image.pixel(0, 0);
    Foreground f;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            const uint8_t* p = image.pixel(x, y);
            if (p[0] == bg[0] && p[1] == bg[1] && p[2] == bg[2]) continue;
            ++f.pixels;
            f.touchesBorder = f.touchesBorder || x == 0 || y == 0 || x == image.width - 1 || y == image.height - 1;
        }
    return f;
}

/// A palette PNG of `indices` (one row) whose palette holds `palette` (RGB) entries only.
std::string palettePng(const std::vector<uint8_t>& palette, const std::vector<uint8_t>& indices)
{
    std::string png("\x89PNG\r\n\x1a\n", 8);
    const auto chunk = [&](const std::string& type, const std::string& data) {
        const uint32_t length = uint32_t(data.size());
        for (int s = 24; s >= 0; s -= 8) png.push_back(char((length >> s) & 0xFF));
        const std::string body = type + data;
        png += body;
        const uint32_t crc = uint32_t(crc32(0L, reinterpret_cast<const Bytef*>(body.data()), uInt(body.size())));
        for (int s = 24; s >= 0; s -= 8) png.push_back(char((crc >> s) & 0xFF));
    };
    std::string header;
    for (uint32_t v : {uint32_t(indices.size()), uint32_t(1)})
        for (int s = 24; s >= 0; s -= 8) header.push_back(char((v >> s) & 0xFF));
    header += std::string("\x08\x03\x00\x00\x00", 5); // 8 bits, palette, no interlace
    chunk("IHDR", header);
    chunk("PLTE", std::string(palette.begin(), palette.end()));
    std::string raw(1, '\0'); // the row's filter: none
    raw.append(indices.begin(), indices.end());
    std::vector<Bytef> packed(compressBound(uLong(raw.size())));
    uLongf packedSize = uLongf(packed.size());
    REQUIRE(compress(packed.data(), &packedSize, reinterpret_cast<const Bytef*>(raw.data()), uLong(raw.size())) == Z_OK);
    chunk("IDAT", std::string(packed.begin(), packed.begin() + std::ptrdiff_t(packedSize)));
    chunk("IEND", "");
    return png;
}

} // namespace

TEST_CASE("render: a camera looking straight along Y draws the scene, and a degenerate up gives way to one that is not", "[render][cli]")
{
    // The view direction and its up: a usable up is never along the view.
    Camera down;
    down.eye = {0, 50, 0};
    down.target = {0, 0, 0};
    CHECK(usableUp(down) == std::array<double, 3>{0, 0, -1});
    Camera up = down;
    up.eye = {0, -50, 0};
    CHECK(usableUp(up) == std::array<double, 3>{0, 0, 1});
    Camera tilted = down;
    tilted.up = {1, 0, 0};
    CHECK(usableUp(tilted) == tilted.up);
    Camera zero;
    zero.up = {0, 0, 0};
    CHECK(usableUp(zero) == std::array<double, 3>{0, 1, 0});

    TempDir dir;
    REQUIRE(runCli(dir, "new s.vdb --shape sphere --size 12").exitCode == 0);
    for (const char* camera : {"0,60,0,0,0,0", "0,-60,0,0,0,0", "0,60,0,0,-5,0"}) {
        INFO(camera);
        REQUIRE(runCli(dir, std::string("render s.vdb -o top.png --size 120x90 --camera ") + camera).exitCode == 0);
        const Foreground f = foreground(readImage(dir.file("top.png")));
        CHECK(f.pixels > 120 * 90 / 10);
        CHECK_FALSE(f.touchesBorder);
    }
}

TEST_CASE("render: the default view frames the content whole: a one-voxel scene, a small sphere in a store as in its .vdb", "[render][cli]")
{
    TempDir dir;
    REQUIRE(runCli(dir, "new one.vdb --shape box --size 0.5").exitCode == 0);
    REQUIRE(runCli(dir, "render one.vdb -o one.png --size 160x120").exitCode == 0);
    const Foreground one = foreground(readImage(dir.file("one.png")));
    CHECK(one.pixels > 160 * 120 / 8);
    CHECK_FALSE(one.touchesBorder);

    REQUIRE(runCli(dir, "new small.vdb --shape sphere --size 6").exitCode == 0);
    REQUIRE(runCli(dir, "import small.vdb -o small.vdbclay").exitCode == 0);
    REQUIRE(runCli(dir, "render small.vdb -o from-vdb.png --size 160x120").exitCode == 0);
    REQUIRE(runCli(dir, "render small.vdbclay -o from-store.png --size 160x120").exitCode == 0);
    const Foreground vdb = foreground(readImage(dir.file("from-vdb.png"))), store = foreground(readImage(dir.file("from-store.png")));
    CHECK_FALSE(store.touchesBorder);
    CHECK(std::abs(store.pixels - vdb.pixels) < vdb.pixels / 10);
}

TEST_CASE("render: pictures are read from regular files only, and a palette's missing entries read one colour", "[render]")
{
    TempDir dir;
    REQUIRE(::mkfifo(dir.file("pipe.png").c_str(), 0644) == 0);
    CHECK_THROWS_WITH(readImage(dir.file("pipe.png")), Catch::Contains("not a regular file"));
    CHECK_THROWS_WITH(readImage("/dev/zero"), Catch::Contains("not a regular file"));
    // Index 0 is red; 1 and 200 name no entry: opaque black, the same each time it is read.
    writeText(dir.file("palette.png"), palettePng({255, 0, 0}, {0, 1, 200}));
    for (int read = 0; read < 2; ++read) {
        const Image image = readImage(dir.file("palette.png"));
        REQUIRE(image.width == 3);
        CHECK(std::vector<uint8_t>(image.pixel(0, 0), image.pixel(0, 0) + 4) == std::vector<uint8_t>{255, 0, 0, 255});
        CHECK(std::vector<uint8_t>(image.pixel(1, 0), image.pixel(1, 0) + 4) == std::vector<uint8_t>{0, 0, 0, 255});
        CHECK(std::vector<uint8_t>(image.pixel(2, 0), image.pixel(2, 0) + 4) == std::vector<uint8_t>{0, 0, 0, 255});
    }
    // A full palette is left as it is.
    std::string full = palettePng(std::vector<uint8_t>(768, 7), {0, 1, 200});
    const std::string copy = full;
    padPngPalette(full);
    CHECK(full == copy);
}

TEST_CASE("render: a flight's pictures mesh apart from the scene: its resident bytes stay its own", "[render]")
{
    TempDir dir;
    const std::string path = dir.file("t.vdbclay");
    REQUIRE(runCli(dir, "synth terrain --extent 128 --seed 3 -o t.vdbclay").exitCode == 0);
    StreamingOptions options;
    options.memoryBudgetBytes = 64ull << 20;
    StreamingScene scene(path, options);
    Viewer viewer;
    viewer.position = {-40, 120, -40};
    viewer.target = {64, 10, 64};
    viewer.viewport = {320, 240};
    FrameReport report;
    for (int i = 0; i < 50 && !(report.settled && report.pending == 0); ++i) {
        report = scene.frame(viewer);
        scene.waitForLoads();
    }
    const uint64_t resident = scene.frame(viewer).residentBytes;
    auto context = validatedContext();
    Renderer renderer(*context);
    StreamedSceneChunks apart(StreamedSceneChunks::Meshes::Apart);
    CHECK(apart.sync(scene, renderer).uploaded > 0);
    CHECK(scene.frame(viewer).residentBytes == resident);
    // Kept by the scene, the meshes count against its budget.
    Renderer kept(*context);
    StreamedSceneChunks inScene;
    inScene.sync(scene, kept);
    CHECK(scene.frame(viewer).residentBytes > resident);
    requireNoValidationMessages(*context);
}

TEST_CASE("render: a headless edit's screenshot draws a material defined in the session with its picture, saved or not", "[render][editor][cli]")
{
    TempDir dir;
    Image red;
    red.width = red.height = 8;
    for (int i = 0; i < 64; ++i) red.rgba.insert(red.rgba.end(), {230, 20, 20, 255});
    writePng(red, dir.file("red.png"));
    REQUIRE(runCli(dir, "new ball.vdb --shape sphere --size 16").exitCode == 0);
    writeText(dir.file("s.json"), R"({"vdbclay_session": 1, "viewport": [160, 120], "commands": [
        {"frame": 0, "command": "material", "material": {"name": "brick", "color": [1, 1, 1], "texture": "red.png"}},
        {"frame": 0, "command": "brush", "brush": {"mode": "paint", "radius": 40, "material": "brick", "strength": 1, "falloff": "constant"}},
        {"frame": 1, "command": "stroke_begin", "point": [0, 16, 0]},
        {"frame": 2, "command": "stroke_end"}]})");
    REQUIRE(runCli(dir, "edit ball.vdb --replay s.json --headless --screenshot unsaved.png").exitCode == 0);
    REQUIRE(runCli(dir, "edit ball.vdb --replay s.json --headless --screenshot saved.png -o out.vdb").exitCode == 0);
    const Image unsaved = readImage(dir.file("unsaved.png")), saved = readImage(dir.file("saved.png"));
    const uint8_t* centre = unsaved.pixel(80, 60);
    INFO("centre " << int(centre[0]) << " " << int(centre[1]) << " " << int(centre[2]));
    CHECK(centre[0] > 2 * centre[1]); // the picture's red, not black
    int differing = 0;
    for (int y = 0; y < 120; ++y)
        for (int x = 0; x < 160; ++x)
            for (int c = 0; c < 3; ++c) differing += std::abs(int(unsaved.pixel(x, y)[c]) - int(saved.pixel(x, y)[c])) > 2;
    CHECK(differing < 160 * 120 / 100);
}

TEST_CASE("render: the masked surface shows darkened in the editor's picture, the rest as it was", "[render][editor][mask]")
{
    TempDir dir;
    REQUIRE(runCli(dir, "new ball.vdb --shape sphere --size 16").exitCode == 0);
    const std::string head = R"({"vdbclay_session": 1, "viewport": [160, 120], "commands": [
        {"frame": 0, "command": "camera", "eye": [0, 0, 70], "target": [0, 0, 0], "up": [0, 1, 0], "fov": 40},
        {"frame": 0, "command": "brush", "brush": {"mode": "mask", "radius": 3}})";
    writeText(dir.file("plain.json"), head + R"(]})");
    writeText(dir.file("masked.json"), head + R"(,
        {"frame": 1, "command": "stroke_begin", "point": [0, 0, 16]},
        {"frame": 2, "command": "stroke_end"}]})");
    REQUIRE(runCli(dir, "edit ball.vdb --replay plain.json --headless --screenshot plain.png").exitCode == 0);
    REQUIRE(runCli(dir, "edit ball.vdb --replay masked.json --headless --screenshot masked.png").exitCode == 0);
    const Image plain = readImage(dir.file("plain.png")), masked = readImage(dir.file("masked.png"));
    const auto luminance = [](const Image& image, int x, int y) {
        const uint8_t* p = image.pixel(x, y);
        return srgbToLinear(p[0]) + srgbToLinear(p[1]) + srgbToLinear(p[2]);
    };
    // The ball (radius 16) shows about 37 pixels wide from its centre, the mask (radius 3 about its front)
    // about 9: the centre is darker by the mask's shade, the rest of the ball untouched.
    const double centrePlain = luminance(plain, 80, 60), centreMasked = luminance(masked, 80, 60);
    INFO("centre luminance " << centrePlain << " -> " << centreMasked);
    CHECK(centrePlain > 0.05);
    CHECK(centreMasked < 0.5 * centrePlain);
    CHECK(centreMasked > 0.2 * centrePlain);
    int rimDiffering = 0, rimSeen = 0;
    for (int y = 0; y < 120; ++y)
        for (int x = 0; x < 160; ++x) {
            const double r = std::hypot(x - 79.5, y - 59.5);
            if (r < 20.0 || luminance(plain, x, y) < 0.02) continue; // near the mask, or the background
            ++rimSeen;
            rimDiffering += std::fabs(luminance(plain, x, y) - luminance(masked, x, y)) > 0.02;
        }
    CHECK(rimSeen > 100);
    CHECK(rimDiffering == 0);

    // `render` shows a masked scene's mask the same way, from a .vdb and from a store.
    writeText(dir.file("mask.json"), R"({"ops": [{"mode": "mask", "brush": {"shape": "sphere", "radius": 3}, "at": [0, 0, 16]}]})");
    REQUIRE(runCli(dir, "sculpt ball.vdb mask.json -o masked.vdb").exitCode == 0);
    REQUIRE(runCli(dir, "import masked.vdb -o masked.vdbclay").exitCode == 0);
    for (const char* scene : {"ball.vdb", "masked.vdb", "masked.vdbclay"})
        REQUIRE(runCli(dir, std::string("render ") + scene + " -o " + scene + ".png --size 160x120 --camera 0,0,70,0,0,0,40").exitCode == 0);
    const Image renderedPlain = readImage(dir.file("ball.vdb.png"));
    for (const char* scene : {"masked.vdb.png", "masked.vdbclay.png"}) {
        INFO(scene);
        const double centre = luminance(readImage(dir.file(scene)), 80, 60), plainCentre = luminance(renderedPlain, 80, 60);
        CHECK(centre < 0.5 * plainCentre);
        CHECK(std::fabs(luminance(readImage(dir.file(scene)), 80, 30) - luminance(renderedPlain, 80, 30)) < 0.02);
    }
}

TEST_CASE("render: a window's pictures load on a worker: procedural until ready, then the picture", "[render]")
{
    TempDir dir;
    Image red;
    red.width = red.height = 2048; // large enough that reading it takes a while
    red.rgba.reserve(std::size_t(2048) * 2048 * 4);
    for (int i = 0; i < 2048 * 2048; ++i) red.rgba.insert(red.rgba.end(), {uint8_t(200 + i % 31), 20, 20, 255});
    writePng(red, dir.file("red.png"));
    auto context = validatedContext();
    Volume volume = slab();
    Material pictured = paintSlab(volume, "pictured", "");
    Renderer renderer(*context);
    const MaterialLook look = materialLook(1.0, dir.path().string());
    uploadVolume(renderer, volume, cmsOptions(), look); // no picture yet
    pictured.texture = "red.png"; // then the material is given one, as a session's material command does
    volume.materials().define(pictured);
    const int size = 64;
    OffscreenTarget target(*context, size, size);
    const RenderView view{frontCamera(120.0), &target, {}};
    const auto centreIsRed = [&] {
        renderer.render({view});
        const uint8_t* p = target.colour().pixel(size / 2, size / 2);
        return p[0] > 2 * p[2] && p[0] > 2 * p[1];
    };
    // Asked for in the background, the call returns at once: the first frame has no picture yet.
    const auto start = std::chrono::steady_clock::now();
    CHECK(renderer.setMaterials(volume.materials(), look, Renderer::PictureLoading::Background).empty());
    if (!renderer.picturesReady()) CHECK_FALSE(centreIsRed());
    while (!renderer.picturesReady() && std::chrono::steady_clock::now() - start < std::chrono::seconds(60))
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    REQUIRE(renderer.picturesReady());
    CHECK(renderer.setMaterials(volume.materials(), look, Renderer::PictureLoading::Background).empty());
    CHECK_FALSE(renderer.picturesReady());
    CHECK(centreIsRed());
    requireNoValidationMessages(*context);
}

TEST_CASE("octahedral vertex normals fold back as mesh.vert unfolds them, within 1e-4 radian", "[mesh][normals]")
{
    // mesh.vert's unfoldNormal, step for step.
    const auto unfold = [](const std::array<int16_t, 2>& e) {
        double n[3] = {std::max(e[0] / 32767.0, -1.0), std::max(e[1] / 32767.0, -1.0), 0.0};
        n[2] = 1.0 - std::fabs(n[0]) - std::fabs(n[1]);
        const double t = std::max(-n[2], 0.0);
        n[0] += n[0] >= 0.0 ? -t : t;
        n[1] += n[1] >= 0.0 ? -t : t;
        const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        return std::array<double, 3>{n[0] / length, n[1] / length, n[2] / length};
    };
    std::vector<std::array<float, 3>> normals;
    // The axes, the octahedron's edges and the folds' diagonals, then random directions.
    for (int a = 0; a < 3; ++a)
        for (const float s : {-1.0f, 1.0f}) {
            std::array<float, 3> n{0.0f, 0.0f, 0.0f};
            n[std::size_t(a)] = s;
            normals.push_back(n);
            std::array<float, 3> edge{0.7071068f, 0.7071068f, 0.7071068f};
            edge[std::size_t(a)] = 0.0f;
            edge[std::size_t((a + 1) % 3)] *= s;
            normals.push_back(edge);
        }
    std::mt19937 rng(8);
    std::normal_distribution<float> g;
    for (int i = 0; i < 20000; ++i) {
        std::array<float, 3> n{g(rng), g(rng), g(rng)};
        const float length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (length < 1e-6f) continue;
        for (float& c : n) c /= length;
        normals.push_back(n);
    }
    double worst = 0.0;
    for (const auto& n : normals) {
        const std::array<double, 3> b = unfold(render::octahedralNormal(n));
        // The angle from its sine and cosine: acos alone loses it near 0 (a float normal's length is 1
        // to within 1e-7, which acos turns into 5e-4 radian).
        const double cross[3] = {b[1] * n[2] - b[2] * n[1], b[2] * n[0] - b[0] * n[2], b[0] * n[1] - b[1] * n[0]};
        const double sine = std::sqrt(cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]);
        worst = std::max(worst, std::atan2(sine, b[0] * n[0] + b[1] * n[1] + b[2] * n[2]));
    }
    INFO("worst angle " << worst << " radian");
    CHECK(worst < 1e-4);
    // A mesh without normals draws them as +z, not as an undefined direction.
    const std::array<double, 3> none = unfold(render::octahedralNormal({0.0f, 0.0f, 0.0f}));
    CHECK(none[2] == 1.0);
}
