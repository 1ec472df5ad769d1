// What the renderer draws and reports, in plain structs: cameras and views, display modes, the brush
// overlay, per-frame figures. Light header: no Vulkan, no OpenVDB.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace vdbclay::render {

using Vec3f = std::array<float, 3>;

/// A pinhole camera in world units, looking from `eye` at `target`, +Y up unless `up` says otherwise.
/// The largest picture or viewport side drawn, in pixels (render --size, a session's viewport).
constexpr int kMaxViewportSide = 8192;

struct Camera {
    std::array<double, 3> eye{0.0, 0.0, 5.0};
    std::array<double, 3> target{0.0, 0.0, 0.0};
    std::array<double, 3> up{0.0, 1.0, 0.0};
    double fovYDegrees = 45.0;
    /// World units. Depth is reversed (1 at the near plane, 0 at infinity) and there is no far plane, so
    /// a view never cuts what lies far away, and the near plane may sit a hair from the eye
    /// (fitNearPlane) without losing depth precision.
    double nearPlane = 0.05;
    /// A headset's eye: the tangents of its view's left, right, up and down half-angles (left and down
    /// negative), which replace fovYDegrees and the viewport's aspect. All zero: a symmetric view.
    std::array<double, 4> fovTangents{0.0, 0.0, 0.0, 0.0};
    bool asymmetric() const { return fovTangents[1] > fovTangents[0] && fovTangents[2] > fovTangents[3]; }
    /// tan of half the vertical field of view (the larger half for an eye's asymmetric view).
    double tanHalfFovY() const;
};

/// The near plane the view uses: Camera::nearPlane, or 1e-3 where that is not a positive number.
double usableNearPlane(const Camera& camera);

/// The camera's up vector as the view uses it: `up` unless it is zero, not finite or along the view
/// direction (a camera looking straight down with up +Y); then world +Y, or for a view along Y the Z
/// axis that puts -Z at the top of a view looking down (as a plan is drawn). Not normalized.
std::array<double, 3> usableUp(const Camera& camera);

/// What the surface's colour shows.
enum class ViewMode : uint32_t {
    Shaded = 0,    // material colour, tri-planar procedural texture, key light and ambient occlusion
    Lod = 1,       // each chunk coloured by the level it is shown at
    Toughness = 2, // colour by material toughness: blue (soft) to red (unerodable)
    Normals = 3,   // the surface normal as RGB
    Clay = 4,      // one warm grey clay lit from the viewer (a matcap look): the form alone, without materials
};
const char* viewModeName(ViewMode mode);
/// "shaded", "lod", "toughness", "normals", "clay"; throws std::invalid_argument listing them.
ViewMode parseViewMode(const std::string& name);

/// The brush's field as the shaders evaluate it: a primitive in its local frame (same shapes and
/// parameters as sculpt's Primitive) and the world-to-local transform of its placement.
/// Where material textures come from and how large they are drawn.
struct MaterialLook {
    std::string textureFolder;  // relative texture paths start here (the scene file's folder)
    double textureTile = 32.0;  // world units one repetition of a texture covers
};

struct BrushOverlay {
    enum class Shape : uint32_t { Sphere = 0, Box = 1, Cylinder = 2, Capsule = 3, Torus = 4, Cone = 5 };
    Shape shape = Shape::Sphere;
    std::array<float, 4> params{1.0f, 1.0f, 1.0f, 0.0f}; // sphere/cylinder/capsule/cone: radius; box: half
                                                          // extents xyz + rounding; torus: major, minor
    float height = 2.0f;                                  // cylinder, cone: full height; capsule: length
    std::array<float, 16> worldToLocal{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}; // column-major
    float distanceScale = 1.0f; // local distances times this are world distances (the smallest scale)
    std::array<float, 4> worldBoundsMin{-1, -1, -1, 0}; // where the preview's ray march looks
    std::array<float, 4> worldBoundsMax{1, 1, 1, 0};
    bool preview = true;    // draw the brush itself, translucent
    bool highlight = true;  // tint the surface the brush reaches (inside the brush's field)
    std::array<float, 4> previewColour{0.35f, 0.65f, 1.0f, 0.35f};
    std::array<float, 4> highlightColour{1.0f, 0.55f, 0.1f, 0.55f};
};

struct ShadingOptions {
    ViewMode mode = ViewMode::Shaded;
    bool wireframe = false;
    bool ambientOcclusion = true;
    std::array<float, 3> background{0.16f, 0.17f, 0.19f};
    std::array<float, 3> lightDirection{0.3f, -0.8f, -0.52f}; // the key light travels along this (from the upper left of the default view)
};

/// Per-frame figures.
struct FrameStats {
    uint64_t triangles = 0;          // drawn, summed over the views
    uint64_t chunksDrawn = 0;        // after frustum culling, summed over the views
    uint64_t chunksCulled = 0;
    uint64_t chunksUploaded = 0;     // this frame
    uint64_t uploadBytes = 0;        // this frame
    uint64_t chunksFreed = 0;        // this frame
    uint64_t chunksWaitingUpload = 0; // queued chunks a frame's upload budget left for later frames
    uint64_t gpuMemoryBytes = 0;     // mesh buffers resident on the device after the frame
    uint64_t gpuBytesAwaitingFree = 0; // mesh buffers removed, kept until the frames in flight that may draw them end
    uint64_t residentChunks = 0;
    double cpuMs = 0.0;              // recording: culling, upload copies and draw commands
    double gpuMs = 0.0;              // device time of the last frame finished (timestamp queries; this frame's when a
                                     // target reads back, else the one before), 0 when unavailable
    double submitWaitMs = 0.0;       // wall time waiting for the device: for the frame before (at the start) and, when
                                     // a target reads back, for this one
    std::vector<int> levelsShown;    // sorted, unique levels of the chunks drawn
};

} // namespace vdbclay::render
