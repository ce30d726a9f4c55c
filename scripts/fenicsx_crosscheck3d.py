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

Contact (conforming `on`, and `slave`/`master` with mortar or "nts"
rows): the mesh is cut as the problem format says (a point per node and
body; bodies are the tetrahedra joined through faces not on a contact
surface), every form assembled once per body with its materials times the
body's indicator and routed to the body's points; rows rebuilt here: a
conforming node pair n·(u_k − u_l) ≤ 0 with n the area-weighted average of
the surface's triangle normals outward of the lower body k (signorini's
master: bodies numbered by their lowest node tag), a slave node projected
orthogonally on the nearest master triangle, n·(Σ w u_m − u_s) ≤ g₀;
mortar rows (the default of a pair, "nts" when the slave is more than 10
times stiffer than the master) from docs/methods.md §11.6: each slave
triangle clipped by every facing master triangle near it projected onto
its plane, the pieces integrated exactly (`mortar_rows`), the dual basis
Φ = D_e M_e⁻¹ N on the projecting part, per slave node
n_j·(u_j − Σ (M_jm/D_jj) u_m) ≤ g̃_j/D_jj. The
QP min ½ξᵀK_rξ − f_rᵀξ, A_r ξ ≤ g_r is solved by fenicsx_crosscheck.py's
`solve_qp` (Clarabel, then an exact active-set polish) and compared with
signorini's displacements, multipliers, pressures (λ over Σ|F|/3, over
D_jj for mortar rows) and the rows' initial gaps (`/mesh/contact_gap0`).

Not checked yet (exit 3, the reason printed): friction (issue 46),
`interference`/`max_gap`, `[[steps]]`.
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


class Groups:
    """The physical groups by name; a name may be both a volume and a
    surface (a sphere's volume and its surface, both "ball")."""

    def __init__(self, gmsh):
        self.by = {}
        for d, t in gmsh.model.getPhysicalGroups():
            self.by.setdefault(gmsh.model.getPhysicalName(d, t), {})[d] = t

    def get(self, name, default=(None, None), dim=None):
        dims = self.by.get(name, {})
        if dim is not None:
            return (dim, dims[dim]) if dim in dims else default
        for d in (2, 1, 0, 3):
            if d in dims:
                return d, dims[d]
        return default

    def volumes(self):
        return [(name, dims[3]) for name, dims in self.by.items() if 3 in dims]


def groups(gmsh) -> Groups:
    return Groups(gmsh)


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
    for i, c in enumerate(cfg.get("contact", [])):
        if "friction" in c or "tresca" in c:
            out.append(f"friction on [[contact]] #{i + 1} (3D friction is issue 46)")
        if c.get("discretization", "mortar") not in ("mortar", "nts"):
            out.append(f"discretization = {c['discretization']!r} of [[contact]] #{i + 1}")
        if c.get("interference") or c.get("max_gap") is not None:
            out.append(f"interference/max_gap of [[contact]] #{i + 1}")
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
            "body": f["mesh/body"][:].astype(np.int64),
            "contact_slave": f["mesh/contact_slave"][:].astype(np.int64) if "contact_slave" in f["mesh"] else None,
            "multipliers": st["multipliers"][:] if "multipliers" in st else None,
            "contact_pressure": st["contact_pressure"][:] if "contact_pressure" in st else None,
            "contact_gap0": f["mesh/contact_gap0"][:] if "contact_gap0" in f["mesh"] else None,
        }


def tri_normal(p):
    """Unit normal and area of the triangle with corners p (3×3)."""
    cr = np.cross(p[1] - p[0], p[2] - p[0])
    a = np.linalg.norm(cr)
    return cr / a, 0.5 * a


# ------------------------------------------------------------ mortar rows
# Written from docs/methods.md §11.6 and the mathematics, not from
# src/fem/contact3d/mortar.rs: the slave triangle is clipped by each
# projected master (the Rust code clips the other way round), the clip
# polygon is fanned from its first vertex (not its centroid), and every
# integrand, affine × affine on a sub-triangle, is integrated in closed
# form, ∫_T f h = |T|/12 (Σ f_i h_i + Σ f_i Σ h_i), not by a Gauss rule.


