#include "mesher/LoopFan.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <utility>
#include <vector>

namespace vdbclay {

namespace {

/// A fan triangle folds when its normal lies more than 120 degrees (this cosine past perpendicular) from
/// the surface's normals at both of its loop points: less is a crease's bridge leaning (and a rotated
/// box's corner fans lean that far without folding).
constexpr double kFoldCosine = 0.5;

/// The ways to place a loop's inner vertex or do without one, on one mesh.
class LoopFan {
public:
    LoopFan(Mesh& mesh, const LoopFanLimits& limits) : mesh_(mesh), limits_(limits) {}

    /// A sharp vertex can land on the line through two neighbouring points of its loop (a feature on a
    /// lattice line, as where a cylinder's rim touches one), which would fan a triangle of zero area.
    /// The vertex then moves towards the loop's mean point, a little first, until every triangle of its
    /// fan has an area and the vertex keeps clear of the loop's points (the mean point itself is kept
    /// if even that fails).
    void keepFanOpen(std::array<double, 3>& centre, const uint32_t* ids, std::size_t n) const
    {
        const auto& positions = mesh_.positions;
        const auto& normals = mesh_.normals;
        auto fanIsOpen = [&](const std::array<double, 3>& exact) {
            // Judged as stored: the vertex becomes a float, which can put it back on the line.
            const std::array<double, 3> c{float(exact[0]), float(exact[1]), float(exact[2])};
            for (std::size_t i = 0; i < n; ++i) {
                const uint32_t a = ids[i], b = ids[i + 1 < n ? i + 1 : 0];
                const auto& p = positions[a];
                const auto& q = positions[b];
                const double ux = p[0] - c[0], uy = p[1] - c[1], uz = p[2] - c[2];
                const double vx = q[0] - c[0], vy = q[1] - c[1], vz = q[2] - c[2];
                const double x = uy * vz - uz * vy, y = uz * vx - ux * vz, z = ux * vy - uy * vx;
                if (x * x + y * y + z * z < limits_.minFanDoubledArea * limits_.minFanDoubledArea) return false;
                if (ux * ux + uy * uy + uz * uz < limits_.minFanSpacing * limits_.minFanSpacing) return false; // on a loop point
                // Folded: the triangle faces clearly against the surface's normals at both of its loop
                // points. A sharp vertex a concave crease's planes put beyond the loop fans triangles that
                // fold back over their neighbours; nearer the mean point they lean, as a crease's bridge may.
                const double bound = -kFoldCosine * std::sqrt(x * x + y * y + z * z);
                const auto against = [&](const std::array<float, 3>& m) { return x * m[0] + y * m[1] + z * m[2] < bound; };
                if (against(normals[a]) && against(normals[b])) return false;
            }
            return true;
        };
        if (fanIsOpen(centre)) return;
        const std::array<double, 3> mean = loopMean(ids, n);
        for (double step : {0.01, 0.1, 0.25, 0.5, 0.75, 1.0}) {
            std::array<double, 3> moved;
            for (int a = 0; a < 3; ++a) moved[a] = centre[a] + step * (mean[a] - centre[a]);
            if (fanIsOpen(moved) || step == 1.0) {
                centre = moved;
                return;
            }
        }
    }
    /// Whether a triangle folds against the surface: its normal lies more than 120 degrees from the
    /// surface's normals at all of `loopPoints` (at one only, a fan at a convex corner may lean so).
    bool foldsAgainst(const std::array<double, 3>& c, uint32_t a, uint32_t b, std::initializer_list<uint32_t> loopPoints) const
    {
        const auto& p = mesh_.positions;
        const double ux = p[a][0] - c[0], uy = p[a][1] - c[1], uz = p[a][2] - c[2];
        const double vx = p[b][0] - c[0], vy = p[b][1] - c[1], vz = p[b][2] - c[2];
        const double x = uy * vz - uz * vy, y = uz * vx - ux * vz, z = ux * vy - uy * vx;
        const double bound = -kFoldCosine * std::sqrt(x * x + y * y + z * z);
        for (const uint32_t q : loopPoints) {
            const auto& m = mesh_.normals[q];
            if (x * m[0] + y * m[1] + z * m[2] >= bound) return false;
        }
        return true;
    }

