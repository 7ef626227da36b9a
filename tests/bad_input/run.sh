#!/usr/bin/env bash
# Runs `kaskad` on every case of tests/bad_input/cases.txt and checks, for each: exit code 1 or 2
# (never 0, never >= 128: a signal), the expected file or value named in the output, no raw
# library lines (libpng, nlohmann's "[json.exception"), a time limit, and that nothing was created
# or changed: neither the previous outputs in {OUT} nor the (empty) working folder.
# Then a failed write under a file-size limit (`ulimit -f`) and into a read-only folder must leave
# the previous output byte-identical.
#   usage: KASKAD=build/release/kaskad KASKAD_CONTENT=content bash tests/bad_input/run.sh [--table FILE]
# --table FILE also writes the markdown table (case, exit code, first line of the message).
set -u
: "${KASKAD:?path to the kaskad binary}" "${KASKAD_CONTENT:?content dir}"
here="$(cd "$(dirname "$0")" && pwd)"
KASKAD="$(cd "$(dirname "$KASKAD")" && pwd)/$(basename "$KASKAD")"
content="$(cd "$KASKAD_CONTENT" && pwd)"
limit="${KASKAD_BAD_INPUT_TIMEOUT:-120}"
table=""
[ "${1:-}" = "--table" ] && table="$2"
tmp="$(mktemp -d "${TMPDIR:-/tmp}/bad_input.XXXXXX")"
trap 'rm -rf "$tmp"' EXIT
export KASKAD_SHADER_CACHE=off
passed=0 failed=0 n=0
rows="" atomic_summary=""

# Previous outputs every case starts from (a real PNG and EXR, so byte changes are meaningful).
if ! setup_log="$("$KASKAD" render --headless --size 24x16 --frames 1 -o "$tmp/prev.png" \
      --aov "$tmp/prev.exr" 2>&1)"; then
  echo "FAIL setup: cannot render the previous outputs"
  echo "$setup_log" | tail -20
  exit 1
fi
"$KASKAD" save "$content/scenes/default.json" -o "$tmp/prev.json" >/dev/null 2>&1 || { echo "FAIL setup: save"; exit 1; }

snapshot() { (cd "$1" && find . -print0 | sort -z | xargs -0 md5sum 2>/dev/null; find . | sort); }

# Files that are not regular files ({FIFO}/...): named pipes, which block a reader that opens
# them until a writer comes, and the glTF files that name them as a buffer and an image.
fifo="$tmp/fifo"
mkdir -p "$fifo/shard"
for f in pipe.json pipe.bin pipe.png shard/bench.csv; do mkfifo "$fifo/$f"; done
cp "$here/gltf/fifo_buffer.gltf" "$here/gltf/fifo_image.gltf" "$fifo/"

# Generated cases ({GEN}/...), too big for git: JSON nested 100,000 deep in a model's node
# settings and in an entity block, and a parent cycle through 100,000 entities.
gen="$tmp/gen"
mkdir -p "$gen"
printf -v blanks '%100000s' ''
deep_array="${blanks// /[}${blanks// /]}"
printf '{"kaskad_scene": 1, "entities": [{"name": "m", "model": {"path": "%s", "nodes": {"n": {"transform": {"translation": %s}}}}}]}\n' \
  "$content/models/Box/glTF-Binary/Box.glb" "$deep_array" >"$gen/deep_node_settings.json"
printf '{"kaskad_scene": 1, "entities": [{"name": "e", "transform": {"translation": %s}}]}\n' \
  "$deep_array" >"$gen/deep_entity.json"
cp "$content/env/equirect/venice_sunset_1k.hdr" "$gen/sky.hdr"  # an input an output may not replace
awk 'BEGIN { n = 100000; printf "{\"kaskad_scene\": 1, \"entities\": [";
             for (i = 0; i < n; ++i) printf "%s{\"name\": \"e%d\", \"transform\": {\"parent\": \"e%d\"}}", (i ? ", " : ""), i, (i + 1) % n;
             print "]}" }' >"$gen/long_parent_cycle.json"

