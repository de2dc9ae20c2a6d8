#!/usr/bin/env bash
# The style check of the default suite (docs/install.md "Style and sanitizers"): every C++
# file of the tree must be formatted as the tree's .clang-format says, so that diffs carry
# changes and not layout. Exit 77 (ctest: skipped) when clang-format is not installed;
# .ci/setup.sh installs it.
# Usage: check_format.sh SOURCE_DIR
set -uo pipefail
src=${1:?source folder}
fmt=$(command -v clang-format-14 || command -v clang-format || true)
if [ -z "$fmt" ]; then
  echo "clang-format not installed: style not checked (apt-get install clang-format)"
  exit 77
fi
cd "$src" || exit 1
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -t files < <(git ls-files '*.cpp' '*.hpp' '*.h')
else  # a source tree without git (an unpacked archive)
  mapfile -t files < <(find core dem probes models calibration app tests bench \
                          \( -name '*.cpp' -o -name '*.hpp' -o -name '*.h' \) | sort)
fi
# One clang-format for the whole tree (2 s; a process per file took 33 s, mostly the start of
# clang-format 250 times); only when it finds a difference, one per file to name them.
bad=()
if ! "$fmt" --style=file --dry-run --Werror "${files[@]}" >/dev/null 2>&1; then
  for f in "${files[@]}"; do
    "$fmt" --style=file --dry-run --Werror "$f" >/dev/null 2>&1 || bad+=("$f")
  done
  [ ${#bad[@]} -gt 0 ] || bad=("(none alone: clang-format failed on the whole tree)")
fi
if [ ${#bad[@]} -gt 0 ]; then
  echo "${#bad[@]} of ${#files[@]} files differ from .clang-format (fix: clang-format -i FILE):"
  printf '  %s\n' "${bad[@]}"
  exit 1
fi
echo "${#files[@]} files formatted as .clang-format says ($("$fmt" --version))"
