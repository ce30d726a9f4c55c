#!/usr/bin/env bash
# Python side of the benchmark's peer solvers (idempotent).
#
#   bash scripts/bench_setup.sh          # or: source scripts/bench_setup.sh; bench_setup
#
# Makes sure <repo>/.venv exists (python3 -m venv) and that it imports the peer
# QP solvers used by scripts/bench_peers.py; pip runs only when an import fails.
# Tested versions (PyPI) below; override with BENCH_PY_PKGS="...".
# scripts/bench_fenicsx.py needs no pip package: it runs under Debian's
# /usr/bin/python3 with python3-dolfinx-real and python3-gmsh (apt, see
# scripts/python_checks.sh), which bench_setup checks and reports.

BENCH_PY_PKGS_DEFAULT="numpy==2.4.6 scipy==1.17.1 clarabel==0.11.1 osqp==1.1.3"

bench_setup() {
    local root venv pkgs
    root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
    venv=$root/.venv
    pkgs=${BENCH_PY_PKGS:-$BENCH_PY_PKGS_DEFAULT}
    if [ ! -x "$venv/bin/python" ]; then
        echo "bench_setup: creating $venv" >&2
        python3 -m venv "$venv" || { echo "bench_setup: python3 -m venv failed (apt-get install python3-venv)" >&2; return 2; }
    fi
    if ! "$venv/bin/python" -c "import numpy, scipy.io, scipy.sparse, clarabel, osqp" >/dev/null 2>&1; then
        echo "bench_setup: pip install $pkgs into $venv" >&2
        "$venv/bin/pip" install -q --no-cache-dir --disable-pip-version-check $pkgs \
            || { echo "bench_setup: pip install failed" >&2; return 2; }
        "$venv/bin/python" -c "import numpy, scipy.io, scipy.sparse, clarabel, osqp" \
            || { echo "bench_setup: the peers still do not import" >&2; return 2; }
    fi
    if ! /usr/bin/python3 -c "import dolfinx, gmsh, petsc4py" >/dev/null 2>&1; then
        echo "bench_setup: note: /usr/bin/python3 lacks dolfinx/gmsh/petsc4py; scripts/bench_fenicsx.py" \
             "needs apt-get install python3-dolfinx-real python3-gmsh" >&2
    fi
    return 0
}

# executed (not sourced): run it
if [ "${BASH_SOURCE[0]}" = "$0" ]; then
    set -uo pipefail
    bench_setup
    exit $?
fi
