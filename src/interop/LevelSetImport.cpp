#include "interop/LevelSetImport.h"

#include "interop/StandardGridRead.h"
#include "interop/StandardVdb.h"
#include "vdb_hermite/HermiteGrid.h"
#include "vdb_hermite/MemoryLimit.h"
#include "vdb_hermite/NumberText.h"
#include "vdb_hermite/PrintableText.h"
#include "vdb_hermite/Quantize.h"
#include "vdb_hermite/VolumeIO.h"

#include <openvdb/tools/GridTransformer.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <set>
#include <stdexcept>

namespace vdbclay {

namespace {

using openvdb::FloatGrid;
using FloatAccessor = openvdb::tree::ValueAccessor<const openvdb::FloatTree>;

/// Where the field is solid: g < 0, with g the level set minus the iso value, or the iso value minus
/// the density, so that the gradient of g points out of the solid.
struct SignedField {
    const openvdb::FloatTree& tree;
    float iso;
    bool fog;
    openvdb::Coord shift; // our index = the grid's index + shift

    float at(const FloatAccessor& a, const openvdb::Coord& ours) const
    {
        const float v = a.getValue(ours - shift);
        return fog ? iso - v : v - iso;
    }
};

std::array<double, 3> gradientAt(const SignedField& f, const FloatAccessor& a, const openvdb::Coord& p)
{
    std::array<double, 3> g{};
    for (int axis = 0; axis < 3; ++axis) {
        openvdb::Coord lo = p, hi = p;
        lo[axis] -= 1;
        hi[axis] += 1;
        g[std::size_t(axis)] = 0.5 * (double(f.at(a, hi)) - double(f.at(a, lo)));
    }
    return g;
}

HermiteLeafData leafData(const SignedField& f, const openvdb::Coord& origin, MaterialId material, uint64_t& crossings)
{
    FloatAccessor a(f.tree);
    HermiteLeafData data;
    for (int x = 0; x < kLeafDim; ++x)
        for (int y = 0; y < kLeafDim; ++y)
            for (int z = 0; z < kLeafDim; ++z) {
                const openvdb::Coord p = origin.offsetBy(x, y, z);
                const int offset = (x << (2 * kLeafLog2Dim)) | (y << kLeafLog2Dim) | z;
                const float gp = f.at(a, p);
                const bool solid = gp < 0.0f;
                data.material[std::size_t(offset)].id = solid ? material : kEmptyMaterial;
                for (int axis = 0; axis < 3; ++axis) {
                    openvdb::Coord q = p;
                    q[axis] += 1;
                    const float gq = f.at(a, q);
                    if ((gq < 0.0f) == solid) continue;
                    const double t = std::clamp(double(gp) / (double(gp) - double(gq)), 0.0, 1.0);
                    const std::array<double, 3> np = gradientAt(f, a, p), nq = gradientAt(f, a, q);
                    std::array<double, 3> n{};
                    double length = 0.0;
                    for (int i = 0; i < 3; ++i) {
                        n[std::size_t(i)] = (1.0 - t) * np[std::size_t(i)] + t * nq[std::size_t(i)];
                        length += n[std::size_t(i)] * n[std::size_t(i)];
                    }
                    if (!(length > 1e-24)) {
                        n = {0.0, 0.0, 0.0};
                        n[std::size_t(axis)] = solid ? 1.0 : -1.0; // out of the solid along the edge
                    }
                    const int bit = HermiteLeaf::edgeBit(Index(offset), axis);
                    data.edgeBits[std::size_t(bit >> 6)] |= uint64_t(1) << (bit & 63);
                    data.samples.push_back(packSample(t, n));
                    ++crossings;
                }
            }
    return data;
}

/// The leaves whose voxels or positive edges touch a leaf of the field, or the face of one of its
/// solid tiles where the sign changes across it (a fog's dense tile beside an empty one).
std::vector<Coord> candidateLeaves(const SignedField& f)
{
    std::set<Coord> out;
    auto addWithLowerNeighbours = [&](const Coord& o) {
        out.insert(o);
        for (int axis = 0; axis < 3; ++axis) {
            Coord n = o;
            n[axis] -= kLeafDim;
            out.insert(n);
        }
    };
    for (auto leaf = f.tree.cbeginLeaf(); leaf; ++leaf) addWithLowerNeighbours(leaf->origin() + f.shift);
    FloatAccessor a(f.tree);
    auto tiles = f.tree.cbeginValueAll();
    tiles.setMaxDepth(openvdb::FloatTree::ValueAllCIter::LEAF_DEPTH - 1);
    for (; tiles; ++tiles) {
        CoordBBox box;
        tiles.getBoundingBox(box);
        box.translate(f.shift);
        // A sign change across a tile's face is found from its solid side (most tiles lie outside).
        const bool solid = f.at(a, box.min()) < 0.0f;
        if (!solid) continue;
        // Each face: the leaves on both sides of it, where the value across differs in sign.
        for (int axis = 0; axis < 3; ++axis)
            for (int side = 0; side < 2; ++side) {
                const int u = (axis + 1) % 3, v = (axis + 2) % 3;
                // A tile as large as this one (or the background) beyond the face covers all of it:
                // of the same sign, the face has no patch to look at. Without this, a tile's face
                // costs (size / 8)^2 probes even inside a uniform region.
                Coord beyond = box.min();
                beyond[axis] = side ? box.max()[axis] + 1 : box.min()[axis] - 1;
                const int depth = a.getValueDepth(beyond - f.shift);
                const bool uniformBeyond = depth <= int(tiles.getDepth()); // -1: the background
                if (uniformBeyond && (f.at(a, beyond) < 0.0f) == solid) continue;
                for (int i = box.min()[u]; i <= box.max()[u]; i += kLeafDim)
                    for (int j = box.min()[v]; j <= box.max()[v]; j += kLeafDim) {
                        Coord inside, outside;
                        inside[axis] = side ? box.max()[axis] : box.min()[axis];
                        outside[axis] = side ? box.max()[axis] + 1 : box.min()[axis] - 1;
                        inside[u] = outside[u] = i;
                        inside[v] = outside[v] = j;
                        // Leaves beyond the face are candidates already; a tile beyond it of the other
                        // sign is uniform over this leaf-sized patch.
                        if (f.tree.probeConstLeaf(outside - f.shift) || (f.at(a, outside) < 0.0f) == solid) continue;
                        out.insert(alignDown(inside, kLeafDim));
                        out.insert(alignDown(outside, kLeafDim));
                    }
            }
    }
    return {out.begin(), out.end()};
}

/// NaN or infinity has no side of the surface: a crossing beside one would have no offset. Such a grid is
/// damaged (no OpenVDB tool writes one), so it is refused with where the first such value lies.
void requireFiniteValues(const FloatGrid& grid, const std::string& name, const std::string& path)
{
    uint64_t count = 0;
    std::optional<Coord> first;
    auto note = [&](const Coord& at) {
        if (!first) first = at;
        ++count;
    };
    if (!std::isfinite(grid.background()))
        throw VolumeIOError("'" + path + "': grid '" + printableText(name, 64) + "' has a background of " +
                            formatNumber(grid.background()) + ", not a finite number: the grid is damaged");
    for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf) {
        const float* values = leaf->buffer().data();
        for (Index n = 0; n < openvdb::FloatTree::LeafNodeType::SIZE; ++n)
            if (!std::isfinite(values[n])) note(leaf->offsetToGlobalCoord(n));
    }
    auto tiles = grid.tree().cbeginValueAll();
    tiles.setMaxDepth(openvdb::FloatTree::ValueAllCIter::LEAF_DEPTH - 1);
    for (; tiles; ++tiles)
        if (!std::isfinite(*tiles)) note(tiles.getCoord());
    if (count == 0) return;
    throw VolumeIOError("'" + path + "': grid '" + printableText(name, 64) + "' holds " + std::to_string(count) +
                        (count == 1 ? " value that is not a finite number" : " values that are not finite numbers") +
                        " (NaN or infinity), the first at index (" +
                        std::to_string(first->x()) + ", " + std::to_string(first->y()) + ", " + std::to_string(first->z()) +
                        "): the grid is damaged");
}

/// What one surface leaf takes while an import builds it: its data, then the leaf in the tree.
constexpr double kLeafBuildBytes = 4096.0;

/// Refuses a grid whose active voxels lie beyond what VDBClay's lattice indexes at `voxelSize` (a level
/// set translated by 1e12 spun for minutes, then said it held nothing).
void requireOnLattice(const FloatGrid& grid, double voxelSize, const std::string& name, const std::string& path)
{
    const CoordBBox box = grid.evalActiveVoxelBoundingBox();
    if (box.empty()) return;
    for (int corner = 0; corner < 8; ++corner) {
        const openvdb::Vec3d index(corner & 1 ? box.max().x() + 1 : box.min().x(), corner & 2 ? box.max().y() + 1 : box.min().y(),
                                   corner & 4 ? box.max().z() + 1 : box.min().z());
        const openvdb::Vec3d world = grid.indexToWorld(index);
        for (int a = 0; a < 3; ++a) {
            if (std::fabs(world[a] / voxelSize) <= kMaxLatticeCoordinate) continue;
            throw VolumeIOError("'" + path + "': grid '" + printableText(name, 64) + "' reaches " + formatNumber(world[a]) + " along " +
                                "xyz"[a] + ", " + formatNumber(std::fabs(world[a] / voxelSize)) + " voxels of " + formatNumber(voxelSize) +
                                " from the origin; VDBClay's lattice indexes at most " + formatNumber(kMaxLatticeCoordinate) +
                                " (move it near the origin, or give a larger --voxel-size)");
        }
    }
}

/// A grid without a class (many tools leave it unset) is a density when its background lies below the
/// iso value: read as a level set, everything outside its active voxels would be solid.
bool readAsFog(const StandardGridInfo& grid, float background, const std::optional<double>& iso)
{
    if (grid.fogVolume() || grid.levelSet()) return grid.fogVolume();
    return iso && double(background) < *iso;
}

/// The grid as a float grid on VDBClay's lattice at `voxelSize`: as it is where its transform allows
/// (`shift` then moves its index space onto ours), else resampled. Returns why it was resampled.
std::string onLattice(FloatGrid::Ptr& grid, double voxelSize, double maxVoxels, openvdb::Coord& shift)
{
    const openvdb::math::Transform& xf = grid->transform();
    std::string why;
    if (!axisAligned(xf)) why = "its transform rotates or shears";
    else if (!grid->hasUniformVoxels()) why = "its voxels are not cubes";
    else if (std::fabs(grid->voxelSize()[0] - voxelSize) > 1e-9 * voxelSize) why = "another voxel size was asked for";
    if (why.empty()) {
        const openvdb::Vec3d origin = xf.indexToWorld(openvdb::Vec3d(0.0));
        for (int i = 0; i < 3 && why.empty(); ++i) {
            const double cells = origin[i] / voxelSize;
            if (std::fabs(cells - std::round(cells)) > 1e-6) why = "its lattice is offset from VDBClay's";
            else shift[i] = int32_t(std::round(cells));
        }
    }
    if (why.empty()) return "";
    // Resampling makes about as many voxels as the grid has, times its voxels' volume over the new one's.
    const double sourceVolume = std::fabs(xf.baseMap()->getAffineMap()->getMat4().getMat3().det());
    const double expected = double(grid->activeVoxelCount()) * sourceVolume / (voxelSize * voxelSize * voxelSize);
    if (!(expected <= maxVoxels))
        throw std::invalid_argument("resampling this grid at a voxel size of " + formatNumber(voxelSize) + " would make about " +
                                    formatNumber(expected) + " voxels; give a larger --voxel-size");
    // OpenVDB rebuilds a level set's band with the background as its outside distance.
    if (grid->getGridClass() == openvdb::GRID_LEVEL_SET && !(grid->background() > 0.0f))
        throw std::invalid_argument("it is a level set whose background, its distance outside the band, is " +
                                    formatNumber(grid->background()) + ", not positive");
    FloatGrid::Ptr out = FloatGrid::create(grid->background());
    out->setTransform(openvdb::math::Transform::createLinearTransform(voxelSize));
    out->setGridClass(grid->getGridClass());
    // Level sets are rebuilt as narrow bands at the new voxel size (resampleToMatch does so for
    // GRID_LEVEL_SET); a fog is resampled with trilinear interpolation.
    openvdb::tools::resampleToMatch<openvdb::tools::BoxSampler>(*grid, *out);
    grid = out;
    shift = openvdb::Coord(0);
    return why;
}

} // namespace

