#include "support/HermiteProbe.h"

#include "vdb_hermite/HermiteGrid.h"

#include <openvdb/io/File.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tree/ValueAccessor.h>

#include <fstream>
#include <iterator>
#include <sstream>
#include <zlib.h>

namespace vdbclay::test {

namespace {

std::string where(const Coord& c, int axis)
{
    std::ostringstream os;
    os << "voxel " << c << " axis " << axis;
    return os.str();
}

} // namespace

std::vector<EdgeRecord> collectEdges(const Volume& volume)
{
    const HermiteTree& tree = volume.impl().grid->constTree();
    openvdb::tree::ValueAccessor<const HermiteTree> acc(tree);
    std::vector<EdgeRecord> out;
    for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) {
        for (Index n = 0; n < Index(kLeafVoxels); ++n) {
            for (int a = 0; a < 3; ++a) {
                const PackedSample* s = leaf->sample(n, a);
                if (!s) continue;
                const Coord c = leaf->offsetToGlobalCoord(n);
                Coord nb = c;
                nb[a] += 1;
                EdgeRecord r;
                r.voxel = {c.x(), c.y(), c.z()};
                r.axis = a;
                r.from = leaf->getValue(n).id;
                r.to = acc.getValue(nb).id;
                r.sample = *s;
                out.push_back(r);
            }
        }
    }
    return out;
}

std::string checkInvariants(const Volume& volume)
{
    const HermiteTree& tree = volume.impl().grid->constTree();
    openvdb::tree::ValueAccessor<const HermiteTree> acc(tree);
    if (tree.background().id != kEmptyMaterial) return "background is not empty";

    // Leaves: samples exactly on the edges whose end materials differ; active iff a sample.
    for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) {
        std::size_t count = 0;
        for (Index n = 0; n < Index(kLeafVoxels); ++n) {
            const Coord c = leaf->offsetToGlobalCoord(n);
            const MaterialValue m = leaf->getValue(n);
            if (m.id > volume.materials().size()) return where(c, 0) + ": undefined material id";
            bool any = false;
            for (int a = 0; a < 3; ++a) {
                Coord nb = c;
                nb[a] += 1;
                const bool differ = acc.getValue(nb) != m;
                const PackedSample* s = leaf->sample(n, a);
                if (differ != (s != nullptr))
                    return where(c, a) + (differ ? ": materials differ but no sample" : ": sample on a uniform edge");
                if (s) {
                    ++count;
                    const double t = dequantizeOffset(s->offset);
                    if (!(t >= 0.0 && t <= 1.0)) return where(c, a) + ": offset outside [0,1]";
                }
                any = any || s;
            }
            if (leaf->isValueOn(n) != any) return where(c, 0) + ": active state does not match its samples";
            // An edge that ends in this leaf but starts outside any leaf cannot store its sample.
            for (int a = 0; a < 3; ++a) {
                Coord lo = c;
                lo[a] -= 1;
                if (acc.probeConstLeaf(lo)) continue;
                if (acc.getValue(lo) != m) return where(lo, a) + ": crossing edge outside any leaf";
            }
        }
        if (count != leaf->sampleCount()) return "leaf sample count does not match its edge mask";
    }
    // Solid tiles: no crossing may touch a tile voxel (tiles hold no samples).
    for (auto it = tree.cbeginValueAll(); it; ++it) {
        if (it.isVoxelValue()) continue;
        if (it.isValueOn()) return "active tile";
        const MaterialValue m = it.getValue();
        if (!m.solid()) continue;
        CoordBBox box;
        it.getBoundingBox(box);
        for (int a = 0; a < 3; ++a) {
            const int b = (a + 1) % 3, d = (a + 2) % 3;
            for (int u = box.min()[b]; u <= box.max()[b]; ++u) {
                for (int v = box.min()[d]; v <= box.max()[d]; ++v) {
                    Coord hi, lo;
                    hi[a] = box.max()[a];
                    hi[b] = u;
                    hi[d] = v;
                    Coord out = hi;
                    out[a] += 1;
                    if (acc.getValue(out) != m) return where(hi, a) + ": crossing edge inside a tile";
                    lo = hi;
                    lo[a] = box.min()[a] - 1;
                    if (!acc.probeConstLeaf(lo) && acc.getValue(lo) != m)
                        return where(lo, a) + ": crossing edge outside any leaf (tile face)";
                }
            }
        }
    }
    return {};
}

