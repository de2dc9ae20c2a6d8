#!/usr/bin/env bash
# The layer check of the default suite (docs/architecture.md "Module layers"): each module
# includes only the modules below it (core -> dem, probes, models -> calibration -> app), and
# the DEM engine (dem/) includes no file format: no results file (results.hpp, envelope_io.hpp,
# HDF5) and no TOML. The engine then runs inside any front-end (the CLI, a Python module, a
# packing from another code) that does its own I/O.
# Usage: check_layers.sh SOURCE_DIR
set -uo pipefail
src=${1:?source folder}
cd "$src" || exit 1
declare -A allowed=(
  [core]="core"
  [dem]="core dem"
  [probes]="core probes"
  [models]="core models"
  [calibration]="core models probes calibration"
  [app]="core dem probes models calibration app"
)
bad=0
for module in "${!allowed[@]}"; do
  [ -d "$module" ] || continue
  while IFS= read -r hit; do
    file=${hit%%:*}
    used=${hit#*#include \"rendulic/}  # the module: a parameter expansion, not a sed per line
    used=${used%%/*}
    if [[ " ${allowed[$module]} " != *" $used "* ]]; then
      echo "$file includes rendulic/$used/ (module $module may include: ${allowed[$module]})"
      bad=1
    fi
  done < <(grep -rn --include='*.hpp' --include='*.cpp' -E '#include "rendulic/[a-z_]+/' "$module")
done
# The engine's sources and headers: no results file, no HDF5, no TOML.
while IFS= read -r hit; do
  echo "engine file format include: $hit"
  bad=1
done < <(grep -rn --include='*.hpp' --include='*.cpp' -E \
           '#include [<"](rendulic/core/(results|envelope_io)\.hpp|H5[A-Za-z]*\.h|hdf5\.h|toml\+\+/)' dem)
if [ "$bad" -ne 0 ]; then
  echo "layer check failed"
  exit 1
fi
echo "module layers as docs/architecture.md says; the engine includes no file format"
