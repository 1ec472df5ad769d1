// Which bricks a view needs, at which level: from the coarsest level down, a brick in the view frustum
// is refined into its (up to) eight children while its screen-space error exceeds the tolerance: how far
// its surface may lie from level 0's (the data error its store keeps, else its level's voxel size),
// projected at its distance. Pure geometry: no store access, no threads.
#pragma once

#include "mesher/LodBrickTable.h"
#include "scene/BrickStore.h"

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <set>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace vdbclay {

struct Viewer {
    std::array<double, 3> position{0.0, 0.0, 0.0}; // world units
    std::array<double, 3> target{0.0, 0.0, -1.0};
    double fovDegrees = 60.0;                      // vertical
    std::array<int, 2> viewport{1920, 1080};       // pixels
};

/// What a drawn frame leaves for the next selections (occlusion culling from the last frame's depth, as
/// GPU-driven renderers do): per tile of its picture, the farthest distance along the view at which a
/// surface was drawn, infinity where none was. A brick whose box lies behind every tile it covers is
/// hidden: its detail cannot show, so it is not refined. Hidden bricks are still shown at the level
/// reached (never culled), so the view keeps no hole where the camera has moved since: what comes into
/// sight is drawn coarse, its depth lands in the next frame's tiles, and the next selection refines it.
class OccluderDepth {
public:
    OccluderDepth() = default;
    /// `viewProjection`: the matrix the frame was drawn with (column-major, reversed depth with the far
    /// plane at infinity, so clip w is the distance along the view); `farthest`: columns x rows tiles,
    /// rows from the top of the picture (NDC y = -1), non-negative, +infinity where nothing was drawn.
    /// Throws std::invalid_argument for an empty grid, a wrong count or a negative or NaN distance.
    OccluderDepth(const std::array<double, 16>& viewProjection, int columns, int rows, std::vector<float> farthest);

    bool empty() const { return levels_.empty(); }
    int columns() const { return empty() ? 0 : levels_[0].columns; }
    int rows() const { return empty() ? 0 : levels_[0].rows; }
    /// A tile's farthest distance (column and row within the grid).
    float farthest(int column, int row) const { return levels_[0].farthest[std::size_t(row) * std::size_t(levels_[0].columns) + std::size_t(column)]; }
    /// Whether the box (world units) lies behind the farthest surface drawn over every tile of the
    /// picture it covers (and of each view it is also seen from). False for an empty grid, a box wholly
    /// beyond the picture and a box reaching the eye's plane.
    bool hides(const std::array<double, 3>& lo, const std::array<double, 3>& hi) const;
    /// The same frame's depth drawn from another view (a headset's other eye): from now on a box is
    /// hidden only when that view hides it too (a brick behind a pillar for one eye may show to the other).
    void alsoSeenFrom(OccluderDepth other) { alsoFrom_.push_back(std::move(other)); }

private:
    bool hidesInThisView(const std::array<double, 3>& lo, const std::array<double, 3>& hi) const;

    struct Level {
        int columns = 0, rows = 0;
        std::vector<float> farthest;
    };
    std::array<double, 16> viewProjection_{};
    std::vector<Level> levels_; // the tiles, then the farthest of each 2x2 of the level before
    std::vector<OccluderDepth> alsoFrom_;
};

struct SelectionOptions {
    double pixelTolerance = 1.0; // screen-space error a brick may show, in pixels
    double voxelSize = 1.0;      // level 0
    int levels = 0;              // coarse levels available (bricks of level k: 64 voxels of 2^k * voxelSize)
    /// Optional: coarse bricks refined whatever their error (those older than the edited level-0 data
    /// below them, so that an edit shows at once).
    const std::unordered_set<BrickKey, BrickKeyHash>* refineAlways = nullptr;
    /// Optional: the last frame's depth. A brick it hides (grown by its voxel, what its drawn stand-in
    /// may lie off its surface) is not refined; refineAlways still is.
    const OccluderDepth* occluders = nullptr;
};

/// The error a view counts for a brick whose level has voxels of size `voxel`, in world units: its data
/// error (StoreLod.h) plus what its mesh's cells may cut off the surface, and never more than the voxel
/// itself: the bound a brick without a data error is shown by. The cells' share is the larger of a
/// quarter voxel (adaptive CMS cells up to 8 voxels wide, split at a 15-degree normal spread, leave a
/// sagitta of about 0.26 voxel) and `meshTolerance`, voxels: how far a coarse brick's mesh may lie from
/// its cells' (MeshOptions::coarseLevelPlaneTolerance plus coarseLevelSimplifyTolerance).
double lodShownError(std::optional<double> dataError, double voxel, double meshTolerance);

struct SelectedBrick {
    BrickKey key;
    double screenError = 0.0; // pixels, at its level; 0 where the occluders hide it (no error shows)
    double distance = 0.0;    // world units, eye to the brick's nearest point
    bool hidden = false;      // left unrefined: SelectionOptions::occluders hide it
};

/// The brick at offset (d % 3 - 1, d / 3 % 3 - 1, d / 9 - 1) from `brick`, d in [0, 27): the order of
/// BrickPresence::neighbours' bits.
inline IndexCoord neighbourBrick(const IndexCoord& brick, int d)
{
    return {brick[0] + d % 3 - 1, brick[1] + (d / 3) % 3 - 1, brick[2] + d / 9 - 1};
}

/// The bricks that exist per level, as the selection asks about them: each level's bricks in order, and
/// per brick the mask of its children one level down (bit x + 2y + 4z of the child's place in it), so a
/// brick is split with one lookup. Bricks are only ever added: an edit makes a new level-0 brick, an LOD
/// update the coarse bricks above it.
class BrickPresence {
public:
    BrickPresence() = default;
    /// `stored[k]`: level k's bricks; each brick's parent must be stored one level up, where there is one.
    explicit BrickPresence(const std::vector<std::set<IndexCoord>>& stored);

    int levelCount() const { return int(levels_.size()); }
    /// Level k's bricks, sorted.
    const std::vector<IndexCoord>& bricks(int level) const { return levels_[std::size_t(level)].sorted; }
    bool contains(int level, const IndexCoord& brick) const;
    /// The children of a brick that exist (bit x + 2y + 4z); 0 when it has none or does not exist.
    uint8_t children(int level, const IndexCoord& brick) const;
    /// The bricks of its own level around a brick that exist: bit (dx + 1) + 3 (dy + 1) + 9 (dz + 1) for
    /// the one at offset (dx, dy, dz) in {-1, 0, 1}^3 (bit 13, the brick itself, clear); 0 when it does
    /// not exist. One lookup where asking contains() of each neighbour takes 26.
    uint32_t neighbours(int level, const IndexCoord& brick) const;
    /// Adds a brick of `level` and every missing ancestor up to the top level; returns whether it was new.
    bool add(int level, const IndexCoord& brick);
    /// The error a view counts for a brick (lodShownError, world units), where one was set.
    std::optional<double> shownError(int level, const IndexCoord& brick) const;
    /// Sets it (the brick must exist); nullopt forgets it.
    void setShownError(int level, const IndexCoord& brick, std::optional<double> error);

private:
    struct Entry {
        uint8_t children = 0; // bit x + 2y + 4z
        uint32_t neighbours = 0; // as neighbours() gives them
        float shownError = -1.0f; // world units; negative: none
    };
    struct Level {
        std::vector<IndexCoord> sorted;
        LodBrickMap<Entry> bricks; // keyed by the brick alone (level 0 in the map's keys)
        Entry* find(const IndexCoord& brick) { return bricks.find(0, brick); }
        const Entry* find(const IndexCoord& brick) const { return bricks.find(0, brick); }
        std::pair<Entry*, bool> insert(const IndexCoord& brick) { return bricks.insert(0, brick); }
    };
    /// Enters a brick new to `level` in its neighbours' masks and theirs in its own.
    void linkNeighbours(Level& level, const IndexCoord& brick);
    std::vector<Level> levels_;
};

/// The bricks to show: every brick of `stored` in the frustum, at the coarsest level whose screen-space
/// error is within the tolerance (or level 0), coarse regions first.
std::vector<SelectedBrick> selectBricks(const Viewer& viewer, const SelectionOptions& options, const BrickPresence& stored);
/// The same with `stored[k]` holding level k's brick coordinates.
std::vector<SelectedBrick> selectBricks(const Viewer& viewer, const SelectionOptions& options,
                                        const std::vector<std::set<IndexCoord>>& stored);

/// What a selection needs resident, every brick once: each selected brick and its ancestors up to
/// `levels` (shown while it loads). Bricks are referred to by their index in `bricks`.
struct ViewNeeds {
    static constexpr uint32_t kNone = ~uint32_t(0);
    std::vector<BrickKey> bricks;
    std::vector<uint32_t> parent;   // per brick: its parent's index, or kNone at the top level
    std::vector<uint32_t> selected; // per selected brick: its index
    /// The loading order: coarse levels first; within a level, in the order of the first selected
    /// brick that needs each.
    std::vector<uint32_t> order;
};
ViewNeeds viewNeeds(const std::vector<SelectedBrick>& selected, int levels);

/// The parent brick (level k + 1) of a brick of level k.
inline IndexCoord parentBrick(const IndexCoord& b)
{
    return {b[0] >> 1, b[1] >> 1, b[2] >> 1};
}

/// Throws std::invalid_argument for a viewer with a zero view direction, a field of view outside
/// (0, 180) or an empty viewport.
void validateViewer(const Viewer& viewer);

} // namespace vdbclay
