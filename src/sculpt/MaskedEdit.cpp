#include "sculpt/MaskedEdit.h"

#include "vdb_hermite/HermiteGrid.h"

#include <algorithm>
#include <bitset>
#include <cmath>
#include <map>
#include <optional>
#include <set>
#include <vector>

namespace vdbclay {

namespace {

IndexCoord indexOf(const Coord& c) { return {c.x(), c.y(), c.z()}; }

/// A leaf-sized block of a tree as plain data: its leaf's content, or its tile's material everywhere.
HermiteLeafData blockData(const HermiteTree& tree, const Coord& origin)
{
    if (const HermiteLeaf* leaf = tree.probeConstLeaf(origin)) return leaf->extract();
    HermiteLeafData data;
    data.material.fill(tree.getValue(origin));
    return data;
}

/// Sample lookup in plain leaf data (its samples are in edge-bit order).
class SampleIndex {
public:
    explicit SampleIndex(const HermiteLeafData& data) : data_(data)
    {
        uint32_t count = 0;
        for (int w = 0; w < kEdgeWords; ++w) {
            prefix_[std::size_t(w)] = count;
            count += uint32_t(HermiteLeaf::bitCount(data.edgeBits[std::size_t(w)]));
        }
    }
    std::optional<PackedSample> at(int bit) const
    {
        const uint64_t word = data_.edgeBits[std::size_t(bit >> 6)];
        if (!((word >> (bit & 63)) & 1u)) return std::nullopt;
        const uint64_t below = word & ((uint64_t(1) << (bit & 63)) - 1);
        return data_.samples[prefix_[std::size_t(bit >> 6)] + uint32_t(HermiteLeaf::bitCount(below))];
    }

private:
    const HermiteLeafData& data_;
    std::array<uint32_t, kEdgeWords> prefix_{};
};

/// A crossing where nothing better is known: the edge's middle, its normal along the edge, out of the
/// solid end (from the first voxel to the second where both or neither are solid).
PackedSample middleCrossing(int axis, MaterialValue from, MaterialValue to)
{
    std::array<double, 3> n{0.0, 0.0, 0.0};
    n[std::size_t(axis)] = (!from.solid() && to.solid()) ? -1.0 : 1.0;
    const std::array<uint16_t, 2> code = quantizeNormal(n);
    return {quantizeOffset(0.5), code[0], code[1]};
}

bool boxesMeet(const CoordBBox& a, const CoordBBox& b) { return a.hasOverlap(b); }

/// The leaf origins in a box.
template<typename Fn>
void forEachLeafOrigin(const CoordBBox& box, Fn&& fn)
{
    const Coord lo = alignDown(box.min(), kLeafDim), hi = alignDown(box.max(), kLeafDim);
    for (int32_t x = lo.x(); x <= hi.x(); x += kLeafDim)
        for (int32_t y = lo.y(); y <= hi.y(); y += kLeafDim)
            for (int32_t z = lo.z(); z <= hi.z(); z += kLeafDim) fn(Coord(x, y, z));
}

} // namespace

struct MaskedVoxels::Impl {
    VoxelMask mask;
    CoordBBox box;                                  // the voxels the brush may change, grown by a leaf
    std::map<Coord, HermiteLeafData> leaves;        // a listed mask: the leaves it keeps, as they were
    std::optional<Volume> whole;                    // an inverted mask: the whole volume as it was

    bool capturing() const { return whole || !leaves.empty(); }

    MaterialValue beforeValue(const Coord& voxel) const
    {
        if (whole) return whole->impl().grid->constTree().getValue(voxel);
        return leaves.at(alignDown(voxel, kLeafDim)).material[HermiteLeaf::coordToOffset(voxel)];
    }
    bool captured(const Coord& voxel) const { return whole || leaves.count(alignDown(voxel, kLeafDim)); }
    HermiteLeafData beforeBlock(const Coord& origin) const
    {
        if (whole) return blockData(whole->impl().grid->constTree(), origin);
        return leaves.at(origin);
    }

