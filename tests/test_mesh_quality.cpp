// MeshQuality: closest points on triangles, the nearest-triangle locator, and mesh-vs-SDF and
// mesh-vs-mesh measurements on hand-built meshes whose answers are known in closed form.
#include "mesher/MeshMetrics.h"
#include "mesher/MeshQuality.h"
#include "support/MeshShapes.h"
#include "support/TestUtil.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>

using namespace vdbclay;
using namespace vdbclay::test;

namespace {

double dist(const Point3d& a, const Point3d& b)
{
    return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

void checkPoint(const Point3d& got, const Point3d& expected)
{
    INFO("got (" << got[0] << ", " << got[1] << ", " << got[2] << "), expected (" << expected[0] << ", "
                 << expected[1] << ", " << expected[2] << ")");
    CHECK(dist(got, expected) < 1e-12);
}

/// Exact signed distance of the box with half-extent h centred at the origin.
double boxSdf(const Point3d& p, double h)
{
    double outside = 0.0, inside = -1e300;
    for (int i = 0; i < 3; ++i) {
        const double q = std::fabs(p[i]) - h;
        outside += std::max(q, 0.0) * std::max(q, 0.0);
        inside = std::max(inside, q);
    }
    return std::sqrt(outside) + std::min(inside, 0.0);
}

double sphereSdf(const Point3d& p, double r) { return std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - r; }

} // namespace

TEST_CASE("closestPointOnTriangle in every Voronoi region", "[quality]")
{
    const Point3d a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
    checkPoint(closestPointOnTriangle({-1, -1, 0.5}, a, b, c), a);           // vertex A
    checkPoint(closestPointOnTriangle({2, -0.5, 1}, a, b, c), b);            // vertex B
    checkPoint(closestPointOnTriangle({-0.5, 2, -3}, a, b, c), c);           // vertex C
    checkPoint(closestPointOnTriangle({0.3, -1, 2}, a, b, c), {0.3, 0, 0});  // edge AB
    checkPoint(closestPointOnTriangle({-2, 0.4, 1}, a, b, c), {0, 0.4, 0});  // edge AC
    checkPoint(closestPointOnTriangle({1, 1, 5}, a, b, c), {0.5, 0.5, 0});   // edge BC
    checkPoint(closestPointOnTriangle({0.2, 0.3, -4}, a, b, c), {0.2, 0.3, 0}); // face
    checkPoint(closestPointOnTriangle({0.25, 0.25, 0}, a, b, c), {0.25, 0.25, 0}); // on the face
    // A tilted triangle: the face region projects along its normal (1,1,1)/sqrt(3).
    const Point3d e0{1, 0, 0}, e1{0, 1, 0}, e2{0, 0, 1};
    checkPoint(closestPointOnTriangle({2, 2, 2}, e0, e1, e2), {1.0 / 3, 1.0 / 3, 1.0 / 3});
    checkPoint(closestPointOnTriangle({1, 1, -5}, e0, e1, e2), {0.5, 0.5, 0}); // edge e0-e1
    // Degenerate (collinear) triangle: the nearest point of the segment.
    checkPoint(closestPointOnTriangle({0.5, 1, 0}, {0, 0, 0}, {1, 0, 0}, {2, 0, 0}), {0.5, 0, 0});
}

TEST_CASE("closestPointOnTriangle is never beaten by a dense sampling of the triangle", "[quality]")
{
    std::mt19937 rng(1234);
    std::uniform_real_distribution<double> u(-2.0, 2.0);
    for (int trial = 0; trial < 200; ++trial) {
        const Point3d a{u(rng), u(rng), u(rng)}, b{u(rng), u(rng), u(rng)}, c{u(rng), u(rng), u(rng)};
        const Point3d p{u(rng), u(rng), u(rng)};
        const Point3d q = closestPointOnTriangle(p, a, b, c);
        const double d = dist(p, q);
        double sampled = 1e300;
        const int n = 60;
        for (int i = 0; i <= n; ++i)
            for (int j = 0; i + j <= n; ++j) {
                const double wa = double(i) / n, wb = double(j) / n, wc = 1 - wa - wb;
                const Point3d s{wa * a[0] + wb * b[0] + wc * c[0], wa * a[1] + wb * b[1] + wc * c[1],
                                wa * a[2] + wb * b[2] + wc * c[2]};
                sampled = std::min(sampled, dist(p, s));
            }
        INFO("trial " << trial);
        CHECK(d <= sampled + 1e-12);
        CHECK(d >= sampled - 0.1); // and q lies on the triangle (within the sampling's resolution)
    }
}

TEST_CASE("TriangleLocator agrees with brute force on an icosphere", "[quality]")
{
    const Mesh mesh = icosphereMesh(3.0, 3, {0.5, -1.0, 2.0});
    const TriangleLocator locator(mesh);
    std::mt19937 rng(99);
    std::uniform_real_distribution<double> u(-8.0, 8.0);
    for (int trial = 0; trial < 300; ++trial) {
        const Point3d p{u(rng), u(rng), u(rng)};
        double brute = 1e300;
        for (const auto& t : mesh.triangles) {
            auto P = [&](uint32_t v) { return Point3d{mesh.positions[v][0], mesh.positions[v][1], mesh.positions[v][2]}; };
            brute = std::min(brute, dist(p, closestPointOnTriangle(p, P(t[0]), P(t[1]), P(t[2]))));
        }
        const TriangleLocator::Hit hit = locator.nearest(p);
        INFO("trial " << trial);
        CHECK(std::fabs(hit.distance - brute) < 1e-12);
        CHECK(std::fabs(dist(p, hit.point) - hit.distance) < 1e-12);
    }
}

TEST_CASE("A cube mesh measured against the cube's exact SDF", "[quality]")
{
    const Mesh cube = cubeMesh(0.5);
    REQUIRE(enclosedVolume(cube) == Approx(1.0));
    SurfaceSampling sampling;
    sampling.spacing = 0.05;
    const auto sdf = [](const Point3d& p) { return boxSdf(p, 0.5); };
    for (bool analyticGradient : {false, true}) {
        SdfGradientFn gradient;
        if (analyticGradient)
            gradient = [](const Point3d& p) {
                // Outward normal of the face nearest the centroid-type points used here.
                int axis = 0;
                for (int i = 1; i < 3; ++i)
                    if (std::fabs(p[i]) > std::fabs(p[axis])) axis = i;
                Point3d g{0, 0, 0};
                g[axis] = p[axis] > 0 ? 1.0 : -1.0;
                return g;
            };
        INFO("analytic gradient " << analyticGradient);
        const MeshQuality q = measureAgainstSdf(cube, sdf, sampling, gradient);
        CHECK(q.triangles == 12);
        CHECK(q.watertight);
        CHECK(q.manifold);
        CHECK(q.maxDistanceToSurface < 1e-6);
        CHECK(q.maxDistanceFromSurface < 1e-6);
        CHECK(q.maxDistance < 1e-6);
        CHECK(q.meanDistance < 1e-6);
        CHECK(q.surfaceSamples > 1000);
        CHECK(q.meshSamples > 1000);
        CHECK(q.maxNormalDeviationDeg < 1e-4);
        CHECK(q.meanNormalDeviationDeg < 1e-4);
        CHECK(q.minTriangleAngleDeg == Approx(45.0).margin(1e-9));
    }
}

TEST_CASE("A cube mesh against its circumscribed sphere", "[quality]")
{
    const Mesh cube = cubeMesh(0.5);
    const double R = 0.5 * std::sqrt(3.0);
    const double h = 0.02;
    SurfaceSampling sampling;
    sampling.spacing = h;
    sampling.margin = 0.5; // the sphere reaches R - 0.5 beyond the cube's faces
    const MeshQuality q = measureAgainstSdf(cube, [R](const Point3d& p) { return sphereSdf(p, R); }, sampling);
    // The farthest points either way are the face centres and the sphere points straight above them.
    const double expected = R - 0.5;
    INFO("to surface " << q.maxDistanceToSurface << ", from surface " << q.maxDistanceFromSurface << ", expected "
                       << expected);
    CHECK(q.maxDistanceToSurface <= expected + 1e-6);
    CHECK(q.maxDistanceToSurface >= expected - 2 * h * h);
    CHECK(q.maxDistanceFromSurface <= expected + 1e-6);
    CHECK(q.maxDistanceFromSurface >= expected - 2 * h * h);
    CHECK(q.maxDistance == Approx(expected).margin(2 * h * h));
    CHECK(q.meanDistanceToSurface > 0.0);
    CHECK(q.meanDistanceToSurface < q.maxDistanceToSurface);
    CHECK(q.meanDistanceFromSurface > 0.0);
    CHECK(q.meanDistanceFromSurface < q.maxDistanceFromSurface);
    // Every triangle's centroid sits at (1/6, -1/6, 1/2) up to symmetry; the radial direction there is
    // tilted from the face normal by atan(sqrt(2)/6 / (1/2)).
    const double tilt = std::atan(std::sqrt(2.0) / 3.0) * 180.0 / kPi;
    CHECK(q.maxNormalDeviationDeg == Approx(tilt).margin(1e-4));
    CHECK(q.meanNormalDeviationDeg == Approx(tilt).margin(1e-4));
}

TEST_CASE("An octahedron against its own SDF and against its circumscribed sphere", "[quality]")
{
    const Mesh oct = octahedronMesh(1.0);
    REQUIRE(enclosedVolume(oct) == Approx(4.0 / 3.0));
    SurfaceSampling sampling;
    sampling.spacing = 0.03;
    // (|x|+|y|+|z|-1)/sqrt(3): exact near the faces and a Lipschitz-1 bound elsewhere.
    const auto octSdf = [](const Point3d& p) {
        return (std::fabs(p[0]) + std::fabs(p[1]) + std::fabs(p[2]) - 1.0) / std::sqrt(3.0);
    };
    const MeshQuality self = measureAgainstSdf(oct, octSdf, sampling);
    CHECK(self.watertight);
    CHECK(self.maxDistance < 1e-6);
    CHECK(self.maxNormalDeviationDeg < 1e-4);
    CHECK(self.minTriangleAngleDeg == Approx(60.0).margin(1e-9));
    CHECK(self.surfaceSamples > 1000);

    sampling.margin = 0.5;
    const MeshQuality sphere = measureAgainstSdf(oct, [](const Point3d& p) { return sphereSdf(p, 1.0); }, sampling);
    const double expected = 1.0 - 1.0 / std::sqrt(3.0); // face centres lie at 1/sqrt(3)
    const double tol = 2 * sampling.spacing * sampling.spacing;
    CHECK(sphere.maxDistanceFromSurface <= expected + 1e-6);
    CHECK(sphere.maxDistanceFromSurface >= expected - tol);
    CHECK(sphere.maxDistance == Approx(expected).margin(tol));
    // At a face centroid the radial direction is the face normal.
    CHECK(sphere.maxNormalDeviationDeg < 1e-3);
}

TEST_CASE("Triangle angles, watertightness and manifoldness of hand-built meshes", "[quality]")
{
    const auto sdf = [](const Point3d& p) { return sphereSdf(p, 1.0); };
    SurfaceSampling sampling;
    sampling.spacing = 0.1;
    // Legs 2 and 1 on the xy face: the smallest angle is atan(1/2).
    const Mesh tet = tetrahedronMesh({{{0, 0, 0}, {2, 0, 0}, {0, 1, 0}, {0, 0, 1}}});
    REQUIRE(enclosedVolume(tet) == Approx(2.0 / 6.0));
    const MeshQuality q = measureAgainstSdf(tet, sdf, sampling);
    CHECK(q.minTriangleAngleDeg == Approx(std::atan(0.5) * 180.0 / kPi).margin(1e-6));
    CHECK(q.watertight);
    CHECK(q.manifold);
    CHECK(q.triangles == 4);

    Mesh open = cubeMesh(0.5);
    open.triangles.pop_back();
    const MeshQuality qo = measureAgainstSdf(open, sdf, sampling);
    CHECK_FALSE(qo.watertight);
    CHECK(qo.manifold);

    Mesh fin = cubeMesh(0.5); // a fin: a third triangle on the edge 0-2
    fin.positions.push_back({-0.5f, -1.5f, 0.0f});
    fin.normals.push_back({0, 0, 1});
    fin.materials.push_back(1);
    fin.triangles.push_back({0, 2, uint32_t(fin.positions.size() - 1)});
    const MeshQuality qf = measureAgainstSdf(fin, sdf, sampling);
    CHECK_FALSE(qf.manifold);
    CHECK_FALSE(qf.watertight);
}

TEST_CASE("A translated cube against the original: the Hausdorff distance is the offset", "[quality]")
{
    const Mesh cube = cubeMesh(0.5);
    const MeshQuality same = measureAgainstMesh(cube, cube);
    CHECK(same.maxDistance < 1e-7);
    CHECK(same.maxNormalDeviationDeg < 1e-6);

    for (double offset : {0.05, 0.1, 0.3}) {
        INFO("offset " << offset);
        const Mesh moved = cubeMesh(0.5, {0.0, 0.0, offset});
        SurfaceSampling sampling;
        sampling.spacing = 0.05;
        const MeshQuality q = measureAgainstMesh(moved, cube, sampling);
        CHECK(q.maxDistanceToSurface == Approx(offset).margin(1e-6));
        CHECK(q.maxDistanceFromSurface == Approx(offset).margin(1e-6));
        CHECK(q.maxDistance == Approx(offset).margin(1e-6));
        // Side faces overlap the original where they coincide, so the mean is below the offset.
        CHECK(q.meanDistance > 0.0);
        CHECK(q.meanDistance < offset);
        CHECK(q.maxNormalDeviationDeg < 1e-6);
        CHECK(q.watertight);
    }
}

TEST_CASE("measureAgainstSdf on an 80k-triangle icosphere matches the chord error", "[quality]")
{
    const double R = 60.0;
    const Mesh sphere = icosphereMesh(R, 6); // 81920 triangles
    REQUIRE(sphere.triangleCount() == 81920);
    const MeshQuality q = measureAgainstSdf(sphere, [R](const Point3d& p) { return sphereSdf(p, R); });
    INFO("max distance " << q.maxDistance);
    CHECK(q.watertight);
    // Chords of a sphere: the deepest point of a flat triangle is below R - R cos(edge/R) ~ edge^2 / (2R).
    CHECK(q.maxDistance > 0.0);
    CHECK(q.maxDistance < 0.05);
    CHECK(q.maxDistanceFromSurface > 0.0);
    CHECK(q.maxDistanceFromSurface <= q.maxDistanceToSurface + 1e-3);
    CHECK(q.surfaceSamples > 10000);
    CHECK(q.maxNormalDeviationDeg < 2.0);
}
