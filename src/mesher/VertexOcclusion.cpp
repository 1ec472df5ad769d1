#include "mesher/VertexOcclusion.h"

#include "mesher/CellGrid.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <array>
#include <cmath>

namespace vdbclay {

namespace {

/// Directions spread over the upper hemisphere of +z (a normal's frame maps them onto the surface).
constexpr std::array<std::array<double, 3>, 9> kHemisphere = {{{0.0, 0.0, 1.0},
                                                               {0.7, 0.0, 0.714},
                                                               {-0.7, 0.0, 0.714},
                                                               {0.0, 0.7, 0.714},
                                                               {0.0, -0.7, 0.714},
                                                               {0.66, 0.66, 0.36},
                                                               {-0.66, 0.66, 0.36},
                                                               {0.66, -0.66, 0.36},
                                                               {-0.66, -0.66, 0.36}}};
constexpr double kDistances[2] = {1.5, 3.5}; // voxels

} // namespace

std::vector<uint8_t> vertexOcclusion(const Volume& volume, const Mesh& mesh, std::size_t firstVertex)
{
    using namespace mesher_detail;
    firstVertex = std::min(firstVertex, mesh.positions.size());
    std::vector<uint8_t> out(mesh.positions.size() - firstVertex, 255);
    const HermiteTree& tree = volume.impl().grid->constTree();
    const double inv = 1.0 / volume.voxelSize();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(firstVertex, mesh.positions.size(), 512), [&](const auto& range) {
        ConstAccessor acc(tree);
        for (std::size_t v = range.begin(); v != range.end(); ++v) {
            if (v >= mesh.normals.size()) break;
            const auto& p = mesh.positions[v];
            const auto& n = mesh.normals[v];
            // A frame (t, b, n) around the normal.
            const double nx = n[0], ny = n[1], nz = n[2];
            double tx, ty, tz;
            if (std::fabs(nx) < 0.9) tx = 0.0, ty = -nz, tz = ny; // n x (1,0,0)
            else tx = nz, ty = 0.0, tz = -nx;                      // n x (0,1,0)
            const double tl = std::sqrt(tx * tx + ty * ty + tz * tz);
            if (tl == 0.0) continue;
            tx /= tl, ty /= tl, tz /= tl;
            const double bx = ny * tz - nz * ty, by = nz * tx - nx * tz, bz = nx * ty - ny * tx;
            int open = 0, total = 0;
            for (const auto& d : kHemisphere)
                for (double r : kDistances) {
                    const double wx = d[0] * tx + d[1] * bx + d[2] * nx;
                    const double wy = d[0] * ty + d[1] * by + d[2] * ny;
                    const double wz = d[0] * tz + d[1] * bz + d[2] * nz;
                    const Coord c(int32_t(std::lround(p[0] * inv + wx * r)), int32_t(std::lround(p[1] * inv + wy * r)),
                                  int32_t(std::lround(p[2] * inv + wz * r)));
                    open += acc.getValue(c).id == kEmptyMaterial;
                    ++total;
                }
            // Every sample lies outside a flat or convex surface; creases and pits hide some.
            const double openness = double(open) / double(total);
            out[v - firstVertex] = uint8_t(std::lround(255.0 * openness));
        }
    });
    return out;
}

} // namespace vdbclay
