#include "vdb_hermite/Volume.h"

#include "vdb_hermite/HermiteGrid.h"
#include "vdb_hermite/NumberText.h"

#include <cmath>
#include <stdexcept>
#include <tuple>
#include <vector>

namespace vdbclay {

Volume::Volume(detail::VolumeGrid*) : impl_(std::make_unique<detail::VolumeGrid>()) { initializeHermiteGrid(); }

Volume::Volume(double voxelSize) : Volume(nullptr)
{
    if (!(voxelSize >= kMinVoxelSize && voxelSize <= kMaxVoxelSize))
        throw std::invalid_argument("a voxel size of " + formatNumber(voxelSize) + " is outside " + formatNumber(kMinVoxelSize) +
                                    " .. " + formatNumber(kMaxVoxelSize) + " world units (OpenVDB's transforms refuse finer voxels: "
                                    "give sizes in a smaller unit, millimetres instead of metres)");
    impl_->grid = HermiteGrid::create(MaterialValue{});
    impl_->grid->setName("hermite");
    impl_->grid->setTransform(openvdb::math::Transform::createLinearTransform(voxelSize));
}

Volume::~Volume() = default;
Volume::Volume(Volume&&) noexcept = default;
Volume& Volume::operator=(Volume&&) noexcept = default;

Volume Volume::clone() const
{
    Volume copy(nullptr);
    copy.impl_->grid = impl_->grid->deepCopy();
    copy.impl_->materials = impl_->materials;
    copy.impl_->mask = impl_->mask;
    copy.impl_->formatVersion = impl_->formatVersion;
    return copy;
}

int Volume::formatVersion() const { return impl_->formatVersion; }

double Volume::voxelSize() const { return impl_->grid->voxelSize()[0]; }
MaterialTable& Volume::materials() { return impl_->materials; }
const MaterialTable& Volume::materials() const { return impl_->materials; }
VoxelMask& Volume::mask() { return impl_->mask; }
const VoxelMask& Volume::mask() const { return impl_->mask; }

MaterialId Volume::materialAt(const std::array<int32_t, 3>& ijk) const
{
    return impl_->grid->tree().getValue(Coord(ijk[0], ijk[1], ijk[2])).id;
}

VolumeStats Volume::stats() const
{
    const HermiteTree& tree = impl_->grid->constTree();
    VolumeStats s;
    s.voxelSize = voxelSize();
    s.activeVoxels = tree.activeVoxelCount();
    s.leafCount = tree.leafCount();
    s.memoryBytes = tree.memUsage();
    CoordBBox bbox;
    for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) {
        s.samples += leaf->sampleCount();
        if (!bbox.empty() && bbox.isInside(leaf->getNodeBoundingBox())) continue; // nothing in it can grow the box
        const MaterialValue* values = leaf->buffer().data();
        for (Index n = 0; n < Index(kLeafVoxels); ++n) {
            if (values[n].solid() || leaf->isValueOn(n)) bbox.expand(leaf->offsetToGlobalCoord(n));
        }
    }
    forEachTile(tree, [&](const CoordBBox& tile, MaterialValue value) {
        if (!value.solid()) return;
        ++s.tileCount;
        bbox.expand(tile);
    });
    s.empty = bbox.empty();
    if (!s.empty) {
        s.bboxMin = {bbox.min().x(), bbox.min().y(), bbox.min().z()};
        s.bboxMax = {bbox.max().x(), bbox.max().y(), bbox.max().z()};
    }
    return s;
}

bool identical(const Volume& a, const Volume& b)
{
    const HermiteGrid& ga = *a.impl().grid;
    const HermiteGrid& gb = *b.impl().grid;
    if (!(a.materials() == b.materials()) || a.mask() != b.mask()) return false;
    if (ga.transform() != gb.transform()) return false;
    const HermiteTree& ta = ga.constTree();
    const HermiteTree& tb = gb.constTree();
    if (ta.background() != tb.background() || ta.leafCount() != tb.leafCount()) return false;
    auto la = ta.cbeginLeaf();
    auto lb = tb.cbeginLeaf();
    for (; la && lb; ++la, ++lb) {
        if (la->origin() != lb->origin() || *la != *lb) return false;
    }
    if (bool(la) != bool(lb)) return false;
    using Tile = std::tuple<Coord, Coord, MaterialId>;
    auto tiles = [](const HermiteTree& t) {
        std::vector<Tile> out;
        forEachTile(t, [&](const CoordBBox& box, MaterialValue value) { out.emplace_back(box.min(), box.max(), value.id); });
        return out;
    };
    return tiles(ta) == tiles(tb);
}

} // namespace vdbclay