std::vector<std::array<int32_t, 3>> changedBlocks(const Volume& a, const Volume& b)
{
    const HermiteTree& ta = a.impl().grid->constTree();
    const HermiteTree& tb = b.impl().grid->constTree();
    CoordBBox bounds;
    for (const HermiteTree* t : {&ta, &tb}) {
        for (auto leaf = t->cbeginLeaf(); leaf; ++leaf) bounds.expand(leaf->getNodeBoundingBox());
        forEachTile(*t, [&](const CoordBBox& tile, MaterialValue value) {
            if (value.solid()) bounds.expand(tile); // empty tiles read as the background
        });
    }
    std::vector<std::array<int32_t, 3>> out;
    if (bounds.empty()) return out;
    openvdb::tree::ValueAccessor<const HermiteTree> accA(ta), accB(tb);
    // Every leaf holds at least one sample or one material boundary, so a leaf facing a tile differs.
    auto differs = [&](const Coord& origin) {
        const HermiteLeaf* la = accA.probeConstLeaf(origin);
        const HermiteLeaf* lb = accB.probeConstLeaf(origin);
        if (la && lb) return *la != *lb;
        if (la || lb) return true;
        return accA.getValue(origin) != accB.getValue(origin);
    };
    for (int x = bounds.min().x(); x <= bounds.max().x(); x += kLeafDim)
        for (int y = bounds.min().y(); y <= bounds.max().y(); y += kLeafDim)
            for (int z = bounds.min().z(); z <= bounds.max().z(); z += kLeafDim)
                if (differs(Coord(x, y, z))) out.push_back({x, y, z});
    return out;
}

std::vector<std::array<int32_t, 3>> leafOrigins(const Volume& volume)
{
    std::vector<std::array<int32_t, 3>> out;
    for (auto leaf = volume.impl().grid->constTree().cbeginLeaf(); leaf; ++leaf) {
        const Coord o = leaf->origin();
        out.push_back({o.x(), o.y(), o.z()});
    }
    std::sort(out.begin(), out.end());
    return out;
}

std::vector<uint64_t> solidVoxelsPerMaterial(const Volume& volume)
{
    const HermiteTree& tree = volume.impl().grid->constTree();
    std::vector<uint64_t> counts(volume.materials().size() + 1, 0);
    for (auto it = tree.cbeginValueAll(); it; ++it) {
        const MaterialId id = it.getValue().id;
        if (id == kEmptyMaterial || id >= counts.size()) continue;
        counts[id] += it.isVoxelValue() ? 1 : it.getVoxelCount();
    }
    return counts;
}

void appendIntegrityTrailer(const std::string& path)
{
    std::vector<char> bytes;
    {
        std::ifstream in(path, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    const uint64_t size = bytes.size();
    const uint32_t crc = uint32_t(::crc32(::crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(bytes.data()), uInt(size)));
    const uint32_t version = 1;
    std::ofstream out(path, std::ios::binary | std::ios::app);
    out.write("VDBCLAY", 8); // seven letters and the terminating zero
    out.write(reinterpret_cast<const char*>(&size), sizeof(size));
    out.write(reinterpret_cast<const char*>(&crc), sizeof(crc));
    out.write(reinterpret_cast<const char*>(&version), sizeof(version));
}

void writeHermiteFile(const Volume& volume, const std::string& path, std::optional<int> formatVersion,
                      std::optional<std::string> materialsJson, bool trailer)
{
    initializeHermiteGrid();
    HermiteGrid::Ptr out = openvdb::gridPtrCast<HermiteGrid>(volume.impl().grid->copyGrid());
    if (formatVersion) out->insertMeta(kFormatVersionKey, openvdb::Int32Metadata(*formatVersion));
    if (materialsJson) out->insertMeta(kMaterialsKey, openvdb::StringMetadata(*materialsJson));
    openvdb::io::File file(path);
    file.write(openvdb::GridCPtrVec{out});
    file.close();
    if (trailer) appendIntegrityTrailer(path);
}

int currentFormatVersion() { return kFormatVersion; }

void writeFloatGridFile(const std::string& path)
{
    openvdb::initialize();
    auto grid = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(10.0f, openvdb::Vec3f(0.0f), 1.0f);
    grid->setName("sphere");
    openvdb::io::File file(path);
    file.write(openvdb::GridCPtrVec{grid});
    file.close();
}

} // namespace vdbclay::test
