#pragma once
// Bars of the benchmark programs, judged and printed the same way by every one of them.
//
// A bar compares our figure with a limit. A ratio bar compares ours / anchor (the anchor measured in
// the same run: meshoptimizer, gltfpack, Draco, or our own previous path; for a speedup, ours is the
// 1-thread figure and the anchor the 2-thread one) with the limit; an absolute
// bar compares our figure itself with a limit the product requirement states as a number (the
// anchor, when the bench measures one, is printed beside it for scale). Every bar is printed as one
// machine-readable line,
//   BAR|bench|bar|ours|anchor|ratio|limit|met
// which scripts/bench.sh collects into its summary table, and `finish` returns the exit code: with
// --check, 1 when any bar is not met (or when the bench judged nothing it should have).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "bench_timing.h"

namespace lodbake_bench {

enum class Limit { AtMost, AtLeast };

struct Bar {
    std::string name;
    double ours = 0;
    double anchor = NAN; // NaN: no anchor measured
    double ratio = NAN;  // ours / anchor when there is an anchor
    double limit = 0;
    Limit direction = Limit::AtMost;
    bool on_ratio = false; // the limit applies to the ratio, else to ours
    bool met = false;
};

/// Removes `--check` from argv (so the bench's own parsing never sees it) and says whether it was there.
inline bool takeCheckFlag(int& argc, char** argv) {
    bool found = false;
    int out = 1;
    for (int i = 1; i < argc; ++i) {
        if (std::strcmp(argv[i], "--check") == 0)
            found = true;
        else
            argv[out++] = argv[i];
    }
    argc = out;
    argv[argc] = nullptr;
    return found;
}

class Bars {
public:
    explicit Bars(std::string bench) : bench_(std::move(bench)) {}

    /// ours / anchor compared with `limit`. A missing or non-positive anchor fails the bar: nothing
    /// was compared.
    const Bar& ratio(const std::string& name, double ours, double anchor, double limit, Limit direction) {
        Bar b{name, ours, anchor, NAN, limit, direction, true, false};
        if (anchor > 0 && std::isfinite(ours)) {
            b.ratio = ours / anchor;
            b.met = passes(b.ratio, limit, direction);
        }
        return add(b);
    }

    /// ours compared with `limit`, a number the requirement states; `anchor` (NaN for none) is printed
    /// beside it for scale.
    const Bar& absolute(const std::string& name, double ours, double limit, Limit direction, double anchor = NAN) {
        Bar b{name, ours, anchor, NAN, limit, direction, false, false};
        if (anchor > 0) b.ratio = ours / anchor;
        b.met = std::isfinite(ours) && passes(ours, limit, direction);
        return add(b);
    }

    /// A bar that could not be measured in this run (its input failed): printed as not met.
    const Bar& unmeasured(const std::string& name, double limit, Limit direction, bool on_ratio) {
        Bar b{name, NAN, NAN, NAN, limit, direction, on_ratio, false};
        return add(b);
    }

    bool allMet() const {
        return std::all_of(bars_.begin(), bars_.end(), [](const Bar& b) { return b.met; });
    }
    const std::vector<Bar>& bars() const { return bars_; }

    /// Prints the bench's verdict and returns its exit code: 0 without --check; with it, 1 when any
    /// bar is not met or when no bar was judged at all.
    int finish(bool check) const {
        size_t met = 0;
        for (const Bar& b : bars_) met += b.met;
        std::printf("%s: %zu of %zu bars met%s\n", bench_.c_str(), met, bars_.size(),
                    bars_.empty() ? " (nothing was judged)" : "");
        std::fflush(stdout);
        if (!check) return 0;
        return bars_.empty() || met != bars_.size() ? 1 : 0;
    }

    /// For a diagnostic bench that has no bar in the docs or issues: says so in the summary's format.
    static void printNone(const char* bench, const char* why) {
        std::printf("NOBAR|%s|%s\n", bench, why);
        std::fflush(stdout);
    }

private:
    static bool passes(double value, double limit, Limit direction) {
        return direction == Limit::AtMost ? value <= limit : value >= limit;
    }

    const Bar& add(const Bar& b) {
        bars_.push_back(b);
        print(b);
        return bars_.back();
    }

    void print(const Bar& b) const {
        char limit[64];
        std::snprintf(limit, sizeof(limit), "%s %s %.4g", b.on_ratio ? "ratio" : "ours",
                      b.direction == Limit::AtMost ? "<=" : ">=", b.limit);
        std::printf("BAR|%s|%s|%s|%s|%s|%s|%s\n", bench_.c_str(), b.name.c_str(), number(b.ours).c_str(),
                    number(b.anchor).c_str(), number(b.ratio).c_str(), limit, b.met ? "met" : "NOT met");
        std::fflush(stdout);
    }

    static std::string number(double v) {
        if (std::isnan(v)) return "-";
        char s[32];
        std::snprintf(s, sizeof(s), "%.4g", v);
        return s;
    }

    std::string bench_;
    std::vector<Bar> bars_;
};

} // namespace lodbake_bench