def _clip(subject, clip):
    """The convex polygon `subject` clipped by the convex counter-clockwise
    polygon `clip` (Sutherland–Hodgman), both lists of 2D points."""
    out = [np.asarray(p, float) for p in subject]
    k = len(clip)
    for i in range(k):
        a, b = clip[i], clip[(i + 1) % k]
        ex, ey = b[0] - a[0], b[1] - a[1]

        def side(p):
            return ex * (p[1] - a[1]) - ey * (p[0] - a[0])

        inp, out = out, []
        if not inp:
            break
        for idx in range(len(inp)):
            p, q = inp[idx - 1], inp[idx]
            sp_, sq = side(p), side(q)
            if sq >= 0.0:
                if sp_ < 0.0:
                    out.append(p + sp_ / (sp_ - sq) * (q - p))
                out.append(q)
            elif sp_ >= 0.0:
                out.append(p + sp_ / (sp_ - sq) * (q - p))
    return out


def _bary2(t, q):
    """Barycentric coordinates of the 2D points q (k×2) in triangle t (3×2)."""
    T = np.array([t[1] - t[0], t[2] - t[0]]).T
    l12 = np.linalg.solve(T, (q - t[0]).T).T
    return np.column_stack([1.0 - l12.sum(axis=1), l12])


def mortar_rows(x, st, s_out, mt, m_out, L):
    """Mortar rows of a slave/master pair (docs/methods.md §11.6).

    x: node coordinates; st, mt: the slave and master triangles (node
    indices); s_out, m_out: their unit outward normals; L: the model's size.
    Returns {slave node: (n_j, {master node: M_jm / D_jj}, g̃_j / D_jj, D_jj)}
    for every slave node with D_jj > 0, n_j the area-weighted average of
    the slave normals around node j (outward of the slave).
    """
    nsum: dict[int, np.ndarray] = {}
    for tri, n in zip(st, s_out):
        _, area = tri_normal(x[tri])
        for v in tri:
            nsum[int(v)] = nsum.get(int(v), 0.0) + area * n
    mlo = x[mt].min(axis=1) - 1e-9 * L
    mhi = x[mt].max(axis=1) + 1e-9 * L
    D: dict[int, float] = {}
    Mw: dict[int, dict[int, float]] = {}
    G: dict[int, float] = {}
    for tri, n in zip(st, s_out):
        xs = x[tri]
        edges = np.linalg.norm(xs[[1, 2, 0]] - xs, axis=1)
        # No max_gap, no limit: a master may lie anywhere ahead of the slave
        # triangle along n. The box of the triangle swept along n by the
        # model's size L (every master is within L of it), widened by its
        # longest edge; the clipping then decides.
        pad = edges.max()
        swept = np.vstack([xs, xs + L * n])
        lo, hi = swept.min(axis=0) - pad, swept.max(axis=0) + pad
        cand = np.where(np.all(mhi >= lo, axis=1) & np.all(mlo <= hi, axis=1) & (m_out @ n < 0.0))[0]
        if len(cand) == 0:
            continue
        # A frame of the slave plane: (e1, e2, n) right-handed.
        e1 = (xs[1] - xs[0]) / np.linalg.norm(xs[1] - xs[0])
        e2 = np.cross(n, e1)
        to2 = lambda y: np.column_stack([(y - xs[0]) @ e1, (y - xs[0]) @ e2])  # noqa: E731
        s2 = to2(xs)
        s_area = 0.5 * abs(np.cross(s2[1] - s2[0], s2[2] - s2[0]))
        Me = np.zeros((3, 3))
        De = np.zeros(3)
        B: dict[int, np.ndarray] = {}  # master node -> ∫ N_a N_m (a = 0..2)
        Gs = np.zeros(3)               # ∫ N_a g
        for j in cand:
            ym = x[mt[j]]
            h = (ym - xs[0]) @ n          # heights of the master corners over the slave plane
            m2 = to2(ym)                  # their projections along n
            sa = 0.5 * np.cross(m2[1] - m2[0], m2[2] - m2[0])
            if abs(sa) <= 1e-14 * s_area:
                continue
            order = [0, 1, 2] if sa > 0 else [0, 2, 1]
            poly = _clip(list(s2), [m2[k] for k in order])
            if len(poly) < 3:
                continue
            P = np.array(poly)
            parea = 0.5 * abs(np.sum(P[:, 0] * np.roll(P[:, 1], -1) - np.roll(P[:, 0], -1) * P[:, 1]))
            if parea < 1e-12 * s_area:
                continue
            for k in range(1, len(P) - 1):
                v = P[[0, k, k + 1]]
                ta = 0.5 * abs(np.cross(v[1] - v[0], v[2] - v[0]))
                if ta == 0.0:
                    continue
                Ns = _bary2(s2, v)              # 3 vertices × 3 slave functions
                Nm = _bary2(m2, v)              # 3 vertices × 3 master functions
                g = Nm @ h                      # the gap n·(y(q) − q) at the vertices
                mass = ta / 12.0 * (np.eye(3) + np.ones((3, 3)))
                Me += Ns.T @ mass @ Ns
                De += ta / 3.0 * Ns.sum(axis=0)
                Gs += Ns.T @ mass @ g
                bm = Ns.T @ mass @ Nm
                for c_, node in enumerate(mt[j]):
                    B[int(node)] = B.get(int(node), np.zeros(3)) + bm[:, c_]
        if not B:
            continue
        scale = np.abs(Me).max()
        if abs(np.linalg.det(Me)) <= 1e-12 * scale ** 3:
            continue  # a projecting part too thin to carry a dual basis
        A = De[:, None] * np.linalg.inv(Me)   # Φ_a = Σ_b A_ab N_b
        for a_, node in enumerate(tri):
            node = int(node)
            D[node] = D.get(node, 0.0) + De[a_]
            G[node] = G.get(node, 0.0) + A[a_] @ Gs
            row = Mw.setdefault(node, {})
            for mnode, bv in B.items():
                row[mnode] = row.get(mnode, 0.0) + A[a_] @ bv
    out = {}
    for node, d in D.items():
        if d <= 0.0:
            continue
        nj = nsum[node] / np.linalg.norm(nsum[node])
        out[node] = (nj, {m: w / d for m, w in Mw.get(node, {}).items()}, G.get(node, 0.0) / d, d)
    return out


