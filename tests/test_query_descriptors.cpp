// Retrieval's descriptors beyond D2: curvature on meshes, ISODATA, ClusterD2+Color and the light field
// (src/query). Tests whose names say "render" draw silhouettes with the Vulkan renderer.
#include "query/ClusterD2Color.h"
#include "query/HistogramDistance.h"
#include "query/Isodata.h"
#include "query/LightField.h"
#include "query/MeshCurvature.h"
#include "query/SilhouetteMesh.h"
#include "query/SyntheticModels.h"
#include "render/ModelViews.h"
#include "render/VulkanContext.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <set>

using namespace vdbclay;
using namespace vdbclay::query;

namespace {

SyntheticShape roundBall(int tessellation)
{
    SyntheticShape s;
    s.family = "ellipsoid";
    s.proportions = {1.0, 1.0 / 0.7, 1.0 / 0.5}; // the family's radii 1, 0.7, 0.5 times these: a unit sphere
    s.tessellation = tessellation;
    return s;
}

/// The shape seen anew: another pose, scale and tessellation.
SyntheticShape movedCopy(SyntheticShape s, std::mt19937_64& random)
{
    const SyntheticShape fresh = randomShape(s.family, random);
    s.rotation = fresh.rotation;
    s.scale = fresh.scale * 2.5;
    s.position = fresh.position;
    s.tessellation += 11;
    return s;
}

/// The soup as the renderer takes it (positions and triangles; silhouettes read nothing else).
Mesh drawable(const TriangleSoup& soup)
{
    Mesh mesh;
    for (const auto& p : soup.positions) mesh.positions.push_back({float(p[0]), float(p[1]), float(p[2])});
    mesh.normals.assign(mesh.positions.size(), {0, 0, 1});
    mesh.materials.assign(mesh.positions.size(), 1);
    mesh.triangles = soup.triangles;
    mesh.triangleMaterials.assign(mesh.triangles.size(), 1);
    return mesh;
}

std::array<double, 3> rotateByQuaternion(const std::array<double, 4>& q, const std::array<double, 3>& v)
{
    const double x = q[0], y = q[1], z = q[2], w = q[3];
    const std::array<double, 3> t{2 * (y * v[2] - z * v[1]), 2 * (z * v[0] - x * v[2]), 2 * (x * v[1] - y * v[0])};
    return {v[0] + w * t[0] + (y * t[2] - z * t[1]), v[1] + w * t[1] + (z * t[0] - x * t[2]), v[2] + w * t[2] + (x * t[1] - y * t[0])};
}

/// An ellipsoid painted red where its model-frame coordinate `axis` passes `threshold`, then posed.
TriangleSoup paintedEllipsoid(int axis, double threshold, int tessellation, const std::array<double, 4>& rotation, double scale)
{
    SyntheticShape s;
    s.family = "ellipsoid";
    s.proportions = {1.2, 1.0, 1.0};
    s.tessellation = tessellation;
    s.colour = {0.9f, 0.9f, 0.9f};
    TriangleSoup soup = buildShape(s);
    MeshMaterial red;
    red.name = "red";
    red.color = {0.8f, 0.1f, 0.1f, 1.0f};
    soup.materials.push_back(red);
    for (std::size_t t = 0; t < soup.triangles.size(); ++t) {
        double c = 0.0;
        for (uint32_t v : soup.triangles[t]) c += soup.positions[v][std::size_t(axis)] / 3.0;
        if (c > threshold) soup.triangleMaterials[t] = 1;
    }
    for (auto& p : soup.positions) {
        p = rotateByQuaternion(rotation, p);
        for (double& c : p) c *= scale;
    }
    return soup;
}

/// The share of the set's models whose nearest other model (by `distance` between positions) is of
/// their family.
double nearestNeighbourPrecision(const std::vector<LabeledModel>& set, const std::function<double(std::size_t, std::size_t)>& distance)
{
    int right = 0;
    for (std::size_t i = 0; i < set.size(); ++i) {
        std::size_t best = i == 0 ? 1 : 0;
        for (std::size_t j = 0; j < set.size(); ++j)
            if (j != i && distance(i, j) < distance(i, best)) best = j;
        right += set[best].label == set[i].label;
    }
    return double(right) / double(set.size());
}

double chance() { return 1.0 / double(syntheticFamilies().size()); }

} // namespace

