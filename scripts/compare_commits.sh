#!/usr/bin/env bash
# Frame times of this build against an earlier commit's, in one interleaved run: the commit is
# checked out into build/compare/REV/src (a git worktree) and built there in release (once; later
# runs reuse it), then every case runs on both binaries in turn, ROUNDS times, one process at a
# time, and the medians and their ratios (this / REV) are printed as a Markdown table.
#   bash scripts/compare_commits.sh REV [ROUNDS (3)] [CASES_FILE]
# A case is one line of CASES_FILE: NAME<TAB>kaskad arguments (the scene, --set ..., relative to the
# repository); `render` cases print the median frame, `play` cases the median of frames.csv's
# frame_ms (frames 2..N). The default cases: the default scene still, with every optimisation off,
# and unshadowed; the peer scene's (../shared/peers/godot-csm) still and moving camera.
set -euo pipefail
cd "$(dirname "$0")/.."
rev="${1:?usage: compare_commits.sh REV [ROUNDS] [CASES_FILE]}"
rounds="${2:-3}"
cases="${3:-}"
here="$(pwd)"
sha="$(git rev-parse --short "$rev")"
old="build/compare/$sha"
[ -x build/release/kaskad ] || bash scripts/setup.sh
if [ ! -x "$old/build/kaskad" ]; then
  [ -d "$old/src" ] || git worktree add --detach "$old/src" "$sha" >/dev/null
  echo "compare: building $sha in $old/build (once)"
  cmake -S "$old/src" -B "$old/build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DKASKAD_BUILD_EDITOR=OFF >/dev/null
  cmake --build "$old/build" --target kaskad
fi
equal="--set render.shadow_cache=false --set render.visibility_cache=false --set shadow.cull_by_receivers=false --set shadow.scissor_to_receivers=false --set shadow.depth_format=d32f --set shadow.blend_band=0"
if [ -z "$cases" ]; then
  cases="$(mktemp)"
  peer="${KASKAD_PEER_DIR:-../shared/peers/godot-csm}"
  {
    printf 'default still\trender content/scenes/default.json --size 1280x720 --frames 60\n'
    printf 'default equal\trender content/scenes/default.json --size 1280x720 --frames 60 %s\n' "$equal"
    printf 'default unshadowed\trender content/scenes/default.json --size 1280x720 --frames 60 --set sun.light.cast_shadows=false\n'
    if [ -f "$peer/scene.py" ]; then
      work="$(mktemp -d)"
      /usr/bin/python3 "$peer/scene.py" "$work" >/dev/null
      /usr/bin/python3 - "$peer" "$work" <<'PY'
import json, os, sys
sys.path.insert(0, sys.argv[1])
import scene
for size in (4096, 2048, 1024):
    sets = ["shadow.cascade_count=4", f"shadow.map_size={size}", "shadow.filter=pcf3x3"]
    json.dump(scene.playback(sets), open(os.path.join(sys.argv[2], f"moving_{size}.json"), "w"))
PY
      for size in 4096 2048 1024; do
        printf 'peer %s still\trender %s --size 1280x720 --frames 60 --set shadow.map_size=%s --set shadow.cascade_count=4 --set shadow.filter=pcf3x3\n' "$size" "$work/scene.json" "$size"
        printf 'peer %s equal, 5 cascades\trender %s --size 1280x720 --frames 60 --set shadow.map_size=%s --set shadow.cascade_count=5 --set shadow.filter=pcf3x3 %s\n' "$size" "$work/scene.json" "$size" "$equal"
        [ -f "$work/moving_$size.json" ] && printf 'peer %s moving\tplay %s\n' "$size" "$work/moving_$size.json"
      done
      printf 'peer unshadowed\trender %s --size 1280x720 --frames 60 --set sun.light.cast_shadows=false\n' "$work/scene.json"
    fi
  } >"$cases"
fi
median_of() {  # median_of BINARY ARGS...: the run's median frame ms
  local bin="$1"; shift
  if [ "$1" = play ]; then
    local out; out="$(mktemp -d)"
    "$bin" "$@" --headless --out "$out" >/dev/null
    /usr/bin/python3 -c 'import csv,glob,statistics,sys; rows=list(csv.DictReader(open(glob.glob(sys.argv[1]+"/*/frames.csv")[0])))[1:]; print(statistics.median(float(r["frame_ms"]) for r in rows))' "$out"
    rm -rf "$out"
  else
    "$bin" "$@" --headless -o "$(mktemp --suffix=.png)" 2>&1 | sed -n 's/.*median \([0-9.]*\) ms.*/\1/p'
  fi
}
results="$(mktemp)"
for r in $(seq "$rounds"); do
  while IFS=$'\t' read -r name args; do
    [ -z "$name" ] && continue
    # shellcheck disable=SC2086
    for side in new old; do
      bin=build/release/kaskad; [ "$side" = old ] && bin="$old/build/kaskad"
      ms="$(median_of "$bin" $args)"
      printf '%s\t%s\t%s\t%s\n' "$r" "$name" "$side" "$ms" | tee -a "$results" >&2
    done
  done <"$cases"
done
/usr/bin/python3 - "$results" "$sha" "$rounds" <<'EOF'
import collections, statistics, sys
runs = collections.defaultdict(list)
order = []
for line in open(sys.argv[1]):
    r, name, side, ms = line.rstrip("\n").split("\t")
    if name not in order: order.append(name)
    runs[(name, side)].append(float(ms))
print(f"\nmedians of {sys.argv[3]} interleaved rounds, ms per frame; this build against {sys.argv[2]}")
print("| case | this | " + sys.argv[2] + " | this / " + sys.argv[2] + " |\n|---|---|---|---|")
for name in order:
    a, b = statistics.median(runs[(name, "new")]), statistics.median(runs[(name, "old")])
    print(f"| {name} | {a:.2f} | {b:.2f} | {a / b:.2f}x |")
EOF
