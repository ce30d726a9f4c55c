#!/usr/bin/python3
"""FEniCSx (dolfinx) linear elastic solve of a signorini problem, timed per phase.

Usage:
    /usr/bin/python3 scripts/bench_fenicsx.py model.toml [--msh FILE.msh] [--solver lu|cholesky|cg-gamg]
                     [--repeats R] [--json OUT.json] [--check-json signorini.json] [--check-tol 1e-6]

Runs under Debian's python3 (python3-dolfinx-real 0.5.2, python3-gmsh, python3-petsc4py).

What is solved: the LINEAR ELASTIC problem without contact, on the mesh as it is: contact
curves are ordinary interior lines (the mesh is conforming there, so the bodies are glued).
This is what `signorini solve model.toml --no-contact` solves.  P1 vector Lagrange elements:

    a(u, v) = t ∫ 2μ ε(u):ε(v) + λ tr ε(u) tr ε(v) dx
    L(v)    = t ∫ ρ g·v dx + t ∫_Γτ (p + pn n)·v ds  (+ point forces t·f at physical points)

(plane stress: λ → 2λμ/(λ+2μ), t = [model] thickness; plane strain: t = 1), λ, μ, ρ
piecewise constant per material surface (DG0).  [[dirichlet]] on a curve or a point:
u = [ux, uy] or ux / uy alone.  [[slip]] (u·n = 0): supported when every segment of the line
is parallel to the x or to the y axis (all to the same one): then it is the Dirichlet
condition u_y = 0 resp. u_x = 0 on the line; any other slip line is IGNORED with a warning
(the answer is then not signorini's).  Non-matching [[contact]] pairs (slave/master) are not
glued by anything: such a problem usually has floating bodies, and signorini refuses it
with --no-contact.  [[steps]] are ignored (the base problem is solved; warning).

Phases (time.perf_counter; medians over --repeats, each repeat redoes everything):
    read      gmsh.open + dolfinx.io.gmshio.model_to_mesh (read_from_msh is broken in 0.5.2)
    compile   FFCx JIT (UFL → C → cffi) of the elements/dofmaps (P1 vector, DG0) and of the
              forms (dolfinx.fem.form).  FFCx caches the compiled code
              (~/.cache/fenics), so only a first run on a fresh machine pays the C compiler;
              t_compile_first is the first repeat's value, t_compile the median.
    assemble  function spaces (dofmaps), material and boundary data, assemble_matrix, assemble_vector,
              apply_lifting, set_bc
    solve     PETSc KSP setup + solve:
                lu        preonly + LU, MUMPS when PETSc has it (else PETSc's default LU)
                cholesky  preonly + Cholesky, MUMPS when available (the matrix is symmetric)
                cg-gamg   CG + GAMG with the rigid modes as near-nullspace, rtol 1e-10
    total     read + compile + assemble + solve

Reports the number of DOFs (all, and free = not prescribed), the displacement at the
[output] probes (nearest mesh node, as signorini does) and, with --check-json, the largest
relative probe difference against signorini's JSON output (NAME.json of
`signorini solve model.toml --no-contact --out DIR`): max over probes of
‖u_fenicsx − u_signorini‖₂ / ‖u_signorini‖₂ (the denominator floored at 1e-12 × the largest
probe displacement).

JSON (--json): {solver, dofs, dofs_free, t_read, t_compile, t_compile_first, t_assemble,
t_solve, t_total, probes: {name: [ux, uy]}, petsc_lu_package, ksp_type, pc_type,
ksp_iterations, ksp_reason, rel_residual, nodes, cells, repeats, warnings, check (when
--check-json)}.
Exit status: 0 done (and the check, if asked, within --check-tol), 1 check above --check-tol
or a failed solve (KSP not converged, or relative residual > 1e-6: a singular system, e.g. a
body left free), 2 usage / setup error.
"""

from __future__ import annotations

import argparse
import json
import logging
import statistics
import sys
import time
import tomllib
from pathlib import Path


class SetupError(Exception):
    """Bad usage, unreadable input or a missing tool (exit 2)."""


def log(msg: str) -> None:
    print(msg, flush=True)


