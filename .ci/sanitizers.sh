#!/usr/bin/env bash
# The sanitizer job (docs/install.md "Style and sanitizers"): builds rendulic with
# AddressSanitizer and UndefinedBehaviorSanitizer in its own folder and runs the default test
# suite (unit and system tests, ctest -LE validate) under them. Any report of either sanitizer
# fails the job: UBSan stops at its first finding, ASan at every finding (including leaks at
# exit).
# Optimised lightly (-O1) with line tables only (-g1): fast enough for the system tests, and the
# stack traces still name each frame's file and line, inlined frames included; full debug
# information (-g) made the build 1.55x longer (docs/install.md). MPI and the benchmarks are
# off (the MPI tests skip without it), -march=native is off so that the binary runs wherever
# the job does. The Python module and its tests are off: an ASan runtime cannot be loaded into
# a Python interpreter started without it.
# Run after .ci/setup.sh (same Debian packages). Environment: BUILD_DIR (default build-asan),
# JOBS (default: all cores), SANITIZERS_BUILD_ONLY (set: build, run nothing; .ci/setup.sh
# does that under CI, and the default suite's ci.SanitizedTests runs its tests).
set -euo pipefail
cd "$(dirname "$0")/.."

build_dir=${BUILD_DIR:-build-asan}
jobs=${JOBS:-$(nproc)}
sanitize="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer"

start=$(date +%s)
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" -DCMAKE_CXX_FLAGS="$sanitize" \
      -DCMAKE_EXE_LINKER_FLAGS="$sanitize" -DCMAKE_SHARED_LINKER_FLAGS="$sanitize" \
      -DRENDULIC_MPI=OFF -DRENDULIC_BENCH=OFF -DRENDULIC_NATIVE=OFF -DRENDULIC_PYTHON=OFF \
      -DRENDULIC_SANITIZER_BUILD= >/dev/null
cmake --build "$build_dir" -j "$jobs"
built=$(date +%s)
if [ -n "${SANITIZERS_BUILD_ONLY:-}" ]; then
  echo "sanitizers: build $((built - start)) s (wall, $jobs jobs)" >&2
  exit 0
fi

# The sanitizer options and the test selection live with the suite's own entry.
status=0
JOBS=$jobs bash tests/style/sanitized_suite.sh "$build_dir" "$PWD" all || status=$?
done=$(date +%s)
echo "sanitizers: build $((built - start)) s, tests $((done - built)) s (wall, $jobs jobs)" >&2
exit $status
