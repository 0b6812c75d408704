#pragma once
// Timing helper shared by the benchmark programs.

#include <time.h>

#include <algorithm>
#include <chrono>
#include <utility>
#include <vector>

namespace lodbake_bench {

/// CPU time of the calling thread, in seconds: on a loaded shared machine wall time also counts the
/// time the thread spent descheduled.
inline double threadCpuSeconds() {
    timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

/// Best wall time of `runs` calls of f, in milliseconds (the minimum is the least noisy figure on
/// a shared machine).
template <class F> double bestMs(int runs, F&& f) {
    double best = 1e300;
    for (int i = 0; i < runs; ++i) {
        const auto t0 = std::chrono::steady_clock::now();
        f();
        const auto t1 = std::chrono::steady_clock::now();
        best = std::min(best, std::chrono::duration<double, std::milli>(t1 - t0).count());
    }
    return best;
}

/// Median of `values` (the mean of the two middle values for an even count); 0 for none.
inline double median(std::vector<double> values) {
    if (values.empty()) return 0;
    std::sort(values.begin(), values.end());
    const size_t h = values.size() / 2;
    return values.size() % 2 ? values[h] : 0.5 * (values[h - 1] + values[h]);
}

/// Median wall time of `runs` calls of f, in milliseconds (what the bars are judged on: a single
/// lucky or preempted run moves it less than the best or the mean).
template <class F> double medianMs(int runs, F&& f) {
    std::vector<double> times;
    for (int i = 0; i < runs; ++i) {
        const auto t0 = std::chrono::steady_clock::now();
        f();
        const auto t1 = std::chrono::steady_clock::now();
        times.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    }
    return median(std::move(times));
}

} // namespace lodbake_bench
