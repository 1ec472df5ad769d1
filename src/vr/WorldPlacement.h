// Where the scene stands in the room: a similarity transform from scene units (voxels) to the headset's
// stage (metres), set when the scene is framed in front of the user and changed by grabbing the world
// with one hand (move), two hands (move, turn about the vertical and scale), or flying. Plain math, no
// OpenXR: the VR front end feeds it hand poses.
#pragma once

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include <array>
#include <optional>

namespace vdbclay::vr {

/// A rigid pose in the stage: orientation, then position (OpenXR's XrPosef).
struct Pose {
    glm::dquat orientation{1.0, 0.0, 0.0, 0.0};
    glm::dvec3 position{0.0};
    glm::dvec3 forward() const { return orientation * glm::dvec3(0, 0, -1); }
    glm::dvec3 up() const { return orientation * glm::dvec3(0, 1, 0); }
};

/// stage = translation + scale * (rotation * scene).
struct WorldTransform {
    double scale = 1.0; // metres per scene unit
    glm::dquat rotation{1.0, 0.0, 0.0, 0.0};
    glm::dvec3 translation{0.0};

    glm::dvec3 toStage(const glm::dvec3& scene) const { return translation + scale * (rotation * scene); }
    glm::dvec3 toScene(const glm::dvec3& stage) const { return glm::conjugate(rotation) * ((stage - translation) / scale); }
    /// A direction of the stage in the scene (unit length kept).
    glm::dvec3 directionToScene(const glm::dvec3& stage) const { return glm::conjugate(rotation) * stage; }
};

/// Widest a framed scene stands (metres): "a 1 m to 2 m wide view of it".
constexpr double kFramedWidthMetres = 1.5;
/// Scales a two-hand grab may reach, relative to the framed scale: 1:1000 to 1000:1.
constexpr double kScaleRange = 1000.0;

/// The scene box [lo, hi] (scene units) standing whole in front of a viewer at `head`: kFramedWidthMetres
/// across its widest side, its centre at chest height a little more than its half-width away, turned
/// so that the scene's -Z faces the viewer's forward on the floor plane (as a desktop's first view).
WorldTransform frameScene(const std::array<double, 3>& lo, const std::array<double, 3>& hi, const Pose& head);

/// Grabbing the world: one hand moves it with the hand; two hands move its midpoint with theirs, turn
/// it about the vertical by their turn and scale it by their spread (within [minScale, maxScale]).
class WorldGrab {
public:
    void setScaleLimits(double minScale, double maxScale) { minScale_ = minScale, maxScale_ = maxScale; }
    /// Each frame: the hands that hold (absent: not grabbing) and the transform now; returns the
    /// transform the grab makes (the same when nothing holds). A change of hands starts the grab again
    /// from the current transform, so nothing jumps.
    WorldTransform update(const std::optional<glm::dvec3>& left, const std::optional<glm::dvec3>& right, const WorldTransform& now);
    bool active() const { return start_.has_value(); }

private:
    struct Start {
        WorldTransform world;
        std::optional<glm::dvec3> left, right;
    };
    std::optional<Start> start_;
    double minScale_ = 0.0, maxScale_ = 1e300;
};

/// Flying: the world moves against `direction` (stage, unit) by `metresPerSecond` x `seconds`.
WorldTransform fly(const WorldTransform& world, const glm::dvec3& direction, double metresPerSecond, double seconds);

} // namespace vdbclay::vr
