#!/usr/bin/env bash
# Regenerate the example meshes meshes/*.msh from meshes/*.geo with Gmsh
# (ASCII msh 4.1, first-order triangles), and the 3D ones meshes/3d/*.msh
# (first-order tetrahedra: a .geo that declares a Physical Volume is meshed
# with -3, as `signorini mesh` does), then run the consistency check
# meshes/check_meshes.py (2D models) if python3 (>= 3.11, for tomllib) is
# available.
#
# Usage: scripts/gen_meshes.sh [NAME ...]     (default: every meshes/*.geo
#        and meshes/3d/*.geo; a 3D one is named 3d/NAME)
# Env:   GMSH=/path/to/gmsh   (default: gmsh from PATH)
#        SKIP_CHECK=1         (do not run the Python check)
# Exits non-zero if gmsh is missing, a mesh fails, or the check fails.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
meshdir="$(cd "$here/../meshes" && pwd)"
GMSH="${GMSH:-gmsh}"

if ! command -v "$GMSH" >/dev/null 2>&1; then
    echo "error: gmsh not found (looked for '$GMSH'); install Gmsh >= 4.8 or set GMSH=/path/to/gmsh" >&2
    exit 127
fi
echo "using $("$GMSH" --version 2>&1 | head -n1 | sed 's/^/gmsh /')"

cd "$meshdir"
if [ "$#" -gt 0 ]; then
    names=("$@")
else
    names=()
    for g in *.geo 3d/*.geo; do names+=("${g%.geo}"); done
fi

fail=0
for n in "${names[@]}"; do
    n="${n%.geo}"
    if [ ! -f "$n.geo" ]; then
        echo "error: $meshdir/$n.geo not found" >&2
        fail=1
        continue
    fi
    log="$(mktemp)"
    dim=2
    if sed 's://.*$::' "$n.geo" | grep -qE 'Physical[[:space:]]+Volume'; then dim=3; fi
    if "$GMSH" -"$dim" -format msh41 "$n.geo" -o "$n.msh" >"$log" 2>&1 && [ -s "$n.msh" ]; then
        counts="$(grep -E 'Info *: [0-9]+ nodes [0-9]+ elements' "$log" | tail -n1 | sed 's/.*: //')"
        echo "ok     $n.msh  ($counts)"
        grep -iE '^(Warning|Error)' "$log" | sed "s/^/       /" || true
    else
        echo "FAILED $n.geo:" >&2
        sed 's/^/       /' "$log" >&2
        fail=1
    fi
    rm -f "$log"
done

if [ "$fail" -ne 0 ]; then
    echo "error: some meshes failed" >&2
    exit 1
fi

if [ "${SKIP_CHECK:-0}" != "1" ]; then
    if command -v python3 >/dev/null 2>&1 && python3 -c 'import tomllib' >/dev/null 2>&1; then
        python3 "$meshdir/check_meshes.py"
    else
        echo "note: python3 >= 3.11 not found, skipping meshes/check_meshes.py"
    fi
fi
