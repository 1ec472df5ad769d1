// Comparing LOD pyramids in stores: densities byte for byte, coarse bricks by content.
#pragma once

#include "scene/SceneStore.h"
#include "scene/StoreLod.h"
#include "vdb_hermite/VolumeRegions.h"

#include <map>
#include <set>
#include <vector>

namespace vdbclay::test {

/// Whether two volumes hold the same voxels and samples (their trees may be cut into tiles differently).
inline bool sameContent(const Volume& a, const Volume& b)
{
    std::vector<IndexCoord> boxes = occupiedBoxes(a, kBrickEdge);
    const std::vector<IndexCoord> more = occupiedBoxes(b, kBrickEdge);
    boxes.insert(boxes.end(), more.begin(), more.end());
    for (const IndexCoord& o : std::set<IndexCoord>(boxes.begin(), boxes.end()))
        if (compareRegion(a, b, {o, kBrickEdge}).any()) return false;
    return true;
}

/// Every stored record of levels 1 .. levels and of their densities.
inline std::map<BrickKey, BrickRecord> pyramidRecords(const SceneStore& scene)
{
    std::map<BrickKey, BrickRecord> out;
    for (int k = 1; k <= scene.lodLevels(); ++k)
        for (const int level : {k, -k})
            for (const IndexCoord& b : scene.brickCoords(level)) out.emplace(BrickKey{level, b}, *scene.bricks().get({level, b}));
    return out;
}

/// Densities and coarse bricks byte for byte (the same content always encodes to the same bytes).
inline bool sameRecords(const std::map<BrickKey, BrickRecord>& a, const std::map<BrickKey, BrickRecord>& b)
{
    if (a.size() != b.size()) return false;
    for (auto i = a.begin(), j = b.begin(); i != a.end(); ++i, ++j)
        if (!(i->first == j->first) || !sameBrick(i->second, j->second)) return false;
    return true;
}

/// Every coarse brick's error (BrickStore::lodError).
inline std::map<BrickKey, double> pyramidErrors(const SceneStore& scene)
{
    std::map<BrickKey, double> out;
    for (int k = 1; k <= scene.lodLevels(); ++k)
        scene.bricks().scanLodErrors(k, [&](const IndexCoord& b, double error) { out.emplace(BrickKey{k, b}, error); });
    return out;
}

/// Whether the store's pyramid, its bricks' errors included, equals one built afresh from its level 0
/// (in a new store at `scratch`).
inline bool pyramidEqualsRebuild(const SceneStore& scene, const std::string& scratch)
{
    writeStoreFile(scene.loadLevel(0), scratch);
    SceneStore rebuilt = SceneStore::open(scratch, StoreAccess::ReadWrite);
    buildStoreLod(rebuilt, scene.lodLevels());
    return sameRecords(pyramidRecords(scene), pyramidRecords(rebuilt)) && pyramidErrors(scene) == pyramidErrors(rebuilt);
}

} // namespace vdbclay::test
