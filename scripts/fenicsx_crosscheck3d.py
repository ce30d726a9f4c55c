"""The 3D half of scripts/fenicsx_crosscheck.py: a model of P1 tetrahedra
(docs/problem-format.md §12) solved by an independent FEniCSx (dolfinx
0.5.2) model of the same mesh and compared with `signorini solve`.

Called by fenicsx_crosscheck.py when the problem's mesh holds tetrahedra;
same exit codes (0 OK, 1 FAIL, 2 setup error, 3 NOT CHECKED).

What it does
------------
The mesh is read with the gmsh Python API and converted with
dolfinx.io.gmshio.model_to_mesh (gdim = 3). dolfinx assembles, on P1
vector Lagrange elements,

    a(u, v) = ∫ 2μ ε(u):ε(v) + λ tr ε(u) tr ε(v) dx
    L(v)    = ∫ ρ g·v dx + ∫_Γτ (p + pn n)·v ds

with λ, μ, ρ DG0 functions of the Physical Volume (the material), and a
point force f on a Physical Point added to the node's entries. Dirichlet
components (`u = [ux, uy, uz]` or `ux`/`uy`/`uz`) and slip planes (u·n = 0,
n the plane's unit normal from its triangles) are eliminated node by node
in scipy: a node's admissible displacements are u0 + T ξ with T an
orthonormal basis of the directions left free (a node on two slip planes
keeps the direction along their intersection). K_r ξ = f_r is solved by
scipy's sparse LU and compared with signorini's HDF5 checkpoint
(displacements matched by coordinates, the six stresses per tetrahedron
recomputed here from the reference's displacements), relative to the
largest value of each.

Not checked yet (exit 3, the reason printed): `[[contact]]` (3D contact is
not in `signorini solve` yet, docs/design.md), `[[steps]]`.
"""

from __future__ import annotations

import subprocess
import sys
import time
import tomllib
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.spatial import cKDTree


class NotChecked(Exception):
    pass


class CheckError(Exception):
    pass


def log(msg: str) -> None:
    print(msg, flush=True)


def mesh_is_3d(gmsh, msh: Path) -> bool:
    """Whether the .msh holds 4-node tetrahedra (Gmsh element type 4)."""
    gmsh.open(str(msh))
    types, _, _ = gmsh.model.mesh.getElements(3)
    gmsh.clear()
    return 4 in list(types)


def groups(gmsh) -> dict[str, tuple[int, int]]:
    return {gmsh.model.getPhysicalName(d, t): (d, t) for d, t in gmsh.model.getPhysicalGroups()}


def group_nodes(gmsh, dim: int, tag: int) -> np.ndarray:
    nodes, _ = gmsh.model.mesh.getNodesForPhysicalGroup(dim, tag)
    return np.asarray(nodes, dtype=np.int64)


def group_triangles(gmsh, tag: int) -> np.ndarray:
    """The triangles (node tags) of Physical Surface `tag`."""
    tris = []
    for e in gmsh.model.getEntitiesForPhysicalGroup(2, tag):
        types, _, nodes = gmsh.model.mesh.getElements(2, e)
        for t, nn in zip(types, nodes):
            if t != 2:
                raise NotChecked(f"surface element type {t} (only 3-node triangles)")
            tris.append(np.asarray(nn, dtype=np.int64).reshape(-1, 3))
    return np.vstack(tris) if tris else np.zeros((0, 3), dtype=np.int64)


def unmodelled(cfg: dict) -> list[str]:
    out = []
    if cfg.get("contact"):
        out.append("[[contact]] (3D contact is not in `signorini solve` yet)")
    if cfg.get("steps"):
        out.append("[[steps]]")
    return out


def lame(mat: dict) -> tuple[float, float, float]:
    e, nu = float(mat["E"]), float(mat["nu"])
    lam = e * nu / ((1 + nu) * (1 - 2 * nu))
    mu = e / (2 * (1 + nu))
    return lam, mu, float(mat.get("rho", 0.0))


def components(entry: dict) -> list[float | None]:
    if "u" in entry:
        return [float(v) for v in entry["u"]]
    return [float(entry[k]) if k in entry else None for k in ("ux", "uy", "uz")]


def read_signorini(h5: Path) -> dict:
    import h5py

    with h5py.File(h5, "r") as f:
        if f.attrs.get("model") not in ("solid", b"solid"):
            raise CheckError(f"{h5.name}: root attribute model = {f.attrs.get('model')!r}, not 'solid'")
        st = f["steps/0001"]
        return {
            "nodes": f["mesh/nodes"][:],
            "tags": f["mesh/node_tags"][:].astype(np.int64),
            "tets": f["mesh/tetrahedra"][:].astype(np.int64),
            "material": f["mesh/material"][:].astype(np.int64),
            "material_names": [m.decode() if isinstance(m, bytes) else str(m)
                               for m in f["mesh"].attrs["material_names"]],
            "u": st["displacement"][:],
            "stress": st["stress"][:],
            "converged": int(st.attrs["converged"]),
        }