def mirrored(n, planes):
    """The normal of a row whose slave node lies on slip planes of unit
    normals `planes` (docs/methods.md §11.7): its part in the planes,
    normalised, unless that is shorter than cos 30° (a wall met at an
    angle) or all of it (already in the planes). Returns (n', n·n')."""
    if not planes:
        return n, 1.0
    q, _ = np.linalg.qr(np.array(planes, dtype=float).T)
    m = n - q @ (q.T @ n)
    ln = np.linalg.norm(m)
    if ln < 0.8660254037844386 or ln >= 1.0:  # cos 30°, as signorini
        return n, 1.0
    m = m / ln
    return m, float(n @ m)


def check(toml: Path, exe: Path, tol: float, tmp: Path, gmsh) -> int:
    """The cross-check of a 3D model; the exit code."""
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
    ntags = np.asarray(ntags, dtype=np.int64)
    ncoord = np.asarray(ncoord).reshape(-1, 3)
    L = float(np.ptp(ncoord, axis=0).max())
    # Gmsh node tag -> dolfinx geometry node: gmshio orders its input by
    # tag (input index = tag − 1 for tags 1..N), and coincident nodes of two
    # volumes meshed apart must stay apart, so not by coordinates.
    if sorted(ntags.tolist()) != list(range(1, len(ntags) + 1)):
        raise NotChecked("the mesh's node tags are not 1..N (renumber with gmsh -renumber)")
    inp = np.asarray(dmesh.geometry.input_global_indices, dtype=np.int64)
    g2d = np.empty(len(ntags), dtype=np.int64)
    g2d[inp] = np.arange(len(inp))
    g2d = g2d[ntags - 1]
    dist = np.linalg.norm(x[g2d] - ncoord, axis=1)
    if dist.max() > 1e-12 * L:
        raise CheckError(f"dolfinx's nodes are not Gmsh's (max distance {dist.max():.3e})")
    of_tag = dict(zip(ntags.tolist(), g2d.tolist()))
    tag_of = np.zeros(len(x), dtype=np.int64)
    tag_of[g2d] = ntags

    V = fem.VectorFunctionSpace(dmesh, ("Lagrange", 1))
    dof_x = V.tabulate_dof_coordinates()[:, :3]
    # P1 on a P1 geometry: the dofs of cell c are its geometry nodes, in
    # the same local order (coincident nodes again rule out coordinates).
    geo2dof = np.empty(len(x), dtype=np.int64)
    gmap = dmesh.geometry.dofmap.array.reshape(-1, 4)
    dmap = V.dofmap.list.array.reshape(-1, 4)
    geo2dof[gmap.ravel()] = dmap.ravel()
    if np.abs(dof_x[geo2dof] - x).max() > 1e-12 * L:
        raise CheckError("P1 dofs do not sit on the mesh nodes")
    nn = len(dof_x)
    cells = dmesh.geometry.dofmap.array.reshape(-1, 4)
    ncells = len(cells)

    # Contact surfaces: their triangles do not join tetrahedra into bodies.
    contact = cfg.get("contact", [])
    def surface(name):
        d, tag = names.get(name, dim=2)
        if d != 2:
            raise CheckError(f"[[contact]]: no Physical Surface named {name!r}")
        return np.array([[of_tag[int(v)] for v in t] for t in group_triangles(gmsh, tag)], dtype=np.int64)
    cut = set()
    for c in contact:
        for key in ("on", "slave", "master"):
            if key in c:
                cut.update(tuple(sorted(t)) for t in surface(c[key]))
    faces: dict[tuple, list] = {}
    for ci, cell in enumerate(cells):
        for skip in range(4):
            f = tuple(sorted(int(v) for k, v in enumerate(cell) if k != skip))
            faces.setdefault(f, []).append(ci)
    parent = list(range(ncells))
    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a
    for f, cs in faces.items():
        if len(cs) == 2 and f not in cut:
            ra, rb = find(cs[0]), find(cs[1])
            if ra != rb:
                parent[ra] = rb
    roots = np.array([find(c) for c in range(ncells)])
    # Bodies numbered by their lowest Gmsh node tag (as signorini numbers them).
    uniq = sorted(set(roots.tolist()), key=lambda r: tag_of[cells[roots == r]].min())
    cell_body = np.array([uniq.index(r) for r in roots])
    nb = len(uniq)
    # Points: one per node and body of its tetrahedra.
    point_of: dict[tuple, int] = {}
    pts_node = []
    for b in range(nb):
        for v in np.unique(cells[cell_body == b]):
            point_of[(int(v), b)] = len(pts_node)
            pts_node.append(int(v))
    pts_node = np.array(pts_node)
    npt = len(pts_node)
    node_points: dict[int, list] = {}
    for (v, b), pnt in sorted(point_of.items(), key=lambda kv: (kv[0][0], kv[0][1])):
        node_points.setdefault(v, []).append(pnt)

    # Materials: a DG0 value per cell from its Physical Volume.
    Q = fem.FunctionSpace(dmesh, ("DG", 0))
    lam_f, mu_f, rho_f = fem.Function(Q), fem.Function(Q), fem.Function(Q)
    mats = cfg["materials"]
    seen = set()
    for name, tag in names.volumes():
        if name not in mats:
            raise CheckError(f"Physical Volume {name!r} has no [materials.{name}]")
        cs = cell_tags.find(tag)
        lam, mu, rho = lame(mats[name])
        lam_f.x.array[cs] = lam
        mu_f.x.array[cs] = mu
        rho_f.x.array[cs] = rho
        seen.update(cs.tolist())
    if len(seen) != ncells:
        raise CheckError(f"{ncells - len(seen)} tetrahedra in no Physical Volume")
    # dolfinx's cell numbering: the geometry dofmap rows are cell_tags' cells.
    ind = fem.Function(Q)

    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    a = ind * (2 * mu_f * ufl.inner(eps(u), eps(v)) + lam_f * ufl.tr(eps(u)) * ufl.tr(eps(v))) * ufl.dx
    g = [float(c) for c in cfg.get("model", {}).get("gravity", [0.0, 0.0, 0.0])]
    # A Constant, not as_vector: UFL folds a zero vector away, and an empty
    # form has no integration domain.
    gvec = fem.Constant(dmesh, np.asarray(g, dtype=PETSc.ScalarType))
    rhs = ind * ufl.inner(rho_f * gvec, v) * ufl.dx
    ds = ufl.Measure("ds", domain=dmesh, subdomain_data=facet_tags)
    nrm = ufl.FacetNormal(dmesh)
    for tr in cfg.get("traction", []):
        d, tag = names.get(tr["on"], dim=2)
        if d != 2:
            raise CheckError(f"[[traction]] on {tr['on']!r}: no Physical Surface of that name")
        if "pn" in tr:
            rhs += ind * float(tr["pn"]) * ufl.inner(nrm, v) * ds(tag)
        if "p" in tr:
            rhs += ind * ufl.inner(ufl.as_vector([float(c) for c in tr["p"]]), v) * ds(tag)
    a_form, l_form = fem.form(a), fem.form(rhs)
    # K = Σ_b E_b K_b E_bᵀ: body b's forms on the uncut mesh, routed to its points.
    rows_, cols_, vals_ = [], [], []
    f = np.zeros(3 * npt)
    for b in range(nb):
        ind.x.array[:] = (cell_body == b).astype(float)
        A = fem.petsc.assemble_matrix(a_form)
        A.assemble()
        ai, aj, av = A.getValuesCSR()
        Kb = sp.csr_matrix((av, aj, ai), shape=(3 * nn, 3 * nn)).tocoo()
        bvec = fem.petsc.assemble_vector(l_form)
        bvec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        fb = bvec.array.copy()
        # dof → point of body b (dolfinx dof d sits on geometry node dof2geo[d]).
        dof2pt = np.full(nn, -1)
        for (vv, bb), pnt in point_of.items():
            if bb == b:
                dof2pt[geo2dof[vv]] = pnt
        keep = (dof2pt[Kb.row // 3] >= 0) & (dof2pt[Kb.col // 3] >= 0)
        rows_.append(3 * dof2pt[Kb.row[keep] // 3] + Kb.row[keep] % 3)
        cols_.append(3 * dof2pt[Kb.col[keep] // 3] + Kb.col[keep] % 3)
        vals_.append(Kb.data[keep])
        for dof in np.where(dof2pt >= 0)[0]:
            f[3 * dof2pt[dof]:3 * dof2pt[dof] + 3] += fb[3 * dof:3 * dof + 3]
    K = sp.csr_matrix((np.concatenate(vals_), (np.concatenate(rows_), np.concatenate(cols_))),
                      shape=(3 * npt, 3 * npt))
    for fo in cfg.get("force", []):
        d, tag = names.get(fo["on"], dim=0)
        if d != 0:
            raise CheckError(f"[[force]] on {fo['on']!r}: no Physical Point of that name")
        for t in group_nodes(gmsh, 0, tag):
            pnt = node_points[of_tag[int(t)]][0]  # the lowest body's copy
            f[3 * pnt:3 * pnt + 3] += np.asarray(fo["f"], dtype=float)

    # Conditions on every point of a held node.
    fixed: dict[int, list[tuple[np.ndarray, float]]] = {}
    for dc in cfg.get("dirichlet", []):
        d, tag = names.get(dc["on"], (None, None))
        if d is None:
            raise CheckError(f"[[dirichlet]] on {dc['on']!r}: no physical group of that name")
        comps = components(dc)
        for t in group_nodes(gmsh, d, tag):
            for pnt in node_points.get(of_tag[int(t)], []):
                for c, val in enumerate(comps):
                    if val is not None:
                        fixed.setdefault(pnt, []).append((np.eye(3)[c], val))
    slip_normals: dict[int, list[np.ndarray]] = {}
    for sl in cfg.get("slip", []):
        d, tag = names.get(sl["on"], dim=2)
        if d != 2:
            raise CheckError(f"[[slip]] on {sl['on']!r}: no Physical Surface of that name")
        tris = surface(sl["on"])
        nsum = sum(np.cross(x[t[1]] - x[t[0]], x[t[2]] - x[t[0]]) for t in tris)
        nsum = nsum / np.linalg.norm(nsum)
        for vv in np.unique(tris):
            slip_normals.setdefault(int(vv), []).append(nsum)
            for pnt in node_points.get(int(vv), []):
                fixed.setdefault(pnt, []).append((nsum, 0.0))

    # u_p = u0_p + T_p ξ_p.
    u0 = np.zeros(3 * npt)
    T_rows, T_cols, T_vals = [], [], []
    k = 0
    for pnt in range(npt):
        conds = fixed.get(pnt, [])
        if conds:
            R = np.array([c[0] for c in conds])
            vals = np.array([c[1] for c in conds])
            _, sv, vt = np.linalg.svd(R)
            rank = int((sv > 1e-10 * sv[0]).sum())
            u0i = np.linalg.lstsq(R, vals, rcond=None)[0]
            if np.abs(R @ u0i - vals).max() > 1e-9 * max(1.0, np.abs(vals).max()):
                raise CheckError(f"conflicting conditions at point {pnt}")
            u0[3 * pnt:3 * pnt + 3] = u0i
            basis = vt[rank:]
        else:
            basis = np.eye(3)
        for bvec_ in basis:
            for c in range(3):
                if bvec_[c] != 0.0:
                    T_rows.append(3 * pnt + c)
                    T_cols.append(k)
                    T_vals.append(bvec_[c])
            k += 1
    T = sp.csr_matrix((T_vals, (T_rows, T_cols)), shape=(3 * npt, k))
    Kr = (T.T @ K @ T).tocsc()
    fr = T.T @ (f - K @ u0)

    # Contact rows: (slave point, [(point, coefficient 3-vector)], g0, tributary area).
    rows = []
    def body_of_face(tri):
        cs = faces.get(tuple(sorted(int(v) for v in tri)), [])
        return cs
    def outward(tri, ci):
        """The unit normal of triangle tri outward of cell ci, and its area."""
        nrm_, area = tri_normal(x[tri])
        opp = [vv for vv in cells[ci] if vv not in tri][0]
        if np.dot(nrm_, x[opp] - x[tri[0]]) > 0:
            nrm_ = -nrm_
        return nrm_, area
    for c in contact:
        if "on" in c:
            tris = surface(c["on"])
            acc: dict[int, np.ndarray] = {}
            trib: dict[int, float] = {}
            bodies = None
            for tri in tris:
                cs = body_of_face(tri)
                if len(cs) != 2:
                    raise CheckError(f"[[contact]] on {c['on']!r}: a triangle not between two tetrahedra")
                bk, bl = sorted(cell_body[cs])
                ck = cs[0] if cell_body[cs[0]] == bk else cs[1]
                nrm_, area = outward(tri, ck)
                bodies = (bk, bl)
                for vv in tri:
                    acc[int(vv)] = acc.get(int(vv), 0.0) + area * nrm_
                    trib[int(vv)] = trib.get(int(vv), 0.0) + area / 3
            bk, bl = bodies
            for vv, s_ in acc.items():
                nrm_, _ = mirrored(s_ / np.linalg.norm(s_), slip_normals.get(vv, []))
                rows.append((point_of[(vv, bl)], [(point_of[(vv, bk)], nrm_), (point_of[(vv, bl)], -nrm_)],
                             0.0, trib[vv]))
        else:
            st, mt = surface(c["slave"]), surface(c["master"])
            mcell = [body_of_face(t)[0] for t in mt]
            mb = cell_body[mcell[0]]
            sb = cell_body[body_of_face(st[0])[0]]
            mn = np.array([outward(t, ci)[0] for t, ci in zip(mt, mcell)])
            disc = c.get("discretization")
            if disc is None:
                # The default (problem-format §12): mortar, unless the slave is
                # more than 10 times stiffer than the master.
                e_of = lambda b: [float(mats[nm]["E"]) for nm, tag in names.volumes()  # noqa: E731
                                  if np.isin(cell_tags.find(tag), np.where(cell_body == b)[0]).any()]
                disc = "nts" if min(e_of(sb)) > 10.0 * max(e_of(mb)) else "mortar"
            if disc == "mortar":
                scell = [body_of_face(t)[0] for t in st]
                sn = np.array([outward(t, ci)[0] for t, ci in zip(st, scell)])
                for vv, (nj, wts, gap, dj) in sorted(mortar_rows(x, st, sn, mt, mn, L).items()):
                    nj, _ = mirrored(nj, slip_normals.get(vv, []))
                    coef = [(point_of[(mnode, mb)], -w * nj) for mnode, w in sorted(wts.items()) if w != 0.0]
                    coef.append((point_of[(vv, sb)], nj))
                    rows.append((point_of[(vv, sb)], coef, gap, dj))
                continue
            trib: dict[int, float] = {}
            for tri in st:
                _, area = tri_normal(x[tri])
                for vv in tri:
                    trib[int(vv)] = trib.get(int(vv), 0.0) + area / 3
            P0, P1, P2 = x[mt[:, 0]], x[mt[:, 1]], x[mt[:, 2]]
            for vv in sorted(trib):
                xs = x[vv]
                d_ = np.einsum("ij,ij->i", xs - P0, mn)
                proj = xs - d_[:, None] * mn
                # barycentric of proj in each triangle
                e1, e2, r = P1 - P0, P2 - P0, proj - P0
                d11 = np.einsum("ij,ij->i", e1, e1)
                d12 = np.einsum("ij,ij->i", e1, e2)
                d22 = np.einsum("ij,ij->i", e2, e2)
                r1 = np.einsum("ij,ij->i", r, e1)
                r2 = np.einsum("ij,ij->i", r, e2)
                den = d11 * d22 - d12 * d12
                w1 = (d22 * r1 - d12 * r2) / den
                w2 = (d11 * r2 - d12 * r1) / den
                w0 = 1 - w1 - w2
                inside = np.minimum(np.minimum(w0, w1), w2) >= -1e-6
                if not inside.any():
                    continue
                cand = np.where(inside)[0]
                j = cand[np.argmin(np.abs(d_[cand]))]
                nrm_, cos_ = mirrored(mn[j], slip_normals.get(vv, []))
                coef = [(point_of[(int(mt[j][q]), mb)], w * nrm_) for q, w in enumerate((w0[j], w1[j], w2[j]))]
                coef.append((point_of[(vv, sb)], -nrm_))
                rows.append((point_of[(vv, sb)], coef, float(d_[j]) * cos_, trib[vv]))
    m = len(rows)
    if m:
        Ar_, Ac_, Av_ = [], [], []
        g0 = np.zeros(m)
        for i, (_, coef, gap, _) in enumerate(rows):
            g0[i] = gap
            for pnt, cv in coef:
                for c_ in range(3):
                    if cv[c_] != 0.0:
                        Ar_.append(i)
                        Ac_.append(3 * pnt + c_)
                        Av_.append(cv[c_])
        A = sp.csr_matrix((Av_, (Ar_, Ac_)), shape=(m, 3 * npt))
        Ared = (A @ T).tocsr()
        gred = g0 - A @ u0
        # Rows on fixed points only are left out as signorini does.
        live = np.diff(Ared.indptr) > 0
        import fenicsx_crosscheck as x2

        try:
            xi, lam_n, _, _ = x2.solve_qp(Kr, fr, Ared[live], gred[live], "3D contact")
        except x2.NotChecked as e:
            raise NotChecked(str(e))
        lam = np.zeros(m)
        lam[live] = lam_n
    else:
        try:
            xi = spla.spsolve(Kr, fr)
        except Exception as e:  # a singular Kr: rigid motions left
            raise NotChecked(f"the reduced stiffness is singular ({e}): a body with rigid motions")
        if not np.all(np.isfinite(xi)):
            raise NotChecked("the reduced stiffness is singular: a body with rigid motions")
        lam = np.zeros(0)
    uref = (u0 + T @ xi).reshape(-1, 3)
    log(f"reference: {nn} nodes, {npt} points, {nb} bodies, {ncells} tetrahedra, {k} unknowns, "
        f"{m} contact rows ({time.time() - t0:.1f} s)")

    out = tmp / "solid"
    out.mkdir(parents=True, exist_ok=True)
    cmd = [str(exe), "solve", str(toml), "--out", str(out), "--quiet"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        log(f"`{' '.join(cmd)}` exited {p.returncode}: {(p.stdout + p.stderr).strip()[-400:]} -> FAIL")
        return 1
    sig = read_signorini(out / f"{toml.stem}.h5")
    # My body b ↔ signorini's body: through a tetrahedron's centroid.
    scent = sig["nodes"][sig["tets"]].mean(axis=1)
    ttree = cKDTree(scent)
    body_map = {}
    for b in range(nb):
        ci = int(np.where(cell_body == b)[0][0])
        dd, j = ttree.query(x[cells[ci]].mean(axis=0))
        if dd > 1e-9 * L:
            raise CheckError("signorini's tetrahedra do not match the mesh's")
        body_map[b] = int(sig["body"][sig["tets"][j][0]])
    mine_key = np.column_stack([x[pts_node], [10.0 * L * body_map[b] for b in
                                              [next(bb for (vv, bb), q in point_of.items() if q == pnt)
                                               for pnt in range(npt)]]])
    theirs_key = np.column_stack([sig["nodes"], 10.0 * L * sig["body"]])
    if len(theirs_key) != npt:
        raise CheckError(f"signorini has {len(theirs_key)} points, this model {npt}")
    dist, idx = cKDTree(mine_key).query(theirs_key)
    if dist.max() > 1e-9 * L or len(set(idx.tolist())) != npt:
        raise CheckError(f"points do not match by coordinates and body (max distance {dist.max():.3e})")
    mine = uref[idx]  # in signorini's point order
    du = np.abs(mine - sig["u"]).max() / max(np.abs(mine).max(), 1e-300)
    # Stresses per tetrahedron from the reference displacements (signorini's
    # tetrahedra and point numbering), VTK's order xx, yy, zz, xy, yz, xz.
    spts = sig["nodes"]
    s_ref = np.zeros((len(sig["tets"]), 6))
    grad_ref = np.array([[-1, -1, -1], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    for e, (tet, mi) in enumerate(zip(sig["tets"], sig["material"])):
        lam_e, mu_e, _ = lame(mats[sig["material_names"][mi]])
        J = (spts[tet][1:] - spts[tet][0]).T
        grads = np.linalg.solve(J.T, grad_ref.T).T
        gu = mine[tet].T @ grads
        eps_ = 0.5 * (gu + gu.T)
        sig_ = 2 * mu_e * eps_ + lam_e * np.trace(eps_) * np.eye(3)
        s_ref[e] = [sig_[0, 0], sig_[1, 1], sig_[2, 2], sig_[0, 1], sig_[1, 2], sig_[0, 2]]
    dsg = np.abs(s_ref - sig["stress"]).max() / max(np.abs(s_ref).max(), 1e-300)
    ok = du <= tol and dsg <= tol
    msg = f"displacement {du:.2e}, stress {dsg:.2e}"
    if m:
        sig_rows = {int(sp_): r for r, sp_ in enumerate(sig["contact_slave"])}
        pos = np.empty(npt, dtype=np.int64)
        pos[idx] = np.arange(npt)  # my point -> signorini point
        if len(sig_rows) != m:
            raise CheckError(f"signorini has {len(sig_rows)} contact rows, this model {m}")
        lam_s = np.array([sig["multipliers"][sig_rows[int(pos[r[0]])]] for r in rows])
        pr_s = np.array([sig["contact_pressure"][sig_rows[int(pos[r[0]])]] for r in rows])
        pr = lam / np.array([r[3] for r in rows])
        dl = np.abs(lam - lam_s).max() / max(np.abs(lam).max(), 1e-300)
        dp = np.abs(pr - pr_s).max() / max(np.abs(pr).max(), 1e-300)
        ok = ok and dl <= tol and dp <= tol
        msg += f", multipliers {dl:.2e}, pressure {dp:.2e}"
        if sig["contact_gap0"] is not None:
            # the rows' initial gaps (weighted gaps g̃_j/D_jj for mortar rows),
            # relative to the largest (at least 10⁻⁶ of the model's size: a
            # patch test's gaps are 0 to round-off)
            g0_s = np.array([sig["contact_gap0"][sig_rows[int(pos[r[0]])]] for r in rows])
            g0 = np.array([r[2] for r in rows])
            dg = np.abs(g0 - g0_s).max() / max(np.abs(g0).max(), 1e-6 * L)
            ok = ok and dg <= tol
            msg += f", gap0 {dg:.2e}"
        msg += f" ({int((lam > 0).sum())} of {m} rows in contact)"
    log(f"3D {'contact' if m else 'linear elasticity'}: {msg} (max |u| {np.abs(mine).max():.4e}) "
        f"-> {'OK' if ok else 'FAIL'}")
    return 0 if ok else 1