struct LevelSetImporter::Impl {
    FloatGrid::Ptr grid;
    float iso = 0.0f;
    bool fog = false;
    openvdb::Coord shift{0};
    double voxelSize = 1.0;
    double memoryLimit = 0.0;
    MaterialTable materials;
    MaterialId material = 1;
    std::vector<Coord> candidates;  // sorted: the leaves near the surface
    std::vector<CoordBBox> solidTiles; // our index space
    LevelSetImportReport report;

    SignedField field() const { return SignedField{grid->tree(), iso, fog, shift}; }
};

LevelSetImporter::LevelSetImporter(const std::string& path, const LevelSetImportOptions& options) : impl_(std::make_unique<Impl>())
{
    const StandardVdbInfo info = describeStandardVdb(path);
    const StandardGridInfo& chosen = chooseImportGrid(info, options.grid, path);
    if (chosen.fogVolume() && !options.iso)
        throw std::invalid_argument("grid '" + printableText(chosen.name, 64) + "' of '" + path +
                                    "' is a fog volume: give --iso VALUE (solid where the density exceeds it)");
    if (options.voxelSize && !(*options.voxelSize >= kMinVoxelSize && *options.voxelSize <= kMaxVoxelSize))
        throw std::invalid_argument("a voxel size must be between " + formatNumber(kMinVoxelSize) + " and " +
                                    formatNumber(kMaxVoxelSize));
    const double voxelSize = options.voxelSize.value_or(chosen.voxelSize[0]);
    if (!(voxelSize >= kMinVoxelSize && voxelSize <= kMaxVoxelSize))
        throw std::invalid_argument("grid '" + printableText(chosen.name, 64) + "' has a voxel size of " +
                                    formatNumber(voxelSize) + "; give --voxel-size");

    openvdb::GridBase::Ptr base = readStandardGrid(path, chosen.name);
    // The grid read must be the one chosen (OpenVDB picks among repeated names by the typed form).
    if (base->valueType() != chosen.header.valueType ||
        base->getGridClass() != openvdb::GridBase::stringToGridClass(chosen.header.gridClass))
        throw VolumeIOError("'" + path + "': reading grid '" + printableText(chosen.name, 64) + "' gave another grid's data");
    FloatGrid::Ptr grid = openvdb::gridPtrCast<FloatGrid>(base);
    if (!grid) {
        const openvdb::DoubleGrid::Ptr d = openvdb::gridPtrCast<openvdb::DoubleGrid>(base);
        if (!d) throw VolumeIOError("'" + path + "': grid '" + printableText(chosen.name, 64) + "' is not a float grid");
        grid = FloatGrid::create(std::make_shared<openvdb::FloatTree>(d->tree())); // values converted
        grid->setTransform(d->transform().copy());
        grid->setGridClass(d->getGridClass());
    }
    requireFiniteValues(*grid, chosen.name, path);
    requireOnLattice(*grid, voxelSize, chosen.name, path);
    const bool fog = readAsFog(chosen, grid->background(), options.iso);
    const float iso = float(options.iso.value_or(0.0));
    if (fog ? grid->background() > iso : grid->background() < iso)
        throw std::invalid_argument("grid '" + printableText(chosen.name, 64) + "' read as a " +
                                    (fog ? "fog volume (solid above the iso value)" : "level set (solid below the iso value)") +
                                    " would be solid everywhere outside its active voxels: its background " +
                                    formatNumber(grid->background()) + " is " + (fog ? "above" : "below") + " the iso value " +
                                    formatNumber(iso) + "; give another --iso");
    openvdb::Coord shift(0);
    std::string resampled;
    try {
        resampled = onLattice(grid, voxelSize, options.maxResampledVoxels, shift);
    } catch (const std::exception& e) { // OpenVDB's own failures (a transform it cannot invert, ...)
        throw VolumeIOError("'" + path + "': grid '" + printableText(chosen.name, 64) +
                            "' cannot be resampled onto VDBClay's lattice: " + printableText(e.what(), 200));
    }

    Impl& m = *impl_;
    m.grid = grid;
    m.iso = iso;
    m.fog = fog;
    m.shift = shift;
    m.voxelSize = voxelSize;
    m.memoryLimit = options.memoryLimitBytes;
    m.material = m.materials.find(options.material).value_or(0) != 0 ? *m.materials.find(options.material)
                                                                       : m.materials.define(Material{options.material});
    const SignedField field = m.field();
    {
        FloatAccessor a(grid->tree());
        auto tiles = grid->tree().cbeginValueAll();
        tiles.setMaxDepth(openvdb::FloatTree::ValueAllCIter::LEAF_DEPTH - 1);
        for (; tiles; ++tiles) {
            CoordBBox box;
            tiles.getBoundingBox(box);
            box.translate(shift);
            if (field.at(a, box.min()) < 0.0f) m.solidTiles.push_back(box);
        }
    }
    m.candidates = candidateLeaves(field);
    std::sort(m.candidates.begin(), m.candidates.end());
    m.report.grid = chosen.name;
    m.report.gridClass = chosen.header.gridClass;
    m.report.valueType = chosen.header.valueType;
    m.report.fog = fog;
    m.report.voxelSize = voxelSize;
    m.report.resampled = resampled;
}

