#pragma once
// Timing helper shared by the benchmark programs.

#include <algorithm>
#include <chrono>

namespace lodbake_bench {

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

} // namespace lodbake_bench
