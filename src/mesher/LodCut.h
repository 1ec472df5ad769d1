// Which bricks a view shows at which level (a cut through the bricks' octree: no brick overlaps
// another), and the questions meshing them side by side asks of it. Levels are vertex-aligned here:
// level k's lattice point i sits at level-0 point 2^k i, so every level's lattice points, edges and
// faces lie on the finer levels' lattices, and a coarse brick's cells can take the finer side's data
// where it meets a finer brick (seed 000 §5: the finer side's segments decide the shared face).
//
// Light header: no OpenVDB.
#pragma once

#include "mesher/LodBrickTable.h"

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

namespace vdbclay {

constexpr int32_t kLodBrickVoxels = 64;

class LodCut {
public:
    using Point = std::array<int64_t, 3>; // level-0 lattice

    LodCut() = default;
    explicit LodCut(const std::vector<LodBrick>& shown);

    bool shows(const LodBrick& b) const { return shown_.contains(b.level, b.brick); }
    const std::vector<LodBrick>& bricks() const { return list_; }
    int finestLevel() const { return finest_; }
    int coarsestLevel() const { return coarsest_; }

    /// The finest level (up to `maxLevel`) of a shown brick whose closed box holds the whole closed box
    /// [lo, hi], or -1.
    int finestHolding(const Point& lo, const Point& hi, int maxLevel = 1 << 30) const;
    /// Whether a shown brick of a level finer than `level` touches the closed box [lo, hi].
    bool finerTouches(const Point& lo, const Point& hi, int level) const;
    /// The shown bricks finer than `level` that touch the closed box [lo, hi].
    std::vector<LodBrick> finerTouching(const Point& lo, const Point& hi, int level) const;
    /// Whether brick b's closed box touches the closed box [lo, hi].
    static bool touches(const LodBrick& b, const Point& lo, const Point& hi);
    /// Calls `fn` with each brick of the cut that touches the closed box [lo, hi], in no set order: by
    /// looking up the bricks of each level around the box where they are fewer than the cut's (a brick's
    /// neighbourhood), else by a pass over the cut.
    void forEachTouching(const Point& lo, const Point& hi, const std::function<void(const LodBrick&)>& fn) const;
    /// The level of the shown brick whose open box holds the point strictly inside [lo, hi] (a cell's
    /// middle), or -1 where no brick is shown.
    int levelAround(const Point& lo, const Point& hi) const;

    /// The brick that meshes the unit cell of `level` at level-`level` index `cell`: the shown brick
    /// holding its middle. Space outside the cut counts as the coarsest level's: a cell of that level
    /// there belongs to the shown brick holding the first of its corners (in corner order, each in
    /// the half-open box of a brick) that one holds. Nullopt: no brick meshes it. A cut should hold
    /// every child of a brick it splits, the empty ones too, so that only space around the whole
    /// cut lies outside it.
    std::optional<LodBrick> cellOwner(int level, const std::array<int32_t, 3>& cell) const;

    /// Whether the unit cell of `level` at level-`level` index `cell` touches a finer shown brick: the
    /// coarse side of a level boundary, meshed by the transition mesher (LodMesh.h).
    bool transitionCell(int level, const std::array<int32_t, 3>& cell) const;
    /// Whether the unit face of `level` with minimum corner `corner` (level-`level` index) and normal
    /// `axis` borders a transition cell on either side: both sides then mesh it plainly (its crossings
    /// joined straight, no sharp point or material transition inside), as the transition mesher does.
    bool plainFace(int level, const std::array<int32_t, 3>& corner, int axis) const;
    /// The widest adaptive cell for a level-`level` leaf at `origin`: voxel cells where the leaf touches a
    /// finer brick (its transition cells) or lies in no brick of this level, else `widest`.
    int leafMaxCellWidth(int level, const std::array<int32_t, 3>& origin, int widest) const;


private:
    static int64_t brickSpan(int level) { return int64_t(kLodBrickVoxels) << level; }
    // Meshing asks whether a brick is shown for every transition face and corner, several times per
    // level: a node-based set's division and pointer chase made that a tenth of meshing a view.
    LodBrickMap<char> shown_;
    std::vector<LodBrick> list_;
    int finest_ = 0, coarsest_ = -1;
};

} // namespace vdbclay
