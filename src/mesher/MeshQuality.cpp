#include "mesher/MeshQuality.h"

#include "mesher/MeshMetrics.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vdbclay {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kRadToDeg = 57.295779513082320876798;

inline Point3d sub(const Point3d& a, const Point3d& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline Point3d add(const Point3d& a, const Point3d& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline Point3d scale(const Point3d& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
inline double dot(const Point3d& a, const Point3d& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Point3d cross(const Point3d& a, const Point3d& b)
{
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double length(const Point3d& a) { return std::sqrt(dot(a, a)); }
inline Point3d toD(const std::array<float, 3>& p) { return {double(p[0]), double(p[1]), double(p[2])}; }

Point3d closestOnSegment(const Point3d& p, const Point3d& a, const Point3d& b)
{
    const Point3d ab = sub(b, a);
    const double len2 = dot(ab, ab);
    if (len2 <= 0.0) return a;
    const double t = std::clamp(dot(sub(p, a), ab) / len2, 0.0, 1.0);
    return add(a, scale(ab, t));
}

struct Corners {
    Point3d a, b, c;
};

inline Corners cornersOf(const Mesh& mesh, const std::array<uint32_t, 3>& t)
{
    return {toD(mesh.positions[t[0]]), toD(mesh.positions[t[1]]), toD(mesh.positions[t[2]])};
}

/// Unit normal of a triangle, or false when it has (almost) no area.
bool triangleNormal(const Corners& k, Point3d& n)
{
    n = cross(sub(k.b, k.a), sub(k.c, k.a));
    const double len = length(n);
    const double e = std::max({dot(sub(k.b, k.a), sub(k.b, k.a)), dot(sub(k.c, k.a), sub(k.c, k.a)),
                               dot(sub(k.c, k.b), sub(k.c, k.b))});
    if (!(len > 1e-12 * e) || len == 0.0) return false;
    n = scale(n, 1.0 / len);
    return true;
}

double angleDeg(const Point3d& u, const Point3d& v) // both unit
{
    return std::acos(std::clamp(dot(u, v), -1.0, 1.0)) * kRadToDeg;
}

/// Sum, maximum and count of a set of non-negative values, for parallel reductions.
struct Stats {
    double sum = 0.0;
    double max = 0.0;
    std::size_t count = 0;
    void add(double v)
    {
        sum += v;
        max = std::max(max, v);
        ++count;
    }
    void join(const Stats& o)
    {
        sum += o.sum;
        max = std::max(max, o.max);
        count += o.count;
    }
    double mean() const { return count ? sum / double(count) : kInf; }
    double maximum() const { return count ? max : kInf; }
};

template <typename Body> Stats reduceStats(std::size_t n, std::size_t grain, const Body& body)
{
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, n, grain), Stats{},
        [&](const tbb::blocked_range<std::size_t>& r, Stats s) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) body(i, s);
            return s;
        },
        [](Stats a, const Stats& b) {
            a.join(b);
            return a;
        });
}

double meanEdgeLength(const Mesh& mesh)
{
    double sum = 0.0;
    std::size_t n = 0;
    for (const auto& t : mesh.triangles) {
        const Corners k = cornersOf(mesh, t);
        sum += length(sub(k.b, k.a)) + length(sub(k.c, k.b)) + length(sub(k.a, k.c));
        n += 3;
    }
    return n ? sum / double(n) : 0.0;
}

void boundsOf(const Mesh& mesh, Point3d& lo, Point3d& hi)
{
    lo = {kInf, kInf, kInf};
    hi = {-kInf, -kInf, -kInf};
    for (const auto& t : mesh.triangles)
        for (uint32_t v : t)
            for (int i = 0; i < 3; ++i) {
                lo[i] = std::min(lo[i], double(mesh.positions[v][i]));
                hi[i] = std::max(hi[i], double(mesh.positions[v][i]));
            }
}

/// Calls f(point) for every vertex used by a triangle, and for barycentric points of every triangle
/// (edge and interior points; corners are the vertices). Index i runs over vertices then triangles.
template <typename F> void sampleMesh(const Mesh& mesh, const std::vector<char>& used, std::size_t i,
                                      double spacing, int maxSub, const F& f)
{
    const std::size_t nv = mesh.positions.size();
    if (i < nv) {
        if (used[i]) f(toD(mesh.positions[i]));
        return;
    }
    const Corners k = cornersOf(mesh, mesh.triangles[i - nv]);
    const double longest =
        std::max({length(sub(k.b, k.a)), length(sub(k.c, k.b)), length(sub(k.a, k.c))});
    const int n = int(std::clamp(std::ceil(longest / spacing), 1.0, double(std::max(1, maxSub))));
    const double inv = 1.0 / n;
    for (int a = 0; a <= n; ++a)
        for (int b = 0; a + b <= n; ++b) {
            const int c = n - a - b;
            if (a == n || b == n || c == n) continue; // a corner: sampled as a vertex
            const double wa = a * inv, wb = b * inv, wc = 1.0 - wa - wb;
            f(Point3d{wa * k.a[0] + wb * k.b[0] + wc * k.c[0], wa * k.a[1] + wb * k.b[1] + wc * k.c[1],
                      wa * k.a[2] + wb * k.b[2] + wc * k.c[2]});
        }
}

std::vector<char> usedVertices(const Mesh& mesh)
{
    std::vector<char> used(mesh.positions.size(), 0);
    for (const auto& t : mesh.triangles)
        for (uint32_t v : t) used[v] = 1;
    return used;
}

/// Distances from the samples of `mesh` to `target`.
Stats sampleAgainst(const Mesh& mesh, const TriangleLocator& target, double spacing, int maxSub)
{
    const std::vector<char> used = usedVertices(mesh);
    return reduceStats(mesh.positions.size() + mesh.triangles.size(), 256, [&](std::size_t i, Stats& s) {
        sampleMesh(mesh, used, i, spacing, maxSub, [&](const Point3d& p) { s.add(target.nearest(p).distance); });
    });
}

void fillCommon(const Mesh& mesh, const SurfaceSampling& sampling, double spacing, MeshQuality& q)
{
    const double merge = sampling.mergeDistance > 0.0 ? sampling.mergeDistance : kMergeDistanceVoxels * spacing;
    const MeshTopology topo = analyzeTopology(mesh, merge);
    q.triangles = mesh.triangleCount();
    q.watertight = topo.watertight();
    q.manifold = topo.nonManifoldEdges == 0;
    double minAngle = kInf;
    for (const auto& t : mesh.triangles) {
        if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) continue;
        const Corners k = cornersOf(mesh, t);
        Point3d n;
        if (!triangleNormal(k, n)) continue;
        const Point3d* c[3] = {&k.a, &k.b, &k.c};
        for (int i = 0; i < 3; ++i) {
            Point3d u = sub(*c[(i + 1) % 3], *c[i]), v = sub(*c[(i + 2) % 3], *c[i]);
            u = scale(u, 1.0 / length(u));
            v = scale(v, 1.0 / length(v));
            minAngle = std::min(minAngle, angleDeg(u, v));
        }
    }
    q.minTriangleAngleDeg = minAngle == kInf ? 0.0 : minAngle;
}

