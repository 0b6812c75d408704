#!/usr/bin/env bash
# One command from a fresh Debian machine to a green test suite (the CI job, .ci/run):
#  1. install dependencies (scripts/install-deps.sh; only what is missing);
#  2. Release build with warnings as errors, every test with CTest;
#  3. sanitizer build (Clang, AddressSanitizer + UndefinedBehaviorSanitizer, findings abort; the
#     runtime still without exceptions), every test again but those labelled `heavy`, plus the
#     libFuzzer targets;
#  4. fuzz smoke: each fuzz target for a fixed number of inputs (about 8 s each here) from its seeds
#     with a fixed libFuzzer seed (LODBAKE_FUZZ_SMOKE_SEED, default 1), so a commit gets the same
#     verdict on every run; one target per core at a time. LODBAKE_FUZZ_SMOKE_SECONDS (default 60)
#     only caps a target's time.
# Set LODBAKE_SKIP_SANITIZERS=1 to stop after step 2. Timings of each step are printed at the end.
set -euo pipefail
cd "$(dirname "$0")/.."
export LODBAKE_REQUIRE_SHARED_MESHES=1 # tests needing ../shared fail instead of skipping when it is missing
export LODBAKE_REQUIRE_LODVIEW=1 # the lodview test fails instead of skipping when lodview or xvfb-run is missing
export LODBAKE_REQUIRE_BROWSER=1 # the browser tests fail instead of skipping when Chromium or the npm packages are missing

t0=$(date +%s)
timings=()
step() { # NAME: records the time since the previous step
    local now
    now=$(date +%s)
    timings+=("$(printf '%-28s %5d s' "$1" $((now - t0)))")
    t0=$now
}

scripts/install-deps.sh
step "install-deps"

build_dir=${LODBAKE_BUILD_DIR:-build}
jobs=$(nproc 2>/dev/null || echo 2)
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DLODBAKE_WERROR=ON
cmake --build "$build_dir" --parallel "$jobs"
step "release build"
ctest --test-dir "$build_dir" --output-on-failure --parallel "$jobs" --timeout 900
step "release tests"