    /// How a fan triangle is judged: folded against the normals at both of its loop points, or strictly,
    /// also against the sheet whose tangent plane lies nearer its centroid (a bridge across a crease
    /// stands for that sheet there, and must not face back from it).
    enum class FoldTest { BothPoints, Strict };

    /// The fan triangles from `centre` (as stored, a float) that fold.
    int foldsOfFan(const std::array<double, 3>& centre, const uint32_t* ids, std::size_t n, FoldTest test) const
    {
        const std::array<double, 3> c{float(centre[0]), float(centre[1]), float(centre[2])};
        int folds = 0;
        for (std::size_t i = 0; i < n; ++i) {
            const uint32_t a = ids[i], b = ids[i + 1 < n ? i + 1 : 0];
            folds += foldsAgainst(c, a, b, {a, b}) || (test == FoldTest::Strict && foldsAgainst(c, a, b, {nearerPlane(c, a, b)}));
        }
        return folds;
    }

    /// Of a triangle's two loop points, the one whose tangent plane lies nearer its centroid: the sheet
    /// of the surface the triangle stands for there, where a crease bridges two.
    uint32_t nearerPlane(const std::array<double, 3>& c, uint32_t a, uint32_t b) const
    {
        const auto& p = mesh_.positions;
        const auto& m = mesh_.normals;
        const auto distance = [&](uint32_t q) {
            double d = 0.0;
            for (int k = 0; k < 3; ++k) d += ((c[k] + p[a][k] + p[b][k]) / 3.0 - p[q][k]) * m[q][k];
            return std::fabs(d);
        };
        return distance(a) <= distance(b) ? a : b;
    }

    /// A fan that folds (at a concave crease the loop's mean point, or its sharp feature, can lie where
    /// some triangles face back) gets another centre where none folds, if one lies between it and the
    /// loop's mean point. Returns whether it found one.
    bool unfoldFan(std::array<double, 3>& centre, const uint32_t* ids, std::size_t n, FoldTest test) const
    {
        const std::array<double, 3> mean = loopMean(ids, n);
        for (double s : {0.25, 0.5, 0.75, 1.0}) {
            const std::array<double, 3> at{centre[0] + s * (mean[0] - centre[0]), centre[1] + s * (mean[1] - centre[1]),
                                           centre[2] + s * (mean[2] - centre[2])};
            if (foldsOfFan(at, ids, n, test) == 0) {
                centre = at;
                return true;
            }
        }
        return false;
    }

    /// Where a crease's two sheets close to under a voxel apart, the edges keep one crossing each and the
    /// crease's vertex lands in the gap between the sheets, where the fan folds whether it sits there or
    /// at the loop's mean point. Another point of the cell may fan its loop without folding: one of a
    /// lattice of candidates across the cell (inset from its sides) that folds none and lies as near the
    /// loop's tangent planes as the vertex does, within a twentieth of a voxel (so a corner the planes
    /// agree on, exact even where its fan folds, stays where it is). Of those, the one
    /// whose triangles lean back least, then the nearest to the planes. The fan stays inside its cell,
    /// so it meets no other cell's triangles. Keeps `centre` when none does.
    void placeUnfolded(std::array<double, 3>& centre, const uint32_t* ids, std::size_t n, const CellBox& cell) const
    {
        constexpr int kSteps = 6;
        const double inset = limits_.inset, span = cell.width - 2.0 * inset;
        const double allowed = tangentPlaneGap(centre, ids, n) + 0.05 * limits_.voxelSize;
        std::pair<int, double> best{std::numeric_limits<int>::max(), 0.0};
        std::array<double, 3> chosen = centre;
        for (int i = 0; i <= kSteps; ++i)
            for (int j = 0; j <= kSteps; ++j)
                for (int k = 0; k <= kSteps; ++k) {
                    const std::array<double, 3> at{cell.lo[0] + inset + span * i / kSteps, cell.lo[1] + inset + span * j / kSteps,
                                                   cell.lo[2] + inset + span * k / kSteps};
                    const double gap = tangentPlaneGap(at, ids, n);
                    if (gap > allowed || foldsOfFan(at, ids, n, FoldTest::Strict) > 0) continue;
                    const std::pair<int, double> score{leansOfFan(at, ids, n), gap};
                    if (score < best) {
                        best = score;
                        chosen = at;
                    }
                }
        centre = chosen;
    }