while IFS= read -r line; do
  case "$line" in ''|'#'*) continue ;; esac
  n=$((n + 1))
  mention="${line%% | *}" words="${line#* | }"
  out="$tmp/case$n/out" cwd="$tmp/case$n/cwd"
  mkdir -p "$out/bench" "$cwd"
  cp "$tmp/prev.png" "$out/out.png"; cp "$tmp/prev.exr" "$out/out.exr"; cp "$tmp/prev.json" "$out/out.json"
  printf 'scene,config\nold,row\n' >"$out/bench/bench.csv"
  words="${words//\{R\}/--headless --size 32x32 --frames 1 -o \{OUT\}/out.png}"
  words="${words//\{FIFO\}/$fifo}" words="${words//\{GEN\}/$gen}"
  words="${words//\{DIR\}/$here}" words="${words//\{CONTENT\}/$content}" words="${words//\{OUT\}/$out}"
  mention="${mention//\{OUT\}/$out}"
  eval "args=($words)"
  before="$(snapshot "$out")"
  msg="$(cd "$cwd" && timeout -k 5 "$limit" "$KASKAD" "${args[@]}" 2>&1)"
  rc=$?
  first="$(grep -a -m1 '^kaskad: ' <<<"$msg" || tail -1 <<<"$msg")"
  problems=""
  [ "$rc" -eq 124 ] || [ "$rc" -eq 137 ] && problems+=" timed out after ${limit}s;"
  { [ "$rc" -eq 1 ] || [ "$rc" -eq 2 ]; } || problems+=" exit $rc;"
  grep -qaF -- "$mention" <<<"$msg" || problems+=" output does not name '$mention';"
  grep -qaE 'libpng|\[json\.exception' <<<"$msg" && problems+=" raw library lines in the output;"
  [ "$before" = "$(snapshot "$out")" ] || problems+=" outputs created or changed;"
  [ -z "$(ls -A "$cwd")" ] || problems+=" files created in the working folder: $(ls -A "$cwd");"
  if [ -n "$problems" ]; then
    echo "FAIL $n ($mention):$problems"; echo "     kaskad ${args[*]}"; tail -3 <<<"$msg" | sed 's/^/     /'
    failed=$((failed + 1))
  else
    echo "ok   $n $mention: exit $rc"
    passed=$((passed + 1))
  fi
  shown="${first//$here\//bad_input/}" shown="${shown//$content\//content/}" shown="${shown//$out/OUT}"
  shown="${shown//|/\\|}"
  shown_args="${line#* | }"
  [ "${#shown_args}" -le 200 ] || shown_args="${shown_args:0:160}... (${#shown_args} characters)"
  rows+="| $n | \`$shown_args\` | $rc | ${shown:0:240} |"$'\n'
done <"$here/cases.txt"

# Failed writes keep the previous output byte-identical.
atomic_case() {  # atomic_case NAME COMMAND...   (the previous output is $dir/out.png)
  local name="$1"; shift
  if "$@" >"$tmp/atomic.log" 2>&1; then rc=0; else rc=$?; fi
  if { [ "$rc" -eq 1 ] || [ "$rc" -eq 2 ]; } && cmp -s "$tmp/prev.png" "$dir/out.png" &&
     [ "$(ls -A "$dir")" = "out.png" ]; then
    echo "ok   $name: exit $rc, previous output byte-identical, no temporary file left"
    atomic_summary+="${atomic_summary:+; }$name: exit $rc, previous output byte-identical"
    passed=$((passed + 1))
  else
    echo "FAIL $name: exit $rc; $(ls -A "$dir" | tr '\n' ' ')"; tail -3 "$tmp/atomic.log"
    failed=$((failed + 1))
  fi
}
dir="$tmp/limited"; mkdir -p "$dir"; cp "$tmp/prev.png" "$dir/out.png"
# 8 KiB: far too little for a 512x512 PNG of the default scene (about 25 KB).
atomic_case write_under_file_size_limit bash -c 'ulimit -f 8; exec "$@"' _ "$KASKAD" render --headless \
  --size 512x512 --frames 1 -o "$dir/out.png"
if [ "$(id -u)" -eq 0 ] && command -v unshare >/dev/null && unshare -m true 2>/dev/null; then
  # Root writes anywhere by permission bits: a read-only bind mount, in a private mount
  # namespace (nothing outside this command sees it), is a folder root cannot write.
  dir="$tmp/readonly"; mkdir -p "$dir"; cp "$tmp/prev.png" "$dir/out.png"
  atomic_case write_into_read_only_folder unshare -m bash -c \
    'mount --bind "$1" "$1" && mount -o remount,bind,ro "$1" && shift && exec "$@"' _ "$dir" \
    "$KASKAD" render --headless --size 64x64 --frames 1 -o "$dir/out.png"
elif [ "$(id -u)" -ne 0 ]; then
  dir="$tmp/readonly"; mkdir -p "$dir"; cp "$tmp/prev.png" "$dir/out.png"; chmod a-w "$dir"
  atomic_case write_into_read_only_folder "$KASKAD" render --headless --size 64x64 --frames 1 -o "$dir/out.png"
  chmod u+w "$dir"
else
  echo "skip write_into_read_only_folder: root without unshare/mount"
fi

if [ -n "$table" ]; then
  {
    echo "# Bad input: what kaskad says, case by case"
    echo
    echo "Written by \`bash tests/bad_input/run.sh --table docs/guide/bad_input_messages.md\` (with \`KASKAD\` and"
    echo "\`KASKAD_CONTENT\` set). One row per case of \`tests/bad_input/cases.txt\`: the arguments"
    echo "(\`{DIR}\` = \`tests/bad_input\`, \`{OUT}\` = a folder of previous outputs that must stay"
    echo "unchanged, \`{R}\` = \`--headless --size 32x32 --frames 1 -o {OUT}/out.png\`), the exit code and"
    echo "the first line of the message. Every case must exit 1 or 2, name the file or value, print no"
    echo "raw library lines and create or change nothing. Then a failed write under \`ulimit -f\` and"
    echo "into a read-only folder must leave the previous output byte-identical: $atomic_summary."
    echo
    echo "| # | arguments | exit | first line of the message |"
    echo "|---|---|---|---|"
    printf '%s' "$rows"
  } >"$table"
fi
echo "$passed passed, $failed failed ($n bad-input cases)"
[ "$failed" -eq 0 ]