LevelSetImporter::LevelSetImporter(LevelSetImporter&&) noexcept = default;
LevelSetImporter& LevelSetImporter::operator=(LevelSetImporter&&) noexcept = default;
LevelSetImporter::~LevelSetImporter() = default;

double LevelSetImporter::voxelSize() const { return impl_->voxelSize; }
const MaterialTable& LevelSetImporter::materials() const { return impl_->materials; }
const LevelSetImportReport& LevelSetImporter::report() const { return impl_->report; }
uint64_t LevelSetImporter::surfaceLeaves() const { return impl_->candidates.size(); }

std::vector<IndexCoord> LevelSetImporter::occupiedBoxes(int32_t edge) const
{
    const auto floorDiv = [edge](int32_t v) { return v >= 0 ? v / edge : -((-int64_t(v) + edge - 1) / edge); };
    // Solid tiles may be huge (a 4096^3 tile is 262,144 bricks): the list is counted before it is made.
    double listed = double(impl_->candidates.size());
    for (const CoordBBox& t : impl_->solidTiles) listed += double(t.volume()) / (double(edge) * edge * edge) + 1.0;
    requireMemory(listed * 64.0, "listing the " + formatNumber(listed) + " boxes of " + std::to_string(edge) + " voxels the grid fills",
                  "give a larger --voxel-size", impl_->memoryLimit);
    std::set<IndexCoord> boxes;
    for (const Coord& c : impl_->candidates) boxes.insert({int32_t(floorDiv(c.x())), int32_t(floorDiv(c.y())), int32_t(floorDiv(c.z()))});
    for (const CoordBBox& t : impl_->solidTiles)
        for (int64_t x = floorDiv(t.min().x()); x <= floorDiv(t.max().x()); ++x)
            for (int64_t y = floorDiv(t.min().y()); y <= floorDiv(t.max().y()); ++y)
                for (int64_t z = floorDiv(t.min().z()); z <= floorDiv(t.max().z()); ++z) boxes.insert({int32_t(x), int32_t(y), int32_t(z)});
    return {boxes.begin(), boxes.end()};
}

