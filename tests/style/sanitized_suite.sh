#!/usr/bin/env bash
# The sanitizer run (docs/install.md "Style and sanitizers"): tests of the AddressSanitizer +
# UndefinedBehaviorSanitizer build that .ci/sanitizers.sh makes in build-asan (.ci/setup.sh
# builds it when CI is set). Any sanitizer finding fails the test that hit it, and so this one.
# Exit 77 (ctest: skipped) when there is no such build.
# Usage: sanitized_suite.sh SANITIZER_BUILD_DIR SOURCE_DIR [unit|all]
#   unit (default, the default suite's entry): the unit tests, ~1.5 min on 2 cores;
#   all (.ci/sanitizers.sh): unit and system tests, far longer (the system tests run the DEM
#   and the calibration at -O1 under the sanitizers: tens of minutes).
set -uo pipefail
dir=${1:?sanitizer build folder}
src=${2:?source folder}
scope=${3:-unit}
if [ ! -f "$dir/CTestTestfile.cmake" ]; then
  echo "no sanitizer build in $dir: not run (bash .ci/sanitizers.sh builds and runs it)"
  exit 77
fi
# detect_leaks: a leak is a finding. The suppressions name leaks of the libraries we link
# (not ours), each with its reason. UBSan stops at its first finding and prints its stack.
export ASAN_OPTIONS="detect_leaks=1:strict_string_checks=1:check_initialization_order=1"
export LSAN_OPTIONS="suppressions=$src/.ci/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
if [ "$scope" = all ]; then
  # The style and sanitizer entries of the sanitizer build itself are not run again.
  ctest --test-dir "$dir" -LE 'validate|ci' --output-on-failure -j "${JOBS:-2}"
else
  ctest --test-dir "$dir" -L unit --output-on-failure -j "${JOBS:-2}"
fi
