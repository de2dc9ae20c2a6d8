#!/usr/bin/env bash
# Set-up from nothing: installs every missing build and run dependency from Debian 12's
# packages (as root, or through sudo), then configures and builds rendulic in ./build.
# Idempotent: a second call installs nothing and only rebuilds what changed.
# Environment: BUILD_DIR (default build), BUILD_TYPE (default Release), JOBS (default nproc),
# RENDULIC_MPI (default ON: installs OpenMPI and builds with it, so that CI runs the
# across-ranks tests; OFF builds without MPI and installs no MPI package), CI set -> warnings
# are errors and the sanitizer build (.ci/sanitizers.sh, build-asan) is made as well, so that
# the default suite runs its tests (ci.SanitizedTests; RENDULIC_SANITIZERS=OFF
# skips it). As root, it also makes the build's Python module importable by Debian's python3
# (a .pth file in /usr/local/lib/python3.X/dist-packages naming <build>/python; docs/python.md).
set -euo pipefail
cd "$(dirname "$0")/.."

pkgs=(g++ make cmake pkg-config git ca-certificates
      libeigen3-dev libceres-dev libgoogle-glog-dev libgflags-dev
      libnlopt-dev libnlopt-cxx-dev libhdf5-dev hdf5-tools libsuitesparse-dev
      libgtest-dev libgmock-dev libbenchmark-dev libcli11-dev libtomlplusplus-dev nlohmann-json3-dev
      python3 python3-matplotlib python3-h5py python3-numpy clang-format gfortran
      python3-dev pybind11-dev python3-pytest lammps locales)
mpi=${RENDULIC_MPI:-ON}
if [ "$mpi" = "ON" ]; then pkgs+=(libopenmpi-dev openmpi-bin); fi

missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}" >&2
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

build_dir=${BUILD_DIR:-build}
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE="${BUILD_TYPE:-Release}" \
      -DRENDULIC_MPI="$mpi" >/dev/null
cmake --build "$build_dir" -j "${JOBS:-$(nproc)}"
# `import rendulic` in a new shell: the system interpreter finds the build's package through a
# .pth file in its site directory for local additions (it holds the path of <build>/python).
if [ "$(id -u)" -eq 0 ] && [ -d "$build_dir/python/rendulic" ]; then
  site=$(/usr/bin/python3 -c 'import site; print(site.getsitepackages()[0])')
  mkdir -p "$site"
  echo "$(cd "$build_dir/python" && pwd)" > "$site/rendulic.pth"
fi
if [ -n "${CI:-}" ] && [ "${RENDULIC_SANITIZERS:-ON}" = "ON" ]; then
  SANITIZERS_BUILD_ONLY=1 bash .ci/sanitizers.sh
fi
