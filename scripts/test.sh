#!/usr/bin/env bash
# The whole test suite: set-up and release build, every test (unit, render, CLI, fuzz smoke),
# then the bad-input and fuzz tests again under AddressSanitizer + UndefinedBehaviorSanitizer.
#   usage: bash scripts/test.sh [--no-asan]
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh release
ctest --preset release -j 2 --timeout 900

if [ "${1:-}" != "--no-asan" ]; then
  echo "== asan preset: unit, CLI and fuzz tests under ASan + UBSan"
  bash scripts/setup.sh asan
  # llvmpipe itself keeps allocations alive until exit: leak checking is for our code only,
  # which the unit and fuzz tests exercise without a GL context.
  ASAN_OPTIONS=detect_leaks=1 ctest --preset asan -j 2 --timeout 1800 -L 'unit|fuzz'
  ASAN_OPTIONS=detect_leaks=0 ctest --preset asan -j 2 --timeout 1800 -L 'cli|render'
fi
