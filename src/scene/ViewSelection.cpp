#include "scene/ViewSelection.h"

#include "scene/SceneStore.h"
#include "vdb_hermite/NumberText.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_map>

namespace vdbclay {

namespace {

using V3 = std::array<double, 3>;

V3 sub(const V3& a, const V3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const V3& a, const V3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
V3 cross(const V3& a, const V3& b) { return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; }
V3 normalized(const V3& a)
{
    const double l = std::sqrt(dot(a, a));
    return {a[0] / l, a[1] / l, a[2] / l};
}

/// The view frustum as planes n . p + d >= 0 (inside), without a far plane.
struct Frustum {
    std::array<V3, 5> normals;
    std::array<double, 5> offsets;

    Frustum(const Viewer& v)
    {
        const V3 forward = normalized(sub(v.target, v.position));
        V3 up{0.0, 1.0, 0.0};
        if (std::fabs(dot(forward, up)) > 0.999) up = {0.0, 0.0, 1.0};
        const V3 right = normalized(cross(forward, up));
        const V3 trueUp = cross(right, forward);
        const double tanY = std::tan(v.fovDegrees * M_PI / 360.0);
        const double tanX = tanY * double(v.viewport[0]) / double(v.viewport[1]);
        // Side planes through the eye: normals point inwards.
        const auto plane = [&](const V3& edgeDir, const V3& along) { return normalized(cross(edgeDir, along)); };
        const V3 dirRight{forward[0] + right[0] * tanX, forward[1] + right[1] * tanX, forward[2] + right[2] * tanX};
        const V3 dirLeft{forward[0] - right[0] * tanX, forward[1] - right[1] * tanX, forward[2] - right[2] * tanX};
        const V3 dirTop{forward[0] + trueUp[0] * tanY, forward[1] + trueUp[1] * tanY, forward[2] + trueUp[2] * tanY};
        const V3 dirBottom{forward[0] - trueUp[0] * tanY, forward[1] - trueUp[1] * tanY, forward[2] - trueUp[2] * tanY};
        normals = {forward, plane(trueUp, dirRight), plane(dirLeft, trueUp), plane(dirTop, right), plane(right, dirBottom)};
        // Every plane passes through the eye (the near plane too: no near clip distance).
        for (int i = 0; i < 5; ++i) offsets[std::size_t(i)] = -dot(normals[std::size_t(i)], v.position);
    }

    /// Whether the box may intersect the frustum (conservative).
    bool overlaps(const V3& lo, const V3& hi) const
    {
        for (int i = 0; i < 5; ++i) {
            const V3& n = normals[std::size_t(i)];
            const V3 far{n[0] >= 0 ? hi[0] : lo[0], n[1] >= 0 ? hi[1] : lo[1], n[2] >= 0 ? hi[2] : lo[2]};
            if (dot(n, far) + offsets[std::size_t(i)] < 0.0) return false;
        }
        return true;
    }
};

double distanceToBox(const V3& p, const V3& lo, const V3& hi)
{
    double s = 0.0;
    for (int i = 0; i < 3; ++i) {
        const double d = std::max({lo[std::size_t(i)] - p[std::size_t(i)], 0.0, p[std::size_t(i)] - hi[std::size_t(i)]});
        s += d * d;
    }
    return std::sqrt(s);
}

} // namespace

void validateViewer(const Viewer& v)
{
    const V3 d = sub(v.target, v.position);
    double largest = 0.0, scale = 1.0;
    for (int a = 0; a < 3; ++a) largest = std::max(largest, std::fabs(d[a])), scale = std::max(scale, std::fabs(v.position[a]));
    if (largest == 0.0) throw std::invalid_argument("a camera's target must differ from its position");
    // Closer than this, the view direction is rounding noise (and its squared length underflows).
    if (largest < 1e-9 * scale)
        throw std::invalid_argument("a camera's target lies " + formatNumber(largest) + " from its position: too close to aim by (at least " +
                                    formatNumber(1e-9 * scale) + " here)");
    if (!(v.fovDegrees > 0.0 && v.fovDegrees < 180.0)) throw std::invalid_argument("the field of view must lie in (0, 180) degrees");
    if (v.viewport[0] <= 0 || v.viewport[1] <= 0) throw std::invalid_argument("the viewport must have a positive size");
}

double lodShownError(std::optional<double> dataError, double voxel, double meshTolerance)
{
    return dataError ? std::min(voxel, *dataError + std::max(0.25, meshTolerance) * voxel) : voxel;
}

OccluderDepth::OccluderDepth(const std::array<double, 16>& viewProjection, int columns, int rows, std::vector<float> farthest)
    : viewProjection_(viewProjection)
{
    if (columns <= 0 || rows <= 0) throw std::invalid_argument("an occluder depth needs at least one tile");
    if (farthest.size() != std::size_t(columns) * std::size_t(rows))
        throw std::invalid_argument("an occluder depth of " + std::to_string(columns) + " x " + std::to_string(rows) + " tiles holds " +
                                    std::to_string(farthest.size()) + " distances");
    for (const float d : farthest)
        if (!(d >= 0.0f)) throw std::invalid_argument("an occluder depth's distances must be non-negative");
    for (const double m : viewProjection)
        if (!std::isfinite(m)) throw std::invalid_argument("an occluder depth's matrix must be finite");
    levels_.push_back({columns, rows, std::move(farthest)});
    // Coarser levels: the farthest of each 2 x 2, so that a box covering many tiles reads a few.
    while (levels_.back().columns > 1 || levels_.back().rows > 1) {
        const Level& fine = levels_.back();
        Level coarse{(fine.columns + 1) / 2, (fine.rows + 1) / 2, {}};
        coarse.farthest.resize(std::size_t(coarse.columns) * std::size_t(coarse.rows));
        for (int r = 0; r < coarse.rows; ++r)
            for (int c = 0; c < coarse.columns; ++c) {
                float far = 0.0f;
                for (int dr = 0; dr < 2; ++dr)
                    for (int dc = 0; dc < 2; ++dc) {
                        const int fr = std::min(2 * r + dr, fine.rows - 1), fc = std::min(2 * c + dc, fine.columns - 1);
                        far = std::max(far, fine.farthest[std::size_t(fr) * std::size_t(fine.columns) + std::size_t(fc)]);
                    }
                coarse.farthest[std::size_t(r) * std::size_t(coarse.columns) + std::size_t(c)] = far;
            }
        levels_.push_back(std::move(coarse));
    }
}

bool OccluderDepth::hides(const std::array<double, 3>& lo, const std::array<double, 3>& hi) const
{
    if (!hidesInThisView(lo, hi)) return false;
    return std::all_of(alsoFrom_.begin(), alsoFrom_.end(), [&](const OccluderDepth& other) { return other.hides(lo, hi); });
}

bool OccluderDepth::hidesInThisView(const std::array<double, 3>& lo, const std::array<double, 3>& hi) const
{
    if (empty()) return false;
    const std::array<double, 16>& m = viewProjection_; // element (row i, column j) at m[4 j + i]
    double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0, nearest = x0;
    for (int c = 0; c < 8; ++c) {
        const double p[3] = {(c & 1) ? hi[0] : lo[0], (c & 2) ? hi[1] : lo[1], (c & 4) ? hi[2] : lo[2]};
        double clip[4];
        for (int i = 0; i < 4; ++i) clip[i] = m[std::size_t(i)] * p[0] + m[std::size_t(4 + i)] * p[1] + m[std::size_t(8 + i)] * p[2] + m[std::size_t(12 + i)];
        // A corner at or behind the eye's plane: the box's outline on the picture is unbounded.
        if (!(clip[3] > 0.0)) return false;
        const double x = clip[0] / clip[3], y = clip[1] / clip[3];
        x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
        nearest = std::min(nearest, clip[3]); // w is affine over the box: its least is at a corner
    }
    // Wholly beyond the picture: the frame knew nothing of what lies there. Partly beyond: judged by the
    // part within (a view turned since sees the rest drawn coarse, and its next depth refines it).
    if (!(x1 >= -1.0 && x0 <= 1.0 && y1 >= -1.0 && y0 <= 1.0)) return false;
    const Level& base = levels_[0];
    // Clamped before the conversion: a corner just in front of the eye's plane projects far off the picture.
    const auto tile = [](double ndc, int count) { return std::min(int((std::clamp(ndc, -1.0, 1.0) + 1.0) * 0.5 * count), count - 1); };
    const int c0 = tile(x0, base.columns), c1 = tile(x1, base.columns), r0 = tile(y0, base.rows), r1 = tile(y1, base.rows);
    // The finest level where the outline covers at most 64 tiles.
    std::size_t k = 0;
    while (k + 1 < levels_.size() && ((c1 >> k) - (c0 >> k) + 1) * ((r1 >> k) - (r0 >> k) + 1) > 64) ++k;
    const Level& level = levels_[k];
    float far = 0.0f;
    for (int r = r0 >> k; r <= (r1 >> k); ++r)
        for (int c = c0 >> k; c <= (c1 >> k); ++c) far = std::max(far, level.farthest[std::size_t(r) * std::size_t(level.columns) + std::size_t(c)]);
    return nearest > double(far);
}

BrickPresence::BrickPresence(const std::vector<std::set<IndexCoord>>& stored)
{
    levels_.resize(stored.size());
    for (std::size_t k = 0; k < stored.size(); ++k) {
        Level& level = levels_[k];
        level.sorted.assign(stored[k].begin(), stored[k].end());
        level.bricks = LodBrickMap<Entry>(stored[k].size());
        for (const IndexCoord& b : stored[k]) {
            level.insert(b);
            linkNeighbours(level, b);
        }
    }
    for (std::size_t k = 1; k < stored.size(); ++k)
        for (const IndexCoord& b : stored[k - 1]) {
            Entry* parent = levels_[k].find(parentBrick(b));
            if (!parent) throw std::invalid_argument("a stored brick's parent is not stored");
            parent->children |= uint8_t(1u << ((b[0] & 1) + 2 * (b[1] & 1) + 4 * (b[2] & 1)));
        }
}

bool BrickPresence::contains(int level, const IndexCoord& brick) const
{
    return level >= 0 && level < levelCount() && levels_[std::size_t(level)].find(brick) != nullptr;
}

void BrickPresence::linkNeighbours(Level& level, const IndexCoord& brick)
{
    Entry& own = *level.find(brick);
    for (int d = 0; d < 27; ++d) {
        if (d == 13) continue;
        Entry* n = level.find(neighbourBrick(brick, d));
        if (!n) continue;
        own.neighbours |= 1u << d;
        n->neighbours |= 1u << (26 - d); // seen from there, the offset is the opposite one
    }
}

uint32_t BrickPresence::neighbours(int level, const IndexCoord& brick) const
{
    if (level < 0 || level >= levelCount()) return 0;
    const Entry* e = levels_[std::size_t(level)].find(brick);
    return e ? e->neighbours : 0u;
}

uint8_t BrickPresence::children(int level, const IndexCoord& brick) const
{
    if (level <= 0 || level >= levelCount()) return 0;
    const Entry* e = levels_[std::size_t(level)].find(brick);
    return e ? e->children : uint8_t(0);
}

std::optional<double> BrickPresence::shownError(int level, const IndexCoord& brick) const
{
    if (level < 0 || level >= levelCount()) return std::nullopt;
    const Entry* e = levels_[std::size_t(level)].find(brick);
    if (!e || e->shownError < 0.0f) return std::nullopt;
    return double(e->shownError);
}

void BrickPresence::setShownError(int level, const IndexCoord& brick, std::optional<double> error)
{
    if (error && !(*error >= 0.0 && std::isfinite(*error))) throw std::invalid_argument("a brick's error must be a length");
    if (level < 0 || level >= levelCount()) throw std::invalid_argument("a brick's level is outside the presence's levels");
    Entry* e = levels_[std::size_t(level)].find(brick);
    if (!e) throw std::invalid_argument("an error for a brick that is not there");
    e->shownError = error ? float(*error) : -1.0f;
}

bool BrickPresence::add(int level, const IndexCoord& brick)
{
    if (level < 0 || level >= levelCount()) throw std::invalid_argument("a brick's level is outside the presence's levels");
    const auto insertSorted = [](std::vector<IndexCoord>& sorted, const IndexCoord& b) {
        sorted.insert(std::lower_bound(sorted.begin(), sorted.end(), b), b);
    };
    Level& own = levels_[std::size_t(level)];
    const bool added = own.insert(brick).second;
    if (added) {
        insertSorted(own.sorted, brick);
        linkNeighbours(own, brick);
    }
    // Up the ancestors until one was there already (its own ancestors are then there too).
    IndexCoord b = brick;
    for (int k = level; k + 1 < levelCount(); ++k) {
        const IndexCoord up = parentBrick(b);
        Level& above = levels_[std::size_t(k + 1)];
        const auto [entry, inserted] = above.insert(up);
        entry->children |= uint8_t(1u << ((b[0] & 1) + 2 * (b[1] & 1) + 4 * (b[2] & 1)));
        if (!inserted) break;
        insertSorted(above.sorted, up);
        linkNeighbours(above, up);
        b = up;
    }
    return added;
}

std::vector<SelectedBrick> selectBricks(const Viewer& viewer, const SelectionOptions& options,
                                        const std::vector<std::set<IndexCoord>>& stored)
{
    return selectBricks(viewer, options, BrickPresence(stored));
}

std::vector<SelectedBrick> selectBricks(const Viewer& viewer, const SelectionOptions& options, const BrickPresence& stored)
{
    validateViewer(viewer);
    const Frustum frustum(viewer);
    const double pixelsPerRadian = double(viewer.viewport[1]) / (2.0 * std::tan(viewer.fovDegrees * M_PI / 360.0));
    const int top = std::min<int>(options.levels, stored.levelCount() - 1);
    std::vector<SelectedBrick> out;
    if (top < 0) return out;
    // Depth-first from each top brick; a brick whose children are not stored (a level not built there)
    // is shown as it is.
    std::vector<BrickKey> stack;
    const std::vector<IndexCoord>& topBricks = stored.bricks(top);
    for (auto it = topBricks.rbegin(); it != topBricks.rend(); ++it) stack.push_back({top, *it});
    while (!stack.empty()) {
        const BrickKey key = stack.back();
        stack.pop_back();
        const double edge = double(kBrickEdge) * double(1 << key.level) * options.voxelSize;
        const V3 lo{key.brick[0] * edge, key.brick[1] * edge, key.brick[2] * edge};
        const V3 hi{lo[0] + edge, lo[1] + edge, lo[2] + edge};
        if (!frustum.overlaps(lo, hi)) continue;
        const double distance = distanceToBox(viewer.position, lo, hi);
        // The brick's error: what its data lies off level 0's where it is known (lodShownError), else its voxel.
        const double worldError = stored.shownError(key.level, key.brick).value_or(options.voxelSize * double(1 << key.level));
        const double error = distance > 0.0 ? worldError * pixelsPerRadian / distance : 1e30;
        const bool refineAnyway = options.refineAlways && options.refineAlways->count(key);
        bool hidden = false;
        if (key.level > 0 && error > options.pixelTolerance && !refineAnyway && options.occluders) {
            // Grown by the brick's voxel: what its drawn stand-in may lie off its surface.
            const double grow = options.voxelSize * double(1 << key.level);
            hidden = options.occluders->hides({lo[0] - grow, lo[1] - grow, lo[2] - grow}, {hi[0] + grow, hi[1] + grow, hi[2] + grow});
        }
        if (key.level > 0 && ((error > options.pixelTolerance && !hidden) || refineAnyway)) {
            const uint8_t children = stored.children(key.level, key.brick);
            if (children != 0) {
                for (int c = 7; c >= 0; --c)
                    if (children & (1u << c))
                        stack.push_back({key.level - 1, {2 * key.brick[0] + (c & 1), 2 * key.brick[1] + ((c >> 1) & 1), 2 * key.brick[2] + ((c >> 2) & 1)}});
                continue;
            }
        }
        out.push_back({key, hidden ? 0.0 : error, distance, hidden});
    }
    std::stable_sort(out.begin(), out.end(), [](const SelectedBrick& a, const SelectedBrick& b) {
        if (a.key.level != b.key.level) return a.key.level > b.key.level;
        return a.distance < b.distance;
    });
    return out;
}

ViewNeeds viewNeeds(const std::vector<SelectedBrick>& selected, int levels)
{
    // A brick's chain of ancestors ends where it meets one already listed, whose own chain is listed.
    ViewNeeds needs;
    needs.selected.assign(selected.size(), ViewNeeds::kNone);
    LodBrickMap<uint32_t> indexOf(2 * selected.size());
    for (std::size_t i = 0; i < selected.size(); ++i) {
        uint32_t child = ViewNeeds::kNone;
        for (BrickKey key = selected[i].key; key.level <= levels; key = {key.level + 1, parentBrick(key.brick)}) {
            const auto [index, inserted] = indexOf.insert(key.level, key.brick);
            if (inserted) *index = uint32_t(needs.bricks.size());
            (child == ViewNeeds::kNone ? needs.selected[i] : needs.parent[child]) = *index;
            if (!inserted) break;
            needs.bricks.push_back(key);
            needs.parent.push_back(ViewNeeds::kNone);
            child = *index;
        }
    }
    needs.order.resize(needs.bricks.size());
    for (uint32_t i = 0; i < needs.order.size(); ++i) needs.order[i] = i;
    std::stable_sort(needs.order.begin(), needs.order.end(),
                     [&](uint32_t a, uint32_t b) { return needs.bricks[a].level > needs.bricks[b].level; });
    return needs;
}

} // namespace vdbclay