TEST_CASE("query curvature: a sphere's mean curvature is 1/R, |K| integrates to 4 pi on a sphere and about 8 pi on a torus, welding joins repeated corners", "[query]")
{
    const TriangleSoup sphere = buildShape(roundBall(32));
    const WeldedMesh welded = weldMesh(sphere);
    CHECK(absoluteGaussianCurvature(welded) == Approx(4.0 * M_PI).epsilon(1e-6)); // discrete Gauss-Bonnet, all defects positive
    std::vector<double> h = meanCurvature(welded);
    std::sort(h.begin(), h.end());
    CHECK(h[h.size() / 2] == Approx(1.0).epsilon(0.03)); // unit radius
    CHECK(h[h.size() / 10] > 0.8);
    SyntheticShape torus;
    torus.family = "torus";
    torus.tessellation = 40;
    CHECK(absoluteGaussianCurvature(weldMesh(buildShape(torus))) == Approx(8.0 * M_PI).epsilon(0.1));

    // A cube of 12 triangles with three corners each: 8 vertices, each with 3 or more neighbours.
    TriangleSoup cube;
    const int faces[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
    const auto corner = [](int i) { return std::array<double, 3>{double(i & 1), double((i >> 1) & 1), double((i >> 2) & 1)}; };
    for (const auto& f : faces)
        for (const std::array<int, 3> tri : {std::array<int, 3>{f[0], f[1], f[2]}, std::array<int, 3>{f[0], f[2], f[3]}}) {
            const uint32_t first = uint32_t(cube.positions.size());
            for (int c : tri) cube.positions.push_back(corner(c));
            cube.triangles.push_back({first, first + 1, first + 2});
        }
    const WeldedMesh box = weldMesh(cube);
    CHECK(box.positions.size() == 8);
    CHECK(std::none_of(box.boundary.begin(), box.boundary.end(), [](bool b) { return b; }));
    CHECK(absoluteGaussianCurvature(box) == Approx(4.0 * M_PI));
}

TEST_CASE("query ISODATA: separated blobs become one cluster each, a handful of strays dissolve into them, the result is repeatable", "[query]")
{
    std::mt19937_64 random(4);
    std::normal_distribution<double> noise(0.0, 0.3);
    std::vector<std::array<double, 3>> points;
    const std::array<std::array<double, 3>, 3> centres{{{0, 0, 0}, {10, 0, 0}, {0, 10, 5}}};
    for (const auto& c : centres)
        for (int i = 0; i < 100; ++i) points.push_back({c[0] + noise(random), c[1] + noise(random), c[2] + noise(random)});
    points.push_back({5, 5, 5});
    points.push_back({5.2, 5, 5});
    IsodataOptions options;
    options.minMembers = 5;
    options.maxSpread = 1.0;
    options.mergeDistance = 2.0;
    const Clustering c = isodataClusters(points, options);
    REQUIRE(c.centres.size() == 3);
    for (int blob = 0; blob < 3; ++blob) {
        const uint32_t id = c.cluster[std::size_t(blob * 100)];
        for (int i = 0; i < 100; ++i) CHECK(c.cluster[std::size_t(blob * 100 + i)] == id);
    }
    CHECK(c.iterations >= options.minIterations);
    CHECK(isodataClusters(points, options).cluster == c.cluster);
    // One wide blob splits until its parts are narrow enough; close centres merge.
    options.maxSpread = 0.1;
    options.mergeDistance = 0.0;
    CHECK(isodataClusters(points, options).centres.size() > 3);
    options.maxSpread = 100.0;
    options.mergeDistance = 100.0;
    CHECK(isodataClusters(points, options).centres.size() == 1);
    CHECK(isodataClusters({}, options).centres.empty());
}

TEST_CASE("query ClusterD2+Color: CIELAB of known colours and their colour codes", "[query]")
{
    const auto white = cieLab({1, 1, 1}), red = cieLab({1, 0, 0}), black = cieLab({0, 0, 0});
    CHECK(white[0] == Approx(100.0).margin(0.01));
    CHECK(white[1] == Approx(0.0).margin(0.01));
    CHECK(white[2] == Approx(0.0).margin(0.01));
    CHECK(red[0] == Approx(53.24).margin(0.05));
    CHECK(red[1] == Approx(80.09).margin(0.05));
    CHECK(red[2] == Approx(67.20).margin(0.05));
    CHECK(black[0] == Approx(0.0).margin(1e-9));
    // a* and b* bins: below -25, -25 to 25 (the greys), 25 to 75, above 75.
    CHECK(colourCode({1, 1, 1}) == (5 * 4 + 1) * 4 + 1);
    CHECK(colourCode({0.5f, 0.5f, 0.5f}) == (3 * 4 + 1) * 4 + 1);
    CHECK(colourCode({0, 0, 0}) == (0 * 4 + 1) * 4 + 1);
    CHECK(colourCode({1, 0, 0}) == (3 * 4 + 3) * 4 + 2);
    CHECK(colourCode({0.9f, 0.9f, 0.9f}) == colourCode({0.95f, 0.95f, 0.95f}));
    CHECK(colourCode({0.9f, 0.9f, 0.9f}) != colourCode({0.8f, 0.1f, 0.1f}));
}

TEST_CASE("query ClusterD2+Color: a model moved, turned, scaled and re-tessellated stays nearest itself, and the descriptor is repeatable", "[query]")
{
    const std::vector<LabeledModel> set = syntheticSet(3, 17);
    std::vector<Histogram> described;
    for (const LabeledModel& m : set) described.push_back(smoothHistogram(clusterD2ColorDescriptor(buildShape(m.shape))));
    std::mt19937_64 random(9);
    for (std::size_t i = 0; i < set.size(); i += 2) {
        INFO(set[i].name);
        ClusterD2Details details;
        const Histogram moved = smoothHistogram(clusterD2ColorDescriptor(buildShape(movedCopy(set[i].shape, random)), {}, &details));
        CHECK(details.samples >= 6144);
        CHECK(details.clusters >= 1);
        const double self = chiSquareDistance(moved, described[i]);
        CHECK(self < 0.05);
        for (std::size_t j = 0; j < set.size(); ++j)
            if (set[j].label != set[i].label) CHECK(chiSquareDistance(moved, described[j]) > self);
    }
    CHECK(clusterD2ColorDescriptor(buildShape(set[0].shape)) == clusterD2ColorDescriptor(buildShape(set[0].shape)));
    TriangleSoup flat = buildShape(set[0].shape);
    for (auto& p : flat.positions) p = {0, 0, 0};
    CHECK_THROWS_AS(clusterD2ColorDescriptor(flat), std::invalid_argument);
}

TEST_CASE("query ClusterD2+Color: the same shape painted another way ranks below the exact colour match", "[query]")
{
    const std::array<double, 4> identity{0, 0, 0, 1}, turned{0.5, 0.5, 0.5, 0.5};
    ClusterD2Details details;
    const Histogram band = smoothHistogram(clusterD2ColorDescriptor(paintedEllipsoid(0, 0.6, 24, identity, 1.0), {}, &details));
    CHECK(details.colourSamples > 0);
    const Histogram other = smoothHistogram(clusterD2ColorDescriptor(paintedEllipsoid(1, 0.2, 24, identity, 1.0)));
    const Histogram plain = smoothHistogram(clusterD2ColorDescriptor(paintedEllipsoid(0, 99.0, 24, identity, 1.0), {}, &details));
    CHECK(details.colourSamples == 0);
    // The band's model seen anew: turned, scaled, tessellated otherwise.
    const Histogram probe = smoothHistogram(clusterD2ColorDescriptor(paintedEllipsoid(0, 0.6, 31, turned, 3.0)));
    const double self = chiSquareDistance(probe, band);
    INFO("to itself " << self << ", to the other pattern " << chiSquareDistance(probe, other) << ", to the plain one " << chiSquareDistance(probe, plain));
    CHECK(self < chiSquareDistance(probe, other));
    CHECK(self < chiSquareDistance(probe, plain));
}

TEST_CASE("query descriptors: on the synthetic set ClusterD2+Color's nearest neighbour is of the same family far above chance", "[query]")
{
    const std::vector<LabeledModel> set = syntheticSet(6, 3);
    std::vector<Histogram> d;
    for (const LabeledModel& m : set) d.push_back(smoothHistogram(clusterD2ColorDescriptor(buildShape(m.shape))));
    const double precision = nearestNeighbourPrecision(set, [&](std::size_t i, std::size_t j) { return chiSquareDistance(d[i], d[j]); });
    INFO("nearest-neighbour precision " << precision << " (chance " << chance() << ")");
    CHECK(precision >= 2.0 * chance());
}

TEST_CASE("query light field: a view's features ignore its turn and mirroring in the image, and a disk's moments and outline coefficients vanish", "[query]")
{
    const int n = kSilhouetteSize;
    std::vector<uint8_t> blob(std::size_t(n * n), 0), turned(blob.size(), 0), mirrored(blob.size(), 0), disk(blob.size(), 0);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const double u = (x + 0.5) / n - 0.5, v = (y + 0.5) / n - 0.5;
            const bool inside = (u + 0.1) * (u + 0.1) / 0.09 + v * v / 0.02 < 1.0 || (std::abs(u - 0.2) < 0.05 && v > -0.3 && v < 0.2);
            blob[std::size_t(y * n + x)] = inside;
            disk[std::size_t(y * n + x)] = u * u + v * v < 0.2;
        }
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            turned[std::size_t(x * n + (n - 1 - y))] = blob[std::size_t(y * n + x)]; // a quarter turn
            mirrored[std::size_t(y * n + (n - 1 - x))] = blob[std::size_t(y * n + x)];
        }
    const auto a = silhouetteFeatures(blob, n), b = silhouetteFeatures(turned, n), c = silhouetteFeatures(mirrored, n);
    double size = 0.0;
    for (int k = 0; k < kViewFeatures; ++k) {
        CHECK(b[std::size_t(k)] == Approx(a[std::size_t(k)]).margin(0.02 * std::abs(a[std::size_t(k)]) + 1e-3));
        CHECK(c[std::size_t(k)] == Approx(a[std::size_t(k)]).margin(0.02 * std::abs(a[std::size_t(k)]) + 1e-3));
        size += a[std::size_t(k)];
    }
    CHECK(size > 0.1);
    // A centred disk: its moments of angular order m > 0 vanish (its radial ones, m = 0, do not: it is
    // smaller than the unit disk), and so do its outline's Fourier coefficients (a circle's extent is
    // the same every way).
    const auto round = silhouetteFeatures(disk, n);
    int k = 0, radial = 0;
    for (int order = 1; order <= 10; ++order)
        for (int m = order % 2; m <= order; m += 2, ++k) {
            INFO("Zernike n " << order << " m " << m);
            if (m > 0) CHECK(round[std::size_t(k)] < 0.01);
            else radial += round[std::size_t(k)] > 0.05;
        }
    REQUIRE(k == kZernikeMoments);
    CHECK(radial > 0);
    for (int f = kZernikeMoments; f < kViewFeatures; ++f) CHECK(round[std::size_t(f)] < 0.02);
    CHECK(silhouetteFeatures(std::vector<uint8_t>(blob.size(), 0), n) == std::array<float, kViewFeatures>{});
    CHECK_THROWS_AS(silhouetteFeatures(blob, n + 1), std::invalid_argument);
}

