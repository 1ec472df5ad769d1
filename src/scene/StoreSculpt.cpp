#include "scene/StoreSculpt.h"

#include "scene/StoreLod.h"
#include "sculpt/Brush.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <set>

namespace vdbclay {

namespace {

int32_t floorDiv(int64_t v, int64_t d) { return int32_t(v >= 0 ? v / d : -((-v + d - 1) / d)); }

/// The bricks an op can read or change (voxelsReachedBy). Nullopt when the op reaches everything.
std::optional<std::pair<IndexCoord, IndexCoord>> brickRange(const ScriptOp& op, double voxelSize)
{
    auto range = voxelsReachedBy(op, voxelSize);
    if (!range) return std::nullopt;
    for (int i = 0; i < 3; ++i) {
        range->first[std::size_t(i)] = floorDiv(range->first[std::size_t(i)], kBrickEdge);
        range->second[std::size_t(i)] = floorDiv(range->second[std::size_t(i)], kBrickEdge);
    }
    return range;
}

} // namespace

std::optional<std::pair<IndexCoord, IndexCoord>> voxelsReachedBy(const ScriptOp& op, double voxelSize)
{
    if (op.maskEdit) return std::pair{IndexCoord{0, 0, 0}, IndexCoord{-1, -1, -1}}; // the mask is not in the bricks
    if (op.mode == CsgMode::Intersect) return std::nullopt;
    const WorldBounds b = opBounds(op, voxelSize);
    if (!b.bounded()) return std::nullopt;
    IndexCoord lo, hi;
    for (int i = 0; i < 3; ++i) {
        const double min = std::floor(b.min[i] / voxelSize) - 2.0, max = std::ceil(b.max[i] / voxelSize) + kLeafDim + 2.0;
        lo[std::size_t(i)] = int32_t(std::max(min, -1e9));
        hi[std::size_t(i)] = int32_t(std::min(max, 1e9));
    }
    return std::pair{lo, hi};
}

std::vector<IndexCoord> bricksReachedBy(const StrokeScript& script, double voxelSize,
                                        const std::function<std::vector<IndexCoord>()>& allBricks)
{
    std::set<IndexCoord> bricks;
    for (const ScriptOp& op : script.ops) {
        const auto range = brickRange(op, voxelSize);
        if (!range) {
            const std::vector<IndexCoord> all = allBricks();
            bricks.insert(all.begin(), all.end());
            continue;
        }
        const auto& [lo, hi] = *range;
        // The limits (checked again by runStrokeScript) keep a brush within +-250,000 voxels; this
        // guard keeps a brush that fails them from enumerating billions of bricks first.
        const double count = double(hi[0] - lo[0] + 1) * double(hi[1] - lo[1] + 1) * double(hi[2] - lo[2] + 1);
        if (count > 5e7) {
            char text[32];
            std::snprintf(text, sizeof text, "%.3g", count); // beyond 2^64 a cast to an integer would read 0
            throw ScriptError(std::string("an op reaches ") + text + " bricks of the store, more than the 5e+07 an edit may read");
        }
        for (int32_t x = lo[0]; x <= hi[0]; ++x)
            for (int32_t y = lo[1]; y <= hi[1]; ++y)
                for (int32_t z = lo[2]; z <= hi[2]; ++z) bricks.insert({x, y, z});
    }
    return {bricks.begin(), bricks.end()};
}

StoreSculptReport sculptStore(SceneStore& scene, const StrokeScript& script,
                              const std::function<void(const ScriptOpReport&)>& onOp)
{
    checkStrokeScript(script, scene.voxelSize(), scene.materials()); // before anything is read
    const std::vector<IndexCoord> order = bricksReachedBy(script, scene.voxelSize(), [&] { return scene.brickCoords(0); });
    Volume part(scene.voxelSize());
    part.materials() = scene.materials();
    part.mask() = scene.mask();
    std::vector<std::optional<BrickRecord>> before;
    scene.loadBricks(0, order, part, {}, &before);

    StoreSculptReport report;
    report.bricksRead = order.size();
    report.ops = runStrokeScript(part, script, onOp);

    // Intersect clears what lies outside the loaded bricks too: every stored brick was loaded then.
    StoreTransaction transaction(scene.bricks());
    std::vector<IndexCoord> written;
    for (std::size_t i = 0; i < order.size(); ++i) {
        const std::optional<BrickRecord> after = encodeBrick(part, order[i]);
        if (sameBrick(after, before[i])) continue;
        if (after) scene.bricks().put({0, order[i]}, *after);
        else scene.bricks().erase({0, order[i]});
        written.push_back(order[i]);
    }
    report.bricksWritten = written.size();
    scene.setMaterials(part.materials());
    if (part.mask() != scene.mask()) scene.setMask(part.mask());
    if (!written.empty()) {
        scene.forgetBounds();
        if (lodFollowsEdits(scene)) report.lodBricksWritten = updateStoreLod(scene, written).bricksWritten();
        else if (scene.lodLevels() > 0) scene.setLod(scene.lodLevels(), true);
    }
    transaction.commit();
    return report;
}

} // namespace vdbclay