Volume LevelSetImporter::region(const LeafAlignedBox& box, uint64_t* crossings) const
{
    // Each leaf-sized block is a surface leaf, or uniform: solid where the field is below zero (inside a
    // solid tile), empty elsewhere. The same content as the whole volume's, block for block.
    const Impl& m = *impl_;
    const SignedField field = m.field();
    FloatAccessor a(m.grid->tree());
    std::vector<Coord> origins, uniformOrigins;
    std::vector<HermiteLeafData> data;
    std::vector<MaterialValue> uniformValues;
    uint64_t count = 0;
    for (int32_t x = 0; x < box.edge; x += kLeafDim)
        for (int32_t y = 0; y < box.edge; y += kLeafDim)
            for (int32_t z = 0; z < box.edge; z += kLeafDim) {
                const Coord origin(box.min[0] + x, box.min[1] + y, box.min[2] + z);
                if (std::binary_search(m.candidates.begin(), m.candidates.end(), origin)) {
                    origins.push_back(origin);
                    data.push_back(leafData(field, origin, m.material, count));
                } else if (field.at(a, origin) < 0.0f) {
                    uniformOrigins.push_back(origin);
                    uniformValues.push_back(MaterialValue{m.material});
                }
            }
    Volume volume(m.voxelSize);
    volume.materials() = m.materials;
    placeLeaves(volume.impl().grid->tree(), origins, data);
    placeUniformLeaves(volume.impl().grid->tree(), uniformOrigins, uniformValues);
    if (crossings) *crossings += count;
    return volume;
}

