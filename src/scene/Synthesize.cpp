#include "scene/Synthesize.h"

#include "sculpt/Csg.h"
#include "sculpt/SyntheticFields.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <stdexcept>

namespace vdbclay {

namespace {

/// One step of a scene: an op with a field, in world units, applied in order.
struct Layer {
    CsgMode mode = CsgMode::Add;
    std::shared_ptr<const SdfField> field;
    MaterialId material = 1;
    WorldBounds bounds; // where the layer can change anything (unbounded: everywhere)
};

struct Recipe {
    MaterialTable materials;
    std::vector<Layer> layers;
    std::vector<IndexCoord> bricks; // sorted
    std::vector<std::shared_ptr<const SdfField>> parts; // fields the layers' fields refer to
};

Material material(const char* name, std::array<float, 4> color, float toughness)
{
    Material m;
    m.name = name;
    m.color = color;
    m.toughness = toughness;
    return m;
}

int32_t floorDiv(double v, int32_t d) { return int32_t(std::floor(v / double(d))); }

/// The bricks a box of world bounds overlaps (grown by two voxels).
void addBricks(std::set<IndexCoord>& out, const WorldBounds& b, double vs)
{
    IndexCoord lo, hi;
    for (int i = 0; i < 3; ++i) {
        lo[std::size_t(i)] = floorDiv(b.min[i] / vs - 2.0, kBrickEdge);
        hi[std::size_t(i)] = floorDiv(b.max[i] / vs + 2.0, kBrickEdge);
    }
    for (int32_t x = lo[0]; x <= hi[0]; ++x)
        for (int32_t y = lo[1]; y <= hi[1]; ++y)
            for (int32_t z = lo[2]; z <= hi[2]; ++z) out.insert({x, y, z});
}

Brush placedBrush(const Primitive& p, const Vec3d& at, const Vec3d& rotation = Vec3d(0.0))
{
    Placement pl;
    pl.translation = at;
    pl.rotationDegrees = rotation;
    return Brush(p, pl);
}

TerrainParams terrainParams(const SynthOptions& o)
{
    const double vs = o.voxelSize, n = double(o.extent);
    TerrainParams tp;
    tp.baseHeight = n * 0.12 * vs;
    tp.amplitude = n * 0.05 * vs;
    tp.wavelength = n * 0.25 * vs;
    tp.octaves = 5;
    tp.seed = o.seed;
    tp.spacing = vs;
    return tp;
}

Recipe terrain(const SynthOptions& o)
{
    Recipe r;
    const double vs = o.voxelSize, n = double(o.extent);
    const MaterialId rock = 1;
    r.materials = MaterialTable();
    r.materials.define(material("default", {0.45f, 0.42f, 0.40f, 1.0f}, 0.8f));
    const MaterialId grass = r.materials.define(material("grass", {0.25f, 0.55f, 0.20f, 1.0f}, 0.3f));
    const MaterialId snow = r.materials.define(material("snow", {0.95f, 0.95f, 0.97f, 1.0f}, 0.1f));
    const TerrainParams tp = terrainParams(o);
    auto ground = std::make_shared<TerrainField>(tp);
    r.parts.push_back(ground);
    // The ground is cut to the scene's square and given a flat bottom inside its lowest bricks, so the
    // scene is a closed solid.
    const int32_t yLo = floorDiv(ground->minHeight() / vs - 2.0, kBrickEdge), yHi = floorDiv(ground->maxHeight() / vs + 2.0, kBrickEdge);
    const WorldBounds all{Vec3d(1.0 * vs, (double(yLo) * kBrickEdge + 1.0) * vs, 1.0 * vs), Vec3d((n - 1.0) * vs, 1e9, (n - 1.0) * vs)};
    r.layers.push_back({CsgMode::Add, std::make_shared<ClippedField>(*ground, all.min, all.max), rock, all});
    // Tunnels just under the surface: where they come near it they leave overhangs and arches.
    std::mt19937_64 rng(o.seed * 7919 + 1);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const int tunnels = std::max(2, int(n * n / (96.0 * 96.0)));
    for (int i = 0; i < tunnels; ++i) {
        const double x = unit(rng) * n * vs, z = unit(rng) * n * vs;
        const double radius = (3.0 + unit(rng) * n / 80.0) * vs;
        const double y = ground->height(x, z) - radius * (0.3 + 0.6 * unit(rng));
        Primitive capsule;
        capsule.shape = Shape::Capsule;
        capsule.radius = radius;
        capsule.length = (0.05 + 0.15 * unit(rng)) * n * vs;
        auto brush = std::make_shared<Brush>(placedBrush(capsule, Vec3d(x, y, z), Vec3d(90.0 * unit(rng), 360.0 * unit(rng), 0.0)));
        r.layers.push_back({CsgMode::Remove, brush, rock, brush->bounds()});
    }
    const double grassLine = tp.baseHeight - 0.2 * tp.amplitude, snowLine = tp.baseHeight + 0.55 * tp.amplitude;
    r.layers.push_back({CsgMode::Paint, std::make_shared<SlabField>(grassLine, snowLine), grass, all});
    r.layers.push_back({CsgMode::Paint, std::make_shared<SlabField>(snowLine, 1e9), snow, all});

    const int32_t bricksXZ = floorDiv(n - 1.0, kBrickEdge);
    for (int32_t x = 0; x <= bricksXZ; ++x)
        for (int32_t z = 0; z <= bricksXZ; ++z)
            for (int32_t y = yLo; y <= yHi; ++y) r.bricks.push_back({x, y, z});
    std::sort(r.bricks.begin(), r.bricks.end());
    return r;
}

Recipe asteroids(const SynthOptions& o)
{
    Recipe r;
    const double vs = o.voxelSize, n = double(o.extent);
    r.materials = MaterialTable();
    r.materials.define(material("default", {0.40f, 0.38f, 0.36f, 1.0f}, 0.7f));
    const MaterialId ice = r.materials.define(material("ice", {0.70f, 0.85f, 0.95f, 1.0f}, 0.2f));
    const MaterialId iron = r.materials.define(material("iron", {0.55f, 0.35f, 0.25f, 1.0f}, 0.95f));
    const MaterialId ids[3] = {1, ice, iron};
    std::mt19937_64 rng(o.seed * 104729 + 3);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const int count = std::clamp(int(std::pow(n / 64.0, 3.0) * 3.0), 8, 20000);
    std::set<IndexCoord> bricks;
    for (int i = 0; i < count; ++i) {
        const double radius = (4.0 + unit(rng) * unit(rng) * n / 12.0) * vs;
        const Vec3d c(unit(rng) * n * vs, unit(rng) * n * vs, unit(rng) * n * vs);
        auto blob = std::make_shared<BlobField>(c, radius, 0.3 * radius, 0.6 * radius, o.seed * 31 + uint64_t(i));
        r.layers.push_back({CsgMode::Add, blob, ids[rng() % 3], blob->bounds()});
        addBricks(bricks, blob->bounds(), vs);
    }
    r.bricks.assign(bricks.begin(), bricks.end());
    return r;
}

Recipe csgStack(const SynthOptions& o)
{
    Recipe r;
    const double vs = o.voxelSize;
    r.materials = MaterialTable();
    r.materials.define(material("default", {0.75f, 0.75f, 0.78f, 1.0f}, 0.6f));
    r.materials.define(material("red", {0.80f, 0.20f, 0.15f, 1.0f}, 0.5f));  // id 2
    r.materials.define(material("blue", {0.15f, 0.30f, 0.80f, 1.0f}, 0.5f)); // id 3: storeys cycle through 1, 2, 3
    std::mt19937_64 rng(o.seed * 15485863 + 5);
    // Towers on a lattice of integer spacing; each storey sits exactly on the one below (coplanar faces),
    // neighbours touch where their sizes reach the spacing, some storeys turn by 45 degrees.
    const int32_t spacing = 32;
    const int towers = std::max(1, o.extent / spacing);
    std::set<IndexCoord> bricks;
    auto add = [&](CsgMode mode, const Brush& b, MaterialId m) {
        auto brush = std::make_shared<Brush>(b);
        r.layers.push_back({mode, brush, m, brush->bounds()});
        addBricks(bricks, brush->bounds(), vs);
    };
    for (int i = 0; i < towers; ++i)
        for (int j = 0; j < towers; ++j) {
            const double x = (double(i * spacing) + spacing / 2.0) * vs, z = (double(j * spacing) + spacing / 2.0) * vs;
            double y = 0.0;
            const int storeys = 1 + int(rng() % 4);
            for (int s = 0; s < storeys; ++s) {
                const int half = 6 + int(rng() % 11); // 6 .. 16: 16 touches the neighbours
                const int height = 4 + int(rng() % 9);
                Primitive p;
                Vec3d rotation(0.0);
                switch (rng() % 4) {
                case 0: p.shape = Shape::Box, p.size = Vec3d(half, height / 2.0, half); break;
                case 1: p.shape = Shape::Box, p.size = Vec3d(half * 0.7, height / 2.0, half * 0.7), rotation = Vec3d(0.0, 45.0, 0.0); break;
                case 2: p.shape = Shape::Cylinder, p.radius = half, p.height = height; break;
                default: p.shape = Shape::Sphere, p.radius = height / 2.0 + 2.0; break;
                }
                p.size *= vs, p.radius *= vs, p.height *= vs;
                const double centreY = y + (p.shape == Shape::Sphere ? p.radius : height / 2.0 * vs);
                add(CsgMode::Add, placedBrush(p, Vec3d(x, centreY, z), rotation), MaterialId(1 + (i + j + s) % 3));
                y = centreY + (p.shape == Shape::Sphere ? p.radius * 0.5 : height / 2.0 * vs);
            }
            if (rng() % 3 == 0) { // a bore through the tower, flush with the lattice
                Primitive bore;
                bore.shape = Shape::Cylinder;
                bore.radius = 3.0 * vs;
                bore.height = 2.0 * spacing * vs;
                add(CsgMode::Remove, placedBrush(bore, Vec3d(x, y / 2.0, z), Vec3d(90.0, 0.0, 0.0)), 1);
            }
        }
    r.bricks.assign(bricks.begin(), bricks.end());
    return r;
}

Recipe recipeFor(const SynthOptions& o)
{
    switch (o.kind) {
    case SynthKind::Terrain: return terrain(o);
    case SynthKind::Asteroids: return asteroids(o);
    case SynthKind::CsgStack: return csgStack(o);
    }
    throw std::logic_error("unknown synth kind");
}

/// One brick of the scene: every layer that reaches it, clipped to the brick and a margin (two voxels
/// below, a leaf and two voxels above, which the CSG kernel reads), so the clip's walls fall outside.
std::optional<BrickRecord> makeBrick(const Recipe& recipe, const IndexCoord& brick, double vs)
{
    Vec3d lo, hi;
    for (int i = 0; i < 3; ++i) {
        lo[i] = (double(brick[std::size_t(i)]) * kBrickEdge - 2.0) * vs;
        hi[i] = (double(brick[std::size_t(i)] + 1) * kBrickEdge + kLeafDim + 2.0) * vs;
    }
    Volume volume(vs);
    volume.materials() = recipe.materials;
    for (const Layer& layer : recipe.layers) {
        const WorldBounds& b = layer.bounds;
        bool overlaps = true;
        for (int i = 0; i < 3; ++i) overlaps = overlaps && b.min[i] <= hi[i] && b.max[i] >= lo[i];
        if (!overlaps) continue;
        const ClippedField clipped(*layer.field, lo, hi);
        CsgOp op;
        op.mode = layer.mode;
        op.material = layer.material;
        applyCsg(volume, clipped, op);
    }
    return encodeBrick(volume, brick);
}

} // namespace

const char* synthKindName(SynthKind kind)
{
    switch (kind) {
    case SynthKind::Terrain: return "terrain";
    case SynthKind::Asteroids: return "asteroids";
    case SynthKind::CsgStack: return "csg-stack";
    }
    return "?";
}

SynthKind parseSynthKind(const std::string& name)
{
    for (SynthKind k : {SynthKind::Terrain, SynthKind::Asteroids, SynthKind::CsgStack})
        if (name == synthKindName(k)) return k;
    throw std::invalid_argument("unknown scene '" + name + "' (expected terrain, asteroids or csg-stack)");
}

void validateSynthOptions(const SynthOptions& o)
{
    if (o.extent < 16 || o.extent > 65536)
        throw std::invalid_argument("--extent must lie in 16 .. 65536 voxels, not " + std::to_string(o.extent));
    Volume probe(o.voxelSize); // checks the voxel size
}

double synthGroundHeight(const SynthOptions& options, double x, double z)
{
    if (options.kind != SynthKind::Terrain) throw std::invalid_argument("only a terrain has a ground height");
    return TerrainField(terrainParams(options)).height(x, z);
}

SynthReport synthesizeStore(const SynthOptions& options, const std::string& path, const Progress& progress)
{
    validateSynthOptions(options);
    const Recipe recipe = recipeFor(options);
    SynthReport report;
    report.bricksVisited = recipe.bricks.size();
    createStoreFile(path, options.voxelSize, recipe.materials, [&](SceneStore& scene) {
        const StoredBricks stored = putNewBricks(
            scene, 0, recipe.bricks, [&](std::size_t i) { return makeBrick(recipe, recipe.bricks[i], options.voxelSize); }, progress);
        report.bricks = stored.bricks;
        report.leaves = stored.leaves;
        report.bytes = stored.bytes;
    });
    return report;
}

} // namespace vdbclay
