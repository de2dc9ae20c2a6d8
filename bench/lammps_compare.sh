#!/usr/bin/env bash
# Back-to-back throughput of rendulic and LAMMPS on the same states (docs/performance.md, "Against
# LAMMPS"): `rendulic bench` prepares the standard states (N = 9261, nu = 0.64 and 0.82), times
# them and writes them as LAMMPS data files; LAMMPS (Debian `lammps`: pair granular hooke with
# velocity damping and no tangential force, fix viscous for the background damping, fix deform
# for the same constant-volume extension, the same time step) then runs each state with a few
# neighbour skins, and the best is reported, in ns per particle-step as rendulic reports it.
# Both codes time the same steps of the same trajectory: 100 warm-up steps, then STEPS (at
# nu = 0.64 the extension unjams the state, and later steps are cheaper).
# With MU > 0 both codes also time one thread / one process with Coulomb friction MU on the same
# states (rendulic: `bench --friction`; LAMMPS: tangential linear_history), and the script
# reports each code's frictional step against its own frictionless one. The pair lines come
# from rendulic (the files nuNN.pair and nuNN-friction.pair of `bench --lammps`), so both codes
# run the same law.
#
# usage: bench/lammps_compare.sh [RENDULIC] [STEPS] [MU]   (defaults: build/rendulic, 2000, 0)
# Not a test: it takes a few minutes and needs an idle machine to mean anything.
set -euo pipefail
rendulic=${1:-build/rendulic}
steps=${2:-2000}
mu=${3:-0}
command -v lmp > /dev/null || { echo "lammps_compare: lmp not found (apt-get install lammps)" >&2; exit 2; }
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT

echo "== rendulic (idle figures: best of 3 rounds of steps 100 to $((100 + steps)))"
friction=()
if awk -v m="$mu" 'BEGIN {exit !(m > 0)}'; then friction=(--friction "$mu"); fi
"$rendulic" bench --json --repetitions 3 --steps "$steps" "${friction[@]}" --lammps "$dir" |
  tee "$dir/rendulic.json"
# rendulic's frictional step against its frictionless one (the JSON rows that carry "friction").
awk '/"volume_fraction"/ {nu = $2 + 0} /"friction"/ {f = $2 + 0; rough = 1}
  /"ns_per_particle_step"/ {ns = $2 + 0}
  /^  }/ {if (rough) {if (f > 0) {r[nu] = ns; m = f} else s[nu] = ns}; rough = 0}
  END {for (nu in r) printf "  rendulic, 1 thread, nu = %s: friction %s against frictionless %.2fx\n",
    nu, m, r[nu] / s[nu]}' "$dir/rendulic.json"

cat > "$dir/in.deform" << 'EOF'
units si
atom_style sphere
boundary p p p
comm_modify vel yes
read_data ${data}
# Normal spring-dashpot: F = k delta - gamma v_n (damping velocity: eta_n = gamma, kg/s); the
# frictionless law's tangential model is required by the syntax and switched off.
include ${pair}
neighbor ${skin} bin
neigh_modify delay 0 every 1 check yes
fix 1 all nve/sphere
fix 2 all viscous 0.1
fix 3 all deform 1 x trate 400 y trate -200 z trate -200 remap x
timestep ${dt}
thermo 1000000
run 100
run ${steps}
EOF

# ns per particle-step of the last "Loop time" line of a LAMMPS log.
# ("Loop time of T on P procs for S steps with N atoms")
ns_of() { awk '/^Loop time of/ {t = $4; s = $9; n = $12} END {printf "%.1f", t / (s * n) * 1e9}' "$1"; }

procs=(1)
if command -v mpirun > /dev/null && [ "$(nproc)" -ge 2 ]; then procs+=(2); fi
echo "== LAMMPS $(lmp -h | sed -n 's/.*Simulator - \(.*\)$/\1/p' | head -1), $steps steps"
printf "%-16s %6s %10s %10s %22s\n" volume_fraction procs friction skin ns_per_particle_step
# The best over the skins of one state, law and process count; prints its rows, sets $best.
time_lammps() {  # data pair procs friction
  local data=$1 pair=$2 p=$3 law=$4 nu dt skin ns cmd
  nu=$(basename "$data" .data | sed 's/nu/0./')
  dt=$(sed -n '1s/.*dt = \([^ ]*\) s.*/\1/p' "$data")
  best=""
  for skin in 1.5e-4 3e-4 4.5e-4; do
    cmd=(lmp -nocite -log "$dir/log" -screen none -var data "$data" -var pair "$pair"
      -var skin $skin -var dt "$dt" -var steps "$steps" -in "$dir/in.deform")
    if [ "$p" -gt 1 ]; then cmd=(mpirun --allow-run-as-root -np "$p" "${cmd[@]}"); fi
    "${cmd[@]}" > /dev/null
    ns=$(ns_of "$dir/log")
    printf "%-16s %6s %10s %10s %22s\n" "$nu" "$p" "$law" "$skin" "$ns"
    if [ -z "$best" ] || awk -v a="$ns" -v b="$best" 'BEGIN {exit !(a < b)}'; then best=$ns; fi
  done
  printf "%-16s %6s %10s %10s %22s  <- best\n" "$nu" "$p" "$law" "" "$best"
}
for data in "$dir"/nu*.data; do
  for p in "${procs[@]}"; do
    time_lammps "$data" "${data%.data}.pair" "$p" 0
    if [ "$p" -eq 1 ]; then smooth=$best; fi
  done
  if [ ${#friction[@]} -gt 0 ]; then
    time_lammps "$data" "${data%.data}-friction.pair" 1 "$mu"
    awk -v r="$best" -v s="$smooth" -v m="$mu" \
      'BEGIN {printf "  LAMMPS, 1 process: friction %s against frictionless %.2fx\n", m, r / s}'
  fi
done
