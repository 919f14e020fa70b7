#!/usr/bin/env bash
# The README's test command: install what is missing, build (Release, g++), run every ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
toolchains/install-deps.sh test
cmake --preset release >/dev/null
cmake --build --preset release -j"$(nproc)"
ctest --preset release -j"$(nproc)"
