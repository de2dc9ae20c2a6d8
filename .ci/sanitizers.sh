#!/usr/bin/env bash
# The sanitizer job (docs/install.md "Sanitizers"): builds rendulic with AddressSanitizer and
# UndefinedBehaviorSanitizer in its own folder and runs the default test suite (unit and
# system tests, ctest -LE validate) under them. Any report of either sanitizer fails the job:
# UBSan stops at its first finding, ASan at every finding (including leaks at exit).
# Optimised lightly (-O1) with debug information: fast enough for the system tests, exact
# enough for the stack traces. MPI and the benchmarks are off (the MPI tests skip without it),
# -march=native is off so that the binary runs wherever the job does.
# Run after .ci/setup.sh (same Debian packages). Environment: BUILD_DIR (default build-asan),
# JOBS (default: all cores).
set -euo pipefail
cd "$(dirname "$0")/.."

build_dir=${BUILD_DIR:-build-asan}
jobs=${JOBS:-$(nproc)}
sanitize="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer"

start=$(date +%s)
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DCMAKE_CXX_FLAGS="$sanitize" \
      -DCMAKE_EXE_LINKER_FLAGS="$sanitize" -DCMAKE_SHARED_LINKER_FLAGS="$sanitize" \
      -DRENDULIC_MPI=OFF -DRENDULIC_BENCH=OFF -DRENDULIC_NATIVE=OFF >/dev/null
cmake --build "$build_dir" -j "$jobs"
built=$(date +%s)

# detect_leaks: a leak is a finding. The suppressions name leaks of the libraries we link
# (not ours), each with its reason. UBSan prints the stack of what it finds.
export ASAN_OPTIONS="detect_leaks=1:strict_string_checks=1:check_initialization_order=1"
export LSAN_OPTIONS="suppressions=$PWD/.ci/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
status=0
ctest --test-dir "$build_dir" -LE validate -j "$jobs" --output-on-failure || status=$?
done=$(date +%s)
echo "sanitizers: build $((built - start)) s, tests $((done - built)) s (wall, $jobs jobs)" >&2
exit $status
