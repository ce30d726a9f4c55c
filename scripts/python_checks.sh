#!/usr/bin/env bash
# Python cross-checks of signorini (installs what is missing, then runs them):
#
#   1. scripts/check_outputs.py   (pyvista + h5py, in the venv .venv): the
#      VTU/PVD/HDF5 outputs of every example against the contract, and an
#      off-screen PNG per example (out dir: $SIGNORINI_CHECK_OUT or a temp dir);
#   2. scripts/fenicsx_crosscheck.py (Debian's /usr/bin/python3 with
#      python3-dolfinx-real, python3-gmsh, python3-scipy, python3-h5py and
#      Clarabel from PyPI in .venv/debian-site): linear elastic and contact solutions
#      of an independent FEniCSx model against signorini's, including two
#      mortar pairs (hertz, the hard punch) whose rows are built in python,
#      and the axisymmetric models tests/data/axi_* (r-weighted forms).
#
# Usage: bash scripts/python_checks.sh [NAME ...]   (default: the examples below)
#   SIGNORINI_WITH_PARAVIEW=1  also install Debian's python3-paraview (it provides
#                              pvpython, ~450 MB) so check_outputs.py opens the files
#                              with ParaView's readers too, and run pvpython headless
#                              under `xvfb-run -a` on the first example: arrays and
#                              their ComponentName (sxx, ux, ...) as ParaView sees
#                              them (skipped with a note otherwise)
#   SIGNORINI_CHECK_OUT=DIR    keep the outputs and PNGs there (default: temp dir)
# Exit status: 0 when every check passed.
set -uo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD

