#include "vdb_hermite/VolumeRegions.h"

#include "vdb_hermite/HermiteGrid.h"
#include "vdb_hermite/RegionBlocks.h"

#include <algorithm>
#include <set>
#include <stdexcept>
#include <string>

namespace vdbclay {

namespace {

void checkBox(const LeafAlignedBox& box)
{
    const auto aligned = [](int32_t v) { return (v & (kLeafDim - 1)) == 0; };
    if (box.edge <= 0 || !aligned(box.edge) || !aligned(box.min[0]) || !aligned(box.min[1]) || !aligned(box.min[2]))
        throw std::invalid_argument("a region must lie on leaf bounds (multiples of " + std::to_string(kLeafDim) + ")");
}

/// Calls fn(origin) for every leaf-sized block of the box.
template<typename Fn>
void forEachBlock(const LeafAlignedBox& box, Fn&& fn)
{
    region_blocks::forEachBlock(box, [&](std::size_t, const Coord& o) { fn(o); });
}

int32_t floorTo(int32_t v, int32_t edge) { return v >= 0 ? v / edge * edge : -((-v + edge - 1) / edge) * edge; }

} // namespace

Volume copyRegion(const Volume& volume, const LeafAlignedBox& box)
{
    checkBox(box);
    Volume part(volume.voxelSize());
    part.materials() = volume.materials();
    const HermiteTree& src = volume.impl().grid->constTree();
    HermiteTree& dst = part.impl().grid->tree();
    forEachBlock(box, [&](const Coord& o) {
        if (const HermiteLeaf* leaf = src.probeConstLeaf(o)) {
            dst.addLeaf(new HermiteLeaf(*leaf));
        } else {
            const MaterialValue value = src.getValue(o);
            if (value.solid()) dst.addTile(1, o, value, false);
        }
    });
    return part;
}

void pasteRegion(Volume& volume, const Volume& part, const LeafAlignedBox& box)
{
    checkBox(box);
    if (part.voxelSize() != volume.voxelSize()) throw std::invalid_argument("a pasted region needs the same voxel size");
    const HermiteTree& src = part.impl().grid->constTree();
    region_blocks::replaceBlocks(volume.impl().grid->tree(), box, [&](std::size_t, const Coord& o) {
        const HermiteLeaf* leaf = src.probeConstLeaf(o);
        return std::pair(leaf ? new HermiteLeaf(*leaf) : nullptr, leaf ? MaterialValue{} : src.getValue(o));
    });
}

void fillRegion(Volume& volume, const LeafAlignedBox& box, MaterialId material)
{
    checkBox(box);
    region_blocks::replaceBlocks(volume.impl().grid->tree(), box, [&](std::size_t, const Coord&) {
        return std::pair<HermiteLeaf*, MaterialValue>(nullptr, MaterialValue{material});
    });
}

uint64_t regionMemoryBytes(const Volume& volume, const LeafAlignedBox& box)
{
    checkBox(box);
    const HermiteTree& tree = volume.impl().grid->constTree();
    uint64_t bytes = 0;
    forEachBlock(box, [&](const Coord& o) {
        if (const HermiteLeaf* leaf = tree.probeConstLeaf(o)) bytes += leaf->memUsage();
    });
    return bytes + nodeShareBytes(box);
}

uint64_t nodeShareBytes(const LeafAlignedBox& box)
{
    const double lowerShare = double(box.edge) * box.edge * box.edge / (double(kLowerDim) * kLowerDim * kLowerDim);
    return uint64_t(lowerShare * double(sizeof(HermiteLower)));
}

std::optional<MaterialId> uniformMaterial(const Volume& volume, const LeafAlignedBox& box)
{
    checkBox(box);
    const HermiteTree& tree = volume.impl().grid->constTree();
    std::optional<MaterialId> value;
    bool uniform = true;
    forEachBlock(box, [&](const Coord& o) {
        if (!uniform) return;
        if (tree.probeConstLeaf(o)) {
            uniform = false;
            return;
        }
        const MaterialId id = tree.getValue(o).id;
        if (value && *value != id) uniform = false;
        value = id;
    });
    return uniform ? value : std::nullopt;
}

RegionDifference compareRegion(const Volume& a, const Volume& b, const LeafAlignedBox& box)
{
    checkBox(box);
    const HermiteTree& ta = a.impl().grid->constTree();
    const HermiteTree& tb = b.impl().grid->constTree();
    RegionDifference d;
    const auto include = [&](const Coord& lo, const Coord& hi) {
        for (int axis = 0; axis < 3; ++axis) {
            d.lo[std::size_t(axis)] = std::min(d.lo[std::size_t(axis)], lo[axis]);
            d.hi[std::size_t(axis)] = std::max(d.hi[std::size_t(axis)], hi[axis]);
        }
    };
    forEachBlock(box, [&](const Coord& o) {
        const HermiteLeaf* la = ta.probeConstLeaf(o);
        const HermiteLeaf* lb = tb.probeConstLeaf(o);
        if (!la && !lb) {
            const MaterialValue va = ta.getValue(o), vb = tb.getValue(o);
            if (va == vb) return;
            (va.solid() && vb.solid() ? d.materials : d.occupancy) += uint64_t(kLeafVoxels);
            include(o, o.offsetBy(kLeafDim - 1));
            return;
        }
        if (la && lb && *la == *lb) return;
        const MaterialValue tileA = la ? MaterialValue{} : ta.getValue(o), tileB = lb ? MaterialValue{} : tb.getValue(o);
        for (Index i = 0; i < Index(kLeafVoxels); ++i) {
            const MaterialValue va = la ? la->getValue(i) : tileA, vb = lb ? lb->getValue(i) : tileB;
            const auto includeVoxel = [&] {
                const Coord voxel = o + HermiteLeaf::offsetToLocalCoord(i);
                include(voxel, voxel);
            };
            if (va != vb) {
                (va.solid() && vb.solid() ? d.materials : d.occupancy)++;
                includeVoxel();
                continue;
            }
            for (int axis = 0; axis < 3; ++axis) {
                const PackedSample* sa = la ? la->sample(i, axis) : nullptr;
                const PackedSample* sb = lb ? lb->sample(i, axis) : nullptr;
                if ((sa == nullptr) != (sb == nullptr) || (sa && !(*sa == *sb))) {
                    ++d.samples;
                    includeVoxel();
                }
            }
        }
    });
    return d;
}

std::vector<IndexCoord> occupiedBoxes(const Volume& volume, int32_t edge)
{
    if (edge <= 0 || edge % kLeafDim != 0) throw std::invalid_argument("a box edge must be a multiple of the leaf size");
    const HermiteTree& tree = volume.impl().grid->constTree();
    std::set<IndexCoord> boxes;
    for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) {
        const Coord o = leaf->origin();
        boxes.insert({floorTo(o.x(), edge), floorTo(o.y(), edge), floorTo(o.z(), edge)});
    }
    forEachTile(tree, [&](const CoordBBox& tile, MaterialValue value) {
        if (!value.solid()) return;
        for (int32_t x = floorTo(tile.min().x(), edge); x <= tile.max().x(); x += edge)
            for (int32_t y = floorTo(tile.min().y(), edge); y <= tile.max().y(); y += edge)
                for (int32_t z = floorTo(tile.min().z(), edge); z <= tile.max().z(); z += edge) boxes.insert({x, y, z});
    });
    return {boxes.begin(), boxes.end()};
}

} // namespace vdbclay
