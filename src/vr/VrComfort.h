// Comfort in a headset: a frame that runs late makes the next ones lighter instead of stuttering. The
// frame's share of full detail drops while frames take most of the display period and comes back slowly
// once they keep time; the streamed view's pixels (a coarser cut of the levels of detail) and the uploads
// per frame follow it.
#pragma once

#include <algorithm>

namespace vdbclay::vr {

class VrComfort {
public:
    static constexpr double kLeastDetail = 0.25;

    /// After a drawn frame that took `cpuMs` of a `periodMs` display period.
    void frameTook(double cpuMs, double periodMs)
    {
        if (cpuMs > 0.8 * periodMs) detail_ = std::max(kLeastDetail, detail_ * 0.8);
        else if (cpuMs < 0.5 * periodMs) detail_ = std::min(1.0, detail_ * 1.02);
    }
    /// 1: full detail.
    double detail() const { return detail_; }

private:
    double detail_ = 1.0;
};

} // namespace vdbclay::vr