def imports():
    try:
        import numpy as np
        import gmsh
        from mpi4py import MPI
        from petsc4py import PETSc
        import dolfinx
        import dolfinx.fem.petsc  # noqa: F401
        import dolfinx.io.gmshio  # noqa: F401
        import ufl
    except ImportError as e:
        raise SetupError(f"{e} under {sys.executable}: run this script with Debian's /usr/bin/python3 "
                         "(apt-get install python3-dolfinx-real python3-gmsh)")
    return np, gmsh, MPI, PETSc, dolfinx, ufl


class Model:
    """The TOML problem, interpreted once (no mesh work here)."""

    def __init__(self, toml: Path, msh: Path | None):
        try:
            self.cfg = tomllib.loads(toml.read_text())
        except (OSError, tomllib.TOMLDecodeError) as e:
            raise SetupError(f"{toml}: {e}")
        cfg = self.cfg
        self.name = toml.stem
        if msh is None:
            if "mesh" not in cfg or "file" not in cfg["mesh"]:
                raise SetupError(f"{toml}: no [mesh] file (and no --msh)")
            msh = toml.parent / cfg["mesh"]["file"]
        self.msh = msh.resolve()
        if not self.msh.is_file():
            raise SetupError(f"mesh file {self.msh} not found")
        mdl = cfg.get("model", {})
        self.plane_stress = mdl.get("plane", "strain") == "stress"
        self.th = float(mdl.get("thickness", 1.0)) if self.plane_stress else 1.0
        self.gravity = [float(v) for v in mdl.get("gravity", [0.0, 0.0])]
        if "materials" not in cfg or not cfg["materials"]:
            raise SetupError(f"{toml}: no [materials]")
        self.materials = cfg["materials"]
        self.dirichlet = cfg.get("dirichlet", [])
        self.traction = cfg.get("traction", [])
        self.force = cfg.get("force", [])
        self.slip = cfg.get("slip", [])
        self.probes = {k: [float(v[0]), float(v[1])] for k, v in cfg.get("output", {}).get("probes", {}).items()}
        self.warnings: list[str] = []
        if cfg.get("steps"):
            self.warn(f"{len(cfg['steps'])} [[steps]] ignored: the base problem (factor 1) is solved")
        if any("slave" in c for c in cfg.get("contact", [])):
            self.warn("non-matching [[contact]] pairs (slave/master) are ignored: the bodies are not glued there")

    def warn(self, msg: str) -> None:
        if msg not in self.warnings:
            self.warnings.append(msg)
            print(f"bench_fenicsx: warning: {msg}", file=sys.stderr, flush=True)


def physical_groups(gmsh) -> dict:
    out = {}
    for dim, tag in gmsh.model.getPhysicalGroups():
        out.setdefault(gmsh.model.getPhysicalName(dim, tag), (dim, tag))
    return out


def physical_point_coords(gmsh, dim: int, tag: int):
    import numpy as np

    xs = []
    for ent in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
        _, coords, _ = gmsh.model.mesh.getNodes(dim, ent, includeBoundary=True)
        xs.append(np.asarray(coords, dtype=float).reshape(-1, 3)[:, :2])
    return np.vstack(xs) if xs else np.zeros((0, 2))


