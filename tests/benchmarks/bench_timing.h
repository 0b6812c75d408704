#pragma once
// Timing helper shared by the benchmark programs.

#include <time.h>

#include <algorithm>
#include <chrono>
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
    if (times.empty()) return 0.0;
    std::sort(times.begin(), times.end());
    const size_t h = times.size() / 2;
    return times.size() % 2 ? times[h] : 0.5 * (times[h - 1] + times[h]);
}

} // namespace lodbake_bench
