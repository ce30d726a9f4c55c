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
#      the axisymmetric models tests/data/axi_* (r-weighted forms), and
#      frictional models (Tresca, Coulomb; plane and axisymmetric; λ_t, slip
#      and stick/slip states compared too).
#
# Usage: bash scripts/python_checks.sh [NAME ...]   (default: the examples below)
#   SIGNORINI_WITH_PARAVIEW=1  also install Debian's python3-paraview (it provides
#                              pvpython, ~450 MB) so check_outputs.py opens the files
#                              with ParaView's readers too, and run pvpython headless
#                              under `xvfb-run -a` on the first example: arrays and
#                              their ComponentName (sxx, ux, ...) as ParaView sees
#                              them (skipped with a note otherwise)
#   SIGNORINI_CHECK_OUT=DIR    keep the outputs and PNGs there (default: temp dir)
#   SIGNORINI=PATH             use this signorini binary instead of building
#                              target/release/signorini (cargo build --release)
# Exit status: 0 when every check passed; a cross-check that answers NOT
# CHECKED (exit 3: the reference cannot check the model) is counted apart and
# also makes the status non-zero, since every model listed here must be checked.
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
if [ -n "${SIGNORINI:-}" ]; then
    [ -x "$SIGNORINI" ] || { echo "python_checks: SIGNORINI=$SIGNORINI is not an executable" >&2; exit 2; }
    EXE=$(cd "$(dirname "$SIGNORINI")" && pwd)/$(basename "$SIGNORINI")
    stamp "using SIGNORINI=$EXE (no build)"
else
    cargo build --release 2>&1 | tail -n 3
    [ "${PIPESTATUS[0]}" -eq 0 ] || { echo "python_checks: cargo build --release failed" >&2; exit 2; }
    EXE=$ROOT/target/release/signorini
    stamp "build done"
fi

