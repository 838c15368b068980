#!/usr/bin/env bash
# Build the core with AddressSanitizer and UBSan (CMake option THINBURN_SANITIZE) into a
# throwaway virtual environment and run the test suite against it (Blender tests excluded:
# Blender's own binary is not instrumented). Usage: bash scripts/sanitize.sh [pytest args]
# (its pip installs run again each time: the instrumented build is incremental in build/asan)
set -euo pipefail
cd "$(dirname "$0")/.."
venv=${VENV:-build/asan-venv}
python -m venv --system-site-packages "$venv"
"$venv/bin/pip" install -q scikit-build-core pybind11 cmeel-eigen cmake ninja
THINBURN_SANITIZE=ON "$venv/bin/pip" install --no-build-isolation -q -C build-dir=build/asan .
# The interpreter itself is not instrumented, so the runtimes are preloaded; leaks are not
# checked (CPython keeps objects alive at exit by design).
export LD_PRELOAD="$(gcc -print-file-name=libasan.so) $(gcc -print-file-name=libubsan.so)"
export ASAN_OPTIONS=detect_leaks=0:abort_on_error=1
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
# With arguments, only those (test files, -k ...); without, the whole suite.
if [ "$#" -gt 0 ]; then
  "$venv/bin/python" -m pytest -q -p no:cacheprovider "$@"
else
  "$venv/bin/python" -m pytest -q -p no:cacheprovider tests --ignore=tests/blender
fi
