#!/usr/bin/env bash
# Back-to-back throughput of rendulic and LAMMPS on the same states (docs/performance.md, "Against
# LAMMPS"): `rendulic bench` prepares the standard states (N = 9261, nu = 0.64 and 0.82), times
# them and writes them as LAMMPS data files; LAMMPS (Debian `lammps`: pair granular hooke with
# velocity damping and no tangential force, fix viscous for the background damping, fix deform
# for the same constant-volume extension, the same time step) then runs each state with a few
# neighbour skins, and the best is reported, in ns per particle-step as rendulic reports it.
#
# usage: bench/lammps_compare.sh [RENDULIC] [STEPS]   (defaults: build/rendulic, 2000)
# Not a test: it takes a few minutes and needs an idle machine to mean anything.
set -euo pipefail
rendulic=${1:-build/rendulic}
steps=${2:-2000}
command -v lmp > /dev/null || { echo "lammps_compare: lmp not found (apt-get install lammps)" >&2; exit 2; }
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT

echo "== rendulic (idle figures: best of 3 x 2 s)"
"$rendulic" bench --json --repetitions 3 --seconds 2 --lammps "$dir" | tee "$dir/rendulic.json"

cat > "$dir/in.deform" << 'EOF'
units si
atom_style sphere
boundary p p p
comm_modify vel yes
read_data ${data}
# Normal spring-dashpot: F = k delta - gamma v_n (damping velocity: eta_n = gamma, kg/s); the
# tangential model is required by the syntax and switched off (no damping, no friction).
pair_style granular
pair_coeff * * hooke 1e8 1.0 damping velocity tangential linear_nohistory 0.0 0.0
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
printf "%-16s %6s %10s %22s\n" volume_fraction procs skin ns_per_particle_step
for data in "$dir"/nu*.data; do
  nu=$(basename "$data" .data | sed 's/nu/0./')
  dt=$(sed -n '1s/.*dt = \([^ ]*\) s.*/\1/p' "$data")
  for p in "${procs[@]}"; do
    best=""
    for skin in 1.5e-4 3e-4 4.5e-4; do
      cmd=(lmp -nocite -log "$dir/log" -screen none -var data "$data" -var skin $skin
        -var dt "$dt" -var steps "$steps" -in "$dir/in.deform")
      if [ "$p" -gt 1 ]; then cmd=(mpirun --allow-run-as-root -np "$p" "${cmd[@]}"); fi
      "${cmd[@]}" > /dev/null
      ns=$(ns_of "$dir/log")
      printf "%-16s %6s %10s %22s\n" "$nu" "$p" "$skin" "$ns"
      if [ -z "$best" ] || awk -v a="$ns" -v b="$best" 'BEGIN {exit !(a < b)}'; then best=$ns; fi
    done
    printf "%-16s %6s %10s %22s  <- best\n" "$nu" "$p" "" "$best"
  done
done
