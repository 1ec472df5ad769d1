#include "query/LightField.h"

#include "query/SilhouetteMesh.h"

#include "render/ModelViews.h"

#include <tbb/parallel_for.h>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <random>
#include <stdexcept>

namespace vdbclay::query {

namespace {

using Vec = std::array<double, 3>;
using Matrix = std::array<Vec, 3>; // rows

Vec normalized(Vec v)
{
    const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (double& c : v) c /= n;
    return v;
}
double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec cross(const Vec& a, const Vec& b) { return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; }
Vec rotate(const Matrix& m, const Vec& v) { return {dot(m[0], v), dot(m[1], v), dot(m[2], v)}; }

std::vector<Vec> dodecahedronVertices()
{
    const double phi = (1.0 + std::sqrt(5.0)) / 2.0, inv = 1.0 / phi;
    std::vector<Vec> v;
    for (double x : {-1.0, 1.0})
        for (double y : {-1.0, 1.0})
            for (double z : {-1.0, 1.0}) v.push_back({x, y, z});
    for (double a : {-1.0, 1.0})
        for (double b : {-1.0, 1.0}) {
            v.push_back({0.0, a * inv, b * phi});
            v.push_back({a * inv, b * phi, 0.0});
            v.push_back({a * phi, 0.0, b * inv});
        }
    for (Vec& p : v) p = normalized(p);
    return v;
}

/// The 10 view axes: one vertex of each opposite pair (the one on the positive side of a generic plane).
std::vector<Vec> viewAxes()
{
    const Vec side{0.31, 0.52, 0.79};
    std::vector<Vec> axes;
    for (const Vec& p : dodecahedronVertices())
        if (dot(p, side) > 0.0) axes.push_back(p);
    return axes;
}

/// The orthonormal frame (rows) of a vertex and one of its neighbours.
Matrix frame(const Vec& vertex, const Vec& neighbour)
{
    const Vec a = vertex;
    const Vec b = normalized({neighbour[0] - dot(neighbour, a) * a[0], neighbour[1] - dot(neighbour, a) * a[1], neighbour[2] - dot(neighbour, a) * a[2]});
    return {a, b, cross(a, b)};
}

/// A random rotation, uniform (Shoemake's quaternion), from a fixed seed: the light fields' turns are
/// part of the descriptor's definition.
Matrix lightFieldRotation(int field)
{
    if (field == 0) return {Vec{1, 0, 0}, Vec{0, 1, 0}, Vec{0, 0, 1}};
    std::mt19937_64 random(uint64_t(2003 + field));
    const auto unit = [&] { return double(random() >> 11) * 0x1.0p-53; };
    const double u1 = unit(), u2 = 2.0 * M_PI * unit(), u3 = 2.0 * M_PI * unit();
    const double w = std::sqrt(1 - u1) * std::sin(u2), x = std::sqrt(1 - u1) * std::cos(u2), y = std::sqrt(u1) * std::sin(u3), z = std::sqrt(u1) * std::cos(u3);
    return {Vec{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)}, Vec{2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
            Vec{2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
}

struct ZernikeTerm {
    int n, m;
};

std::vector<ZernikeTerm> zernikeTerms()
{
    std::vector<ZernikeTerm> terms;
    for (int n = 1; n <= 10; ++n)
        for (int m = n % 2; m <= n; m += 2) terms.push_back({n, m});
    return terms;
}

double factorial(int k)
{
    double f = 1.0;
    for (int i = 2; i <= k; ++i) f *= i;
    return f;
}

/// Per pixel of the inscribed disk: its index and, per Zernike term, the conjugate basis value times
/// (n + 1) / pi times the pixel's area.
struct ZernikeBasis {
    std::vector<uint32_t> pixels;
    std::vector<std::complex<float>> values; // pixels.size() x kZernikeMoments
};

ZernikeBasis makeBasis(int size)
{
    const std::vector<ZernikeTerm> terms = zernikeTerms();
    ZernikeBasis basis;
    const double pixelArea = (2.0 / size) * (2.0 / size);
    for (int j = 0; j < size; ++j)
        for (int i = 0; i < size; ++i) {
            const double x = 2.0 * (i + 0.5) / size - 1.0, y = 1.0 - 2.0 * (j + 0.5) / size;
            const double rho = std::sqrt(x * x + y * y);
            if (rho > 1.0) continue;
            const double theta = std::atan2(y, x);
            basis.pixels.push_back(uint32_t(j * size + i));
            for (const ZernikeTerm& t : terms) {
                double radial = 0.0;
                for (int s = 0; s <= (t.n - t.m) / 2; ++s)
                    radial += (s % 2 ? -1.0 : 1.0) * factorial(t.n - s) /
                              (factorial(s) * factorial((t.n + t.m) / 2 - s) * factorial((t.n - t.m) / 2 - s)) * std::pow(rho, t.n - 2 * s);
                const double w = (t.n + 1) / M_PI * pixelArea * radial;
                basis.values.emplace_back(float(w * std::cos(t.m * theta)), float(-w * std::sin(t.m * theta)));
            }
        }
    return basis;
}

const ZernikeBasis& basisFor(int size)
{
    static const ZernikeBasis standard = makeBasis(kSilhouetteSize);
    if (size == kSilhouetteSize) return standard;
    thread_local ZernikeBasis other;
    thread_local int otherSize = 0;
    if (otherSize != size) other = makeBasis(size), otherSize = size;
    return other;
}

/// L1 over a view's features, in eight running sums the compiler keeps in one vector register (a single
/// sum's order would forbid it): the light field's distance is a hundred of these per pair of fields.
float viewDistance(const float* a, const float* b)
{
    float lanes[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    int k = 0;
    for (; k + 8 <= kViewFeatures; k += 8)
        for (int l = 0; l < 8; ++l) lanes[l] += std::abs(a[k + l] - b[k + l]);
    float d = 0.0f;
    for (; k < kViewFeatures; ++k) d += std::abs(a[k] - b[k]);
    for (float lane : lanes) d += lane;
    return d;
}

} // namespace

const std::vector<std::array<uint8_t, kViewsPerLightField>>& dodecahedronRotations()
{
    static const std::vector<std::array<uint8_t, kViewsPerLightField>> rotations = [] {
        const std::vector<Vec> vertices = dodecahedronVertices(), axes = viewAxes();
        double edge = std::numeric_limits<double>::max();
        for (std::size_t i = 1; i < vertices.size(); ++i) {
            const Vec d{vertices[i][0] - vertices[0][0], vertices[i][1] - vertices[0][1], vertices[i][2] - vertices[0][2]};
            edge = std::min(edge, std::sqrt(dot(d, d)));
        }
        const auto neighbours = [&](const Vec& v) {
            std::vector<Vec> out;
            for (const Vec& w : vertices) {
                const Vec d{w[0] - v[0], w[1] - v[1], w[2] - v[2]};
                if (std::abs(std::sqrt(dot(d, d)) - edge) < 1e-6) out.push_back(w);
            }
            return out;
        };
        // The group acts on (vertex, neighbour) pairs one to one: 20 x 3 rotations.
        const Matrix from = frame(vertices[0], neighbours(vertices[0])[0]);
        std::vector<std::array<uint8_t, kViewsPerLightField>> out;
        for (const Vec& v : vertices)
            for (const Vec& n : neighbours(v)) {
                const Matrix to = frame(v, n);
                Matrix r; // to^T from: takes from's frame onto to's
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j)
                        r[std::size_t(i)][std::size_t(j)] = to[0][std::size_t(i)] * from[0][std::size_t(j)] + to[1][std::size_t(i)] * from[1][std::size_t(j)] +
                                                            to[2][std::size_t(i)] * from[2][std::size_t(j)];
                std::array<uint8_t, kViewsPerLightField> permutation{};
                for (std::size_t a = 0; a < axes.size(); ++a) {
                    const Vec turned = rotate(r, axes[a]);
                    std::size_t best = 0;
                    for (std::size_t b = 1; b < axes.size(); ++b)
                        if (std::abs(dot(turned, axes[b])) > std::abs(dot(turned, axes[best]))) best = b;
                    permutation[a] = uint8_t(best);
                }
                out.push_back(permutation);
            }
        return out;
    }();
    return rotations;
}

const std::vector<std::array<double, 3>>& lightFieldDirections()
{
    static const std::vector<Vec> directions = [] {
        const std::vector<Vec> axes = viewAxes();
        std::vector<Vec> out;
        for (int f = 0; f < kLightFields; ++f) {
            const Matrix r = lightFieldRotation(f);
            for (const Vec& a : axes) out.push_back(rotate(r, a));
        }
        return out;
    }();
    return directions;
}

std::array<float, kViewFeatures> silhouetteFeatures(const std::vector<uint8_t>& mask, int size)
{
    if (size < 1 || mask.size() != std::size_t(size) * std::size_t(size)) throw std::invalid_argument("a silhouette of the wrong size");
    std::array<float, kViewFeatures> out{};
    // Region: Zernike moments' magnitudes.
    const ZernikeBasis& basis = basisFor(size);
    std::array<std::complex<double>, kZernikeMoments> moments{};
    for (std::size_t p = 0; p < basis.pixels.size(); ++p)
        if (mask[basis.pixels[p]])
            for (int k = 0; k < kZernikeMoments; ++k) moments[std::size_t(k)] += std::complex<double>(basis.values[p * kZernikeMoments + std::size_t(k)]);
    for (int k = 0; k < kZernikeMoments; ++k) out[std::size_t(k)] = float(std::abs(moments[std::size_t(k)]));
    // Contour: the farthest extent from the centroid per angle, and its Fourier magnitudes over the mean.
    double cx = 0.0, cy = 0.0, count = 0.0;
    for (int j = 0; j < size; ++j)
        for (int i = 0; i < size; ++i)
            if (mask[std::size_t(j) * std::size_t(size) + std::size_t(i)]) cx += i, cy += j, count += 1.0;
    if (count == 0.0) return out;
    cx /= count, cy /= count;
    constexpr int kAngles = 128;
    std::array<double, kAngles> extent{};
    for (int j = 0; j < size; ++j)
        for (int i = 0; i < size; ++i)
            if (mask[std::size_t(j) * std::size_t(size) + std::size_t(i)]) {
                const double dx = i - cx, dy = j - cy;
                const int bin = std::clamp(int((std::atan2(dy, dx) + M_PI) / (2.0 * M_PI) * kAngles), 0, kAngles - 1);
                extent[std::size_t(bin)] = std::max(extent[std::size_t(bin)], std::sqrt(dx * dx + dy * dy) + 0.5);
            }
    double mean = 0.0;
    for (double e : extent) mean += e;
    if (!(mean > 0.0)) return out;
    for (int k = 1; k <= kFourierCoefficients; ++k) {
        std::complex<double> f = 0.0;
        for (int t = 0; t < kAngles; ++t) f += extent[std::size_t(t)] * std::polar(1.0, -2.0 * M_PI * k * t / kAngles);
        out[std::size_t(kZernikeMoments + k - 1)] = float(std::abs(f) / mean);
    }
    return out;
}

std::vector<float> lightFieldFromSilhouettes(const std::vector<std::vector<uint8_t>>& masks, int size)
{
    const std::size_t views = std::size_t(kLightFields * kViewsPerLightField);
    if (masks.size() != views) throw std::invalid_argument("the light field needs " + std::to_string(views) + " silhouettes");
    std::vector<float> out(kLightFieldLength, 0.0f);
    tbb::parallel_for(std::size_t(0), views, [&](std::size_t v) {
        const std::array<float, kViewFeatures> f = silhouetteFeatures(masks[v], size);
        std::copy(f.begin(), f.end(), out.begin() + std::ptrdiff_t((1 + v) * kViewFeatures));
    });
    for (std::size_t v = 0; v < views; ++v)
        for (std::size_t k = 0; k < std::size_t(kViewFeatures); ++k) out[k] += out[(1 + v) * kViewFeatures + k] / float(views);
    return out;
}

std::vector<float> lightFieldDescriptor(render::ModelViews& views, const TriangleSoup& soup)
{
    // The surface's centroid and the farthest vertex from it: both turn with the model.
    std::array<double, 3> centre{0, 0, 0};
    double area = 0.0;
    for (const auto& t : soup.triangles) {
        const Vec &a = soup.positions[t[0]], &b = soup.positions[t[1]], &c = soup.positions[t[2]];
        const Vec n = cross({b[0] - a[0], b[1] - a[1], b[2] - a[2]}, {c[0] - a[0], c[1] - a[1], c[2] - a[2]});
        const double w = 0.5 * std::sqrt(dot(n, n));
        for (int k = 0; k < 3; ++k) centre[std::size_t(k)] += w * (a[std::size_t(k)] + b[std::size_t(k)] + c[std::size_t(k)]) / 3.0;
        area += w;
    }
    if (!(area > 0.0) || !std::isfinite(area)) throw std::invalid_argument("the mesh has no surface area to describe");
    for (double& c : centre) c /= area;
    double radius = 0.0;
    for (const auto& t : soup.triangles)
        for (uint32_t v : t) {
            const Vec& p = soup.positions[v];
            const Vec d{p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]};
            radius = std::max(radius, std::sqrt(dot(d, d)));
        }
    // Vertices clustered in cells of about a pixel (the view is 2 radii across).
    const SilhouetteMesh shape = silhouetteMesh(soup, kSilhouetteCellPixels * 2.0 * radius / kSilhouetteSize);
    const std::vector<std::vector<uint8_t>> masks =
        views.silhouettes(shape.mesh, centre, radius, lightFieldDirections(), kSilhouetteSize, shape.closed);
    return lightFieldFromSilhouettes(masks, kSilhouetteSize);
}

std::vector<float> lightFieldSummary(const std::vector<float>& descriptor)
{
    if (descriptor.size() != kLightFieldLength) throw std::invalid_argument("not a light-field descriptor");
    return std::vector<float>(descriptor.begin(), descriptor.begin() + kViewFeatures);
}

double lightFieldDistance(const std::vector<float>& a, const std::vector<float>& b, int queryFields)
{
    if (a.size() != kLightFieldLength || b.size() != kLightFieldLength) throw std::invalid_argument("not a light-field descriptor");
    const auto view = [](const std::vector<float>& d, int field, int v) {
        return d.data() + std::size_t(1 + field * kViewsPerLightField + v) * kViewFeatures;
    };
    const auto& rotations = dodecahedronRotations();
    double best = std::numeric_limits<double>::max();
    std::array<float, kViewsPerLightField * kViewsPerLightField> cost{};
    for (int fa = 0; fa < std::clamp(queryFields, 1, kLightFields); ++fa)
        for (int fb = 0; fb < kLightFields; ++fb) {
            for (int va = 0; va < kViewsPerLightField; ++va)
                for (int vb = 0; vb < kViewsPerLightField; ++vb)
                    cost[std::size_t(va * kViewsPerLightField + vb)] = viewDistance(view(a, fa, va), view(b, fb, vb));
            for (const auto& p : rotations) {
                float sum = 0.0f;
                for (int v = 0; v < kViewsPerLightField; ++v) sum += cost[std::size_t(v * kViewsPerLightField + p[std::size_t(v)])];
                best = std::min(best, double(sum));
            }
        }
    return best;
}

namespace {

float dequantizedFeature(uint8_t q)
{
    const float v = float(q) / 255.0f;
    return v * v;
}

} // namespace

QuantizedLightField quantizeLightField(const std::vector<float>& descriptor)
{
    if (descriptor.size() != kLightFieldLength) throw std::invalid_argument("not a light-field descriptor");
    QuantizedLightField out(descriptor.size());
    for (std::size_t i = 0; i < descriptor.size(); ++i) {
        const double v = std::clamp(double(descriptor[i]), 0.0, 1.0); // NaN reads 0
        out[i] = uint8_t(std::lround(255.0 * std::sqrt(std::isnan(v) ? 0.0 : v)));
    }
    return out;
}

std::vector<float> dequantizeLightField(const QuantizedLightField& descriptor)
{
    if (descriptor.size() != kLightFieldLength) throw std::invalid_argument("not a light-field descriptor");
    std::vector<float> out(descriptor.size());
    for (std::size_t i = 0; i < descriptor.size(); ++i) out[i] = dequantizedFeature(descriptor[i]);
    return out;
}

std::vector<float> quantizedLightFieldSummary(const uint8_t* descriptor)
{
    std::vector<float> out(kViewFeatures);
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = dequantizedFeature(descriptor[i]);
    return out;
}

namespace {

/// A quantized view's features padded with zeros to three 16-byte blocks.
constexpr int kPaddedFeatures = 48;
static_assert(kViewFeatures <= kPaddedFeatures);
using PaddedView = std::array<uint8_t, kPaddedFeatures>;

/// The views of light fields [0, fields) of a quantized light field, padded.
std::vector<PaddedView> paddedViews(const uint8_t* d, int fields)
{
    std::vector<PaddedView> out(std::size_t(fields * kViewsPerLightField), PaddedView{});
    for (std::size_t v = 0; v < out.size(); ++v) std::copy_n(d + (1 + v) * kViewFeatures, kViewFeatures, out[v].data());
    return out;
}

/// L1 of two padded views: sums of absolute byte differences, 16 at a time.
inline int viewSad(const PaddedView& a, const PaddedView& b)
{
#ifdef __SSE2__
    __m128i sum = _mm_setzero_si128();
    for (int block = 0; block < kPaddedFeatures; block += 16) {
        const __m128i x = _mm_loadu_si128(reinterpret_cast<const __m128i*>(a.data() + block));
        const __m128i y = _mm_loadu_si128(reinterpret_cast<const __m128i*>(b.data() + block));
        sum = _mm_add_epi64(sum, _mm_sad_epu8(x, y));
    }
    return _mm_cvtsi128_si32(sum) + _mm_cvtsi128_si32(_mm_srli_si128(sum, 8));
#else
    int sum = 0;
    for (int k = 0; k < kPaddedFeatures; ++k) sum += std::abs(int(a[std::size_t(k)]) - int(b[std::size_t(k)]));
    return sum;
#endif
}

} // namespace

double lightFieldDistance(const QuantizedLightField& a, const QuantizedLightField& b, int queryFields)
{
    if (a.size() != kLightFieldLength || b.size() != kLightFieldLength) throw std::invalid_argument("not a light-field descriptor");
    return lightFieldDistance(a.data(), b.data(), queryFields);
}

double lightFieldDistance(const uint8_t* a, const uint8_t* b, int queryFields)
{
    const int fields = std::clamp(queryFields, 1, kLightFields);
    const std::vector<PaddedView> va = paddedViews(a, fields), vb = paddedViews(b, kLightFields);
    const auto& rotations = dodecahedronRotations();
    int best = std::numeric_limits<int>::max();
    std::array<int, kViewsPerLightField * kViewsPerLightField> cost{};
    for (int fa = 0; fa < fields; ++fa)
        for (int fb = 0; fb < kLightFields; ++fb) {
            for (int i = 0; i < kViewsPerLightField; ++i)
                for (int j = 0; j < kViewsPerLightField; ++j)
                    cost[std::size_t(i * kViewsPerLightField + j)] =
                        viewSad(va[std::size_t(fa * kViewsPerLightField + i)], vb[std::size_t(fb * kViewsPerLightField + j)]);
            for (const auto& p : rotations) {
                int sum = 0;
                for (int v = 0; v < kViewsPerLightField; ++v) sum += cost[std::size_t(v * kViewsPerLightField + p[std::size_t(v)])];
                best = std::min(best, sum);
            }
        }
    return double(best) / 255.0;
}

} // namespace vdbclay::query
