#include "query/HistogramDistance.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace vdbclay::query {

Histogram smoothHistogram(const Histogram& h, double sigmaBins)
{
    if (h.empty() || !(sigmaBins > 0.0)) return h;
    const int n = int(h.size()), reach = int(std::ceil(3.0 * sigmaBins));
    std::vector<double> kernel(std::size_t(2 * reach + 1));
    for (int k = -reach; k <= reach; ++k) kernel[std::size_t(k + reach)] = std::exp(-0.5 * (k * k) / (sigmaBins * sigmaBins));
    Histogram out(h.size(), 0.0);
    double total = 0.0;
    for (int i = 0; i < n; ++i) {
        if (h[std::size_t(i)] == 0.0) continue;
        for (int k = -reach; k <= reach; ++k) {
            int j = i + k;
            if (j < 0) j = -j - 1;             // reflect at the edges: mass stays inside
            if (j >= n) j = 2 * n - j - 1;
            if (j < 0 || j >= n) continue;
            const double w = h[std::size_t(i)] * kernel[std::size_t(k + reach)];
            out[std::size_t(j)] += w;
            total += w;
        }
    }
    if (total > 0.0)
        for (double& v : out) v /= total;
    return out;
}

double chiSquareDistance(const Histogram& a, const Histogram& b)
{
    if (a.size() != b.size()) throw std::invalid_argument("histograms of different sizes");
    double d = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const double s = a[i] + b[i];
        if (s > 0.0) d += (a[i] - b[i]) * (a[i] - b[i]) / s;
    }
    return 0.5 * d;
}

double jensenShannonDistance(const Histogram& a, const Histogram& b)
{
    if (a.size() != b.size()) throw std::invalid_argument("histograms of different sizes");
    double d = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const double m = 0.5 * (a[i] + b[i]);
        if (a[i] > 0.0) d += 0.5 * a[i] * std::log2(a[i] / m);
        if (b[i] > 0.0) d += 0.5 * b[i] * std::log2(b[i] / m);
    }
    return std::max(0.0, d);
}

} // namespace vdbclay::query