    /// The blocks to rebuild: those captured, or (an inverted mask) every block within the box that the
    /// brush changed, found by comparing the trees node by node.
    std::set<Coord> candidates(const HermiteTree& after) const;
};

std::set<Coord> MaskedVoxels::Impl::candidates(const HermiteTree& after) const
{
    std::set<Coord> out;
    if (!whole) {
        for (const auto& [origin, data] : leaves) out.insert(origin);
        return out;
    }
    const HermiteTree& before = whole->impl().grid->constTree();
    const auto addLeaves = [&](const HermiteTree& tree) {
        for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf)
            if (box.isInside(leaf->origin())) out.insert(leaf->origin());
    };
    addLeaves(before);
    addLeaves(after);
    // Blocks uniform on both sides but of another material: only a tile of `after` can hold them.
    forEachTile(after, [&](const CoordBBox& tile, MaterialValue value) {
        if (!boxesMeet(tile, box)) return;
        CoordBBox part = tile;
        part.intersect(box);
        forEachLeafOrigin(part, [&](const Coord& o) {
            if (!before.probeConstLeaf(o) && before.getValue(o) != value) out.insert(o);
        });
    });
    return out;
}

MaskedVoxels::MaskedVoxels(const Volume& volume, const WorldBounds& reach) : impl_(std::make_unique<Impl>())
{
    Impl& m = *impl_;
    m.mask = volume.mask();
    if (!m.mask.any()) return;
    const double h = volume.voxelSize();
    if (reach.bounded()) {
        if (reach.min[0] > reach.max[0]) return; // reaches nothing
        Coord lo, hi;
        for (int a = 0; a < 3; ++a) {
            lo[a] = int32_t(std::clamp(std::floor(reach.min[a] / h) - 2.0, -1e9, 1e9));
            hi[a] = int32_t(std::clamp(std::ceil(reach.max[a] / h) + 2.0, -1e9, 1e9));
        }
        m.box = CoordBBox(lo, hi);
    } else {
        const VolumeStats stats = volume.stats();
        if (stats.empty) return; // an unbounded brush (a half-space) changes only what is there
        m.box = CoordBBox(Coord(stats.bboxMin[0], stats.bboxMin[1], stats.bboxMin[2]), Coord(stats.bboxMax[0], stats.bboxMax[1], stats.bboxMax[2]));
        m.box.expand(2);
    }
    m.box.expand(kLeafDim); // edges from the leaves below end in it
    if (m.mask.inverted()) {
        m.whole = volume.clone();
        return;
    }
    const HermiteTree& tree = volume.impl().grid->constTree();
    for (const auto& [origin, bits] : m.mask.listedLeaves()) {
        const Coord o(origin[0], origin[1], origin[2]);
        // The leaf, and the leaves whose positive edges end in it.
        for (const Coord& c : {o, o.offsetBy(-kLeafDim, 0, 0), o.offsetBy(0, -kLeafDim, 0), o.offsetBy(0, 0, -kLeafDim)}) {
            if (!boxesMeet(CoordBBox::createCube(c, kLeafDim), m.box) || m.leaves.count(c)) continue;
            m.leaves.emplace(c, blockData(tree, c));
        }
    }
}

MaskedVoxels::~MaskedVoxels() = default;
MaskedVoxels::MaskedVoxels(MaskedVoxels&&) noexcept = default;
MaskedVoxels& MaskedVoxels::operator=(MaskedVoxels&&) noexcept = default;

std::size_t MaskedVoxels::leaves() const { return impl_->leaves.size(); }

