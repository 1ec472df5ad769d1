#include "scene/SceneDiff.h"

#include "mesher/MeshQuality.h"
#include "mesher/Mesh.h"
#include "mesher/Mesher.h"
#include "scene/SceneStore.h"
#include "vdb_hermite/VolumeIO.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <set>

namespace vdbclay {

namespace {

/// A scene read brick by brick: a store, or a .vdb loaded whole.
class SceneSource {
public:
    explicit SceneSource(const std::string& path)
    {
        if (isStorePath(path)) store_.emplace(SceneStore::open(path, StoreAccess::ReadOnly));
        else volume_.emplace(loadVolume(path));
    }
    double voxelSize() const { return store_ ? store_->voxelSize() : volume_->voxelSize(); }
    const MaterialTable& materials() const { return store_ ? store_->materials() : volume_->materials(); }
    std::vector<IndexCoord> bricks() const
    {
        if (store_) return store_->brickCoords(0);
        std::vector<IndexCoord> out;
        for (const IndexCoord& o : occupiedBoxes(*volume_, kBrickEdge))
            out.push_back({o[0] / kBrickEdge, o[1] / kBrickEdge, o[2] / kBrickEdge});
        return out;
    }
    std::optional<BrickRecord> record(const IndexCoord& brick) const
    {
        return store_ ? store_->bricks().get({0, brick}) : encodeBrick(*volume_, brick);
    }
    Volume region(const std::vector<IndexCoord>& bricks) const
    {
        Volume out(voxelSize());
        out.materials() = materials();
        if (store_) {
            store_->loadBricks(0, bricks, out);
        } else {
            for (const IndexCoord& b : bricks) {
                pasteRegion(out, copyRegion(*volume_, brickBox(b)), brickBox(b));
            }
        }
        return out;
    }

private:
    std::optional<SceneStore> store_;
    std::optional<Volume> volume_;
};

} // namespace

bool SceneDiff::withinTolerance(double toleranceVoxels) const
{
    if (identical()) return true;
    if (voxelSizesDiffer || materialTablesDiffer || materialDifferences > 0) return false;
    return surfaceDistance <= toleranceVoxels * voxelSize;
}

SceneDiff diffScenes(const std::string& pathA, const std::string& pathB, bool measureSurface)
{
    const SceneSource a(pathA), b(pathB);
    SceneDiff diff;
    diff.voxelSize = a.voxelSize();
    diff.otherVoxelSize = b.voxelSize();
    if (a.voxelSize() != b.voxelSize()) { // other lattices: no voxel or brick of one is one of the other
        diff.voxelSizesDiffer = true;
        diff.surfaceDistance = std::numeric_limits<double>::quiet_NaN();
        return diff;
    }
    diff.materialTablesDiffer = !(a.materials() == b.materials());
    std::set<IndexCoord> all;
    for (const IndexCoord& c : a.bricks()) all.insert(c);
    for (const IndexCoord& c : b.bricks()) all.insert(c);
    for (const IndexCoord& brick : all) {
        if (sameBrick(a.record(brick), b.record(brick))) continue;
        // Different bytes may still hold the same voxels (a tree laid out otherwise): compare those.
        const RegionDifference d = compareRegion(a.region({brick}), b.region({brick}), brickBox(brick));
        if (!d.any()) continue;
        diff.differingBricks.push_back(brick);
        diff.occupancyDifferences += d.occupancy;
        diff.materialDifferences += d.materials;
        diff.sampleDifferences += d.samples;
    }
    const double vs = diff.voxelSize;
    diff.differenceVolume = double(diff.occupancyDifferences) * vs * vs * vs;
    if (diff.differingBricks.empty()) return diff;

    if (!measureSurface || (diff.occupancyDifferences == 0 && diff.sampleDifferences == 0)) return diff; // the same surface

    // The surfaces around the differing bricks, meshed with a ring of bricks around them so the region's
    // cut walls lie in bricks both scenes share. Only the triangles in the differing bricks (grown by a
    // leaf, as cells read their neighbours) are measured, each side against the other side's whole mesh:
    // elsewhere the surfaces are the same.
    std::set<IndexCoord> region;
    for (const IndexCoord& c : diff.differingBricks)
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz) region.insert({c[0] + dx, c[1] + dy, c[2] + dz});
    const std::vector<IndexCoord> bricks(region.begin(), region.end());
    MeshOptions options;
    options.kind = MesherKind::CubicalMarchingSquares;
    const Mesh meshA = meshVolume(a.region(bricks), options), meshB = meshVolume(b.region(bricks), options);
    const std::set<IndexCoord> differing(diff.differingBricks.begin(), diff.differingBricks.end());
    const auto crop = [&](const Mesh& mesh) {
        Mesh out = mesh;
        out.triangles.clear();
        out.triangleMaterials.clear();
        for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
            bool near = false;
            for (uint32_t v : mesh.triangles[t]) {
                for (int dx = -1; dx <= 1 && !near; dx += 2)
                    for (int dy = -1; dy <= 1 && !near; dy += 2)
                        for (int dz = -1; dz <= 1 && !near; dz += 2) {
                            const double margin = kLeafDim * vs;
                            const auto& p = mesh.positions[v];
                            const IndexCoord c{int32_t(std::floor((p[0] + dx * margin) / (kBrickEdge * vs))),
                                               int32_t(std::floor((p[1] + dy * margin) / (kBrickEdge * vs))),
                                               int32_t(std::floor((p[2] + dz * margin) / (kBrickEdge * vs)))};
                            near = differing.count(c) > 0;
                        }
            }
            if (!near) continue;
            out.triangles.push_back(mesh.triangles[t]);
            if (t < mesh.triangleMaterials.size()) out.triangleMaterials.push_back(mesh.triangleMaterials[t]);
        }
        return out;
    };
    // Samples a quarter voxel apart for a local change; a voxel apart where much of the scene changed.
    const double spacing = (diff.differingBricks.size() <= 8 ? 0.25 : 1.0) * vs;
    diff.surfaceDistance = std::max(maxDistanceToMesh(crop(meshA), meshB, spacing), maxDistanceToMesh(crop(meshB), meshA, spacing));
    return diff;
}

} // namespace vdbclay