void fillDistances(MeshQuality& q, const Stats& to, const Stats& from)
{
    q.meanDistanceToSurface = to.mean();
    q.maxDistanceToSurface = to.maximum();
    q.meanDistanceFromSurface = from.mean();
    q.maxDistanceFromSurface = from.maximum();
    q.meanDistance = 0.5 * (q.meanDistanceToSurface + q.meanDistanceFromSurface);
    q.maxDistance = std::max(q.maxDistanceToSurface, q.maxDistanceFromSurface);
    q.meshSamples = to.count;
    q.surfaceSamples = from.count;
}

void fillNormals(MeshQuality& q, const Stats& normals)
{
    q.meanNormalDeviationDeg = normals.count ? normals.mean() : 0.0;
    q.maxNormalDeviationDeg = normals.count ? normals.max : 0.0;
}

} // namespace

Point3d closestPointOnTriangle(const Point3d& p, const Point3d& a, const Point3d& b, const Point3d& c)
{
    const Point3d ab = sub(b, a), ac = sub(c, a);
    const Point3d n = cross(ab, ac);
    const double scaleSq = std::max({dot(ab, ab), dot(ac, ac), dot(sub(c, b), sub(c, b))});
    if (!(dot(n, n) > 1e-24 * scaleSq * scaleSq)) { // degenerate: the nearest of the three edges
        const Point3d q1 = closestOnSegment(p, a, b), q2 = closestOnSegment(p, b, c), q3 = closestOnSegment(p, c, a);
        const double d1 = dot(sub(p, q1), sub(p, q1)), d2 = dot(sub(p, q2), sub(p, q2)),
                     d3 = dot(sub(p, q3), sub(p, q3));
        if (d1 <= d2 && d1 <= d3) return q1;
        return d2 <= d3 ? q2 : q3;
    }
    // Vertex region A.
    const Point3d ap = sub(p, a);
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) return a;
    // Vertex region B.
    const Point3d bp = sub(p, b);
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return b;
    // Edge region AB.
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return add(a, scale(ab, d1 / (d1 - d3)));
    // Vertex region C.
    const Point3d cp = sub(p, c);
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return c;
    // Edge region AC.
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return add(a, scale(ac, d2 / (d2 - d6)));
    // Edge region BC.
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
        return add(b, scale(sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))));
    // Face region: barycentric coordinates (u, v, w) = (va, vb, vc) / (va + vb + vc).
    const double denom = 1.0 / (va + vb + vc);
    return add(a, add(scale(ab, vb * denom), scale(ac, vc * denom)));
}

