#!/usr/bin/env python3
"""An independent solver on signorini's exported QP, friction included: Clarabel
(an interior-point conic solver) on the problem of `signorini export --qp DIR
--solution`, compared with signorini's x, lambda and energy.

Usage:
    python3 scripts/peer_friction.py DIR [DIR ...] [--tol 1e-5]   (numpy, scipy, clarabel)

The problem (docs/guide.md §10, meta.json "objective"): with k = meta
"tangential_rows" (1 in 2D, 2 in 3D) rows of T per contact row i,

    min  1/2 x'Cx - d'x + sum_i s_i ||v_i||_2,   v_i = (Tx - t0)[k i : k i + k]
    s.t. Ax <= g,

a second-order cone program: an epigraph variable tau_i >= ||v_i|| per contact
row, so that Clarabel solves, over z = (x, tau),

    min 1/2 x'Cx - d'x + s'tau   s.t.  g - Ax in R+^m,  (tau_i, v_i) in SOC(1 + k).

Tresca: s is s.mtx. Coulomb (s = mu lambda, a fixed point, no convex program of
its own): s_i = mu_i lambda_i with signorini's lambda; signorini's answer must
then be the Tresca problem's own solution (the fixed point's defining
property), which Clarabel finds independently. Without friction the cone
part is empty and this is the QP of bench_peers.py.

Compared: ||x - x_sig|| / ||x_sig||, ||lambda - lambda_sig|| / ||lambda_sig||
(Clarabel's duals of the nonnegative cone), and the objective J at each x.
A check passes when Clarabel says Solved, both relative differences are
<= --tol (default 1e-5: an interior-point method's x and duals on these
stiffness matrices, 1e11 on the diagonal against displacements of 1e-2,
are good to about 1e-6; signorini's pass a KKT target of 1e-8) and
signorini's objective is no higher than Clarabel's by more than 1e-12 of it
(J is flat at the optimum: it tells which answer is nearer, and on every
model tried so far signorini's is the lower). Exit 0 when every DIR passes, 1 when one does not, 2 on
unreadable input.

Written for signorini (no code copied); the cone form is Clarabel's
documented standard form (A z + s = b, s in K; P upper triangular).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import scipy.io
import scipy.sparse as sp


def read_vec(path: Path) -> np.ndarray:
    # Matrix Market "array" files: header comments, a size line, one value per line.
    vals = []
    size_seen = False
    for line in path.read_text().splitlines():
        if line.startswith("%") or not line.strip():
            continue
        if not size_seen:
            size_seen = True
            continue
        vals.append(float(line.split()[0]))
    return np.array(vals)


def read_mat(path: Path) -> sp.csr_matrix:
    return sp.csr_matrix(scipy.io.mmread(str(path)))


def check(d: Path, tol: float) -> bool:
    import clarabel

    meta = json.loads((d / "meta.json").read_text())
    if meta.get("format") != "signorini-qp":
        raise ValueError(f"{d}/meta.json: not a signorini export")
    c = read_mat(d / "C.mtx")
    a = read_mat(d / "A.mtx")
    dv, g = read_vec(d / "d.mtx"), read_vec(d / "g.mtx")
    x_sig, l_sig = read_vec(d / "x.mtx"), read_vec(d / "lambda.mtx")
    n, m = dv.size, g.size
    law = meta.get("friction")
    k = int(meta.get("tangential_rows", 1)) if law else 0
    if law:
        t = read_mat(d / "T.mtx")
        t0 = read_vec(d / "t0.mtx")
        if law == "tresca":
            s = read_vec(d / "s.mtx")
        else:
            s = read_vec(d / "mu.mtx") * np.maximum(l_sig, 0.0)
        if t.shape != (k * m, n) or s.size != m:
            raise ValueError(f"{d}: T is {t.shape}, s has {s.size}; expected ({k * m}, {n}), {m}")
    nz = n + (m if law else 0)
    # P = [C 0; 0 0] (upper triangle), q = (-d, s); Clarabel equilibrates
    # the data itself (scaling x here by the load's length scale made the
    # stacked cubes' solve stop short, AlmostSolved).
    p = sp.block_diag([c, sp.csr_matrix((nz - n, nz - n))]).tocsc()
    p = sp.triu(p).tocsc()
    q = np.concatenate([-dv, s if law else np.zeros(0)])
    # Nonnegative cone: s = g - A x >= 0  ->  [A 0] z + s = g.
    blocks = [sp.hstack([a, sp.csr_matrix((m, nz - n))])]
    rhs = [g]
    cones = [clarabel.NonnegativeConeT(m)] if m else []
    if law:
        # Per contact row i: s = (tau_i, T_i x - t0_i) in SOC(1 + k):
        # tau_i = -(-tau_i) -> row [0, -e_i], b = 0; T_i x - t0_i -> row [-T_i, 0], b = -t0_i.
        rows, b = [], []
        for i in range(m):
            e = sp.csr_matrix(([-1.0], ([0], [n + i])), shape=(1, nz))
            rows.append(e)
            b.append(0.0)
            ti = t[k * i : k * i + k]
            rows.append(sp.hstack([-ti, sp.csr_matrix((k, nz - n))]))
            b.extend(-t0[k * i : k * i + k])
            cones.append(clarabel.SecondOrderConeT(1 + k))
        blocks.extend(rows)
        rhs.append(np.array(b))
    amat = sp.vstack(blocks).tocsc()
    bvec = np.concatenate(rhs)
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = 1e-9
    settings.max_iter = 400
    sol = clarabel.DefaultSolver(p, q, amat, bvec, cones, settings).solve()
    status = str(sol.status)
    z = np.array(sol.x)
    x = z[:n]
    lam = np.array(sol.z)[:m]
    dx = np.linalg.norm(x - x_sig) / max(np.linalg.norm(x_sig), 1e-300)
    dl = np.linalg.norm(lam - l_sig) / max(np.linalg.norm(l_sig), 1e-300)

    def objective(xx: np.ndarray) -> float:
        j = 0.5 * xx @ (c @ xx) - dv @ xx
        if law:
            v = (t @ xx - t0).reshape(m, k)
            j += float(s @ np.linalg.norm(v, axis=1))
        return float(j)

    j, j_sig = objective(x), objective(x_sig)
    # signorini's x (feasible: its certificate) must be no worse than
    # Clarabel's by more than rounding: J(x_sig) - J(x) <= 1e-12 |J|.
    dj = (j_sig - j) / max(abs(j_sig), 1e-300)
    ok = (
        status.endswith("Solved")
        and not status.endswith("AlmostSolved")
        and dx <= tol
        and dl <= tol
        and dj <= 1e-12
    )
    print(
        f"{'PASS' if ok else 'FAIL'}  {d}: {meta.get('dim', 2)}D, n = {n}, m = {m}, "
        f"friction {law or 'none'}{f' ({k} per row)' if law else ''}; Clarabel {status} in "
        f"{sol.iterations} iterations; |x - x_sig|/|x_sig| = {dx:.2e}, "
        f"|lambda - lambda_sig|/|lambda_sig| = {dl:.2e}; J(x) = {j:.12e}, "
        f"J(x_sig) = {j_sig:.12e}, (J(x_sig) - J(x))/|J| = {dj:.1e}"
    )
    return ok


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dirs", nargs="+", type=Path)
    ap.add_argument("--tol", type=float, default=1e-5)
    args = ap.parse_args()
    ok = True
    for d in args.dirs:
        try:
            ok &= check(d, args.tol)
        except (OSError, ValueError, KeyError) as e:
            print(f"peer_friction: {d}: {e}", file=sys.stderr)
            return 2
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