# ------------------------------------------------------------------ checks
passed=0
failed=0
failed_names=()
unchecked=0
unchecked_names=()
record() {  # name, status (fenicsx_crosscheck.py: 3 = NOT CHECKED)
    if [ "$2" -eq 0 ]; then passed=$((passed + 1))
    elif [ "$2" -eq 3 ]; then unchecked=$((unchecked + 1)); unchecked_names+=("$1")
    else failed=$((failed + 1)); failed_names+=("$1"); fi
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

# 3D models (P1 tetrahedra, scripts/fenicsx_crosscheck3d.py): the shipped
# cantilever; a steel base under an aluminium cover with a rubber plug held
# by three slip planes (two of them meet on an edge), pn and p tractions and
# gravity; contact: stacked cubes with a conforming interface and with
# node-to-surface rows and with mortar rows (steel under rubber, the upper
# cube held along z by contact alone), and a half-sphere on a block (NTS and
# mortar, a partial contact zone). About 3 s each.
for t in meshes/3d/cantilever_3d.toml tests/data/solid/xcheck/twomat.toml \
         tests/data/solid/xcheck/stack_conforming.toml tests/data/solid/xcheck/stack_nts.toml \
         tests/data/solid/xcheck/stack_mortar.toml \
         tests/data/solid/xcheck/hertz_nts.toml tests/data/solid/xcheck/hertz_mortar.toml; do
    stamp "fenicsx_crosscheck.py $t (3D)"
    SIGNORINI="$EXE" SIGNORINI_PYDEPS="$PYDEPS" /usr/bin/python3 scripts/fenicsx_crosscheck.py "$t" --tol 1e-8
    record "crosscheck $(basename "$t" .toml)" $?
done

# Code_Aster SSNV104's two hemispheres in 3D (verification/ssnv104, hc = 2 mm,
# meshed here): mortar rows between two curved caps, the displacements
# prescribed. Without max_gap, which the reference does not model (no
# limit: every slave node finds the master ahead; 33 of 103 rows active). 2 s.
hemi_dir=$OUT/hemispheres
mkdir -p "$hemi_dir"
if gmsh -3 -format msh41 -v 1 -setnumber hc 2 verification/ssnv104/ssnv104_3d.geo -o "$hemi_dir/ssnv104_3d.msh" >/dev/null \
    && sed '/^max_gap = /d' verification/ssnv104/ssnv104_3d.toml > "$hemi_dir/ssnv104_3d.toml" \
    && ! grep -q '^max_gap' "$hemi_dir/ssnv104_3d.toml"; then
    stamp "fenicsx_crosscheck.py ssnv104_3d (3D, mortar between two curved caps)"
    SIGNORINI="$EXE" SIGNORINI_PYDEPS="$PYDEPS" /usr/bin/python3 scripts/fenicsx_crosscheck.py "$hemi_dir/ssnv104_3d.toml" --tol 1e-8
    record "crosscheck ssnv104_3d" $?
else
    echo "FAIL ssnv104_3d: gmsh could not mesh it, or the variant without max_gap was not written" >&2
    record "crosscheck ssnv104_3d" 1
fi
# The mortar rows' reach without max_gap (verification_3d.md §7d): at
# hc = 1 mm the initial gap at the zone's edge exceeds the slave triangles;
# the rows must reach past the zone and the caps not overlap. A few s.
stamp "ssnv104 reach.py (3D mortar rows without max_gap)"
SIGNORINI="$EXE" "$VENV/bin/python" verification/ssnv104/reach.py
record "ssnv104 reach" $?

# Friction (docs/methods.md §9): signorini's Tresca and Coulomb answers
# against the reference's own (Clarabel on the Tresca problem with auxiliary
# variables, polished; Coulomb by its own fixed point on s = μλ_n), comparing
# λ_t, the slip and the open/stick/slip states too. Plane strain:
# Cattaneo–Mindlin (verification/cattaneo, coarse hc = 0.02) with a third step
# that moves the block back, so the slip reverses and the path (the slip
# measured from the previous step) matters; the pad on two bumps (Coulomb, and
# Tresca by ssn and by mprgp); the patch test with mortar rows and Coulomb
# friction (its row on the line of symmetry has no tangential row). Plane
# stress: the hip with
# Tresca on its conforming joint (bound × thickness). Axisymmetric: the shrink
# fit (verification/shrinkfit, n = 8; its fit step has no load at all, only the
# interference) with Coulomb, with Tresca and frictionless, and the half-ball
# on a block with mortar rows and Coulomb friction (a row on the axis).
fric_dir=$OUT/friction
mkdir -p "$fric_dir"
absmesh() { sed "s#^file *= *\"\(.*\)\"#file = \"$1/\1\"#"; }
gmsh -2 -format msh41 -v 1 -setnumber hc 0.02 verification/cattaneo/cattaneo.geo -o "$fric_dir/cattaneo.msh" >/dev/null \
    && gmsh -2 -format msh41 -v 1 -setnumber n 8 verification/shrinkfit/shrinkfit.geo -o "$fric_dir/shrinkfit.msh" >/dev/null \
    && gmsh -2 -format msh41 -v 1 verification/patch/patch.geo -o "$fric_dir/patch.msh" >/dev/null \
    || { echo "FAIL gmsh could not mesh the friction models" >&2; record "gmsh friction meshes" 1; }
{ sed 's#^file = .*#file = "cattaneo.msh"#' verification/cattaneo/cattaneo.toml
  printf '\n[[steps]]\nfactor = 1.0\ndirichlet = { block_bottom = [2.0e-3, 0.0] }\n'; } > "$fric_dir/cattaneo3.toml"
absmesh "$ROOT/tests/data/bumps" < tests/data/bumps/bumps.toml > "$fric_dir/bumps.toml"
sed 's/^friction = 0.4$/tresca = 2.0e5/' "$fric_dir/bumps.toml" > "$fric_dir/bumps_tresca.toml"
sed 's/^method = "ssn"$/method = "mprgp"/' "$fric_dir/bumps_tresca.toml" > "$fric_dir/bumps_tresca_mprgp.toml"
sed 's#^file = .*#file = "patch.msh"#; s/^discretization = "mortar"$/discretization = "mortar"\nfriction = 0.3/' \
    verification/patch/patch_mortar.toml > "$fric_dir/patch_mortar_coulomb.toml"
absmesh "$ROOT/meshes" < meshes/hip.toml | sed 's/^on = "joint"$/on = "joint"\ntresca = 2.0e5/' > "$fric_dir/hip_tresca.toml"
sed 's#^file = .*#file = "shrinkfit.msh"#' verification/shrinkfit/shrinkfit.toml > "$fric_dir/shrinkfit.toml"
sed 's/^friction = 0.2$/tresca = 5.0e6/' "$fric_dir/shrinkfit.toml" > "$fric_dir/shrinkfit_tresca.toml"
sed '/^friction = 0.2$/d' "$fric_dir/shrinkfit.toml" > "$fric_dir/shrinkfit_frictionless.toml"
absmesh "$ROOT/tests/data/axi_sphere" < tests/data/axi_sphere/axi_sphere_mortar.toml \
    | sed 's/^master = "block_top"$/master = "block_top"\nfriction = 0.3/' > "$fric_dir/axi_sphere_mortar_coulomb.toml"
# name:part:the line the variant must have (a sed that did not match fails
# here):tolerance. mprgp's Tresca answers are exact to its tolerance, not to
# rounding (methods.md §9.2): 4.5e-8 in λ_t measured, hence 1e-6.
for t in cattaneo3:both:friction:1e-8 bumps:b:friction:1e-8 bumps_tresca:b:tresca:1e-8 \
         bumps_tresca_mprgp:b:method:1e-6 patch_mortar_coulomb:both:friction:1e-8 hip_tresca:b:tresca:1e-8 \
         shrinkfit:both:friction:1e-8 shrinkfit_tresca:b:tresca:1e-8 shrinkfit_frictionless:b:interference:1e-8 \
         axi_sphere_mortar_coulomb:b:friction:1e-8; do
    IFS=: read -r name part key tol <<< "$t"
    stamp "fenicsx_crosscheck.py $name (friction, part $part)"
    if ! grep -q "^$key = " "$fric_dir/$name.toml" \
        || { [ "$name" = shrinkfit_frictionless ] && grep -q '^friction' "$fric_dir/$name.toml"; } \
        || { [ "$name" = bumps_tresca_mprgp ] && ! grep -q '^method = "mprgp"' "$fric_dir/$name.toml"; }; then
        echo "FAIL $name: the variant was not written (sed did not match)" >&2
        record "crosscheck $name" 1
        continue
    fi
    SIGNORINI="$EXE" SIGNORINI_PYDEPS="$PYDEPS" /usr/bin/python3 scripts/fenicsx_crosscheck.py "$fric_dir/$name.toml" --tol "$tol" --part $part
    record "crosscheck $name" $?
done

# The exported QP with friction against an independent conic solver
# (scripts/peer_friction.py: Clarabel on the second-order cone program of
# the Tresca problem, for Coulomb at s = mu lambda of signorini's answer;
# docs/verification_3d.md §7k): the 3D soft cube on a steel one (two
# tangential rows per contact row, tangents held on the planes of
# symmetry) with Coulomb and with Tresca, Cattaneo-Mindlin's sphere on a
# block (coarse, hc = 0.03) sheared in one step, and the 2D pad on two
# bumps (one row per contact row). About 5 s.
peer_dir=$OUT/peer
mkdir -p "$peer_dir"
cp tests/data/solid/xcheck/soft_cube_coulomb.toml "$peer_dir/"
sed -i "s#^file = .*#file = \"$ROOT/tests/data/solid_contact/stack_nm.msh\"#" "$peer_dir/soft_cube_coulomb.toml"
sed 's/^friction = 0.3$/tresca = 1.5e4/' "$peer_dir/soft_cube_coulomb.toml" > "$peer_dir/soft_cube_tresca.toml"
gmsh -3 -format msh22 -v 1 -setnumber hc 0.03 verification/cattaneo3d/cattaneo3d.geo -o "$peer_dir/cattaneo3d.msh" >/dev/null \
    || { echo "FAIL gmsh could not mesh cattaneo3d" >&2; record "gmsh cattaneo3d" 1; }
sed '/^\[\[steps\]\]/,$d; s#^file = .*#file = "cattaneo3d.msh"#; s#^u = \[0.0, 0.0, 0.0\]#u = [1.0e-3, 0.5e-3, 0.0]#' \
    verification/cattaneo3d/cattaneo3d.toml > "$peer_dir/cattaneo3d_sheared.toml"
cp "$fric_dir/bumps.toml" "$peer_dir/bumps.toml"
peer_dirs=()
for t in soft_cube_coulomb:friction soft_cube_tresca:tresca cattaneo3d_sheared:1.0e-3 bumps:friction; do
    IFS=: read -r name key <<< "$t"
    if ! grep -q "$key" "$peer_dir/$name.toml"; then
        echo "FAIL $name: the variant was not written (sed did not match)" >&2
        record "peer $name" 1
        continue
    fi
    if "$EXE" export --qp "$peer_dir/$name" "$peer_dir/$name.toml" --solution -q; then
        peer_dirs+=("$peer_dir/$name")
    else
        echo "FAIL signorini export $name" >&2
        record "peer $name" 1
    fi
done
if [ ${#peer_dirs[@]} -gt 0 ]; then
    stamp "peer_friction.py (Clarabel on the exported frictional QPs)"
    PYTHONPATH="$PYDEPS" /usr/bin/python3 scripts/peer_friction.py "${peer_dirs[@]}"
    record "peer friction" $?
fi

stamp "finished"
[ $failed -eq 0 ] || echo "python_checks: failed: ${failed_names[*]}" >&2
[ $unchecked -eq 0 ] || echo "python_checks: not checked (the reference cannot check them): ${unchecked_names[*]}" >&2
echo "python_checks: $passed passed, $failed failed, $unchecked not checked"
[ $failed -eq 0 ] && [ $unchecked -eq 0 ]
