// The force and torque history the plots draw: every servo tick's sample (drained from the servo
// loop's telemetry each frame) in a ring of fixed size, and a per-column envelope for drawing many
// samples into few pixels without losing a peak. Owned by the UI thread.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace sulcus::desktop {

struct HistorySample {
    double time_s = 0.0;
    float force_N = 0.0f;    // |force| sent
    float torque_Nm = 0.0f;  // |torque| sent
};

class ForceHistory {
public:
    explicit ForceHistory(std::size_t capacity = 20000) : ring_(capacity) {}

    void push(const HistorySample& s) {
        ring_[head_] = s;
        head_ = (head_ + 1) % ring_.size();
        if (count_ < ring_.size()) ++count_;
    }
    std::size_t size() const { return count_; }
    // i = 0 is the oldest kept sample.
    const HistorySample& at(std::size_t i) const { return ring_[(head_ + ring_.size() - count_ + i) % ring_.size()]; }
    const HistorySample* latest() const { return count_ ? &at(count_ - 1) : nullptr; }

    // Min and max of `torque ? torque : force` in each of `columns` equal time slices of
    // [t1 - window_s, t1]; a column without samples gets NaN. Written into lo/hi (resized).
    void envelope(double t1, double window_s, std::size_t columns, bool torque, std::vector<float>& lo,
                  std::vector<float>& hi) const {
        lo.assign(columns, NAN);
        hi.assign(columns, NAN);
        if (columns == 0 || window_s <= 0) return;
        const double t0 = t1 - window_s;
        for (std::size_t i = 0; i < count_; ++i) {
            const HistorySample& s = at(i);
            if (s.time_s < t0 || s.time_s > t1) continue;
            std::size_t c = static_cast<std::size_t>((s.time_s - t0) / window_s * double(columns));
            c = std::min(c, columns - 1);
            const float v = torque ? s.torque_Nm : s.force_N;
            if (std::isnan(lo[c]) || v < lo[c]) lo[c] = v;
            if (std::isnan(hi[c]) || v > hi[c]) hi[c] = v;
        }
    }
    // Time spent in the last `window_s` with the force above `threshold_N` (samples times their
    // spacing).
    double time_above(double t1, double window_s, double threshold_N) const {
        double total = 0.0;
        for (std::size_t i = 1; i < count_; ++i) {
            const HistorySample& a = at(i - 1);
            const HistorySample& b = at(i);
            if (b.time_s < t1 - window_s || b.time_s > t1) continue;
            if (b.force_N > threshold_N) total += b.time_s - a.time_s;
        }
        return total;
    }

private:
    std::vector<HistorySample> ring_;
    std::size_t head_ = 0, count_ = 0;
};

}  // namespace sulcus::desktop
