// The Vulkan renderer, offscreen on whatever device there is (lavapipe in CI) with the Khronos
// validation layer on: every test ends with zero validation messages. Each property is measured on the
// picture: silhouettes against their analytic projection, colours against the material table, the
// brush highlight against the brush's field, uploads and frees counted.
#include "mesher/Mesher.h"
#include "render/Framing.h"
#include "render/ImageFile.h"
#include "render/OffscreenTarget.h"
#include "render/Renderer.h"
#include "render/Thumbnail.h"
#include "render/VulkanContext.h"
#include "support/Sculpt.h"
#include "support/TestUtil.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <memory>

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
    for (std::size_t i = 0; i < depth.size(); ++i) covered[i] = depth[i] < 1.0f;
    return covered;
}

double srgbToLinear(uint8_t v) { return std::pow(double(v) / 255.0, 2.2); }

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
    view.camera.farPlane = 200.0;
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
    CHECK(context->validationMessages() == 0);
}