TEST_CASE("query light field: the dodecahedron's 60 rotations are distinct permutations of its 10 view axes and form a group", "[query]")
{
    const auto& rotations = dodecahedronRotations();
    REQUIRE(rotations.size() == 60);
    const std::set<std::array<uint8_t, kViewsPerLightField>> distinct(rotations.begin(), rotations.end());
    CHECK(distinct.size() == 60);
    std::array<uint8_t, kViewsPerLightField> identity{};
    for (int i = 0; i < kViewsPerLightField; ++i) identity[std::size_t(i)] = uint8_t(i);
    CHECK(distinct.count(identity) == 1);
    for (const auto& p : rotations) {
        std::array<uint8_t, kViewsPerLightField> sorted = p;
        std::sort(sorted.begin(), sorted.end());
        CHECK(sorted == identity);
        for (const auto& q : rotations) {
            std::array<uint8_t, kViewsPerLightField> composed{};
            for (int i = 0; i < kViewsPerLightField; ++i) composed[std::size_t(i)] = p[q[std::size_t(i)]];
            CHECK(distinct.count(composed) == 1);
        }
    }
    CHECK(lightFieldDirections().size() == std::size_t(kLightFields * kViewsPerLightField));
}

TEST_CASE("query light field: 8-bit light fields round-trip within a quantum, and their distance is the L1 of the bytes, least over the turns", "[query]")
{
    std::mt19937 rng(13);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    // Features spread over [0, 1] with many small ones, as the real ones are; and the clamped ends.
    const auto randomField = [&] {
        std::vector<float> f(kLightFieldLength);
        for (float& v : f) v = std::pow(unit(rng), 3.0f);
        return f;
    };
    const std::vector<float> a = randomField(), b = randomField();
    const QuantizedLightField qa = quantizeLightField(a), qb = quantizeLightField(b);
    REQUIRE(qa.size() == kLightFieldLength);
    const std::vector<float> back = dequantizeLightField(qa);
    for (std::size_t i = 0; i < a.size(); ++i) {
        // Half a step of 1/255 on the square root.
        CHECK(std::fabs(std::sqrt(back[i]) - std::sqrt(a[i])) <= 0.5f / 255.0f + 1e-6f);
    }
    CHECK(quantizeLightField(back) == qa); // quantized again: the same bytes
    std::vector<float> ends(kLightFieldLength, 0.0f);
    ends[0] = -0.5f, ends[1] = 1.0f, ends[2] = 7.0f, ends[3] = std::numeric_limits<float>::quiet_NaN();
    const QuantizedLightField qe = quantizeLightField(ends);
    CHECK(int(qe[0]) == 0);
    CHECK(int(qe[1]) == 255);
    CHECK(int(qe[2]) == 255);
    CHECK(int(qe[3]) == 0);
    CHECK_THROWS_AS(quantizeLightField(std::vector<float>(10)), std::invalid_argument);

    // The distance against its definition, computed plainly: least over b's light fields and the 60
    // turns of the sum over a's first light field's views of the L1 of their bytes, over 255.
    const auto plain = [](const QuantizedLightField& x, const QuantizedLightField& y) {
        long best = std::numeric_limits<long>::max();
        for (int fb = 0; fb < kLightFields; ++fb)
            for (const auto& turn : dodecahedronRotations()) {
                long sum = 0;
                for (int v = 0; v < kViewsPerLightField; ++v)
                    for (int k = 0; k < kViewFeatures; ++k)
                        sum += std::abs(int(x[std::size_t((1 + v) * kViewFeatures + k)]) -
                                        int(y[std::size_t((1 + fb * kViewsPerLightField + turn[std::size_t(v)]) * kViewFeatures + k)]));
                best = std::min(best, sum);
            }
        return double(best) / 255.0;
    };
    CHECK(lightFieldDistance(qa, qb) == plain(qa, qb));
    CHECK(lightFieldDistance(qb, qa) == plain(qb, qa));
    CHECK(lightFieldDistance(qa, qa) == 0.0);
    // b's views taken from a, light field 3 turned: the distance is zero again.
    QuantizedLightField turned = qb;
    const auto& turn = dodecahedronRotations()[17];
    for (int v = 0; v < kViewsPerLightField; ++v)
        std::copy_n(qa.begin() + (1 + v) * kViewFeatures, kViewFeatures, turned.begin() + (1 + 3 * kViewsPerLightField + turn[std::size_t(v)]) * kViewFeatures);
    CHECK(lightFieldDistance(qa, turned) == 0.0);
    CHECK(plain(qa, turned) == 0.0);
    // Near the float distance of the square roots: each feature a half step off at most.
    std::vector<float> rootA(a.size()), rootB(b.size());
    for (std::size_t i = 0; i < a.size(); ++i) rootA[i] = std::sqrt(a[i]), rootB[i] = std::sqrt(b[i]);
    CHECK(std::fabs(lightFieldDistance(qa, qb) - lightFieldDistance(rootA, rootB)) <= kViewsPerLightField * kViewFeatures * (1.0 / 255.0) + 1e-3);
}