def check(toml: Path, exe: Path, tol: float, tmp: Path, gmsh) -> int:
    """Part a of the cross-check on a 3D model; the exit code."""
    import dolfinx.fem.petsc  # noqa: F401
    import ufl
    from dolfinx import fem
    from dolfinx.io import gmshio
    from mpi4py import MPI
    from petsc4py import PETSc

    t0 = time.time()
    cfg = tomllib.loads(toml.read_text())
    extra = unmodelled(cfg)
    if extra:
        raise NotChecked(f"the 3D reference does not model {', '.join(extra)}; nothing was compared")
    msh = (toml.parent / cfg["mesh"]["file"]).resolve()
    gmsh.open(str(msh))
    names = groups(gmsh)
    dmesh, cell_tags, facet_tags = gmshio.model_to_mesh(gmsh.model, MPI.COMM_SELF, 0, gdim=3)
    x = dmesh.geometry.x[:, :3]
    ntags, ncoord, _ = gmsh.model.mesh.getNodes()
    ncoord = np.asarray(ncoord).reshape(-1, 3)
    L = float(np.ptp(ncoord, axis=0).max())
    # Gmsh node tag -> dolfinx vertex (P1: geometry nodes are the dofs).
    tree = cKDTree(x)
    dist, g2d = tree.query(ncoord)
    if dist.max() > 1e-12 * L:
        raise CheckError(f"dolfinx's nodes are not Gmsh's (max distance {dist.max():.3e})")
    of_tag = dict(zip(np.asarray(ntags, dtype=np.int64).tolist(), g2d.tolist()))

    V = fem.VectorFunctionSpace(dmesh, ("Lagrange", 1))
    # P1 on a P1 geometry: dof i of the scalar layout is geometry node i?
    # Map through the dof coordinates to be sure.
    dof_x = V.tabulate_dof_coordinates()[:, :3]
    dist, geo2dof = cKDTree(dof_x).query(x)
    if dist.max() > 1e-12 * L:
        raise CheckError("P1 dofs do not sit on the mesh nodes")
    n = len(dof_x)

    # Materials: a DG0 value per cell from its Physical Volume.
    Q = fem.FunctionSpace(dmesh, ("DG", 0))
    lam_f, mu_f, rho_f = fem.Function(Q), fem.Function(Q), fem.Function(Q)
    mats = cfg["materials"]
    seen = set()
    for name, (d, tag) in names.items():
        if d != 3:
            continue
        if name not in mats:
            raise CheckError(f"Physical Volume {name!r} has no [materials.{name}]")
        cells = cell_tags.find(tag)
        lam, mu, rho = lame(mats[name])
        lam_f.x.array[cells] = lam
        mu_f.x.array[cells] = mu
        rho_f.x.array[cells] = rho
        seen.update(cells.tolist())
    ncells = dmesh.topology.index_map(3).size_local
    if len(seen) != ncells:
        raise CheckError(f"{ncells - len(seen)} tetrahedra in no Physical Volume")

    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    a = (2 * mu_f * ufl.inner(eps(u), eps(v)) + lam_f * ufl.tr(eps(u)) * ufl.tr(eps(v))) * ufl.dx
    g = [float(c) for c in cfg.get("model", {}).get("gravity", [0.0, 0.0, 0.0])]
    rhs = ufl.inner(rho_f * ufl.as_vector(g), v) * ufl.dx
    ds = ufl.Measure("ds", domain=dmesh, subdomain_data=facet_tags)
    nrm = ufl.FacetNormal(dmesh)
    for tr in cfg.get("traction", []):
        d, tag = names.get(tr["on"], (None, None))
        if d != 2:
            raise CheckError(f"[[traction]] on {tr['on']!r}: no Physical Surface of that name")
        if "pn" in tr:
            rhs += float(tr["pn"]) * ufl.inner(nrm, v) * ds(tag)
        if "p" in tr:
            rhs += ufl.inner(ufl.as_vector([float(c) for c in tr["p"]]), v) * ds(tag)
    A = fem.petsc.assemble_matrix(fem.form(a))
    A.assemble()
    ai, aj, av = A.getValuesCSR()
    K = sp.csr_matrix((av, aj, ai), shape=(3 * n, 3 * n))
    bvec = fem.petsc.assemble_vector(fem.form(rhs))
    bvec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    f = bvec.array.copy()
    for fo in cfg.get("force", []):
        d, tag = names.get(fo["on"], (None, None))
        if d != 0:
            raise CheckError(f"[[force]] on {fo['on']!r}: no Physical Point of that name")
        for t in group_nodes(gmsh, 0, tag):
            i = geo2dof[of_tag[int(t)]]
            f[3 * i:3 * i + 3] += np.asarray(fo["f"], dtype=float)

    # Conditions per dof node: prescribed values and constrained directions.
    fixed: dict[int, list[tuple[np.ndarray, float]]] = {}
    for dc in cfg.get("dirichlet", []):
        d, tag = names.get(dc["on"], (None, None))
        if d is None:
            raise CheckError(f"[[dirichlet]] on {dc['on']!r}: no physical group of that name")
        comps = components(dc)
        for t in group_nodes(gmsh, d, tag):
            i = geo2dof[of_tag[int(t)]]
            for c, val in enumerate(comps):
                if val is not None:
                    fixed.setdefault(i, []).append((np.eye(3)[c], val))
    for sl in cfg.get("slip", []):
        d, tag = names.get(sl["on"], (None, None))
        if d != 2:
            raise CheckError(f"[[slip]] on {sl['on']!r}: no Physical Surface of that name")
        tris = group_triangles(gmsh, tag)
        idx = {int(t): k for k, t in enumerate(np.asarray(ntags, dtype=np.int64))}
        p = np.array([[ncoord[idx[int(v)]] for v in tri] for tri in tris])
        cr = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        nn = cr.sum(axis=0)
        nn /= np.linalg.norm(nn)
        for t in np.unique(tris):
            i = geo2dof[of_tag[int(t)]]
            fixed.setdefault(i, []).append((nn, 0.0))

    # u_i = u0_i + T_i ξ_i: T_i an orthonormal basis of the complement of the
    # constrained directions, u0_i the least-squares prescribed part.
    cols, u0 = [], np.zeros(3 * n)
    T_rows, T_cols, T_vals = [], [], []
    k = 0
    for i in range(n):
        conds = fixed.get(i, [])
        if conds:
            R = np.array([c[0] for c in conds])
            vals = np.array([c[1] for c in conds])
            _, sv, vt = np.linalg.svd(R)
            rank = int((sv > 1e-10 * sv[0]).sum())
            u0i = np.linalg.lstsq(R, vals, rcond=None)[0]
            if np.abs(R @ u0i - vals).max() > 1e-9 * max(1.0, np.abs(vals).max()):
                raise CheckError(f"conflicting conditions at node {i}")
            u0[3 * i:3 * i + 3] = u0i
            basis = vt[rank:]
        else:
            basis = np.eye(3)
        for b in basis:
            for c in range(3):
                if b[c] != 0.0:
                    T_rows.append(3 * i + c)
                    T_cols.append(k)
                    T_vals.append(b[c])
            k += 1
        cols.append(k)
    T = sp.csr_matrix((T_vals, (T_rows, T_cols)), shape=(3 * n, k))
    Kr = (T.T @ K @ T).tocsc()
    fr = T.T @ (f - K @ u0)
    try:
        xi = spla.spsolve(Kr, fr)
    except Exception as e:  # a singular Kr: rigid motions left
        raise NotChecked(f"the reduced stiffness is singular ({e}): a body with rigid motions")
    if not np.all(np.isfinite(xi)):
        raise NotChecked("the reduced stiffness is singular: a body with rigid motions")
    uref = (u0 + T @ xi).reshape(-1, 3)
    log(f"reference: {n} nodes, {ncells} tetrahedra, {k} unknowns ({time.time() - t0:.1f} s)")

    out = tmp / "solid"
    out.mkdir(parents=True, exist_ok=True)
    cmd = [str(exe), "solve", str(toml), "--out", str(out), "--quiet"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        log(f"`{' '.join(cmd)}` exited {p.returncode}: {(p.stdout + p.stderr).strip()[-400:]} -> FAIL")
        return 1
    sig = read_signorini(out / f"{toml.stem}.h5")
    dist, idx = cKDTree(x).query(sig["nodes"])
    if dist.max() > 1e-9 * L:
        raise CheckError(f"signorini's nodes do not match the mesh (max distance {dist.max():.3e})")
    mine = uref[geo2dof[idx]]
    du = np.abs(mine - sig["u"]).max() / max(np.abs(mine).max(), 1e-300)

    # Stresses per tetrahedron from the reference displacements (signorini's
    # tetrahedra, its point numbering), VTK's order xx, yy, zz, xy, yz, xz.
    pts = sig["nodes"]
    names_m = sig["material_names"]
    s_ref = np.zeros((len(sig["tets"]), 6))
    for e, (tet, m) in enumerate(zip(sig["tets"], sig["material"])):
        lam, mu, _ = lame(mats[names_m[m]])
        X = pts[tet]
        J = (X[1:] - X[0]).T
        grads = np.linalg.solve(J.T, np.array([[-1, -1, -1], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float).T).T
        gu = mine[tet].T @ grads  # ∂u_a/∂x_b
        eps_ = 0.5 * (gu + gu.T)
        sig_ = 2 * mu * eps_ + lam * np.trace(eps_) * np.eye(3)
        s_ref[e] = [sig_[0, 0], sig_[1, 1], sig_[2, 2], sig_[0, 1], sig_[1, 2], sig_[0, 2]]
    ds_ = np.abs(s_ref - sig["stress"]).max() / max(np.abs(s_ref).max(), 1e-300)
    ok = du <= tol and ds_ <= tol
    log(f"part a (3D linear elasticity): displacement {du:.2e}, stress {ds_:.2e} "
        f"(max |u| {np.abs(mine).max():.4e}) -> {'OK' if ok else 'FAIL'}")
    return 0 if ok else 1
