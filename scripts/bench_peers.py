#!/usr/bin/env python3
"""Peer QP solvers (Clarabel, OSQP) on a QP exported by `signorini export --qp DIR`.

Usage:
    .venv/bin/python scripts/bench_peers.py DIR [--solvers clarabel,osqp] [--time-limit SEC]
                                               [--repeats R] [--json OUT.json] [--in-process]
                                               [--mem-limit MB]

(`source scripts/bench_setup.sh` installs the pinned Clarabel/OSQP/SciPy into .venv.)

Input (the export contract, format "signorini-qp" version 1):
    DIR/C.mtx   Matrix Market coordinate real symmetric, n×n, lower triangle (C SPD or PSD)
    DIR/A.mtx   coordinate real general, m×n
    DIR/d.mtx   array real general, n×1;  DIR/g.mtx  array real general, m×1
    DIR/meta.json  {"format": "signorini-qp", "version": 1, "n", "m", "kernel_dim", "energy", ...}
    DIR/x.mtx   (optional) signorini's solution, n×1
The problem is  min ½xᵀCx − dᵀx  s.t.  Ax ≤ g.  It is handed to the solvers exactly as
exported (no scaling here: both solvers equilibrate the data themselves).

Solvers and settings
    clarabel  interior point.  P = triu(C) (CSC), q = −d, Ax + s = g, s ∈ NonnegativeCone(m);
              tol_gap_abs = tol_gap_rel = tol_feas = 1e-8, time_limit, verbose off, all
              other settings Clarabel's defaults (QDLDL direct solver).
              converged ⇔ status "Solved" ("AlmostSolved" is reported, not counted).
    osqp      ADMM.  P = triu(C) (CSC), q = −d, A, l = −inf, u = g;
              eps_abs = eps_rel = 1e-6, max_iter = 100000, time_limit, polishing on,
              other settings OSQP's defaults (direct QDLDL linear solver, adaptive rho).
              OSQP may stall on positive semidefinite (floating body) or badly scaled
              problems: its status is reported as it is; converged ⇔ status "solved".

Timings (time.perf_counter, medians over --repeats): t_read = reading C, A, d, g (+ meta)
with scipy.io.mmread; t_setup = building the solver's matrices (triu, CSC) and its setup
(Clarabel: DefaultSolver(...), which factors symbolically; OSQP: setup(), which scales and
factors the KKT matrix); t_solve = solve(); t_total = t_read + t_setup + t_solve.

Quality (of the last repeat's solution x):
    objective    ½xᵀCx − dᵀx (C the full symmetric matrix)
    rel_obj_diff |J − J*| / |J*|, J* = meta.json "energy" (signorini's optimum; when it is null
                 and x.mtx is present, J* = objective of signorini's x)
    rel_x_diff   ‖x − x_sig‖₂ / ‖x_sig‖₂ when x.mtx is present
    violation    max(Ax − g)₊ / max(‖g‖∞, ‖|A||x|‖∞): the largest constraint violation relative
                 to the scale of g and of the terms of Ax (0 when feasible)

By default each solver runs in a child process (this script with --worker), so a crash, an
out-of-memory kill or a hang (wall-clock cap: repeats × (2 × time limit + 60 s) + 60 s) is
reported as that solver's status and the other solvers still run (the child is killed with
its parent, PR_SET_PDEATHSIG, should an outer timeout kill this script); --in-process runs them
here (no protection against hard crashes).  --mem-limit MB caps the child's address space
(RLIMIT_AS), so running out of memory becomes a MemoryError / failed allocation status.

Output: one line per solver; --json OUT writes a list of dicts {solver, version, status,
converged, iterations, t_read, t_setup, t_solve, t_total, objective, rel_obj_diff, rel_x_diff,
violation, ...} (a few extra keys: repeats, max_rss_mb, error, settings).
Exit status: 0 when the input could be read (even if a peer failed: it is a benchmark),
2 on unreadable input or bad usage.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
import traceback
from pathlib import Path

SOLVERS = ("clarabel", "osqp")
TOL_CLARABEL = 1e-8
EPS_OSQP = 1e-6
OSQP_MAX_ITER = 100000


class InputError(Exception):
    """The QP directory cannot be read (exit 2)."""


def _imports():
    try:
        import numpy as np
        import scipy.io
        import scipy.sparse as sp
    except ImportError as e:
        raise InputError(f"{e} under {sys.executable}: run `source scripts/bench_setup.sh` "
                         "and use .venv/bin/python")
    return np, scipy.io, sp


# ------------------------------------------------------------------- input


def read_meta(qp: Path) -> dict:
    mp = qp / "meta.json"
    if not qp.is_dir():
        raise InputError(f"{qp} is not a directory")
    if not mp.is_file():
        raise InputError(f"{mp} is missing")
    try:
        meta = json.loads(mp.read_text())
    except (OSError, ValueError) as e:
        raise InputError(f"{mp}: {e}")
    if meta.get("format") != "signorini-qp":
        raise InputError(f"{mp}: format is {meta.get('format')!r}, expected 'signorini-qp'")
    if int(meta.get("version", 0)) != 1:
        raise InputError(f"{mp}: version {meta.get('version')!r} is not supported (1 is)")
    try:
        meta["n"], meta["m"] = int(meta["n"]), int(meta["m"])
    except (KeyError, TypeError, ValueError):
        raise InputError(f"{mp}: n and m must be integers")
    return meta


def _file(qp: Path, meta: dict, key: str) -> Path:
    name = (meta.get("files") or {}).get(key, f"{key}.mtx")
    return qp / name


def _mm_header(path: Path):
    """(banner fields, size-line integers) of a Matrix Market file."""
    with open(path, "r") as f:
        banner = f.readline().split()
        if len(banner) < 5 or banner[0].lower() != "%%matrixmarket" or banner[1].lower() != "matrix":
            raise InputError(f"{path}: not a Matrix Market matrix file")
        line = f.readline()
        while line and (line.startswith("%") or not line.strip()):
            line = f.readline()
        try:
            size = [int(t) for t in line.split()]
        except ValueError:
            raise InputError(f"{path}: bad size line {line.strip()!r}")
    return [b.lower() for b in banner[2:5]], size


def read_array(path: Path):
    """A dense `array real general` Matrix Market file as a vector (own parser: scipy 1.17's
    mmread dies with SIGFPE on a 0×1 array, which an export without contact rows has)."""
    np = _imports()[0]
    kind, size = _mm_header(path)
    if kind[0] != "array" or kind[1] not in ("real", "double", "integer") or len(size) != 2:
        raise InputError(f"{path}: expected `array real general`, got {' '.join(kind)}")
    r, c = size
    with open(path, "r") as f:
        body = [ln for ln in f.read().splitlines() if ln.strip() and not ln.startswith("%")]
    vals = np.array(" ".join(body[1:]).split(), dtype=float)
    if vals.size != r * c:
        raise InputError(f"{path}: {vals.size} values for a {r}×{c} array")
    return vals.reshape((c, r)).T.ravel() if c > 1 else vals


def read_coordinate(path: Path, n_rows: int, n_cols: int):
    np, sio, sp = _imports()
    kind, size = _mm_header(path)
    if kind[0] != "coordinate" or len(size) != 3:
        raise InputError(f"{path}: expected a `coordinate` matrix, got {' '.join(kind)}")
    if size[2] == 0 or size[0] == 0 or size[1] == 0:  # nothing to parse (and no empty-file edge cases)
        return sp.csc_matrix((size[0], size[1]))
    return sp.csc_matrix(sio.mmread(str(path)))


def read_qp(qp: Path):
    """(C full symmetric CSC, A CSC, d, g, meta) — the timed read."""
    np, sio, sp = _imports()
    meta = read_meta(qp)
    n, m = int(meta["n"]), int(meta["m"])
    try:
        C = read_coordinate(_file(qp, meta, "C"), n, n)
        A = read_coordinate(_file(qp, meta, "A"), m, n)
        d = read_array(_file(qp, meta, "d"))
        g = read_array(_file(qp, meta, "g"))
    except InputError:
        raise
    except Exception as e:  # noqa: BLE001 (any parse error: unreadable input)
        raise InputError(f"reading {qp}: {type(e).__name__}: {e}")
    if C.shape != (n, n) or A.shape != (m, n) or d.shape != (n,) or g.shape != (m,):
        raise InputError(f"{qp}: shapes C {C.shape}, A {A.shape}, d {d.shape}, g {g.shape} "
                         f"do not match meta n = {n}, m = {m}")
    return C, A, d, g, meta


def read_reference(qp: Path, meta: dict):
    p = _file(qp, meta, "x")
    if not p.is_file():
        return None
    try:
        x = read_array(p)
    except Exception as e:  # noqa: BLE001
        print(f"bench_peers: warning: cannot read {p}: {e}; no rel_x_diff", file=sys.stderr)
        return None
    return x if x.shape == (int(meta["n"]),) else None


# ----------------------------------------------------------------- quality


def objective(C, d, x) -> float:
    return float(0.5 * x @ (C @ x) - d @ x)


def violation(A, g, x) -> float:
    np = _imports()[0]
    if A.shape[0] == 0:
        return 0.0
    r = A @ x - g
    scale = max(np.abs(g).max(initial=0.0), (abs(A) @ np.abs(x)).max(initial=0.0), 1e-300)
    return float(max(r.max(initial=0.0), 0.0) / scale)


def quality(C, A, d, g, x, j_ref, x_ref) -> dict:
    np = _imports()[0]
    out = {"objective": None, "rel_obj_diff": None, "rel_x_diff": None, "violation": None}
    if x is None or len(x) != C.shape[0] or not np.all(np.isfinite(x)):
        return out
    J = objective(C, d, x)
    out["objective"] = J
    out["violation"] = violation(A, g, x)
    if j_ref is not None and math.isfinite(j_ref):
        out["rel_obj_diff"] = abs(J - j_ref) / max(abs(j_ref), 1e-300)
    if x_ref is not None:
        out["rel_x_diff"] = float(np.linalg.norm(x - x_ref) / max(np.linalg.norm(x_ref), 1e-300))
    return out


# ----------------------------------------------------------------- solvers


def run_clarabel(C, A, d, g, time_limit):
    import clarabel
    import numpy as np
    import scipy.sparse as sp

    t0 = time.perf_counter()
    P = sp.triu(C, format="csc")
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.tol_gap_abs = TOL_CLARABEL
    settings.tol_gap_rel = TOL_CLARABEL
    settings.tol_feas = TOL_CLARABEL
    settings.time_limit = float(time_limit)
    m = A.shape[0]
    cones = [clarabel.NonnegativeConeT(m)] if m > 0 else []
    solver = clarabel.DefaultSolver(P, -d, A, g, cones, settings)
    t1 = time.perf_counter()
    sol = solver.solve()
    t2 = time.perf_counter()
    status = str(sol.status)
    x = np.array(sol.x, dtype=float)
    return dict(status=status, converged=status == "Solved", iterations=int(sol.iterations),
                x=x, t_setup=t1 - t0, t_solve=t2 - t1)


def run_osqp(C, A, d, g, time_limit):
    import numpy as np
    import osqp
    import scipy.sparse as sp

    t0 = time.perf_counter()
    P = sp.triu(C, format="csc")
    m = A.shape[0]
    prob = osqp.OSQP()
    prob.setup(P, -d, A, np.full(m, -np.inf), g, eps_abs=EPS_OSQP, eps_rel=EPS_OSQP,
               max_iter=OSQP_MAX_ITER, time_limit=float(time_limit), polishing=True, verbose=False)
    t1 = time.perf_counter()
    res = prob.solve(raise_error=False)
    t2 = time.perf_counter()
    status = str(res.info.status)
    x = None if res.x is None else np.array(res.x, dtype=float)
    extra = {"polish_status": int(getattr(res.info, "status_polish", 0))}
    return dict(status=status, converged=status == "solved", iterations=int(res.info.iter),
                x=x, t_setup=t1 - t0, t_solve=t2 - t1, **extra)


RUNNERS = {"clarabel": run_clarabel, "osqp": run_osqp}


def solver_version(name: str) -> str | None:
    try:
        if name == "clarabel":
            import clarabel
            return str(getattr(clarabel, "__version__", None) or clarabel.__version__)
        if name == "osqp":
            import osqp
            return str(osqp.__version__)
    except Exception:  # noqa: BLE001
        return None
    return None


def settings_of(name: str, time_limit: float) -> dict:
    if name == "clarabel":
        return {"tol_gap_abs": TOL_CLARABEL, "tol_gap_rel": TOL_CLARABEL, "tol_feas": TOL_CLARABEL,
                "time_limit": time_limit}
    return {"eps_abs": EPS_OSQP, "eps_rel": EPS_OSQP, "max_iter": OSQP_MAX_ITER,
            "time_limit": time_limit, "polishing": True}


def bench_one(name: str, qp: Path, time_limit: float, repeats: int) -> dict:
    """All repeats of one solver in this process; never raises for a solver failure."""
    import resource

    rec = {"solver": name, "version": solver_version(name), "status": None, "converged": False,
           "iterations": None, "t_read": None, "t_setup": None, "t_solve": None, "t_total": None,
           "objective": None, "rel_obj_diff": None, "rel_x_diff": None, "violation": None,
           "repeats": 0, "settings": settings_of(name, time_limit)}
    if rec["version"] is None:
        rec["status"] = f"not installed (import {name} failed under {sys.executable})"
        return rec
    _imports()  # module imports are not part of t_read
    times = {"t_read": [], "t_setup": [], "t_solve": [], "t_total": []}
    last = None
    data = None
    for r in range(repeats):
        t0 = time.perf_counter()
        C, A, d, g, meta = read_qp(qp)  # InputError propagates (exit 2)
        t_read = time.perf_counter() - t0
        data = (C, A, d, g, meta)
        try:
            res = RUNNERS[name](C, A, d, g, time_limit)
        except MemoryError:
            rec["status"] = "failed: out of memory (MemoryError)"
            rec["error"] = "MemoryError"
            break
        except Exception as e:  # noqa: BLE001
            rec["status"] = f"failed: {type(e).__name__}: {e}"
            rec["error"] = traceback.format_exc(limit=3)
            break
        times["t_read"].append(t_read)
        times["t_setup"].append(res["t_setup"])
        times["t_solve"].append(res["t_solve"])
        times["t_total"].append(t_read + res["t_setup"] + res["t_solve"])
        last = res
        rec["repeats"] = r + 1
        if not res["converged"]:
            break  # a failed / timed-out run is not repeated
    for k, v in times.items():
        rec[k] = statistics.median(v) if v else None
    if last is not None:
        C, A, d, g, meta = data
        x_ref = read_reference(qp, meta)
        j_ref = meta.get("energy")
        if j_ref is None and x_ref is not None:
            j_ref = objective(C, d, x_ref)
        rec["status"] = last["status"] if rec["status"] is None else rec["status"]
        rec["converged"] = bool(last["converged"]) and "error" not in rec
        rec["iterations"] = last["iterations"]
        rec.update(quality(C, A, d, g, last["x"], j_ref, x_ref))
        for k in ("polish_status",):
            if k in last:
                rec[k] = last[k]
    rec["max_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return rec


def bench_isolated(name: str, qp: Path, time_limit: float, repeats: int, mem_limit: float | None) -> dict:
    """bench_one in a child process (this script, --worker)."""
    base = {"solver": name, "version": None, "status": None, "converged": False, "iterations": None,
            "t_read": None, "t_setup": None, "t_solve": None, "t_total": None, "objective": None,
            "rel_obj_diff": None, "rel_x_diff": None, "violation": None, "repeats": 0,
            "settings": settings_of(name, time_limit)}
    with tempfile.TemporaryDirectory(prefix="bench_peers_") as tmp:
        out = Path(tmp) / "result.json"
        cmd = [sys.executable, str(Path(__file__).resolve()), str(qp), "--worker", name,
               "--time-limit", str(time_limit), "--repeats", str(repeats), "--json", str(out)]
        if mem_limit:
            cmd += ["--mem-limit", str(mem_limit)]
        cap = repeats * (2 * time_limit + 60) + 60
        try:
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=cap)
        except subprocess.TimeoutExpired:
            base["version"] = solver_version(name)
            base["status"] = f"killed: no result after the wall-clock cap of {cap:.0f} s"
            return base
        if out.is_file():
            try:
                recs = json.loads(out.read_text())
                if recs:
                    return recs[0]
            except ValueError:
                pass
        base["version"] = solver_version(name)
        if p.returncode == 2:
            raise InputError(p.stderr.strip().splitlines()[-1] if p.stderr.strip() else "unreadable input")
        if p.returncode < 0:
            sig = -p.returncode
            hint = " (out of memory? the kernel's OOM killer sends 9)" if sig == 9 else ""
            if mem_limit:
                hint = f" (probably out of memory under --mem-limit {mem_limit:g} MB)"
            base["status"] = f"killed by signal {sig}{hint}"
        else:
            tail = (p.stderr.strip().splitlines() or ["no output"])[-1]
            base["status"] = f"failed: worker exited {p.returncode}: {tail}"
        base["error"] = p.stderr[-2000:]
        return base


def _die_with_parent() -> None:
    """Linux: SIGKILL this worker when its parent dies (e.g. killed by an outer timeout), so
    no orphaned solver keeps a core busy."""
    import signal
    try:
        import ctypes
        libc = ctypes.CDLL("libc.so.6", use_errno=True)
        libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)  # PR_SET_PDEATHSIG
    except Exception:  # noqa: BLE001 (not Linux / no libc: no protection)
        return
    if os.getppid() == 1:  # the parent is already gone
        sys.exit(1)


# -------------------------------------------------------------------- main


def fmt(v, spec):
    return "-" if v is None else format(v, spec)


def line(rec: dict) -> str:
    return (f"{rec['solver']:<9} {str(rec.get('version')):<7} {str(rec['status'])[:40]:<22} "
            f"it {fmt(rec['iterations'], '>6')}  read {fmt(rec['t_read'], '8.3f')}  "
            f"setup {fmt(rec['t_setup'], '8.3f')}  solve {fmt(rec['t_solve'], '8.3f')}  "
            f"total {fmt(rec['t_total'], '8.3f')} s  J {fmt(rec['objective'], '.10e')}  "
            f"dJ {fmt(rec['rel_obj_diff'], '.1e')}  dx {fmt(rec['rel_x_diff'], '.1e')}  "
            f"viol {fmt(rec['violation'], '.1e')}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("qp", type=Path, help="directory written by `signorini export --qp DIR`")
    ap.add_argument("--solvers", default="clarabel,osqp", help="comma-separated: clarabel,osqp")
    ap.add_argument("--time-limit", type=float, default=300.0, help="per solve, seconds (default 300)")
    ap.add_argument("--repeats", type=int, default=1, help="runs per solver; times are medians")
    ap.add_argument("--json", type=Path, default=None, help="write the results as a JSON list")
    ap.add_argument("--in-process", action="store_true", help="run the solvers in this process")
    ap.add_argument("--mem-limit", type=float, default=None, help="address-space cap per solver, MB")
    ap.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)

    solvers = [s.strip().lower() for s in args.solvers.split(",") if s.strip()]
    bad = [s for s in solvers if s not in SOLVERS]
    if bad or not solvers or args.repeats < 1 or args.time_limit <= 0:
        print(f"bench_peers: error: unknown solver(s) {bad} (known: {', '.join(SOLVERS)}) "
              "or bad --repeats/--time-limit", file=sys.stderr)
        return 2

    if args.worker:  # child: one solver, result to --json
        _die_with_parent()
        if args.mem_limit:
            import resource
            lim = int(args.mem_limit * 1024 * 1024)
            resource.setrlimit(resource.RLIMIT_AS, (lim, lim))
        rec = bench_one(args.worker, args.qp, args.time_limit, args.repeats)
        args.json.write_text(json.dumps([rec], indent=1, default=float))
        return 0

    # the parent reads the input once itself: unreadable input -> exit 2 before any solver
    _imports()  # numpy/scipy present, else exit 2
    C, A, d, g, meta = read_qp(args.qp)
    x_ref = read_reference(args.qp, meta)
    j_meta = meta.get("energy")
    import scipy.sparse as sp
    print(f"QP {args.qp}: n = {meta['n']}, m = {meta['m']}, nnz(C, lower) = {sp.tril(C).nnz}, "
          f"nnz(A) = {A.nnz}, kernel_dim = {meta.get('kernel_dim')}, problem {meta.get('problem')}")
    if x_ref is not None:
        print(f"reference (signorini x.mtx): J = {objective(C, d, x_ref):.10e}, meta energy = {j_meta}, "
              f"violation {violation(A, g, x_ref):.1e}")
    else:
        print(f"reference: meta energy = {j_meta} (no x.mtx)")
    print(f"settings: clarabel tol_gap_abs/rel = tol_feas = {TOL_CLARABEL:g}; osqp eps_abs = eps_rel = "
          f"{EPS_OSQP:g}, max_iter {OSQP_MAX_ITER}, polishing on; time limit {args.time_limit:g} s; "
          f"repeats {args.repeats} (median times)")
    del C, A, d, g

    results = []
    for s in solvers:
        try:
            if args.in_process:
                rec = bench_one(s, args.qp, args.time_limit, args.repeats)
            else:
                rec = bench_isolated(s, args.qp, args.time_limit, args.repeats, args.mem_limit)
        except InputError:
            raise
        except Exception as e:  # noqa: BLE001 (never crash on a peer)
            rec = {"solver": s, "version": solver_version(s), "status": f"failed: {type(e).__name__}: {e}",
                   "converged": False, "iterations": None, "t_read": None, "t_setup": None,
                   "t_solve": None, "t_total": None, "objective": None, "rel_obj_diff": None,
                   "rel_x_diff": None, "violation": None}
        results.append(rec)
        print(line(rec), flush=True)
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(results, indent=1, default=float) + "\n")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except InputError as e:
        print(f"bench_peers: error: {e}", file=sys.stderr)
        sys.exit(2)