    /// How far a point lies from the farthest of the tangent planes at a loop's points.
    double tangentPlaneGap(const std::array<double, 3>& at, const uint32_t* ids, std::size_t n) const
    {
        const auto& positions = mesh_.positions;
        const auto& normals = mesh_.normals;
        double gap = 0.0;
        for (std::size_t i = 0; i < n; ++i) {
            const auto& p = positions[ids[i]];
            const auto& m = normals[ids[i]];
            gap = std::max(gap, std::fabs((at[0] - p[0]) * m[0] + (at[1] - p[1]) * m[1] + (at[2] - p[2]) * m[2]));
        }
        return gap;
    }

    std::array<double, 3> loopMean(const uint32_t* ids, std::size_t n) const
    {
        std::array<double, 3> mean{};
        for (std::size_t i = 0; i < n; ++i)
            for (int a = 0; a < 3; ++a) mean[a] += mesh_.positions[ids[i]][a] / double(n);
        return mean;
    }

    /// Whether a sharp vertex sits below its loop's mean point along the loop's normal: a valley (a
    /// concave crease or corner), not a ridge or a tip.
    bool concaveFeature(const std::array<double, 3>& centre, const std::array<double, 3>& normalSum, const uint32_t* ids, std::size_t n) const
    {
        const std::array<double, 3> mean = loopMean(ids, n);
        double along = 0.0;
        for (int a = 0; a < 3; ++a) along += (centre[a] - mean[a]) * normalSum[a];
        return along < 0.0;
    }

    /// The fan triangles from `centre` that face more than 120 degrees from the normal at either of their
    /// loop points.
    int leansOfFan(const std::array<double, 3>& centre, const uint32_t* ids, std::size_t n) const
    {
        const std::array<double, 3> c{float(centre[0]), float(centre[1]), float(centre[2])};
        int leans = 0;
        for (std::size_t i = 0; i < n; ++i) {
            const uint32_t a = ids[i], b = ids[i + 1 < n ? i + 1 : 0];
            leans += foldsAgainst(c, a, b, {a}) || foldsAgainst(c, a, b, {b});
        }
        return leans;
    }

