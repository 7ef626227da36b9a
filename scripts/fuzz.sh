#!/usr/bin/env bash
# libFuzzer campaigns over the fuzz targets in tests/fuzz (clang, ASan + UBSan; preset `fuzz`).
#   usage: bash scripts/fuzz.sh [TARGET|all] [SECONDS]     (default: all, 60 s per target)
# TARGET: gltf image scene envmap material set playback. Each run starts from the repository corpus
# tests/fuzz/corpus/TARGET/ plus what earlier runs found (build/fuzz/corpus/TARGET/, not in git).
# Crashes, leaks and timeouts are written to build/fuzz/artifacts/TARGET/; turn each one into a
# fix and a regression file in tests/fuzz/corpus/TARGET/ (CTest replays that folder).
# A summary line per target (executions, wall seconds, cov/ft at the end, artifacts) is printed
# and appended to build/fuzz/summary.tsv. Installs clang and the libFuzzer runtime (Debian 12:
# clang, libclang-rt-14-dev) as root when missing. KASKAD_FUZZ_ARGS adds libFuzzer flags, e.g.
# KASKAD_FUZZ_ARGS=-max_len=4096 for more executions per second on the image-decoding targets.
set -euo pipefail
cd "$(dirname "$0")/.."
all=(gltf image scene envmap material set playback)
target="${1:-all}"
seconds="${2:-60}"
if [ "$target" = all ]; then targets=("${all[@]}"); else targets=("$target"); fi
for t in "${targets[@]}"; do
  [[ " ${all[*]} " == *" $t "* ]] || { echo "fuzz.sh: unknown target '$t' (one of: ${all[*]})" >&2; exit 2; }
done

bash scripts/install_packages.sh fuzz.sh clang libclang-rt-14-dev

cmake --preset fuzz >/dev/null
cmake --build build/fuzz -j "$(nproc 2>/dev/null || echo 2)" --target "${targets[@]/#/fuzz_}"

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
status=0
for t in "${targets[@]}"; do
  work="build/fuzz/corpus/$t" artifacts="build/fuzz/artifacts/$t" log="build/fuzz/logs/$t.log"
  mkdir -p "$work" "$artifacts" "$(dirname "$log")"
  start=$(date +%s)
  rc=0
  # shellcheck disable=SC2086  # KASKAD_FUZZ_ARGS is a list of flags
  nice build/fuzz/tests/fuzz_"$t" -max_total_time="$seconds" -timeout=20 -rss_limit_mb=4096 ${KASKAD_FUZZ_ARGS:-} \
    -print_final_stats=1 -artifact_prefix="$artifacts/" "$work" "tests/fuzz/corpus/$t" >"$log" 2>&1 || rc=$?
  wall=$(($(date +%s) - start))
  # A crash ends the run without final stats: the last status line gives the count then.
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1 || true)
  last=$(grep -E '^#[0-9]+' "$log" | tail -1 || true)
  [ -n "$execs" ] || execs=$(grep -o '^#[0-9]*' <<<"$last" | tr -d '#' || true)
  cov=$(grep -o 'cov: [0-9]*' <<<"$last" | grep -o '[0-9]*' || true)
  ft=$(grep -o 'ft: [0-9]*' <<<"$last" | grep -o '[0-9]*' || true)
  found=$(find "$artifacts" -type f | wc -l)
  line=$(printf '%s\t%s\t%s\t%s\t%s\t%s\t%s' "$t" "${execs:-?}" "$wall" "${cov:-?}" "${ft:-?}" "$found" "$rc")
  echo "fuzz $t: ${execs:-?} executions in ${wall} s, cov ${cov:-?} ft ${ft:-?}, ${found} artifacts, exit ${rc} (log $log)"
  [ -s build/fuzz/summary.tsv ] || printf 'target\texecutions\twall_s\tcov\tft\tartifacts\texit\n' >build/fuzz/summary.tsv
  echo "$line" >>build/fuzz/summary.tsv
  [ "$rc" -eq 0 ] || status=1
done
exit "$status"
