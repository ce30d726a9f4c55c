#!/usr/bin/env bash
# Install what signorini needs on a fresh Debian machine (idempotent):
# Debian's serial HDF5 (hdf5-metno links against it) and Gmsh (to remesh
# the .geo examples; the shipped .msh files do not need it).
set -euo pipefail
need=()
dpkg -s libhdf5-dev >/dev/null 2>&1 || need+=(libhdf5-dev)
dpkg -s pkg-config >/dev/null 2>&1 || need+=(pkg-config)
command -v gmsh >/dev/null 2>&1 || need+=(gmsh)
if [ ${#need[@]} -gt 0 ]; then
    echo "setup: installing ${need[*]}" >&2
    SUDO=""
    [ "$(id -u)" -eq 0 ] || SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null
fi
# hdf5-metno must link Debian's *serial* HDF5 (installing gmsh makes
# pkg-config point at the MPI build); .cargo/config.toml sets HDF5_DIR.
test -d /usr/lib/x86_64-linux-gnu/hdf5/serial || { echo "setup: serial HDF5 not found" >&2; exit 1; }
