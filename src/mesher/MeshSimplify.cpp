#include "mesher/MeshSimplify.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <queue>
#include <vector>

namespace vdbclay {

namespace {

using Point = std::array<double, 3>;

/// The most neighbours a vertex may have after a collapse onto it.
constexpr std::size_t kMostNeighbours = 12;

/// The sum of squared distances to a set of planes, as a symmetric 4x4 matrix.
struct Quadric {
    std::array<double, 10> q{}; // aa ab ac ad bb bc bd cc cd dd

    void addPlane(double a, double b, double c, double d)
    {
        const std::array<double, 10> add{a * a, a * b, a * c, a * d, b * b, b * c, b * d, c * c, c * d, d * d};
        for (std::size_t i = 0; i < q.size(); ++i) q[i] += add[i];
    }
    Quadric operator+(const Quadric& o) const
    {
        Quadric out = *this;
        for (std::size_t i = 0; i < q.size(); ++i) out.q[i] += o.q[i];
        return out;
    }
    double at(const Point& p) const
    {
        const double x = p[0], y = p[1], z = p[2];
        return q[0] * x * x + 2.0 * q[1] * x * y + 2.0 * q[2] * x * z + 2.0 * q[3] * x + q[4] * y * y + 2.0 * q[5] * y * z +
               2.0 * q[6] * y + q[7] * z * z + 2.0 * q[8] * z + q[9];
    }
};

Point sub(const Point& a, const Point& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Point cross(const Point& a, const Point& b) { return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; }
double dot(const Point& a, const Point& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/// The collapse of vertex `from` onto its neighbour `onto`, as queued.
struct Collapse {
    double cost;
    uint32_t from, onto;
    uint64_t entry; // `from`'s entry number: only its latest entry counts
    bool operator>(const Collapse& o) const { return cost > o.cost; }
};

class Simplifier {
public:
    Simplifier(Mesh& mesh, double maxError) : mesh_(mesh), maxSquared_(maxError * maxError)
    {
        const std::size_t n = mesh.positions.size(), m = mesh.triangles.size();
        // Positions about the mesh's first vertex: the quadrics' terms stay small where coordinates are large.
        const std::array<float, 3> origin = n ? mesh.positions[0] : std::array<float, 3>{0.f, 0.f, 0.f};
        points_.resize(n);
        for (std::size_t i = 0; i < n; ++i)
            for (std::size_t a = 0; a < 3; ++a) points_[i][a] = double(mesh.positions[i][a]) - double(origin[a]);
        around_.resize(n);
        quadrics_.resize(n);
        alive_.assign(n, 1);
        locked_.assign(n, 0);
        entry_.assign(n, 0);
        ring_.resize(n);
        ringValid_.assign(n, 0);
        queued_.assign(n, 0);
        stale_.assign(n, 0);
        triangleAlive_.assign(m, 1);
        const bool perTriangleMaterial = mesh.triangleMaterials.size() == m;
        const bool perVertexMaterial = mesh.materials.size() == n;
        std::vector<int64_t> firstMaterial(n, -1);
        std::vector<uint64_t> edges;
        edges.reserve(3 * m);
        for (uint32_t t = 0; t < m; ++t) {
            const auto& tri = mesh.triangles[t];
            for (int c = 0; c < 3; ++c) {
                const uint32_t a = tri[std::size_t(c)], b = tri[std::size_t((c + 1) % 3)];
                around_[a].push_back(t);
                edges.push_back(uint64_t(std::min(a, b)) << 32 | std::max(a, b));
                if (perTriangleMaterial) {
                    const int64_t material = int64_t(mesh.triangleMaterials[t]);
                    if (firstMaterial[a] < 0) firstMaterial[a] = material;
                    else if (firstMaterial[a] != material) locked_[a] = 1;
                }
            }
            if (perVertexMaterial && !(mesh.materials[tri[0]] == mesh.materials[tri[1]] && mesh.materials[tri[1]] == mesh.materials[tri[2]]))
                for (uint32_t v : tri) locked_[v] = 1;
            const Point normal = cross(sub(points_[tri[1]], points_[tri[0]]), sub(points_[tri[2]], points_[tri[0]]));
            const double length = std::sqrt(dot(normal, normal));
            if (length <= 0.0) continue;
            const Point unit{normal[0] / length, normal[1] / length, normal[2] / length};
            const double d = -dot(unit, points_[tri[0]]);
            for (uint32_t v : tri) quadrics_[v].addPlane(unit[0], unit[1], unit[2], d);
        }
        // A vertex on an edge of one triangle (the open boundary) or of more than two stays.
        std::sort(edges.begin(), edges.end());
        for (std::size_t i = 0; i < edges.size();) {
            std::size_t j = i;
            while (j < edges.size() && edges[j] == edges[i]) ++j;
            if (j - i != 2) {
                locked_[uint32_t(edges[i] >> 32)] = 1;
                locked_[uint32_t(edges[i] & 0xffffffffu)] = 1;
            }
            i = j;
        }
    }

    SimplifyReport run(std::vector<uint32_t>* kept)
    {
        SimplifyReport report;
        report.trianglesBefore = mesh_.triangles.size();
        for (uint32_t v = 0; v < points_.size(); ++v) queueBest(v);
        while (!queue_.empty()) {
            const Collapse c = queue_.top();
            queue_.pop();
            if (!alive_[c.from] || c.entry != entry_[c.from]) continue;
            queued_[c.from] = 0;
            // A vertex whose neighbourhood changed since its entry: its cost then was a lower bound (the
            // quadrics only grow), so its best collapse is found again now that it is due.
            double cost = 0.0;
            if (stale_[c.from] || !alive_[c.onto] || !allowed(c.from, c.onto, cost)) {
                queueBest(c.from);
                continue;
            }
            report.largestError = std::max(report.largestError, std::sqrt(std::max(cost, 0.0)));
            collapse(c.from, c.onto);
        }
        compact(kept);
        report.trianglesAfter = mesh_.triangles.size();
        return report;
    }

private:
    /// The vertices sharing a live triangle with v, sorted: kept until a collapse changes them.
    const std::vector<uint32_t>& ring(uint32_t v)
    {
        std::vector<uint32_t>& out = ring_[v];
        if (ringValid_[v]) return out;
        out.clear();
        for (uint32_t t : around_[v]) {
            if (!triangleAlive_[t]) continue;
            for (uint32_t w : mesh_.triangles[t])
                if (w != v) out.push_back(w);
        }
        std::sort(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
        ringValid_[v] = 1;
        return out;
    }

    /// Whether `from` may collapse onto `onto` (see simplifyMesh), and at what cost.
    bool allowed(uint32_t from, uint32_t onto, double& cost)
    {
        if (locked_[from]) return false;
        cost = costOf(from, onto);
        return cost <= maxSquared_ && keepsShape(from, onto);
    }

    double costOf(uint32_t from, uint32_t onto) const { return (quadrics_[from] + quadrics_[onto]).at(points_[onto]); }

    /// Whether collapsing `from` onto `onto` keeps the mesh a manifold of small fans whose triangles keep
    /// their side and some area.
    bool keepsShape(uint32_t from, uint32_t onto)
    {
        // The link condition: the vertices both neighbour are exactly the third corners of the two
        // triangles on the edge.
        const std::vector<uint32_t>& a = ring(from);
        const std::vector<uint32_t>& b = ring(onto);
        common_.clear();
        std::set_intersection(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(common_));
        opposite_.clear();
        for (uint32_t t : around_[from]) {
            if (!triangleAlive_[t]) continue;
            const auto& tri = mesh_.triangles[t];
            if (tri[0] != onto && tri[1] != onto && tri[2] != onto) continue;
            for (uint32_t w : tri)
                if (w != from && w != onto) opposite_.push_back(w);
        }
        std::sort(opposite_.begin(), opposite_.end());
        if (opposite_.size() != 2 || common_ != opposite_) return false;
        // Fans stay small: a vertex that took every collapse of a flat stretch would make slivers (and
        // make each later step as slow as its fan is wide).
        if (a.size() + b.size() - common_.size() - 2 > kMostNeighbours) return false;
        // The triangles that stay keep their side and some area.
        for (uint32_t t : around_[from]) {
            if (!triangleAlive_[t]) continue;
            const auto& tri = mesh_.triangles[t];
            if (tri[0] == onto || tri[1] == onto || tri[2] == onto) continue;
            std::array<Point, 3> corners{points_[tri[0]], points_[tri[1]], points_[tri[2]]};
            const Point before = cross(sub(corners[1], corners[0]), sub(corners[2], corners[0]));
            for (std::size_t c = 0; c < 3; ++c)
                if (tri[c] == from) corners[c] = points_[onto];
            const Point after = cross(sub(corners[1], corners[0]), sub(corners[2], corners[0]));
            const double lengths = std::sqrt(dot(before, before) * dot(after, after));
            if (!(dot(after, after) > 1e-12 * dot(before, before)) || dot(before, after) < 0.5 * lengths) return false;
        }
        return true;
    }

    /// Queues v's cheapest allowed collapse, if it has one (its earlier entries no longer count).
    void queueBest(uint32_t v)
    {
        ++entry_[v];
        stale_[v] = 0;
        queued_[v] = 0;
        if (!alive_[v] || locked_[v]) return;
        // The cheapest first; the shape checked only until one keeps it.
        candidates_.clear();
        for (uint32_t w : ring(v)) {
            const double cost = costOf(v, w);
            if (cost <= maxSquared_) candidates_.push_back({cost, w});
        }
        std::sort(candidates_.begin(), candidates_.end());
        for (const auto& [cost, w] : candidates_)
            if (keepsShape(v, w)) {
                queue_.push({cost, v, w, entry_[v]});
                queued_[v] = 1;
                return;
            }
    }

    void collapse(uint32_t from, uint32_t onto)
    {
        // The rings that change: those of `from`'s neighbours (it leaves them, `onto` joins) and `onto`'s.
        for (uint32_t w : ring(from)) ringValid_[w] = 0;
        ringValid_[onto] = 0;
        std::vector<uint32_t> kept;
        for (uint32_t t : around_[onto])
            if (triangleAlive_[t]) kept.push_back(t);
        for (uint32_t t : around_[from]) {
            if (!triangleAlive_[t]) continue;
            auto& tri = mesh_.triangles[t];
            if (tri[0] == onto || tri[1] == onto || tri[2] == onto) {
                triangleAlive_[t] = 0;
                continue;
            }
            for (uint32_t& w : tri)
                if (w == from) w = onto;
            kept.push_back(t);
        }
        kept.erase(std::remove_if(kept.begin(), kept.end(), [&](uint32_t t) { return !triangleAlive_[t]; }), kept.end());
        around_[onto] = std::move(kept);
        around_[from].clear();
        alive_[from] = 0;
        quadrics_[onto] = quadrics_[onto] + quadrics_[from];
        // What the collapse changed: the candidates of the kept vertex, found now, and of those around it,
        // found again when their entries come up (those without one, now).
        queueBest(onto);
        changed_ = ring(onto);
        for (uint32_t w : changed_) {
            if (queued_[w]) stale_[w] = 1;
            else queueBest(w);
        }
    }

    /// Drops the collapsed vertices and triangles, in their order.
    void compact(std::vector<uint32_t>* kept)
    {
        if (kept) kept->clear();
        const std::size_t n = points_.size();
        std::vector<uint32_t> index(n, ~0u);
        Mesh out;
        const bool normals = mesh_.normals.size() == n, materials = mesh_.materials.size() == n;
        const bool triangleMaterials = mesh_.triangleMaterials.size() == mesh_.triangles.size();
        for (std::size_t t = 0; t < mesh_.triangles.size(); ++t) {
            if (!triangleAlive_[t]) continue;
            std::array<uint32_t, 3> tri{};
            for (std::size_t c = 0; c < 3; ++c) {
                const uint32_t v = mesh_.triangles[t][c];
                if (index[v] == ~0u) {
                    index[v] = uint32_t(out.positions.size());
                    out.positions.push_back(mesh_.positions[v]);
                    if (kept) kept->push_back(v);
                    if (normals) out.normals.push_back(mesh_.normals[v]);
                    if (materials) out.materials.push_back(mesh_.materials[v]);
                }
                tri[c] = index[v];
            }
            out.triangles.push_back(tri);
            if (triangleMaterials) out.triangleMaterials.push_back(mesh_.triangleMaterials[t]);
        }
        mesh_ = std::move(out);
    }

    Mesh& mesh_;
    double maxSquared_;
    std::vector<Point> points_;
    std::vector<std::vector<uint32_t>> around_; // per vertex: its triangles (some collapsed)
    std::vector<Quadric> quadrics_;
    std::vector<char> alive_, locked_, triangleAlive_;
    std::vector<uint64_t> entry_; // per vertex: its latest queue entry's number
    std::vector<char> queued_;    // per vertex: whether its latest entry is in the queue
    std::vector<char> stale_;     // per vertex: its neighbourhood changed since its entry
    std::vector<std::vector<uint32_t>> ring_; // per vertex: ring(v) when ringValid_
    std::vector<char> ringValid_;
    std::vector<uint32_t> common_, opposite_, changed_; // scratch
    std::vector<std::pair<double, uint32_t>> candidates_;
    std::priority_queue<Collapse, std::vector<Collapse>, std::greater<Collapse>> queue_;
};

} // namespace

SimplifyReport simplifyMesh(Mesh& mesh, double maxError, std::vector<uint32_t>* kept)
{
    if (!(maxError > 0.0) || mesh.triangles.empty()) {
        if (kept) {
            kept->resize(mesh.positions.size());
            for (uint32_t v = 0; v < kept->size(); ++v) (*kept)[v] = v;
        }
        return {mesh.triangles.size(), mesh.triangles.size(), 0.0};
    }
    return Simplifier(mesh, maxError).run(kept);
}

} // namespace vdbclay