if [ "${LODBAKE_SKIP_SANITIZERS:-0}" != 1 ]; then
    # One instrumented tree serves both the test suite and the fuzzers: LODBAKE_BUILD_FUZZERS adds
    # -fsanitize=fuzzer-no-link (coverage instrumentation) to lodrt and to the baker's readers
    # (lodbake_readers), whose objects lodbake_lib and the fuzz targets share (tests/fuzz/CMakeLists.txt).
    asan_dir=${LODBAKE_ASAN_BUILD_DIR:-build-asan}
    sanitize="-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"
    CC=clang CXX=clang++ cmake -S . -B "$asan_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release \
        -DCMAKE_CXX_FLAGS_RELEASE="-O2" -DCMAKE_C_FLAGS_RELEASE="-O2" \
        -DCMAKE_CXX_FLAGS="$sanitize" -DCMAKE_C_FLAGS="$sanitize" \
        -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
        -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" \
        -DCMAKE_MODULE_LINKER_FLAGS="-fsanitize=address,undefined" \
        -DLODBAKE_BUILD_FUZZERS=ON -DLODBAKE_BUILD_BENCHMARKS=OFF
    cmake --build "$asan_dir" --parallel "$jobs"
    step "sanitizer build"
    # Packs must not depend on the compiler: shared scans baked by both trees, sha256 compared.
    scripts/compare-compilers.sh "$build_dir" "$asan_dir"
    step "compiler comparison"
    # Asserts stay on in this build (no NDEBUG). Leaks are reported too. Tests labelled `heavy` (big
    # scans again, whole-batch byte identity; never a truncation, corruption or fuzz test) ran in the
    # Release step and are left out here (tests/CMakeLists.txt, docs/robustness.md).
    # Tests labelled `unsanitized` run no code of this tree (the browser clients reading a pack the
    # sanitized lodbake baked in Browser.Bake.*).
    echo "sanitizer tests: leaving out the tests labelled heavy or unsanitized:"
    ctest --test-dir "$asan_dir" -N -L 'heavy|unsanitized' | grep -E '^ *Test +#' || true
    ASAN_OPTIONS=abort_on_error=1:detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1 \
        UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
        ctest --test-dir "$asan_dir" --output-on-failure --parallel "$jobs" --timeout 1800 -LE 'heavy|unsanitized'
    step "sanitizer tests"

    smoke=${LODBAKE_FUZZ_SMOKE_SECONDS:-60}
    smoke_seed=${LODBAKE_FUZZ_SMOKE_SEED:-1}
    fuzz_targets=(ply obj off gltf preset conf manifest cache stream lod pack pfrep valence meshopt cluster jobs)
    # Inputs per target: about 8 s of each on two shared cores. A count, not a time, so that the run
    # does not depend on the machine's speed (scripts/fuzz.sh, LODBAKE_FUZZ_SEED).
    declare -A smoke_runs=([ply]=300000 [obj]=100000 [off]=400000 [gltf]=40000 [preset]=200000
        [conf]=50000 [manifest]=200000 [cache]=400000 [stream]=200000 [lod]=40000 [pack]=200000
        [pfrep]=10000 [valence]=120000 [meshopt]=100000 [cluster]=20000 [jobs]=60000)
    # Seeds once (fuzz.sh would build them on its first call), then one target per core at a time.
    ASAN_OPTIONS=detect_leaks=0 scripts/fuzz-seeds.sh "$asan_dir/seeds" "$build_dir/baker/lodbake" \
        >"$asan_dir/fuzz-seeds.log" 2>&1 || {
        tail -n 60 "$asan_dir/fuzz-seeds.log"
        echo "fuzz smoke: building the seeds failed (log: $asan_dir/fuzz-seeds.log)" >&2
        exit 1
    }
    touch "$asan_dir/seeds/.done"
    export asan_dir build_dir smoke
    export smoke_seed
    rm -f "$asan_dir"/fuzz-smoke-*.failed
    # shellcheck disable=SC2016 # expanded by the inner shell
    for target in "${fuzz_targets[@]}"; do echo "$target ${smoke_runs[$target]}"; done | xargs -P "$jobs" -L1 bash -c '
        LODBAKE_FUZZ_BUILD_DIR="$asan_dir" LODBAKE_FUZZ_NO_BUILD=1 LODBAKE_CLI="$build_dir/baker/lodbake" \
            LODBAKE_FUZZ_SEED="$smoke_seed" scripts/fuzz.sh "$0" "$smoke" -runs="$1" \
            >"$asan_dir/fuzz-smoke-$0.log" 2>&1 || touch "$asan_dir/fuzz-smoke-$0.failed"'
    for target in "${fuzz_targets[@]}"; do
        if [ -e "$asan_dir/fuzz-smoke-$target.failed" ]; then
            tail -n 60 "$asan_dir/fuzz-smoke-$target.log"
            echo "fuzz smoke: $target failed (log: $asan_dir/fuzz-smoke-$target.log)" >&2
            exit 1
        fi
    done
    for target in "${fuzz_targets[@]}"; do
        log="$asan_dir/fuzz-smoke-$target.log"
        echo "fuzz smoke: $target seed $smoke_seed $(grep -E '^(stat::number_of_executed_units|stat::peak_rss_mb)' \
            "$log" | tr '\n' ' ')$(grep -oE 'Done [0-9]+ runs in [0-9]+ second' "$log" | sed 's/^Done [0-9]* runs in /in /')s"
        # Stopped by the cap: a slower machine ran fewer inputs, so the verdict may differ from others'.
        grep -qE "^stat::number_of_executed_units: *${smoke_runs[$target]}\$" "$log" ||
            echo "fuzz smoke: warning: $target stopped at the ${smoke} s cap before ${smoke_runs[$target]} inputs"
    done
    step "fuzz smoke"
fi

printf '%s\n' "timings:" "${timings[@]}"