def run_once(model: Model, solver: str, lu_package: str | None) -> dict:
    np, gmsh, MPI, PETSc, dolfinx, ufl = imports()
    import dolfinx.fem.petsc as fp

    rec: dict = {}
    # ------------------------------------------------------------ read
    t0 = time.perf_counter()
    gmsh.clear()
    gmsh.open(str(model.msh))
    msh, ct, ft = dolfinx.io.gmshio.model_to_mesh(gmsh.model, MPI.COMM_WORLD, 0, gdim=2)
    t_read = time.perf_counter() - t0
    groups = physical_groups(gmsh)

    def group(name: str, dims=(0, 1, 2)):
        if name not in groups:
            raise SetupError(f"no physical group named {name!r} in {model.msh.name}")
        g = groups[name]
        if g[0] not in dims:
            raise SetupError(f"{name!r} is a physical group of dimension {g[0]}, expected {dims}")
        return g

    # ------------------------------------------------------------ compile (part 1: elements)
    # FunctionSpace(...) JIT-compiles its element and dofmap; done here first, so that the
    # function space creation below (timed as assembly) only finds them in the cache
    t0 = time.perf_counter()
    el_v = ufl.VectorElement("Lagrange", msh.ufl_cell(), 1, dim=2)
    el_q = ufl.FiniteElement("DG", msh.ufl_cell(), 0)
    for el in (el_v, el_q):
        dolfinx.jit.ffcx_jit(msh.comm, el)
    t_compile = time.perf_counter() - t0
    # -------------------------------------------------------- assemble (part 1: spaces, data)
    t1 = time.perf_counter()
    tdim, fdim = 2, 1
    V = dolfinx.fem.FunctionSpace(msh, el_v)
    Q = dolfinx.fem.FunctionSpace(msh, el_q)
    mu, lam, rho = (dolfinx.fem.Function(Q) for _ in range(3))
    ncell = msh.topology.index_map(tdim).size_local
    assigned = np.zeros(ncell, dtype=bool)
    for mname, mat in model.materials.items():
        _, tag = group(mname, (2,))
        cells = ct.indices[ct.values == tag]
        E, nu, rh = float(mat["E"]), float(mat["nu"]), float(mat.get("rho", 0.0))
        m_ = E / (2 * (1 + nu))
        l_ = E * nu / ((1 + nu) * (1 - 2 * nu))
        if model.plane_stress:
            l_ = 2 * l_ * m_ / (l_ + 2 * m_)
        dofs = Q.dofmap.list.array[cells]  # DG0: one dof per cell
        mu.x.array[dofs], lam.x.array[dofs], rho.x.array[dofs] = m_, l_, rh
        assigned[cells] = True
    if not assigned.all():
        raise SetupError(f"{int((~assigned).sum())} cells belong to no material surface")
    th = dolfinx.fem.Constant(msh, PETSc.ScalarType(model.th))
    grav = dolfinx.fem.Constant(msh, np.array(model.gravity, dtype=PETSc.ScalarType))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    ds = ufl.Measure("ds", domain=msh, subdomain_data=ft)
    n = ufl.FacetNormal(msh)
    L_ufl = th * rho * ufl.dot(grav, v) * ufl.dx
    for tr in model.traction:
        _, tag = group(tr["on"], (1,))
        p = tr.get("p", [0.0, 0.0])
        pn = float(tr.get("pn", 0.0))
        P = dolfinx.fem.Constant(msh, np.array(p, dtype=PETSc.ScalarType))
        PN = dolfinx.fem.Constant(msh, PETSc.ScalarType(pn))
        L_ufl = L_ufl + th * (ufl.dot(P, v) + PN * ufl.dot(n, v)) * ds(int(tag))
    a_ufl = th * (2 * mu * ufl.inner(eps(u), eps(v)) + lam * ufl.tr(eps(u)) * ufl.tr(eps(v))) * ufl.dx
    t_asm = time.perf_counter() - t1
    # ------------------------------------------------------------ compile
    t2 = time.perf_counter()
    a = dolfinx.fem.form(a_ufl)
    L = dolfinx.fem.form(L_ufl)
    t_compile += time.perf_counter() - t2
    # -------------------------------------------------------- assemble (part 2: BCs, matrices)
    t3 = time.perf_counter()
    x_geo = msh.geometry.x[:, :2]
    scale = float(np.ptp(x_geo, axis=0).max())
    bcs = []

    def dofs_on(name: str, comp: int | None):
        dim, tag = group(name, (0, 1))
        sub = V if comp is None else V.sub(comp)
        if dim == 1:
            facets = ft.indices[ft.values == tag]
            return dolfinx.fem.locate_dofs_topological(sub, fdim, facets)
        pts = physical_point_coords(gmsh, dim, tag)
        tol = 1e-10 * scale

        def at(x):
            hit = np.zeros(x.shape[1], dtype=bool)
            for q in pts:
                hit |= (np.abs(x[0] - q[0]) <= tol) & (np.abs(x[1] - q[1]) <= tol)
            return hit
        if comp is None:
            return dolfinx.fem.locate_dofs_geometrical(V, at)
        return dolfinx.fem.locate_dofs_geometrical((sub, sub.collapse()[0]), at)[0]

    def bc(name: str, ux, uy):
        if ux is not None and uy is not None:
            dofs = dofs_on(name, None)
            bcs.append(dolfinx.fem.dirichletbc(np.array([ux, uy], dtype=PETSc.ScalarType), dofs, V))
            return
        for comp, val in ((0, ux), (1, uy)):
            if val is not None:
                dofs = dofs_on(name, comp)
                bcs.append(dolfinx.fem.dirichletbc(PETSc.ScalarType(val), dofs, V.sub(comp)))

    for d in model.dirichlet:
        ux, uy = (d["u"] if "u" in d else (d.get("ux"), d.get("uy")))
        bc(d["on"], None if ux is None else float(ux), None if uy is None else float(uy))
    for s in model.slip:
        dim, tag = group(s["on"], (1,))
        facets = ft.indices[ft.values == tag]
        msh.topology.create_connectivity(fdim, 0)
        f2v = msh.topology.connectivity(fdim, 0)
        fv = np.array([f2v.links(f) for f in facets], dtype=np.int32).reshape(-1, 2)
        xv = dolfinx.mesh.compute_midpoints(msh, 0, fv.ravel())[:, :2].reshape(-1, 2, 2)
        dx_, dy_ = (xv[:, 1] - xv[:, 0]).T
        seg = np.hypot(dx_, dy_)
        if len(facets) and np.all(np.abs(dy_) <= 1e-12 * seg):
            bc(s["on"], None, 0.0)  # horizontal line: n = ±e_y
        elif len(facets) and np.all(np.abs(dx_) <= 1e-12 * seg):
            bc(s["on"], 0.0, None)  # vertical line: n = ±e_x
        else:
            model.warn(f"slip line {s['on']!r} is not parallel to an axis: IGNORED "
                       "(the answer differs from signorini's)")
    A = fp.assemble_matrix(a, bcs=bcs)
    A.assemble()
    b = fp.assemble_vector(L)
    fp.apply_lifting(b, [a], bcs=[bcs])
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    if model.force:  # point forces [N per unit thickness] × thickness, at the nearest node
        dofx = V.tabulate_dof_coordinates()[:, :2]
        bs = V.dofmap.index_map_bs
        for fo in model.force:
            dim, tag = group(fo["on"], (0,))
            for q in physical_point_coords(gmsh, dim, tag):
                k = int(np.argmin(np.hypot(*(dofx - q).T)))
                for c in range(2):
                    b.setValue(bs * k + c, model.th * float(fo["f"][c]), addv=PETSc.InsertMode.ADD_VALUES)
        b.assemble()
    fp.set_bc(b, bcs)
    t_asm += time.perf_counter() - t3
    # ------------------------------------------------------------ solve
    t4 = time.perf_counter()
    ksp = PETSc.KSP().create(msh.comm)
    ksp.setOperators(A)
    pc = ksp.getPC()
    ns = None
    if solver in ("lu", "cholesky"):
        ksp.setType("preonly")
        pc.setType(solver)
        if lu_package:
            pc.setFactorSolverType(lu_package)
    else:
        # rigid modes (1,0), (0,1), (−y, x) as near-nullspace, orthonormalized
        dofx = V.tabulate_dof_coordinates()[:, :2]
        bs = V.dofmap.index_map_bs
        nloc = V.dofmap.index_map.size_local
        vecs = [dolfinx.la.create_petsc_vector(V.dofmap.index_map, bs) for _ in range(3)]
        with vecs[0].localForm() as v0, vecs[1].localForm() as v1, vecs[2].localForm() as v2:
            a0, a1, a2 = v0.array, v1.array, v2.array
            a0[:] = 0.0
            a1[:] = 0.0
            a0[0:bs * nloc:bs] = 1.0
            a1[1:bs * nloc:bs] = 1.0
            c = dofx[:nloc].mean(axis=0)
            a2[0:bs * nloc:bs] = -(dofx[:nloc, 1] - c[1])
            a2[1:bs * nloc:bs] = dofx[:nloc, 0] - c[0]
        dolfinx.la.orthonormalize(vecs)
        ns = PETSc.NullSpace().create(vectors=vecs)
        A.setNearNullSpace(ns)
        ksp.setType("cg")
        pc.setType("gamg")
        ksp.setTolerances(rtol=1e-10, atol=1e-300, max_it=10000)
    ksp.setFromOptions()
    x = A.createVecRight()
    ksp.solve(b, x)
    t_solve = time.perf_counter() - t4
    # ------------------------------------------------------------ results (not timed)
    reason = ksp.getConvergedReason()
    r = b.duplicate()
    A.mult(x, r)
    r.axpy(-1.0, b)
    bn = b.norm()
    rec["rel_residual"] = float(r.norm() / bn) if bn > 0 else float(r.norm())
    rec["ksp_type"], rec["pc_type"] = ksp.getType(), pc.getType()
    rec["ksp_iterations"], rec["ksp_reason"] = int(ksp.getIterationNumber()), int(reason)
    if solver in ("lu", "cholesky"):
        rec["petsc_lu_package"] = pc.getFactorSolverType()
    bs = V.dofmap.index_map_bs
    ndof = V.dofmap.index_map.size_global * bs
    nbc = len(set().union(*[set(int(i) for i in bc_.dof_indices()[0]) for bc_ in bcs])) if bcs else 0
    rec["dofs"], rec["dofs_free"] = int(ndof), int(ndof - nbc)
    rec["nodes"] = int(msh.geometry.x.shape[0])
    rec["cells"] = int(ncell)
    U = x.getArray(readonly=True).reshape(-1, bs)[:, :2].copy()
    dofx = V.tabulate_dof_coordinates()[:, :2]
    probes = {}
    for name, q in model.probes.items():
        k = int(np.argmin(np.hypot(*(dofx - np.asarray(q)).T)))
        probes[name] = {"u": [float(U[k, 0]), float(U[k, 1])], "x": [float(dofx[k, 0]), float(dofx[k, 1])]}
    rec["probes"] = probes
    rec.update(t_read=t_read, t_compile=t_compile, t_assemble=t_asm, t_solve=t_solve,
               t_total=t_read + t_compile + t_asm + t_solve)
    for obj in (ksp, A, b, x, r) + ((ns,) if ns is not None else ()):
        obj.destroy()
    return rec


