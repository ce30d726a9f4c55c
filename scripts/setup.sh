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
# rustfmt and clippy for the format and lint stages of scripts/test.sh: from
# rustup when they are missing; without rustup (or when it cannot reach its
# server) say so, and test.sh skips the stage with a message.
for comp in rustfmt clippy; do
    case $comp in
        rustfmt) probe=(cargo fmt --version) ;;
        clippy) probe=(cargo clippy --version) ;;
    esac
    "${probe[@]}" >/dev/null 2>&1 && continue
    if command -v rustup >/dev/null 2>&1; then
        echo "setup: installing $comp (rustup component add $comp)" >&2
        rustup component add "$comp" >&2 || echo "setup: rustup could not install $comp" >&2
    else
        echo "setup: $comp is missing and there is no rustup to install it" >&2
    fi
done