TEST_CASE("query light field (render): a sphere's silhouettes are discs filling the view, and a turned, scaled, re-tessellated model is nearest itself", "[query]")
{
    render::ContextOptions contextOptions;
    contextOptions.validation = true;
    render::VulkanContext context(contextOptions);
    render::ModelViews views(context);

    // A unit sphere framed by its own radius: every silhouette is the inscribed disc (pi / 4 of the square).
    const TriangleSoup sphere = buildShape(roundBall(48));
    const std::vector<float> ball = lightFieldDescriptor(views, sphere);
    REQUIRE(ball.size() == kLightFieldLength);
    {
        const Mesh mesh = drawable(sphere);
        const std::vector<render::Mask> masks = views.silhouettes(mesh, {0, 0, 0}, 1.0, {{1, 0, 0}, {0, 0.6, 0.8}}, 64);
        REQUIRE(masks.size() == 2);
        for (const render::Mask& m : masks) {
            const double covered = double(std::count(m.begin(), m.end(), 1)) / double(m.size());
            CHECK(covered == Approx(M_PI / 4.0).epsilon(0.03));
            CHECK(m[0] == 0);
            CHECK(m[32 * 64 + 32] == 1);
        }
        CHECK_THROWS_AS(views.silhouettes(Mesh{}, {0, 0, 0}, 1.0, {{1, 0, 0}}, 64), std::invalid_argument);
    }

    const std::vector<LabeledModel> set = syntheticSet(2, 23);
    std::vector<std::vector<float>> described;
    for (const LabeledModel& m : set) described.push_back(lightFieldDescriptor(views, buildShape(m.shape)));
    std::mt19937_64 random(12);
    for (std::size_t i = 0; i < set.size(); i += 3) {
        INFO(set[i].name);
        const std::vector<float> moved = lightFieldDescriptor(views, buildShape(movedCopy(set[i].shape, random)));
        const double self = lightFieldDistance(moved, described[i]);
        for (std::size_t j = 0; j < set.size(); ++j)
            if (set[j].label != set[i].label) CHECK(lightFieldDistance(moved, described[j]) > self);
    }
    // The set's nearest neighbours by light field: of the same family far above chance.
    const double precision =
        nearestNeighbourPrecision(set, [&](std::size_t i, std::size_t j) { return lightFieldDistance(described[i], described[j]); });
    INFO("nearest-neighbour precision " << precision << " (chance " << chance() << ")");
    CHECK(precision >= 3.0 * chance());
    CHECK(lightFieldDistance(ball, ball) == 0.0);
    CHECK(context.validationMessages() == 0);
}

