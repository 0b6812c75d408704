// Checks bench_bar.h, the verdict and exit code every benchmark's --check relies on: ratio and
// absolute bars in both directions, a missing anchor, an unmeasured bar, and finish() with and
// without --check. Exits 1 on the first wrong answer (run by ctest as BenchBar.Verdicts).

#include <cmath>
#include <cstdio>

#include "bench_bar.h"

namespace {

int failures = 0;

void expect(bool ok, const char* what) {
    if (!ok) {
        std::fprintf(stderr, "FAILED: %s\n", what);
        ++failures;
    }
}

} // namespace

int main() {
    using lodbake_bench::Bars;
    using lodbake_bench::Limit;

    {
        Bars bars("test");
        expect(bars.ratio("at most, under", 2.0, 1.0, 3.0, Limit::AtMost).met, "2/1 <= 3 is met");
        expect(!bars.ratio("at most, over", 4.0, 1.0, 3.0, Limit::AtMost).met, "4/1 <= 3 is not met");
        expect(bars.ratio("at least, over", 2.0, 1.0, 1.7, Limit::AtLeast).met, "2/1 >= 1.7 is met");
        expect(!bars.ratio("at least, under", 1.5, 1.0, 1.7, Limit::AtLeast).met, "1.5/1 >= 1.7 is not met");
        expect(std::fabs(bars.bars().back().ratio - 1.5) < 1e-12, "the ratio is ours / anchor");
        expect(!bars.ratio("no anchor", 1.0, 0.0, 3.0, Limit::AtMost).met, "a zero anchor fails the bar");
        expect(!bars.ratio("nan ours", NAN, 1.0, 3.0, Limit::AtMost).met, "a NaN figure fails the bar");
        expect(bars.absolute("absolute, under", 297.0, 300.0, Limit::AtMost, 99.0).met, "297 <= 300 is met");
        expect(!bars.absolute("absolute, over", 301.0, 300.0, Limit::AtMost).met, "301 <= 300 is not met");
        expect(!bars.absolute("absolute, at least", 33.0, 50.0, Limit::AtLeast).met, "33 >= 50 is not met");
        expect(!bars.unmeasured("unmeasured", 1.0, Limit::AtMost, true).met, "an unmeasured bar is not met");
        expect(!bars.allMet(), "allMet sees the failures");
        expect(bars.finish(false) == 0, "without --check the exit code is 0");
        expect(bars.finish(true) == 1, "with --check a bar not met gives 1");
    }
    {
        Bars bars("test");
        bars.ratio("met", 1.0, 2.0, 1.0, Limit::AtMost);
        bars.absolute("met too", 0.0, 0.0, Limit::AtMost);
        expect(bars.allMet(), "every bar met");
        expect(bars.finish(true) == 0, "with --check and every bar met the exit code is 0");
    }
    {
        Bars bars("test");
        expect(bars.finish(true) == 1, "with --check, judging nothing gives 1");
    }
    {
        char a0[] = "bench", a1[] = "--check", a2[] = "--runs", a3[] = "3";
        char* argv[] = {a0, a1, a2, a3, nullptr};
        int argc = 4;
        expect(lodbake_bench::takeCheckFlag(argc, argv), "--check is found");
        expect(argc == 3 && argv[1] == a2 && argv[2] == a3 && argv[3] == nullptr, "--check is removed from argv");
        expect(!lodbake_bench::takeCheckFlag(argc, argv), "no second --check");
    }
    expect(lodbake_bench::median({3.0, 1.0, 2.0}) == 2.0, "median of an odd count");
    expect(lodbake_bench::median({4.0, 1.0, 2.0, 3.0}) == 2.5, "median of an even count");
    if (failures) std::fprintf(stderr, "%d check(s) failed\n", failures);
    return failures ? 1 : 0;
}
