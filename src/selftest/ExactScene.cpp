#include "selftest/ExactScene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace vdbclay {

struct ExactScene::Op {
    CsgMode mode;
    std::shared_ptr<const SdfField> field;
    MaterialId material;
    std::vector<double> erodeOffset; // per material id; +inf where the op cannot bite
};

ExactScene::ExactScene(const StrokeScript& script, const MaterialTable& materials, double voxelSize)
    : onSurface_(1e-9 * voxelSize) // the CSG kernel's band (Csg.cpp, kOnSurfaceVoxels)
{
    for (const ScriptOp& s : script.ops) {
        // Reshaping brushes have no closed form to compare with.
        if (s.field || s.maskEdit) throw std::invalid_argument(std::string("exact evaluation has no closed form for ") + opModeName(s));
        Op op;
        op.mode = s.mode;
        op.field = s.path.size() > 1 ? std::shared_ptr<const SdfField>(std::make_shared<SweptBrush>(s.brush, s.path))
                                     : std::shared_ptr<const SdfField>(std::make_shared<Brush>(s.brush));
        op.material = s.material.empty() ? MaterialId(1) : materials.find(s.material).value_or(MaterialId(1));
        if (s.mode == CsgMode::Erode) {
            const double depth = s.depth ? *s.depth : s.brush.innerRadius();
            op.erodeOffset.assign(materials.size() + 1, 0.0);
            for (MaterialId id = 1; id <= materials.size(); ++id) {
                const double bite = s.strength * (1.0 - materials.at(id).toughness);
                op.erodeOffset[id] = bite > 0.0 ? (1.0 - bite) * depth : std::numeric_limits<double>::infinity();
            }
        }
        ops_.push_back(op);
        // Symmetry: the same op through each further copy, in the order runStrokeScript applies them.
        if (!s.symmetry.any()) continue;
        const std::vector<Mat3d> copies = symmetryCopies(s.symmetry);
        for (std::size_t c = 1; c < copies.size(); ++c) {
            Op copy = op;
            copy.field = std::make_shared<TransformedField>(op.field, copies[c], s.symmetry.center);
            ops_.push_back(std::move(copy));
        }
    }
}

ExactScene::~ExactScene() = default;

MaterialId ExactScene::materialAt(const Vec3d& p) const
{
    MaterialId m = 0;
    for (const Op& op : ops_) {
        const double d = op.field->distance(p) - onSurface_;
        switch (op.mode) {
        case CsgMode::Add:
            if (d < 0.0) m = op.material;
            break;
        case CsgMode::Remove:
            if (d < 0.0) m = 0;
            break;
        case CsgMode::Intersect:
            if (!(d < 0.0)) m = 0;
            break;
        case CsgMode::Paint:
            if (d < 0.0 && m != 0) m = op.material;
            break;
        case CsgMode::Erode:
            if (m != 0 && d + op.erodeOffset[m] < 0.0) m = 0;
            break;
        }
    }
    return m;
}

bool ExactScene::nearSurface(const Vec3d& p, double band) const
{
    for (const Op& op : ops_) {
        const double d = op.field->distance(p);
        if (std::fabs(d) < band) return true;
        if (op.mode == CsgMode::Erode)
            for (double offset : op.erodeOffset)
                if (std::isfinite(offset) && std::fabs(d + offset) < band) return true;
    }
    return false;
}

WorldBounds ExactScene::solidBounds() const
{
    WorldBounds box{Vec3d(std::numeric_limits<double>::infinity()), Vec3d(-std::numeric_limits<double>::infinity())};
    for (const Op& op : ops_) {
        if (op.mode != CsgMode::Add) continue;
        const WorldBounds b = op.field->bounds();
        for (int i = 0; i < 3; ++i) {
            box.min[i] = std::min(box.min[i], b.min[i]);
            box.max[i] = std::max(box.max[i], b.max[i]);
        }
    }
    return box;
}

} // namespace vdbclay