uint64_t MaskedVoxels::restore(Volume& volume) const
{
    const Impl& m = *impl_;
    if (!m.capturing()) return 0;
    HermiteTree& tree = volume.impl().grid->tree();
    const auto masked = [&](const Coord& c) { return m.mask.masked(indexOf(c)); };
    // A voxel's material once the mask is respected: as it was where masked (and captured), else the brush's.
    const auto finalValue = [&](const Coord& c) { return masked(c) && m.captured(c) ? m.beforeValue(c) : tree.getValue(c); };

    std::vector<std::pair<Coord, HermiteLeafData>> writes;
    for (const Coord& origin : m.candidates(tree)) {
        const HermiteLeafData before = m.beforeBlock(origin);
        const HermiteLeafData after = blockData(tree, origin);
        std::bitset<kLeafVoxels> keep;
        HermiteLeafData out;
        out.material = after.material;
        for (Index n = 0; n < Index(kLeafVoxels); ++n) {
            keep[n] = masked(HermiteLeaf::offsetToLocalCoord(n) + origin);
            if (keep[n]) out.material[n] = before.material[n];
        }
        const SampleIndex beforeSamples(before), afterSamples(after);
        for (Index n = 0; n < Index(kLeafVoxels); ++n) {
            const Coord v = HermiteLeaf::offsetToLocalCoord(n) + origin;
            for (int axis = 0; axis < 3; ++axis) {
                Coord w = v;
                w[axis] += 1;
                const bool inside = (w[axis] & (kLeafDim - 1)) != 0;
                const Index nw = inside ? HermiteLeaf::coordToOffset(w) : 0;
                const MaterialValue mv = out.material[n];
                const MaterialValue mw = inside ? out.material[nw] : finalValue(w);
                if (mv == mw) continue;
                const bool keepW = inside ? bool(keep[nw]) : masked(w);
                const int bit = HermiteLeaf::edgeBit(n, axis);
                // Between two kept voxels the old crossing stands; elsewhere the brush's, where it made one.
                std::optional<PackedSample> sample = keep[n] && keepW ? beforeSamples.at(bit) : afterSamples.at(bit);
                if (!sample) sample = keep[n] && keepW ? afterSamples.at(bit) : beforeSamples.at(bit);
                out.edgeBits[std::size_t(bit >> 6)] |= uint64_t(1) << (bit & 63);
                out.samples.push_back(sample ? *sample : middleCrossing(axis, mv, mw));
            }
        }
        if (out.material == after.material && out.edgeBits == after.edgeBits && out.samples == after.samples) continue;
        writes.emplace_back(origin, std::move(out));
    }
    // Written once every block is decided: the decisions read the brush's materials around them.
    std::set<Coord> lowers;
    for (auto& [origin, data] : writes) {
        MaterialValue uniform;
        if (uniformWithoutSamples(data, uniform)) {
            tree.addTile(1, origin, uniform, false);
        } else if (HermiteLeaf* leaf = tree.probeLeaf(origin)) {
            leaf->assign(std::move(data));
        } else {
            auto* fresh = new HermiteLeaf(origin);
            fresh->assign(std::move(data));
            tree.addLeaf(fresh);
        }
        lowers.insert(alignDown(origin, kLowerDim));
    }
    pruneNodes(tree, lowers);
    return writes.size();
}

uint64_t paintMask(VoxelMask& mask, const SdfField& field, double voxelSize, bool masked)
{
    const WorldBounds b = field.bounds();
    if (!b.bounded()) throw std::invalid_argument("a mask brush must be bounded");
    Coord lo, hi;
    for (int a = 0; a < 3; ++a) {
        lo[a] = int32_t(std::clamp(std::floor(b.min[a] / voxelSize), -1e9, 1e9));
        hi[a] = int32_t(std::clamp(std::ceil(b.max[a] / voxelSize), -1e9, 1e9));
    }
    double leafCount = 1.0;
    for (int a = 0; a < 3; ++a) leafCount *= double(hi[a] - lo[a]) / kLeafDim + 2.0;
    if (leafCount > kMaxMaskBrushLeaves) throw std::invalid_argument("the mask brush spans too many leaves");
    // A leaf whose centre lies farther from the surface than its half diagonal is wholly on one side.
    const double halfDiagonal = 0.5 * std::sqrt(3.0) * (kLeafDim - 1) * voxelSize * field.lipschitz() + 1e-9;
    uint64_t tested = 0;
    forEachLeafOrigin(CoordBBox(lo, hi), [&](const Coord& o) {
        const Vec3d centre = (Vec3d(o.x(), o.y(), o.z()) + Vec3d(0.5 * (kLeafDim - 1))) * voxelSize;
        const double d = field.distance(centre);
        if (d > halfDiagonal) return;
        if (d < -halfDiagonal) {
            mask.setLeaf(indexOf(o), masked);
            return;
        }
        for (Index n = 0; n < Index(kLeafVoxels); ++n) {
            const Coord v = HermiteLeaf::offsetToLocalCoord(n) + o;
            ++tested;
            if (field.distance(Vec3d(v.x(), v.y(), v.z()) * voxelSize) <= 0.0) mask.set(indexOf(v), masked);
        }
    });
    return tested;
}

} // namespace vdbclay
