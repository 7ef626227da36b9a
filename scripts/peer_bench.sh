#!/usr/bin/env bash
# Kaskad against Godot 3 on LearnOpenGL's cascaded-shadow-map scene (../shared/peers/godot-csm,
# its README): builds Kaskad if needed, installs godot3-runner and xvfb when missing (as root),
# runs the peer's interleaved runner and writes its table, with the machine and the command, to
# docs/bench/peers.md.
#   bash scripts/peer_bench.sh [ROUNDS (3)] [SIZES (4096,2048,1024)]
set -euo pipefail
cd "$(dirname "$0")/.."
rounds="${1:-3}"
sizes="${2:-4096,2048,1024}"
peer="${KASKAD_PEER_DIR:-../shared/peers/godot-csm}"
[ -f "$peer/bench.py" ] || { echo "error: no $peer/bench.py (set KASKAD_PEER_DIR)" >&2; exit 1; }
[ -x build/release/kaskad ] || bash scripts/setup.sh
if ! command -v godot3-runner >/dev/null || ! command -v xvfb-run >/dev/null; then
  [ "$(id -u)" -eq 0 ] || { echo "error: needs godot3-runner and xvfb (run as root to install)" >&2; exit 1; }
  apt-get update -q && apt-get install -y -q godot3-runner xvfb
fi
mkdir -p out docs/bench
command=(/usr/bin/python3 "$peer/bench.py" --kaskad build/release/kaskad --rounds "$rounds"
         --sizes "$sizes" --json out/peers.json)
echo "peer_bench: ${command[*]}"
"${command[@]}" | tee out/peers.txt
tmp="$(mktemp docs/bench/peers.md.XXXXXX)"
{
  echo "# Kaskad against Godot 3 (written by scripts/peer_bench.sh)"
  echo
  echo "$(date -u +%Y-%m-%d), commit $(git rev-parse --short HEAD)$(git diff --quiet || echo ' (with uncommitted changes)'),"
  echo "$(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) cores, Mesa llvmpipe."
  echo "Command: \`bash scripts/peer_bench.sh $rounds $sizes\` (\`${command[*]}\`)."
  echo "The scene, the camera path and what each column means: $peer/README.md."
  echo
  sed -n '/^medians of/,$p' out/peers.txt
} >"$tmp"
mv "$tmp" docs/bench/peers.md
echo "peer_bench: wrote docs/bench/peers.md"