def check_against(probes: dict, sig_path: Path) -> tuple[float, dict]:
    """max relative probe difference vs signorini's JSON output."""
    import numpy as np

    try:
        sig = json.loads(sig_path.read_text())
    except (OSError, ValueError) as e:
        raise SetupError(f"--check-json {sig_path}: {e}")
    sp_ = sig.get("probes") or {}
    common = [k for k in probes if k in sp_]
    if not common:
        raise SetupError(f"--check-json {sig_path}: no probe in common (signorini: {sorted(sp_)}, "
                         f"here: {sorted(probes)})")
    big = max(float(np.linalg.norm(sp_[k]["u"])) for k in common)
    per = {}
    for k in common:
        us = np.asarray(sp_[k]["u"], dtype=float)
        uf = np.asarray(probes[k]["u"], dtype=float)
        per[k] = float(np.linalg.norm(uf - us) / max(np.linalg.norm(us), 1e-12 * big, 1e-300))
    return max(per.values()), per


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("toml", type=Path)
    ap.add_argument("--msh", type=Path, default=None, help="mesh file overriding [mesh] file")
    ap.add_argument("--solver", choices=["lu", "cholesky", "cg-gamg"], default="lu")
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--check-json", type=Path, default=None,
                    help="signorini's NAME.json (solve --no-contact): print the max relative probe difference")
    ap.add_argument("--check-tol", type=float, default=1e-6, help="exit 1 above it (default 1e-6)")
    args = ap.parse_args(argv)
    if args.repeats < 1:
        raise SetupError("--repeats must be >= 1")

    np, gmsh, MPI, PETSc, dolfinx, ufl = imports()
    logging.disable(logging.INFO)  # the JIT logs every compiler call at INFO
    model = Model(args.toml.resolve(), args.msh)
    lu_package = None
    if args.solver in ("lu", "cholesky"):
        lu_package = "mumps" if PETSc.Sys.hasExternalPackage("mumps") else None
        if lu_package is None:
            model.warn("PETSc has no MUMPS: PETSc's default (sequential) factorization is used")
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    runs = []
    try:
        for r in range(args.repeats):
            rec = run_once(model, args.solver, lu_package)
            runs.append(rec)
            log(f"run {r + 1}/{args.repeats}: read {rec['t_read']:.3f}  compile {rec['t_compile']:.3f}  "
                f"assemble {rec['t_assemble']:.3f}  solve {rec['t_solve']:.3f}  total {rec['t_total']:.3f} s"
                f"  ({rec['ksp_type']}/{rec['pc_type']}"
                f"{'/' + rec['petsc_lu_package'] if rec.get('petsc_lu_package') else ''}, "
                f"{rec['ksp_iterations']} it, reason {rec['ksp_reason']}, rel. residual {rec['rel_residual']:.1e})")
    finally:
        gmsh.finalize()
    last = runs[-1]
    med = {k: statistics.median(r[k] for r in runs) for k in ("t_read", "t_compile", "t_assemble", "t_solve", "t_total")}
    out = {"solver": args.solver, "dofs": last["dofs"], "dofs_free": last["dofs_free"], **med,
           "t_compile_first": runs[0]["t_compile"],
           "probes": {k: p["u"] for k, p in last["probes"].items()},
           "probe_nodes": {k: p["x"] for k, p in last["probes"].items()},
           "petsc_lu_package": last.get("petsc_lu_package"),
           "ksp_type": last["ksp_type"], "pc_type": last["pc_type"],
           "ksp_iterations": last["ksp_iterations"], "ksp_reason": last["ksp_reason"],
           "rel_residual": last["rel_residual"], "nodes": last["nodes"], "cells": last["cells"],
           "repeats": args.repeats, "problem": str(args.toml), "mesh": str(model.msh),
           "dolfinx_version": dolfinx.__version__,
           "petsc_version": ".".join(str(v) for v in PETSc.Sys.getVersion()),
           "warnings": model.warnings}
    log(f"FEniCSx {model.name} ({model.msh.name}): {out['dofs']} DOFs ({out['dofs_free']} free), "
        f"{out['nodes']} nodes, {out['cells']} cells; solver {args.solver}"
        f"{' (' + out['petsc_lu_package'] + ')' if out['petsc_lu_package'] else ''}; median of {args.repeats}: "
        f"read {med['t_read']:.3f}  compile {med['t_compile']:.3f} (first {out['t_compile_first']:.3f})  "
        f"assemble {med['t_assemble']:.3f}  solve {med['t_solve']:.3f}  total {med['t_total']:.3f} s")
    for k, uu in out["probes"].items():
        log(f"  probe {k} at node {out['probe_nodes'][k]}: u = ({uu[0]:.12e}, {uu[1]:.12e})")
    rc = 0
    if last["ksp_reason"] <= 0:
        log(f"bench_fenicsx: the KSP did not converge (reason {last['ksp_reason']})")
        rc = 1
    elif last["rel_residual"] > 1e-6:
        log(f"bench_fenicsx: relative residual {last['rel_residual']:.1e}: the system is singular "
            "(a body left free without contact?); the answer is meaningless")
        rc = 1
    if args.check_json:
        worst, per = check_against(last["probes"], args.check_json)
        out["check"] = {"signorini_json": str(args.check_json), "max_rel_probe_diff": worst, "per_probe": per,
                        "tol": args.check_tol, "ok": worst <= args.check_tol}
        log(f"check vs {args.check_json}: max relative probe difference {worst:.3e} "
            f"({', '.join(f'{k} {v:.1e}' for k, v in per.items())}) -> "
            f"{'OK' if worst <= args.check_tol else 'ABOVE'} tol {args.check_tol:g}")
        if worst > args.check_tol:
            rc = 1
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(out, indent=1) + "\n")
    return rc


if __name__ == "__main__":
    try:
        sys.exit(main())
    except SetupError as e:
        print(f"bench_fenicsx: error: {e}", file=sys.stderr)
        sys.exit(2)