TriangleLocator::TriangleLocator(const Mesh& mesh) : mesh_(&mesh), triangleCount_(mesh.triangles.size())
{
    if (triangleCount_ == 0) {
        cellStart_.assign(2, 0);
        return;
    }
    Point3d lo, hi;
    boundsOf(mesh, lo, hi);
    const Point3d ext = sub(hi, lo);
    const double diag = length(ext);
    double cell = 2.0 * meanEdgeLength(mesh);
    if (!(cell > 0.0)) cell = diag > 0.0 ? diag : 1.0;
    // At most about 32 cells per triangle and 1024 per axis.
    const double maxCells = std::max(64.0, 32.0 * double(triangleCount_));
    for (;;) {
        double total = 1.0;
        for (int i = 0; i < 3; ++i) total *= std::floor(ext[i] / cell) + 1.0;
        if (total <= maxCells && ext[0] / cell < 1023 && ext[1] / cell < 1023 && ext[2] / cell < 1023) break;
        cell *= 1.25;
    }
    cell_ = cell;
    origin_ = lo;
    for (int i = 0; i < 3; ++i) dims_[i] = int(std::floor(ext[i] / cell)) + 1;

    auto cellRange = [&](const Corners& k, std::array<int, 3>& c0, std::array<int, 3>& c1) {
        for (int i = 0; i < 3; ++i) {
            const double mn = std::min({k.a[i], k.b[i], k.c[i]}), mx = std::max({k.a[i], k.b[i], k.c[i]});
            c0[i] = std::clamp(int(std::floor((mn - origin_[i]) / cell_)), 0, dims_[i] - 1);
            c1[i] = std::clamp(int(std::floor((mx - origin_[i]) / cell_)), 0, dims_[i] - 1);
        }
    };
    const std::size_t cells = std::size_t(dims_[0]) * dims_[1] * dims_[2];
    cellStart_.assign(cells + 1, 0);
    for (int pass = 0; pass < 2; ++pass) {
        std::vector<uint32_t> fill;
        if (pass == 1) {
            for (std::size_t i = 0; i < cells; ++i) cellStart_[i + 1] += cellStart_[i];
            items_.resize(cellStart_[cells]);
            fill.assign(cellStart_.begin(), cellStart_.end() - 1);
        }
        for (std::size_t t = 0; t < triangleCount_; ++t) {
            std::array<int, 3> c0, c1;
            cellRange(cornersOf(mesh, mesh.triangles[t]), c0, c1);
            for (int z = c0[2]; z <= c1[2]; ++z)
                for (int y = c0[1]; y <= c1[1]; ++y)
                    for (int x = c0[0]; x <= c1[0]; ++x) {
                        const std::size_t id = (std::size_t(z) * dims_[1] + y) * dims_[0] + x;
                        if (pass == 0) ++cellStart_[id + 1];
                        else items_[fill[id]++] = uint32_t(t);
                    }
        }
    }
}

