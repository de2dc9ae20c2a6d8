#!/usr/bin/env bash
# Regenerates the key tables of docs/scenario-keys.md from the code (`rendulic keys`), so the
# reference can never drift from what the parser accepts (tests/app/cli_system_test.cpp checks it).
set -euo pipefail
cd "$(dirname "$0")/.."
exe=${1:-build/rendulic}
doc=docs/scenario-keys.md
tmp=$(mktemp)
awk '/<!-- BEGIN rendulic keys -->/{print; exit} {print}' "$doc" > "$tmp"
"$exe" keys >> "$tmp"
awk 'f{print} /<!-- END rendulic keys -->/{f=1; print}' "$doc" | sed -n '1,$p' >> "$tmp"
mv "$tmp" "$doc"
