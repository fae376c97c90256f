#!/usr/bin/env bash
# The bounded fuzzing of CI (ctest -L fuzz, tests/fuzz/CMakeLists.txt):
#   fuzz_ci.sh build SOURCE_DIR
#       configures and builds the `fuzz` preset (clang-14, libFuzzer, ASan + UBSan): only the fuzz
#       targets and the libraries they link (build preset `fuzz`)
#   fuzz_ci.sh run SOURCE_DIR TARGET SECONDS WORK_DIR
#       fuzzes TARGET for SECONDS from a copy of its corpus and regression inputs in WORK_DIR (the
#       repository's corpus is never written), and fails on any crash, leak, timeout or memory
#       blow-up libFuzzer reports; the input is kept in WORK_DIR/TARGET/artifacts/ and named.
set -euo pipefail

mode=${1:?usage: fuzz_ci.sh build SOURCE_DIR | run SOURCE_DIR TARGET SECONDS WORK_DIR}
src=${2:?source dir}

case "$mode" in
  build)
    cd "$src"
    start=$(date +%s)
    cmake --preset fuzz
    cmake --build --preset fuzz
    echo "fuzz build: $(( $(date +%s) - start )) s"
    ;;
  run)
    target=${3:?target}
    seconds=${4:?seconds}
    work=${5:?work dir}/$target
    binary="$src/build/fuzz/tests/fuzz/${target}_fuzz"
    [ -x "$binary" ] || { echo "no $binary: run Fuzz.Build (the fuzz preset) first" >&2; exit 1; }
    rm -rf "$work"
    mkdir -p "$work/corpus" "$work/artifacts"
    cp "$src/tests/fuzz/corpus/$target/"* "$work/corpus/"
    if [ -d "$src/tests/fuzz/regressions/$target" ]; then
      cp "$src/tests/fuzz/regressions/$target/"* "$work/corpus/" 2>/dev/null || true
    fi
    # -timeout: one input may take 10 s (the services' calls have 10 s deadlines); -rss_limit_mb:
    # the largest model the limits let through stays far below 2 GiB; -max_len: the seeds' size
    # or 64 KiB, whichever is larger, so mutations can grow models past their seeds.
    # -seed: a fixed one, so that the mutations' random draws are the same in every CI run. The
    # inputs tried still differ from run to run and machine to machine: the values libFuzzer
    # traces at comparisons include addresses and hashes that move with ASLR, and a faster machine
    # gets further in its seconds. A crash CI finds is real, so it is minimised into regressions/
    # and fixed, however unlucky the draw; longer runs by hand (README, Fuzzing) break new ground.
    status=0
    # Leaks inside Debian's Assimp are the one kind tolerated, by lsan.supp's single rule.
    ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1} UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1} \
    LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$src/tests/fuzz/lsan.supp:print_suppressions=0} \
      "$binary" -seed=1 -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
        -print_final_stats=1 -artifact_prefix="$work/artifacts/" "$work/corpus" \
        >"$work/log" 2>&1 || status=$?
    runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$work/log" | grep -o '[0-9]*$' || echo "?")
    if [ "$status" -ne 0 ]; then
      tail -n 60 "$work/log"
      echo "fuzz $target: FAILED (exit $status) after $runs executions; input: $(ls "$work/artifacts/" | head -1)"
      echo "  reproduce: $binary $work/artifacts/<file>"
      exit 1
    fi
    echo "fuzz $target: $runs executions in $seconds s, no crash, leak or timeout" \
         "(corpus $(ls "$work/corpus" | wc -l) inputs)"
    ;;
  *)
    echo "fuzz_ci.sh: unknown mode '$mode'" >&2
    exit 2
    ;;
esac