TriangleLocator::Hit TriangleLocator::nearest(const Point3d& p) const
{
    Hit hit;
    hit.distance = kInf;
    if (triangleCount_ == 0) return hit;
    double best2 = kInf;
    std::array<int, 3> c;
    for (int i = 0; i < 3; ++i)
        c[i] = std::clamp(int(std::floor((p[i] - origin_[i]) / cell_)), 0, dims_[i] - 1);

    auto visit = [&](int x, int y, int z) {
        // Skip cells that cannot hold anything nearer than the best so far.
        double box2 = 0.0;
        const int idx[3] = {x, y, z};
        for (int i = 0; i < 3; ++i) {
            const double lo = origin_[i] + idx[i] * cell_, hi = lo + cell_;
            const double d = p[i] < lo ? lo - p[i] : (p[i] > hi ? p[i] - hi : 0.0);
            box2 += d * d;
        }
        if (box2 > best2) return;
        const std::size_t id = (std::size_t(z) * dims_[1] + y) * dims_[0] + x;
        for (uint32_t k = cellStart_[id]; k < cellStart_[id + 1]; ++k) {
            const uint32_t t = items_[k];
            const Corners tc = cornersOf(*mesh_, mesh_->triangles[t]);
            const Point3d q = closestPointOnTriangle(p, tc.a, tc.b, tc.c);
            const Point3d d = sub(p, q);
            const double d2 = dot(d, d);
            if (d2 < best2) {
                best2 = d2;
                hit.triangle = t;
                hit.point = q;
            }
        }
    };

    for (int k = 0;; ++k) {
        const int x0 = std::max(c[0] - k, 0), x1 = std::min(c[0] + k, dims_[0] - 1);
        const int y0 = std::max(c[1] - k, 0), y1 = std::min(c[1] + k, dims_[1] - 1);
        const int z0 = std::max(c[2] - k, 0), z1 = std::min(c[2] + k, dims_[2] - 1);
        for (int x = x0; x <= x1; ++x)
            for (int y = y0; y <= y1; ++y) {
                if (x == c[0] - k || x == c[0] + k || y == c[1] - k || y == c[1] + k) {
                    for (int z = z0; z <= z1; ++z) visit(x, y, z);
                } else {
                    if (c[2] - k >= 0) visit(x, y, c[2] - k);
                    if (k > 0 && c[2] + k < dims_[2]) visit(x, y, c[2] + k);
                }
            }
        // Cells on later rings are at least k cells away from p.
        const double bound = double(k) * cell_;
        if (best2 <= bound * bound) break;
        if (c[0] - k <= 0 && c[1] - k <= 0 && c[2] - k <= 0 && c[0] + k >= dims_[0] - 1 &&
            c[1] + k >= dims_[1] - 1 && c[2] + k >= dims_[2] - 1)
            break; // the whole grid has been visited
    }
    hit.distance = std::sqrt(best2);
    return hit;
}