namespace {

/// The soup with each triangle's corners its own (as a file without shared vertices has them).
TriangleSoup unshared(const TriangleSoup& soup)
{
    TriangleSoup out = soup;
    out.positions.clear();
    for (auto& t : out.triangles)
        for (uint32_t& v : t) {
            out.positions.push_back(soup.positions[v]);
            v = uint32_t(out.positions.size() - 1);
        }
    return out;
}

/// Whether every pixel where two masks differ lies within `reach` pixels of the first mask's outline
/// (a pixel of the other value within the square of that reach around it).
bool differOnlyNearOutline(const render::Mask& a, const render::Mask& b, int size, int reach)
{
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            if (a[std::size_t(y * size + x)] == b[std::size_t(y * size + x)]) continue;
            bool nearOutline = false;
            for (int dy = -reach; dy <= reach && !nearOutline; ++dy)
                for (int dx = -reach; dx <= reach && !nearOutline; ++dx) {
                    const int u = x + dx, v = y + dy;
                    nearOutline = u >= 0 && v >= 0 && u < size && v < size && a[std::size_t(v * size + u)] != a[std::size_t(y * size + x)];
                }
            if (!nearOutline) return false;
        }
    return true;
}

} // namespace

TEST_CASE("query silhouette mesh: clustering keeps closed surfaces closed and open ones open, welds unshared corners, and thins with the cell", "[query]")
{
    std::mt19937_64 random(5);
    for (const std::string& family : syntheticFamilies()) {
        INFO(family);
        const TriangleSoup soup = buildShape(randomShape(family, random));
        std::array<double, 3> lo{HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
        for (const auto& p : soup.positions)
            for (std::size_t a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
        const double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
        std::size_t previous = soup.triangles.size();
        for (const double cell : {extent / 400.0, extent / 100.0, extent / 25.0}) {
            const SilhouetteMesh fine = silhouetteMesh(soup, cell);
            CHECK(fine.closed);
            CHECK(fine.mesh.triangles.size() <= previous);
            previous = fine.mesh.triangles.size();
            // A cluster's point is the mean of its corners: inside the model's box.
            for (const auto& p : fine.mesh.positions)
                for (std::size_t a = 0; a < 3; ++a) CHECK((p[a] >= float(lo[a]) - 1e-4f && p[a] <= float(hi[a]) + 1e-4f));
            // Corners that are not shared cluster the same way.
            const SilhouetteMesh loose = silhouetteMesh(unshared(soup), cell);
            CHECK(loose.closed);
            CHECK(loose.mesh.triangles.size() == fine.mesh.triangles.size());
        }
        TriangleSoup open = soup;
        open.triangles.erase(open.triangles.begin() + std::ptrdiff_t(open.triangles.size() / 2));
        CHECK_FALSE(silhouetteMesh(open, extent / 400.0).closed);
    }
    // A fine unit sphere (about 100k triangles) in cells of a pixel of a 128-pixel view: about 4 pi
    // 64^2 cells on the surface, two triangles each.
    const TriangleSoup fine = buildShape(roundBall(158));
    const SilhouetteMesh pixels = silhouetteMesh(fine, 2.0 / 128.0);
    CHECK(pixels.closed);
    CHECK(pixels.mesh.triangles.size() < fine.triangles.size() * 3 / 4);
    CHECK(silhouetteMesh(fine, 8.0 / 128.0).mesh.triangles.size() < fine.triangles.size() / 8);
    // A cell wider than the model: every triangle would vanish, so the welded triangles are kept.
    const SilhouetteMesh whole = silhouetteMesh(fine, 10.0);
    CHECK(whole.closed);
    CHECK(whole.mesh.triangles.size() == silhouetteMesh(fine, 1e-12).mesh.triangles.size());
    CHECK(whole.mesh.triangles.size() > fine.triangles.size() * 9 / 10);
    CHECK_THROWS_AS(silhouetteMesh(fine, 0.0), std::invalid_argument);
}

TEST_CASE("query silhouette mesh (render): a clustered closed surface's front faces draw the silhouettes of all its triangles but near the outline, inside out too", "[query]")
{
    render::ContextOptions contextOptions;
    contextOptions.validation = true;
    render::VulkanContext context(contextOptions);
    render::ModelViews views(context);
    std::mt19937_64 random(8);
    constexpr int kSize = 128;
    for (const std::string& family : syntheticFamilies()) {
        INFO(family);
        SyntheticShape shape = randomShape(family, random);
        shape.tessellation = 64;
        const TriangleSoup soup = buildShape(shape);
        std::array<double, 3> centre{0, 0, 0};
        for (const auto& p : soup.positions)
            for (std::size_t a = 0; a < 3; ++a) centre[a] += p[a] / double(soup.positions.size());
        double radius = 0.0;
        for (const auto& p : soup.positions)
            radius = std::max(radius, std::sqrt((p[0] - centre[0]) * (p[0] - centre[0]) + (p[1] - centre[1]) * (p[1] - centre[1]) +
                                                (p[2] - centre[2]) * (p[2] - centre[2])));
        const std::vector<std::array<double, 3>> directions(lightFieldDirections().begin(), lightFieldDirections().begin() + 10);
        const std::vector<render::Mask> full = views.silhouettes(drawable(soup), centre, radius, directions, kSize);
        const SilhouetteMesh clustered = silhouetteMesh(soup, kSilhouetteCellPixels * 2.0 * radius / kSize);
        REQUIRE(clustered.closed);
        const std::vector<render::Mask> fronts = views.silhouettes(clustered.mesh, centre, radius, directions, kSize, true);
        // Turned inside out, the other faces face the eye and cover the same.
        Mesh inverted = clustered.mesh;
        for (auto& t : inverted.triangles) std::swap(t[1], t[2]);
        const std::vector<render::Mask> backs = views.silhouettes(inverted, centre, radius, directions, kSize, true);
        for (std::size_t i = 0; i < directions.size(); ++i) {
            INFO("view " << i);
            CHECK(std::count(full[i].begin(), full[i].end(), 1) > kSize * kSize / 20);
            // A cluster's point lies in its cell: a corner moves by at most the cell's diagonal.
            CHECK(differOnlyNearOutline(full[i], fronts[i], kSize, int(std::ceil(kSilhouetteCellPixels * std::sqrt(3.0)))));
            CHECK(differOnlyNearOutline(fronts[i], backs[i], kSize, 1));
        }
    }
    CHECK(context.validationMessages() == 0);
}