# Examples checked by default.
DEFAULT_EXAMPLES=(two_blocks_eccentric three_bodies column hertz floating_block cantilevers two_blocks two_blocks_glued geodynamic geodynamic_steps hip rollers)
EXAMPLES=("$@")
[ ${#EXAMPLES[@]} -gt 0 ] || EXAMPLES=("${DEFAULT_EXAMPLES[@]}")

# Tested versions (PyPI); override with e.g. PY_VENV_PKGS="pyvista h5py meshio numpy".
PY_VENV_PKGS=${PY_VENV_PKGS:-"pyvista==0.49.1 vtk==9.7.2 h5py==3.16.0 meshio==5.3.5 numpy==2.4.6"}
PY_QP_PKG=${PY_QP_PKG:-"clarabel==0.11.1"}

SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
t_start=$(date +%s)
stamp() { echo "[python_checks $(($(date +%s) - t_start)) s] $*"; }

# ---------------------------------------------------------------- installs
bash scripts/setup.sh || { echo "python_checks: scripts/setup.sh failed" >&2; exit 2; }
need=()
for p in python3-dolfinx-real python3-gmsh python3-scipy python3-h5py python3-venv xvfb xauth libegl1 libegl-mesa0; do
    dpkg -s "$p" >/dev/null 2>&1 || need+=("$p")
done
if [ "${SIGNORINI_WITH_PARAVIEW:-0}" = 1 ] && ! command -v pvpython >/dev/null 2>&1; then
    need+=(python3-paraview)
fi
if [ ${#need[@]} -gt 0 ]; then
    stamp "apt-get install ${need[*]}"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${need[@]}" >/dev/null \
        || { echo "python_checks: apt-get install ${need[*]} failed" >&2; exit 2; }
    stamp "apt-get done"
fi

VENV=$ROOT/.venv
if ! "$VENV/bin/python" -c "import pyvista, h5py, meshio, numpy" >/dev/null 2>&1; then
    stamp "creating $VENV: pip install $PY_VENV_PKGS"
    rm -rf "$VENV"
    python3 -m venv "$VENV" || { echo "python_checks: python3 -m venv failed" >&2; exit 2; }
    "$VENV/bin/pip" install -q --no-cache-dir --disable-pip-version-check $PY_VENV_PKGS \
        || { echo "python_checks: pip install into .venv failed" >&2; exit 2; }
    stamp "venv done"
fi

# Clarabel for Debian's python3: an abi3 wheel, installed without its
# dependencies (numpy and scipy are Debian's) into .venv/debian-site.
PYDEPS=$ROOT/.venv/debian-site
if ! /usr/bin/python3 -c "import sys; sys.path.append('$PYDEPS'); import clarabel" >/dev/null 2>&1; then
    debver=$(/usr/bin/python3 -c 'import sys; print(f"{sys.version_info[0]}.{sys.version_info[1]}")')
    stamp "pip install --target .venv/debian-site $PY_QP_PKG (for /usr/bin/python3 $debver)"
    rm -rf "$PYDEPS"
    "$VENV/bin/pip" install -q --no-cache-dir --disable-pip-version-check --no-deps --only-binary=:all: \
        --python-version "$debver" --target "$PYDEPS" $PY_QP_PKG \
        || { echo "python_checks: pip install --target .venv/debian-site failed" >&2; exit 2; }
    /usr/bin/python3 -c "import sys; sys.path.append('$PYDEPS'); import clarabel" \
        || { echo "python_checks: clarabel does not import under /usr/bin/python3" >&2; exit 2; }
fi
stamp "installs ready"

# ------------------------------------------------------------------- build
cargo build --release 2>&1 | tail -n 3
[ "${PIPESTATUS[0]}" -eq 0 ] || { echo "python_checks: cargo build --release failed" >&2; exit 2; }
EXE=$ROOT/target/release/signorini
stamp "build done"

# ------------------------------------------------------------------ checks
passed=0
failed=0
failed_names=()
record() {  # name, status
    if [ "$2" -eq 0 ]; then passed=$((passed + 1)); else failed=$((failed + 1)); failed_names+=("$1"); fi
}

if [ -n "${SIGNORINI_CHECK_OUT:-}" ]; then
    OUT=$SIGNORINI_CHECK_OUT
    rm -rf "$OUT"; mkdir -p "$OUT"
else
    OUT=$(mktemp -d -t signorini_pychecks.XXXXXX)
    trap 'rm -rf "$OUT"' EXIT
fi

# Outputs of every example, plus a two-step variant of the first one (so the
# .pvd collection and the NAME_NNNN files are checked too).
for n in "${EXAMPLES[@]}"; do
    if ! "$EXE" solve "meshes/$n.toml" --out "$OUT" --quiet; then
        echo "FAIL signorini solve meshes/$n.toml" >&2
        record "solve $n" 1
    fi
done
steps_toml=$OUT/steps_${EXAMPLES[0]}.toml
{
    sed "s#^file *= *\"\(.*\)\"#file = \"$ROOT/meshes/\1\"#" "meshes/${EXAMPLES[0]}.toml"
    printf '\n[[steps]]\nfactor = 0.5\n\n[[steps]]\nfactor = 1.0\n'
} > "$steps_toml"
if ! "$EXE" solve "$steps_toml" --out "$OUT" --quiet; then
    echo "FAIL signorini solve $steps_toml" >&2
    record "solve steps_${EXAMPLES[0]}" 1
fi
rm -f "$steps_toml"

stamp "check_outputs.py $OUT"
"$VENV/bin/python" scripts/check_outputs.py "$OUT"
record check_outputs $?

# ParaView itself (opt-in): Debian's python3-paraview provides pvpython; it
# needs a display even for reading, so it runs under xvfb-run -a.
if [ "${SIGNORINI_WITH_PARAVIEW:-0}" = 1 ]; then
    stamp "pvpython (xvfb-run -a): component names in $OUT/${EXAMPLES[0]}.vtu"
    pv_script=$OUT/pv_component_names.py
    cat > "$pv_script" <<'PYEOF'
import sys
from paraview import simple
r = simple.XMLUnstructuredGridReader(FileName=[sys.argv[1]])
r.UpdatePipeline()
want = {"displacement": ["ux", "uy", "uz"], "reaction": ["Rx", "Ry", "Rz"],
        "stress": ["sxx", "syy", "sxy", "szz"], "principal_stress": ["s1", "s2"]}
bad = []
for arrays in (r.PointData, r.CellData):
    for name in arrays.keys():
        info = arrays[name]
        if name in want:
            got = [info.GetComponentName(k) for k in range(info.GetNumberOfComponents())]
            exp = want[name][:info.GetNumberOfComponents()]
            print(f"pvpython: {name}: {got}")
            if got != exp:
                bad.append(f"{name}: ParaView shows {got}, expected {exp}")
missing = [n for n in ("displacement", "stress", "reaction") if n not in list(r.PointData.keys()) + list(r.CellData.keys())]
bad += [f"array {n} missing" for n in missing]
print("pvpython: " + ("; ".join(bad) if bad else "component names OK"))
sys.exit(1 if bad else 0)
PYEOF
    if command -v pvpython >/dev/null 2>&1 && command -v xvfb-run >/dev/null 2>&1; then
        xvfb-run -a pvpython "$pv_script" "$OUT/${EXAMPLES[0]}.vtu"
        record "pvpython component names" $?
    else
        echo "note: pvpython or xvfb-run not found: the ParaView component-name check is skipped"
    fi
    rm -f "$pv_script"
fi

for n in "${EXAMPLES[@]}"; do
    stamp "fenicsx_crosscheck.py meshes/$n.toml"
    SIGNORINI="$EXE" SIGNORINI_PYDEPS="$PYDEPS" /usr/bin/python3 scripts/fenicsx_crosscheck.py "meshes/$n.toml" --tol 1e-8
    record "crosscheck $n" $?
done

# Mortar rows (docs/methods.md §7.1): hertz and the hard punch (foundation as
# slave: a slave curve longer than the master, curved master corners) with
# discretization = "mortar", against rows built independently in python.
mortar_dir=$OUT/mortar
mkdir -p "$mortar_dir"
sed "s#^file *= *\"\(.*\)\"#file = \"$ROOT/meshes/\1\"#; s#^master = \"block_top\"#master = \"block_top\"\ndiscretization = \"mortar\"#" \
    meshes/hertz.toml > "$mortar_dir/hertz_mortar.toml"
sed "s#^file *= *\"\(.*\)\"#file = \"$ROOT/tests/hard/\1\"#; s#^slave = \"punch_bottom\"#slave = \"found_top\"#; s#^master = \"found_top\"#master = \"punch_bottom\"\ndiscretization = \"mortar\"#" \
    tests/hard/punch.toml > "$mortar_dir/punch_mortar.toml"
for t in hertz_mortar punch_mortar; do
    stamp "fenicsx_crosscheck.py $t (mortar rows)"
    if grep -q '^discretization = "mortar"' "$mortar_dir/$t.toml"; then
        SIGNORINI="$EXE" SIGNORINI_PYDEPS="$PYDEPS" /usr/bin/python3 scripts/fenicsx_crosscheck.py "$mortar_dir/$t.toml" --tol 1e-8 --part b
        record "crosscheck $t" $?
    else
        echo "FAIL $t: the mortar variant was not written (sed did not match)" >&2
        record "crosscheck $t" 1
    fi
done

# Axisymmetric models (docs/methods.md §10), r-weighted forms in FEniCSx:
# a cup with its bottom on the axis (pressure, gravity, spin, two steps)
# and a plug on a conforming seat,
# a half-ball on a block (NTS; mortar rows, part b only) and a shrink fit
# with interference = true (NTS and mortar sleeves).
for t in axi_cup/axi_cup axi_sphere/axi_sphere axi_sphere/axi_sphere_mortar:b axi_shrink/axi_shrink; do
    part=both
    case $t in *:b) part=b; t=${t%:b} ;; esac
    stamp "fenicsx_crosscheck.py tests/data/$t.toml (axisymmetric, part $part)"
    SIGNORINI="$EXE" SIGNORINI_PYDEPS="$PYDEPS" /usr/bin/python3 scripts/fenicsx_crosscheck.py "tests/data/$t.toml" --tol 1e-8 --part $part
    record "crosscheck ${t#*/}" $?
done

stamp "finished"
[ $failed -eq 0 ] || echo "python_checks: failed: ${failed_names[*]}" >&2
echo "python_checks: $passed passed, $failed failed"
[ $failed -eq 0 ]
