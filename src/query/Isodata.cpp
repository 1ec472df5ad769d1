#include "query/Isodata.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <tuple>

namespace vdbclay::query {

namespace {

using Vec = std::array<double, 3>;

double distance2(const Vec& a, const Vec& b)
{
    const double x = a[0] - b[0], y = a[1] - b[1], z = a[2] - b[2];
    return x * x + y * y + z * z;
}

/// Each point to its nearest centre; returns whether any point changed cluster.
bool assign(const std::vector<Vec>& points, const std::vector<Vec>& centres, std::vector<uint32_t>& cluster)
{
    bool changed = false;
    for (std::size_t i = 0; i < points.size(); ++i) {
        uint32_t best = 0;
        double bestD = std::numeric_limits<double>::max();
        for (std::size_t c = 0; c < centres.size(); ++c) {
            const double d = distance2(points[i], centres[c]);
            if (d < bestD) bestD = d, best = uint32_t(c);
        }
        changed |= cluster[i] != best;
        cluster[i] = best;
    }
    return changed;
}

struct Stats {
    std::vector<Vec> mean, spread; // spread: standard deviation per axis
    std::vector<std::size_t> members;
};

Stats statistics(const std::vector<Vec>& points, const std::vector<uint32_t>& cluster, std::size_t clusters)
{
    Stats s;
    s.mean.assign(clusters, Vec{0, 0, 0});
    s.spread.assign(clusters, Vec{0, 0, 0});
    s.members.assign(clusters, 0);
    for (std::size_t i = 0; i < points.size(); ++i) {
        ++s.members[cluster[i]];
        for (int k = 0; k < 3; ++k) s.mean[cluster[i]][std::size_t(k)] += points[i][std::size_t(k)];
    }
    for (std::size_t c = 0; c < clusters; ++c)
        if (s.members[c])
            for (double& v : s.mean[c]) v /= double(s.members[c]);
    for (std::size_t i = 0; i < points.size(); ++i)
        for (int k = 0; k < 3; ++k) {
            const double d = points[i][std::size_t(k)] - s.mean[cluster[i]][std::size_t(k)];
            s.spread[cluster[i]][std::size_t(k)] += d * d;
        }
    for (std::size_t c = 0; c < clusters; ++c)
        if (s.members[c])
            for (double& v : s.spread[c]) v = std::sqrt(v / double(s.members[c]));
    return s;
}

} // namespace

Clustering isodataClusters(const std::vector<Vec>& points, const IsodataOptions& options)
{
    Clustering out;
    if (points.empty()) return out;
    // First centres: a seeded point, then each the point farthest from those chosen.
    std::mt19937_64 random(options.seed);
    std::vector<Vec> centres{points[std::size_t(random() % points.size())]};
    std::vector<double> nearest(points.size(), std::numeric_limits<double>::max());
    while (centres.size() < std::min(options.initialClusters, points.size())) {
        std::size_t far = 0;
        for (std::size_t i = 0; i < points.size(); ++i) {
            nearest[i] = std::min(nearest[i], distance2(points[i], centres.back()));
            if (nearest[i] > nearest[far]) far = i;
        }
        if (!(nearest[far] > 0.0)) break; // every point is a centre already
        centres.push_back(points[far]);
    }
    std::vector<uint32_t>& cluster = out.cluster;
    cluster.assign(points.size(), std::numeric_limits<uint32_t>::max());
    for (int round = 0; round < options.maxIterations && out.sweeps < options.maxSweeps; ++round) {
        out.iterations = round + 1;
        // k-means sweeps to a fixed assignment (or the sweep budget).
        bool moved = false;
        while (out.sweeps < options.maxSweeps) {
            ++out.sweeps;
            const bool changed = assign(points, centres, cluster);
            moved |= changed;
            Stats s = statistics(points, cluster, centres.size());
            for (std::size_t c = 0; c < centres.size(); ++c)
                if (s.members[c]) centres[c] = s.mean[c];
            if (!changed) break;
        }
        Stats s = statistics(points, cluster, centres.size());
        // Clusters with too few points dissolve (the largest stays whatever its size).
        const std::size_t largest = std::size_t(std::max_element(s.members.begin(), s.members.end()) - s.members.begin());
        std::vector<Vec> kept;
        std::vector<Vec> keptSpread;
        std::vector<std::size_t> keptMembers;
        for (std::size_t c = 0; c < centres.size(); ++c)
            if (c == largest || s.members[c] >= std::max<std::size_t>(options.minMembers, 1)) {
                kept.push_back(s.mean[c]);
                keptSpread.push_back(s.spread[c]);
                keptMembers.push_back(s.members[c]);
            }
        bool restructured = kept.size() != centres.size();
        centres = kept;
        // Rounds alternate splitting (the first) and merging, as the classic ISODATA does; the last merges.
        const bool lastRound = round + 1 == options.maxIterations;
        std::vector<Vec> next;
        if (round % 2 == 0 && !lastRound) {
            for (std::size_t c = 0; c < centres.size(); ++c) {
                const std::size_t axis = std::size_t(std::max_element(keptSpread[c].begin(), keptSpread[c].end()) - keptSpread[c].begin());
                const double sigma = keptSpread[c][axis];
                if (sigma > options.maxSpread && keptMembers[c] >= 2 * std::max<std::size_t>(options.minMembers, 1)) {
                    Vec a = centres[c], b = centres[c];
                    a[axis] -= sigma, b[axis] += sigma;
                    next.push_back(a), next.push_back(b);
                    restructured = true;
                } else {
                    next.push_back(centres[c]);
                }
            }
        } else {
            // The closest pairs under the merge distance first; a cluster merges once per round.
            std::vector<std::tuple<double, std::size_t, std::size_t>> pairs;
            for (std::size_t a = 0; a < centres.size(); ++a)
                for (std::size_t b = a + 1; b < centres.size(); ++b) {
                    const double d = std::sqrt(distance2(centres[a], centres[b]));
                    if (d < options.mergeDistance) pairs.emplace_back(d, a, b);
                }
            std::sort(pairs.begin(), pairs.end());
            std::vector<bool> merged(centres.size(), false);
            for (const auto& [d, a, b] : pairs) {
                if (merged[a] || merged[b]) continue;
                merged[a] = merged[b] = true;
                const double wa = double(keptMembers[a]), wb = double(keptMembers[b]), w = std::max(1.0, wa + wb);
                Vec m;
                for (int k = 0; k < 3; ++k) m[std::size_t(k)] = (wa * centres[a][std::size_t(k)] + wb * centres[b][std::size_t(k)]) / w;
                next.push_back(m);
                restructured = true;
            }
            for (std::size_t c = 0; c < centres.size(); ++c)
                if (!merged[c]) next.push_back(centres[c]);
        }
        centres = next;
        if (!moved && !restructured && round + 1 >= options.minIterations) {
            out.converged = true;
            break;
        }
    }
    // The final assignment to the final centres; empty clusters are dropped and the rest renumbered.
    assign(points, centres, cluster);
    Stats s = statistics(points, cluster, centres.size());
    std::vector<uint32_t> renumber(centres.size(), 0);
    for (std::size_t c = 0; c < centres.size(); ++c)
        if (s.members[c]) {
            renumber[c] = uint32_t(out.centres.size());
            out.centres.push_back(s.mean[c]);
        }
    for (uint32_t& c : cluster) c = renumber[c];
    return out;
}

} // namespace vdbclay::query