    /// Triangulates a loop of one material without an inner vertex, choosing the diagonals (dynamic
    /// programming over the loop) so that the fewest triangles fold, then the triangles best face the
    /// loop's normals. A diagonal between two points that may share a cell face (an equal coordinate)
    /// is never drawn: the cell beside could draw it too. Returns false, adding nothing, when the loop
    /// has several materials, no triangulation avoids such diagonals, or the best still folds, or it has
    /// fewer than `fewest` points (a loop of three is its own triangle, which cuts a convex corner off).
    bool triangulateLoop(const uint32_t* ids, const MaterialId* materials, std::size_t n, std::size_t fewest = 4)
    {
        if (n < fewest || n > 24) return false;
        for (std::size_t i = 1; i < n; ++i)
            if (materials[i] != materials[0]) return false;
        const auto& p = mesh_.positions;
        const auto& normals = mesh_.normals;
        const auto mayShareFace = [&](uint32_t a, uint32_t b) { return p[a][0] == p[b][0] || p[a][1] == p[b][1] || p[a][2] == p[b][2]; };
        constexpr double kInvalid = 1e30, kFold = 1e6;
        const auto triangleCost = [&](std::size_t i, std::size_t k, std::size_t j) {
            const uint32_t a = ids[i], b = ids[k], c = ids[j];
            const double ux = p[b][0] - p[a][0], uy = p[b][1] - p[a][1], uz = p[b][2] - p[a][2];
            const double vx = p[c][0] - p[a][0], vy = p[c][1] - p[a][1], vz = p[c][2] - p[a][2];
            const double x = uy * vz - uz * vy, y = uz * vx - ux * vz, z = ux * vy - uy * vx;
            const double area = std::sqrt(x * x + y * y + z * z);
            if (area < limits_.minFanDoubledArea) return kInvalid;
            double cost = 0.0;
            for (const uint32_t q : {a, b, c}) {
                const double d = (x * normals[q][0] + y * normals[q][1] + z * normals[q][2]) / area;
                cost += (d < -kFoldCosine ? kFold : 0.0) + (1.0 - d);
            }
            return cost;
        };
        // best[i][j]: the polygon ids[i..j] closed by the edge (i, j), which is a loop edge for (0, n-1)
        // and a diagonal otherwise.
        std::vector<double> best(n * n, 0.0);
        std::vector<uint8_t> split(n * n, 0);
        for (std::size_t span = 2; span < n; ++span)
            for (std::size_t i = 0; i + span < n; ++i) {
                const std::size_t j = i + span;
                double& out = best[i * n + j];
                out = kInvalid;
                if (!(i == 0 && j == n - 1) && mayShareFace(ids[i], ids[j])) continue;
                for (std::size_t k = i + 1; k < j; ++k) {
                    const double c = best[i * n + k] + best[k * n + j] + triangleCost(i, k, j);
                    if (c < out) {
                        out = c;
                        split[i * n + j] = uint8_t(k);
                    }
                }
            }
        if (best[n - 1] >= kFold) return false;
        Mesh& mesh = mesh_;
        std::vector<std::pair<std::size_t, std::size_t>> stack{{0, n - 1}};
        while (!stack.empty()) {
            const auto [i, j] = stack.back();
            stack.pop_back();
            if (j - i < 2) continue;
            const std::size_t k = split[i * n + j];
            mesh.triangles.push_back({ids[i], ids[k], ids[j]});
            mesh.triangleMaterials.push_back(materials[0]);
            stack.push_back({i, k});
            stack.push_back({k, j});
        }
        return true;
    }

private:
    Mesh& mesh_;
    const LoopFanLimits& limits_;
};

} // namespace

std::optional<std::array<double, 3>> closeLoop(Mesh& mesh, std::array<double, 3> centre, const std::array<double, 3>& normalSum,
                                               const uint32_t* ids, const MaterialId* materials, std::size_t n, bool sharp,
                                               const CellBox& cell, const LoopFanLimits& limits)
{
    LoopFan fan(mesh, limits);
    if (sharp) fan.keepFanOpen(centre, ids, n);
    // Nearer the mean point first, then the loop alone, then anywhere in the cell. A concave crease's
    // vertex (below its loop's mean point) whose fan leans back past one loop point's normal gives way
    // to the loop alone too.
    // Judged strictly first (a bridge facing back from the sheet it stands for folds too); a centre that
    // only leans so, as a ridge's fans may, stays when no strictly unfolded centre lies towards the mean.
    using FoldTest = LoopFan::FoldTest;
    if (fan.foldsOfFan(centre, ids, n, FoldTest::Strict) > 0 && !fan.unfoldFan(centre, ids, n, FoldTest::Strict) &&
        fan.foldsOfFan(centre, ids, n, FoldTest::BothPoints) > 0 && !fan.unfoldFan(centre, ids, n, FoldTest::BothPoints)) {
        if (fan.triangulateLoop(ids, materials, n)) return std::nullopt;
        fan.placeUnfolded(centre, ids, n, cell);
    }
    if (sharp && fan.concaveFeature(centre, normalSum, ids, n) && fan.leansOfFan(centre, ids, n) > 0 && fan.triangulateLoop(ids, materials, n, 3))
        return std::nullopt;
    return centre;
}

} // namespace vdbclay
