#include "mesher/LodCut.h"

#include <algorithm>

namespace vdbclay {

namespace {

int64_t floorDiv(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

} // namespace

LodCut::LodCut(const std::vector<LodBrick>& shown) : list_(shown)
{
    finest_ = 1 << 30;
    for (const LodBrick& b : shown) {
        finest_ = std::min(finest_, b.level);
        coarsest_ = std::max(coarsest_, b.level);
    }
    if (shown.empty()) finest_ = 0;
    shown_ = LodBrickMap<char>(shown.size());
    for (const LodBrick& b : shown) shown_.insert(b.level, b.brick);
}

int LodCut::finestHolding(const Point& lo, const Point& hi, int maxLevel) const
{
    for (int level = finest_; level <= std::min(coarsest_, maxLevel); ++level) {
        const int64_t span = brickSpan(level);
        // The bricks whose closed box holds the box: those whose box holds lo, of which the one with
        // a face on lo's plane may be either side.
        int64_t from[3], to[3];
        for (int a = 0; a < 3; ++a) {
            to[a] = floorDiv(lo[std::size_t(a)], span);
            from[a] = lo[std::size_t(a)] % span == 0 ? to[a] - 1 : to[a];
        }
        for (int64_t x = from[0]; x <= to[0]; ++x)
            for (int64_t y = from[1]; y <= to[1]; ++y)
                for (int64_t z = from[2]; z <= to[2]; ++z) {
                    const int64_t b[3] = {x, y, z};
                    bool holds = true;
                    for (int a = 0; a < 3 && holds; ++a)
                        holds = b[a] * span <= lo[std::size_t(a)] && hi[std::size_t(a)] <= (b[a] + 1) * span;
                    if (holds && shows({level, {int32_t(x), int32_t(y), int32_t(z)}})) return level;
                }
    }
    return -1;
}

bool LodCut::finerTouches(const Point& lo, const Point& hi, int level) const
{
    for (int l = finest_; l < level && l <= coarsest_; ++l) {
        const int64_t span = brickSpan(l);
        int64_t from[3], to[3];
        for (int a = 0; a < 3; ++a) {
            from[a] = floorDiv(lo[std::size_t(a)], span) - (lo[std::size_t(a)] % span == 0 ? 1 : 0);
            to[a] = floorDiv(hi[std::size_t(a)], span);
        }
        if ((to[0] - from[0] + 1) * (to[1] - from[1] + 1) * (to[2] - from[2] + 1) > 4096) {
            // A box far wider than this level's bricks (a coarse cell beside very fine bricks): scan the cut.
            for (const LodBrick& b : list_) {
                if (b.level != l) continue;
                bool touches = true;
                for (int a = 0; a < 3 && touches; ++a)
                    touches = int64_t(b.brick[std::size_t(a)]) * span <= hi[std::size_t(a)] &&
                              lo[std::size_t(a)] <= (int64_t(b.brick[std::size_t(a)]) + 1) * span;
                if (touches) return true;
            }
            continue;
        }
        for (int64_t x = from[0]; x <= to[0]; ++x)
            for (int64_t y = from[1]; y <= to[1]; ++y)
                for (int64_t z = from[2]; z <= to[2]; ++z)
                    if (shows({l, {int32_t(x), int32_t(y), int32_t(z)}})) return true;
    }
    return false;
}

bool LodCut::touches(const LodBrick& b, const Point& lo, const Point& hi)
{
    const int64_t span = brickSpan(b.level);
    for (int a = 0; a < 3; ++a)
        if (int64_t(b.brick[std::size_t(a)]) * span > hi[std::size_t(a)] || lo[std::size_t(a)] > (int64_t(b.brick[std::size_t(a)]) + 1) * span)
            return false;
    return true;
}

void LodCut::forEachTouching(const Point& lo, const Point& hi, const std::function<void(const LodBrick&)>& fn) const
{
    if (list_.empty()) return;
    // Per level, the bricks b with b * span <= hi and (b + 1) * span >= lo on every axis.
    const auto floorDiv = [](int64_t v, int64_t d) { return v >= 0 ? v / d : -((-v + d - 1) / d); };
    std::vector<std::array<std::array<int64_t, 2>, 3>> ranges;
    uint64_t candidates = 0;
    for (int level = finest_; level <= coarsest_; ++level) {
        const int64_t span = brickSpan(level);
        std::array<std::array<int64_t, 2>, 3> r{};
        uint64_t count = 1;
        for (std::size_t a = 0; a < 3; ++a) {
            r[a] = {-floorDiv(-lo[a], span) - 1, floorDiv(hi[a], span)};
            count *= uint64_t(std::max<int64_t>(0, r[a][1] - r[a][0] + 1));
        }
        ranges.push_back(r);
        candidates += count;
        if (candidates > list_.size()) break;
    }
    if (candidates > list_.size()) {
        for (const LodBrick& b : list_)
            if (touches(b, lo, hi)) fn(b);
        return;
    }
    for (int level = finest_; level <= coarsest_; ++level) {
        const auto& r = ranges[std::size_t(level - finest_)];
        for (int64_t x = r[0][0]; x <= r[0][1]; ++x)
            for (int64_t y = r[1][0]; y <= r[1][1]; ++y)
                for (int64_t z = r[2][0]; z <= r[2][1]; ++z) {
                    const LodBrick b{level, {int32_t(x), int32_t(y), int32_t(z)}};
                    if (shows(b)) fn(b);
                }
    }
}

std::vector<LodBrick> LodCut::finerTouching(const Point& lo, const Point& hi, int level) const
{
    std::vector<LodBrick> out;
    for (const LodBrick& b : list_)
        if (b.level < level && touches(b, lo, hi)) out.push_back(b);
    return out;
}

int LodCut::levelAround(const Point& lo, const Point& hi) const
{
    for (int level = finest_; level <= coarsest_; ++level) {
        const int64_t span = brickSpan(level);
        // The middle of [lo, hi], doubled to stay on integers: inside exactly one brick per level.
        std::array<int32_t, 3> b;
        for (int a = 0; a < 3; ++a)
            b[std::size_t(a)] = int32_t(floorDiv(lo[std::size_t(a)] + hi[std::size_t(a)], 2 * span));
        if (shows({level, b})) return level;
    }
    return -1;
}

std::optional<LodBrick> LodCut::cellOwner(int level, const std::array<int32_t, 3>& cell) const
{
    Point lo, hi;
    for (int a = 0; a < 3; ++a) {
        lo[std::size_t(a)] = int64_t(cell[std::size_t(a)]) * (int64_t(1) << level);
        hi[std::size_t(a)] = (int64_t(cell[std::size_t(a)]) + 1) * (int64_t(1) << level);
    }
    const int around = levelAround(lo, hi);
    if (around >= 0) {
        const int64_t span = brickSpan(around);
        LodBrick b{around, {}};
        for (int a = 0; a < 3; ++a) b.brick[std::size_t(a)] = int32_t(floorDiv(lo[std::size_t(a)] + hi[std::size_t(a)], 2 * span));
        return b;
    }
    // Space outside the cut is the coarsest level's: only its cells there have an owner.
    if (level != coarsest_) return std::nullopt;
    for (int c = 0; c < 8; ++c) {
        Point p;
        for (int a = 0; a < 3; ++a) p[std::size_t(a)] = (c >> a) & 1 ? hi[std::size_t(a)] : lo[std::size_t(a)];
        for (int l = finest_; l <= coarsest_; ++l) {
            const int64_t span = brickSpan(l);
            const LodBrick b{l, {int32_t(floorDiv(p[0], span)), int32_t(floorDiv(p[1], span)), int32_t(floorDiv(p[2], span))}};
            if (shows(b)) return b;
        }
    }
    return std::nullopt;
}

bool LodCut::transitionCell(int level, const std::array<int32_t, 3>& cell) const
{
    if (level <= finest_) return false;
    Point lo, hi;
    for (int a = 0; a < 3; ++a) {
        lo[std::size_t(a)] = int64_t(cell[std::size_t(a)]) * (int64_t(1) << level);
        hi[std::size_t(a)] = (int64_t(cell[std::size_t(a)]) + 1) * (int64_t(1) << level);
    }
    return finerTouches(lo, hi, level);
}

bool LodCut::plainFace(int level, const std::array<int32_t, 3>& corner, int axis) const
{
    for (int side = 0; side < 2; ++side) {
        std::array<int32_t, 3> cell = corner;
        cell[std::size_t(axis)] -= side;
        Point lo, hi;
        for (int a = 0; a < 3; ++a) {
            lo[std::size_t(a)] = int64_t(cell[std::size_t(a)]) * (int64_t(1) << level);
            hi[std::size_t(a)] = (int64_t(cell[std::size_t(a)]) + 1) * (int64_t(1) << level);
        }
        int around = levelAround(lo, hi);
        if (around < 0) around = coarsest_; // outside the cut: the coarsest level's space
        if (around > level) return true;    // a coarser cell holds the face, and it touches this finer one
        if (around == level && transitionCell(level, cell)) return true;
    }
    return false;
}

int LodCut::leafMaxCellWidth(int level, const std::array<int32_t, 3>& origin, int widest) const
{
    Point lo, hi;
    for (int a = 0; a < 3; ++a) {
        lo[std::size_t(a)] = int64_t(origin[std::size_t(a)]) * (int64_t(1) << level);
        hi[std::size_t(a)] = (int64_t(origin[std::size_t(a)]) + 8) * (int64_t(1) << level);
    }
    if (levelAround(lo, hi) != level) return 1;
    // A finer brick touching the leaf: its transition cells are voxel cells. (A coarser one needs
    // nothing here: the leaves across, in no brick of this level, hold voxel cells, so the faces
    // towards it are split into unit squares, which are meshed plainly.)
    if (finerTouches(lo, hi, level)) return 1;
    return widest;
}

} // namespace vdbclay