Volume LevelSetImporter::whole()
{
    Impl& m = *impl_;
    // A file of a few tiles may hold a huge solid: its surface leaves are built as data, then as leaves.
    requireMemory(double(m.candidates.size()) * kLeafBuildBytes,
                  "importing grid '" + printableText(m.report.grid, 64) + "' (" + std::to_string(m.candidates.size()) +
                      " surface leaves) into memory",
                  "import it into a store (-o NAME.vdbclay), which is written brick by brick, or give a larger --voxel-size",
                  m.memoryLimit);
    Volume volume(m.voxelSize);
    volume.materials() = m.materials;
    HermiteTree& out = volume.impl().grid->tree();
    // Solid tiles first; the leaves near the surface then replace what they cover.
    for (const CoordBBox& box : m.solidTiles) out.fill(box, MaterialValue{m.material}, false);
    const SignedField field = m.field();
    std::vector<HermiteLeafData> data(m.candidates.size());
    std::vector<uint64_t> crossings(m.candidates.size(), 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m.candidates.size(), 16), [&](const auto& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) data[i] = leafData(field, m.candidates[i], m.material, crossings[i]);
    });
    m.report.crossings = 0;
    for (uint64_t c : crossings) m.report.crossings += c;
    placeLeaves(out, m.candidates, data);
    return volume;
}

Volume importLevelSet(const std::string& path, const LevelSetImportOptions& options, LevelSetImportReport* report)
{
    LevelSetImporter importer(path, options);
    Volume volume = importer.whole();
    if (report) *report = importer.report();
    return volume;
}

} // namespace vdbclay