MeshQuality measureAgainstSdf(const Mesh& mesh, const SignedDistanceFn& sdf, const SurfaceSampling& sampling,
                              const SdfGradientFn& gradient)
{
    MeshQuality q;
    double h = sampling.spacing > 0.0 ? sampling.spacing : meanEdgeLength(mesh);
    if (!(h > 0.0)) h = 1.0;
    fillCommon(mesh, sampling, h, q);
    const double triSpacing = sampling.triangleSpacing > 0.0 ? sampling.triangleSpacing : 0.5 * h;
    const double tol = sampling.projectionTolerance > 0.0 ? sampling.projectionTolerance : 1e-6 * h;
    const double step = sampling.gradientStep > 0.0 ? sampling.gradientStep : 1e-4 * h;

    auto grad = [&](const Point3d& p) -> Point3d {
        if (gradient) return gradient(p);
        Point3d g;
        for (int i = 0; i < 3; ++i) {
            Point3d a = p, b = p;
            a[i] += step;
            b[i] -= step;
            g[i] = (sdf(a) - sdf(b)) / (2.0 * step);
        }
        return g;
    };

    // Mesh -> surface: |sdf| at the mesh samples.
    const std::vector<char> used = usedVertices(mesh);
    const Stats to = reduceStats(mesh.positions.size() + mesh.triangles.size(), 256, [&](std::size_t i, Stats& s) {
        sampleMesh(mesh, used, i, triSpacing, sampling.maxTriangleSubdivisions,
                   [&](const Point3d& p) { s.add(std::fabs(sdf(p))); });
    });

    // Surface -> mesh: grid points near the zero set, projected onto it, measured against the mesh.
    Stats from;
    if (!mesh.triangles.empty()) {
        const TriangleLocator locator(mesh);
        Point3d lo, hi;
        boundsOf(mesh, lo, hi);
        const double margin = sampling.margin >= 0.0 ? sampling.margin : std::max(2.0 * h, 0.1 * length(sub(hi, lo)));
        std::array<long, 3> n;
        for (int i = 0; i < 3; ++i) {
            lo[i] -= margin;
            hi[i] += margin;
            n[i] = long(std::ceil((hi[i] - lo[i]) / h)) + 1;
        }
        constexpr long B = 8; // points per block edge; a block is skipped when the zero set cannot reach it
        const std::array<long, 3> nb{(n[0] + B - 1) / B, (n[1] + B - 1) / B, (n[2] + B - 1) / B};
        const double reach = std::sqrt(3.0) * 0.5 * double(B - 1) * h + h;
        from = reduceStats(std::size_t(nb[0] * nb[1] * nb[2]), 1, [&](std::size_t blockIndex, Stats& s) {
            const long bx = long(blockIndex % nb[0]), by = long((blockIndex / nb[0]) % nb[1]),
                       bz = long(blockIndex / (nb[0] * nb[1]));
            const Point3d centre{lo[0] + (bx * B + 0.5 * (B - 1)) * h, lo[1] + (by * B + 0.5 * (B - 1)) * h,
                                 lo[2] + (bz * B + 0.5 * (B - 1)) * h};
            if (std::fabs(sdf(centre)) >= reach) return;
            for (long z = bz * B; z < std::min((bz + 1) * B, n[2]); ++z)
                for (long y = by * B; y < std::min((by + 1) * B, n[1]); ++y)
                    for (long x = bx * B; x < std::min((bx + 1) * B, n[0]); ++x) {
                        Point3d p{lo[0] + x * h, lo[1] + y * h, lo[2] + z * h};
                        double d = sdf(p);
                        if (!(std::fabs(d) < h)) continue;
                        for (int it = 0; it < sampling.newtonSteps && std::fabs(d) > 1e-3 * tol; ++it) {
                            const Point3d g = grad(p);
                            const double g2 = dot(g, g);
                            if (!(g2 > 1e-12)) break;
                            p = sub(p, scale(g, d / g2));
                            d = sdf(p);
                        }
                        if (!(std::fabs(d) <= tol)) continue;
                        s.add(locator.nearest(p).distance);
                    }
        });
    }
    fillDistances(q, to, from);

    // Normal deviation: triangle normal against the gradient at the centroid.
    const Stats normals = reduceStats(mesh.triangles.size(), 256, [&](std::size_t t, Stats& s) {
        const Corners k = cornersOf(mesh, mesh.triangles[t]);
        Point3d n;
        if (!triangleNormal(k, n)) return;
        const Point3d centroid = scale(add(add(k.a, k.b), k.c), 1.0 / 3.0);
        const Point3d g = grad(centroid);
        const double len = length(g);
        if (!(len > 0.0)) return;
        s.add(angleDeg(n, scale(g, 1.0 / len)));
    });
    fillNormals(q, normals);
    return q;
}

double maxDistanceToMesh(const Mesh& from, const Mesh& to, double spacing)
{
    if (from.triangles.empty()) return 0.0;
    const TriangleLocator locator(to);
    if (locator.empty()) return kInf;
    return sampleAgainst(from, locator, spacing, 64).maximum();
}

MeshQuality measureAgainstMesh(const Mesh& mesh, const Mesh& reference, const SurfaceSampling& sampling)
{
    MeshQuality q;
    double h = sampling.spacing > 0.0 ? sampling.spacing : meanEdgeLength(reference);
    if (!(h > 0.0)) h = 1.0;
    fillCommon(mesh, sampling, h, q);
    const double triSpacing = sampling.triangleSpacing > 0.0 ? sampling.triangleSpacing : 0.5 * h;
    const TriangleLocator meshLocator(mesh), referenceLocator(reference);
    const Stats to = sampleAgainst(mesh, referenceLocator, triSpacing, sampling.maxTriangleSubdivisions);
    const Stats from = sampleAgainst(reference, meshLocator, triSpacing, sampling.maxTriangleSubdivisions);
    fillDistances(q, to, from);

    const Stats normals = reduceStats(mesh.triangles.size(), 256, [&](std::size_t t, Stats& s) {
        if (referenceLocator.empty()) return;
        const Corners k = cornersOf(mesh, mesh.triangles[t]);
        Point3d n, rn;
        if (!triangleNormal(k, n)) return;
        const Point3d centroid = scale(add(add(k.a, k.b), k.c), 1.0 / 3.0);
        const TriangleLocator::Hit hit = referenceLocator.nearest(centroid);
        if (!triangleNormal(cornersOf(reference, reference.triangles[hit.triangle]), rn)) return;
        s.add(angleDeg(n, rn));
    });
    fillNormals(q, normals);
    return q;
}

} // namespace vdbclay
