#!/usr/bin/env bash
# AddressSanitizer + UndefinedBehaviorSanitizer build (clang) of the CLI and the unit tests, run on
# the unit tests (not the GUI ones) and the bad-input corpus, then each libFuzzer target for
# FUZZ_SECONDS (default 60) seeded from the shipped scenes and the bad-scene files, with a fixed
# libFuzzer seed so that CI's run is the same sequence of inputs every time (a slower machine runs a
# prefix of it). CI runs this after the main suite (README's test command).
# Usage: bash scripts/sanitize.sh [FUZZ_SECONDS]. A long fuzz run: bash scripts/sanitize.sh 600
# (crash inputs are written to build-asan/fuzz/, named crash-*).
set -euo pipefail
cd "$(dirname "$0")/.."
FUZZ_SECONDS=${1:-60}
ROOT=$PWD
B=build-asan
cmake -S . -B $B -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DCANDELA_SANITIZE=ON -DCANDELA_FUZZ=ON \
  -DCANDELA_BUILD_BENCHMARKS=OFF -DCANDELA_CORPUS_MEMORY_GB=0 >/dev/null
cmake --build $B -j2 --target candela-cli hostile_vdb fuzz_scene fuzz_vdb phase_test majorant_test closed_form_test \
  scene_errors_test render_test emission_test guiding_test workflow_test emission_units_test document_test
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:detect_stack_use_after_return=0
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1:suppressions=$ROOT/tests/sanitizers/ubsan.supp
export LSAN_OPTIONS=suppressions=$ROOT/tests/sanitizers/lsan.supp:print_suppressions=0
# Unit tests whose executables this build made (GUI, OCIO and session tests need the viewer's
# libraries and are left to the main build).
ctest --test-dir $B -j2 -L unit -LE gui -E '^(OcioPipeline|ColorPipeline|RenderSession|Display|cli_bench|report_quick)' \
  --output-on-failure --timeout 1500

mkdir -p $B/fuzz/scene-seeds $B/fuzz/vdb-seeds
cp assets/scenes/*.json assets/scenes/test/*.json tests/bad_scenes/*.json $B/fuzz/scene-seeds/
[ -f $B/fuzz/vdb-seeds/torch.vdb ] || CANDELA_CACHE_DIR=$ROOT/$B/test-cache $B/app/candela-cli generate torch --resolution 8 -o $B/fuzz/vdb-seeds/torch.vdb >/dev/null
for target in fuzz_scene fuzz_vdb; do
  seeds=$B/fuzz/scene-seeds
  [ $target = fuzz_vdb ] && seeds=$B/fuzz/vdb-seeds
  mkdir -p $B/fuzz/$target-corpus
  echo "fuzzing $target for $FUZZ_SECONDS s"
  # fast_unwind_on_malloc=0: OpenVDB is built without frame pointers, so the fast unwinder stops in
  # it and LeakSanitizer cannot match its known leak (lsan.supp) by the frames above.
  (cd $B/fuzz && ASAN_OPTIONS=$ASAN_OPTIONS:fast_unwind_on_malloc=0 ../tests/$target -seed=1 -max_total_time=$FUZZ_SECONDS -max_len=4096 -timeout=20 -rss_limit_mb=4096 -print_final_stats=1 \
     $target-corpus "$ROOT/$seeds" 2>&1 | tail -15)
done
echo "sanitizers and fuzzing: clean"
