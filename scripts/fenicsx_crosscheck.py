#!/usr/bin/python3
"""Cross-check `signorini` against an independent FEniCSx (dolfinx) model.

Usage:  /usr/bin/python3 scripts/fenicsx_crosscheck.py meshes/NAME.toml [--tol 1e-8]
        exit 0 OK, 1 FAIL, 2 usage/setup error, 3 NOT CHECKED (see the end)

A mesh of tetrahedra (a 3D model) is checked by scripts/fenicsx_crosscheck3d.py
(linear elasticity; 3D contact is NOT CHECKED until `solve` runs it).

Runs under Debian's python3 (python3-dolfinx-real 0.5.2, python3-gmsh,
python3-scipy, python3-h5py); the QP solver Clarabel comes from PyPI and is
looked for in <repo>/.venv/debian-site (pip install --target, see python_checks.sh) or
$SIGNORINI_PYDEPS.

What it does
------------
The mesh is read with the gmsh Python API (gmsh.open) and converted with
dolfinx.io.gmshio.model_to_mesh (read_from_msh is broken in dolfinx 0.5.2).
The stiffness and the loads are assembled by dolfinx on P1 vector Lagrange
elements:

    a(u, v) = t ∫ 2μ ε(u):ε(v) + λ tr ε(u) tr ε(v) dx
    L(v)    = t ∫ ρ g·v dx + t ∫_Γτ (P + pn n)·v ds

(λ → 2λμ/(λ+2μ) in plane stress; t = thickness in plane stress, 1 in plane
strain).  λ, μ, ρ are DG0 functions.

Cut mesh (contact): the problem-format contract duplicates the nodes of each
conforming contact curve, one copy per body.  Rather than re-meshing, every
form is assembled once *per body* on the uncut dolfinx mesh, with λ, μ, ρ
multiplied by the body's indicator (and tractions on that body's facets
only).  K_b then couples only nodes of body b, and the cut stiffness is
K = Σ_b E_b K_b E_bᵀ, E_b mapping node v of body b to its copy (v, b).  This
is exact (element contributions are simply routed to the body's copy), and
with no contact curve it reduces to the ordinary assembly.

Dirichlet data, slip lines (u·n = 0 with the per-node averaged unit outward
normal of the line's segments) and point conditions are eliminated node by
node exactly as documented (u_p = u0_p + T_p ξ_p), in scipy.

Part a (linear elasticity): the contact curves are ordinary interior lines
(no copies).  Solve K_r ξ = f_r with scipy.sparse.linalg.spsolve and compare
with `signorini solve TOML --no-contact` (nodal displacements matched by
coordinates; stresses per triangle).  A body left with rigid motions is
refused by signorini (exit 2): then part a only checks that refusal.

Part b (contact): rows built from the mesh as problem-format.md says:
conforming curves → one row per node copy pair (averaged unit outward normal
of the lower-numbered body, row n·(u_k − u_l) ≤ 0; `normals = "segment"` gives
one row per distinct segment normal); non-matching pairs → nearest master
segment projection, n·((1−ξ)u_m1 + ξ u_m2 − u_s) ≤ g.  The QP
min ½xᵀKx − fᵀx, Ax ≤ g is solved by Clarabel (interior point, handles the
positive semidefinite K of floating bodies), then polished by a primal-dual
active-set iteration that solves the equality-constrained KKT system of the
active rows exactly (sparse LU).  Compared with `signorini solve TOML`:
displacements, stresses, multipliers, initial gaps and contact pressures
(λ/(trib × thickness), trib = ∫N ds of the row's node on the contact
segments; the mortar weight D_jj on a mortar pair).

Axisymmetric models (`[model] plane = "axisymmetric"`, x = r ≥ 0, y = z,
docs/methods.md §10): every form carries r (per radian),

    a(u, v) = ∫ 2μ (ε(u):ε(v) + u_r v_r/r²) + λ (div u + u_r/r)(div v + v_r/r) r dx₁
    L(v)    = ∫ ρ (g·v + ω² r v_r) r dx + ∫_Γτ (P + pn n)·v r ds

with dx₁ the one-point (centroid) rule: signorini's element evaluates the
hoop strain u_r/r at the centroid (r̄|T| B4ᵀD4B4) and its in-plane strains
are constant, so dx₁ is its quadrature exactly (with FEniCSx's default,
estimated quadrature degree the displacements differ by O(h²): 8.3e-3,
2.5e-3, 6.1e-4, 1.7e-4 on tests/data/axi_cup at h = 0.3 … 0.0375,
multipliers 2.1e-3 … 3.7e-5). Loads are integrated exactly (degree 4 and
2), as signorini does; a step's load factor scales ρω²r. u_r = 0 is added on every node with r ≤ 1e-9 max r, the only rigid
motion is the axial translation, contact rows keep their pointwise form,
mortar integrals (D, M, g̃) and tributary weights (∫N r ds) carry r. An
`interference = true` pair keeps its negative gap.

Friction (`[[contact]] friction = μ` or `tresca = τ`, docs/methods.md §9):
every contact row gets a tangential row, its own coefficients with n turned
by +90° (t = (−n_y, n_x)), built here from the same geometry; its slip over a
load step is v = T u − T u_prev (u_prev: this reference's previous step, 0
before the first). The Tresca bound is s = τ × tributary weight ×
thickness (∫N r ds axisymmetric, D on a mortar row), and the problem

    min ½uᵀKu − fᵀu + Σ sᵢ|vᵢ|  s.t.  A u ≤ g

is solved by Clarabel with one auxiliary variable per row (wᵢ ≥ ±vᵢ,
objective + Σ sᵢwᵢ), λ_n and λ_t = z₊ − z₋ from its duals, then polished by
an active-set iteration (open/contact, stick/slip) that solves the exact
KKT system. Coulomb (s = μλ_n) is this reference's own fixed point: Tresca
solves with s ← s + ω(μλ_n − s), ω = 1 halved while the change grows, from
the glued answer (s = ∞: every row sticks, so a body held by friction alone
is held from the start; s¹ = μλ_n of it) until max|μλ_n − s| ≤ 1e-12 max μλ_n
or the change stalls at the solves' round-off (the count of solves is
printed). A hand case (a node on a floor) checks the signs against the
analytic answer on every frictional run. A mortar row on a line of symmetry (its slave point
held along t, at the end of its run of rows) has no tangential row, and a
row whose tangential row has no unknowns slips by prescription (λ_t =
s·sign v), as methods.md §9 says. Compared besides the frictionless
fields: λ_t (`multipliers_t`), the slip v (`slip`, relative to the larger of
max|v| and 1e-6 max|u|) and the states 0 open / 1 stick / 2 slip (`state`),
the reference's by signorini's rule (slip where |λ_t| ≥ (1 − 1e-6) s). A
state may differ only on a row at a state boundary as the reference sees
it: open/contact where λ_n ≤ 10·tol·max|λ| and the gap left ≤ 10·tol·max|u|,
stick/slip where |λ_t| is within 10·tol·max|λ| of (1 − 1e-6) s.

What the problem leaves undetermined is said and not compared as if it were
determined (uniqueness()): the displacement along a rigid motion that no row
in contact or sticking holds is compared modulo that motion, and rows whose
columns are linearly dependent (a slave node of two pairs on one master
corner) have their multipliers and states left out.

Exit code: 0 all comparisons within --tol; 1 FAIL: a difference above it
(or a failed self-check, or signorini failing on the problem); 2 usage or
setup error; 3 NOT CHECKED: the reference cannot check this problem, with
the reason (a problem-file key it does not model, Tresca and Coulomb pairs
in one problem, its own Coulomb fixed point not settling in 300 Tresca
solves, or its own solve failing or not certified to 1e-9): no verdict on
signorini.
"""

from __future__ import annotations

import argparse
import logging
import math
import os
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
for _d in (os.environ.get("SIGNORINI_PYDEPS"), str(REPO / ".venv" / "debian-site")):
    if _d and Path(_d).is_dir() and _d not in sys.path:
        sys.path.append(_d)  # after dist-packages: Debian's numpy/scipy win

try:
    import numpy as np
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla
    import scipy.sparse.csgraph  # noqa: F401  (sp.csgraph)
    from scipy.spatial import cKDTree
except ImportError as _e:
    print(f"fenicsx_crosscheck: error: {_e} under {sys.executable}: run this script with Debian's "
          "/usr/bin/python3 (python3-dolfinx-real, python3-gmsh, python3-scipy, python3-h5py; "
          "scripts/python_checks.sh installs them)", file=sys.stderr)
    sys.exit(2)


class CheckError(Exception):
    """A comparison failed (exit 1)."""


class SetupError(Exception):
    """Bad usage or a missing tool (exit 2)."""


class NotChecked(Exception):
    """The reference cannot check this (exit 3): a feature it does not model, or
    its own solve did not settle. Never a FAIL of signorini."""


class Conflict(Exception):
    """Conditions at a point contradict each other (signorini: exit 2)."""


def log(msg: str) -> None:
    print(msg, flush=True)


# --------------------------------------------------------------------- mesh


class GmshMesh:
    """Nodes, triangles, lines and points of a .msh with physical names."""

    def __init__(self, gmsh, path: Path, materials: dict):
        gmsh.open(str(path))
        tags, coords, _ = gmsh.model.mesh.getNodes()
        order = np.argsort(tags)
        self.tags = np.asarray(tags, dtype=np.int64)[order]
        self.x = np.asarray(coords, dtype=float).reshape(-1, 3)[order, :2]
        self.index = {int(t): i for i, t in enumerate(self.tags)}
        self.groups: dict[str, tuple[int, int]] = {}
        for dim, ptag in gmsh.model.getPhysicalGroups():
            name = gmsh.model.getPhysicalName(dim, ptag)
            self.groups.setdefault(name, (dim, ptag))
        self._gmsh = gmsh
        # triangles of the material surfaces
        tris, mat, seen = [], [], set()
        self.material_names = list(materials.keys())
        for mi, name in enumerate(self.material_names):
            dim, ptag = self.group(name, 2)
            for ent in gmsh.model.getEntitiesForPhysicalGroup(dim, ptag):
                etypes, etags, enodes = gmsh.model.mesh.getElements(2, ent)
                for ty, et, en in zip(etypes, etags, enodes):
                    if ty != 2:
                        raise SetupError(f"surface {name}: element type {ty} is not a 3-node triangle")
                    en = np.asarray(en, dtype=np.int64).reshape(-1, 3)
                    for t, nodes in zip(et, en):
                        if int(t) in seen:
                            continue
                        seen.add(int(t))
                        tris.append([self.index[int(v)] for v in nodes])
                        mat.append(mi)
        self.tri = np.array(tris, dtype=np.int64)
        self.tri_mat = np.array(mat, dtype=np.int64)
        # edge -> triangles
        self.edge_tris: dict[tuple[int, int], list[int]] = {}
        for t, tri in enumerate(self.tri):
            for k in range(3):
                a, b = int(tri[k]), int(tri[(k + 1) % 3])
                self.edge_tris.setdefault((min(a, b), max(a, b)), []).append(t)

    def group(self, name: str, dim: int | None = None) -> tuple[int, int]:
        if name not in self.groups:
            raise SetupError(f"no physical group named {name!r} in the mesh")
        g = self.groups[name]
        if dim is not None and g[0] != dim:
            raise SetupError(f"{name!r} is a physical group of dimension {g[0]}, expected {dim}")
        return g

    def lines(self, name: str) -> list[tuple[int, int]]:
        """Segments (node indices) of a physical curve, in element order."""
        dim, ptag = self.group(name, 1)
        out = []
        for ent in self._gmsh.model.getEntitiesForPhysicalGroup(dim, ptag):
            etypes, _, enodes = self._gmsh.model.mesh.getElements(1, ent)
            for ty, en in zip(etypes, enodes):
                if ty != 1:
                    raise SetupError(f"curve {name}: element type {ty} is not a 2-node line")
                for a, b in np.asarray(en, dtype=np.int64).reshape(-1, 2):
                    out.append((self.index[int(a)], self.index[int(b)]))
        return out

    def points(self, name: str) -> list[int]:
        dim, ptag = self.group(name, 0)
        out = []
        for ent in self._gmsh.model.getEntitiesForPhysicalGroup(dim, ptag):
            ntags, _, _ = self._gmsh.model.mesh.getNodes(0, ent)
            out += [self.index[int(v)] for v in ntags]
        return out

    def outward_normal(self, t: int, a: int, b: int) -> np.ndarray:
        tri = self.tri[t]
        c = [int(v) for v in tri if v != a and v != b][0]
        pa, pb, pc = self.x[a], self.x[b], self.x[c]
        d = pb - pa
        n = np.array([d[1], -d[0]]) / np.hypot(*d)
        if n @ (pc - pa) > 0:
            n = -n
        return n


class Topology:
    """Bodies after cutting along the conforming contact curves, node copies."""

    def __init__(self, m: GmshMesh, contact_curves: list[str]):
        self.contact_edge: dict[tuple[int, int], int] = {}
        for cid, name in enumerate(contact_curves):
            for a, b in m.lines(name):
                self.contact_edge[(min(a, b), max(a, b))] = cid
        nt = len(m.tri)
        parent = list(range(nt))

        def find(x):
            while parent[x] != x:
                parent[x] = parent[parent[x]]
                x = parent[x]
            return x

        for e, ts in m.edge_tris.items():
            if len(ts) > 2:
                raise SetupError(f"edge {e} shared by more than two triangles")
            if len(ts) == 2 and e not in self.contact_edge:
                ra, rb = find(ts[0]), find(ts[1])
                if ra != rb:
                    parent[ra] = rb
        roots = {}
        for t in range(nt):
            r = find(t)
            mt = int(m.tags[m.tri[t]].min())
            roots[r] = min(roots.get(r, 1 << 62), mt)
        order = sorted(roots, key=lambda r: roots[r])
        body_of_root = {r: i for i, r in enumerate(order)}
        self.nbodies = len(order)
        self.tri_body = np.array([body_of_root[find(t)] for t in range(nt)], dtype=np.int64)
        pairs = sorted({(int(self.tri_body[t]), int(v)) for t in range(nt) for v in m.tri[t]},
                       key=lambda p: (p[0], int(m.tags[p[1]])))
        self.point_body = np.array([p[0] for p in pairs], dtype=np.int64)
        self.point_node = np.array([p[1] for p in pairs], dtype=np.int64)
        self.point_of = {(v, b): i for i, (b, v) in enumerate(pairs)}
        self.copies: dict[int, list[int]] = {}
        for i, (b, v) in enumerate(pairs):
            self.copies.setdefault(v, []).append(i)  # ascending body
        self.np = len(pairs)
        self.x = m.x[self.point_node]


# ------------------------------------------------------------- dolfinx part


class Assembler:
    """dolfinx forms on the uncut mesh, assembled per body."""

    def __init__(self, gmsh, m: GmshMesh, cfg: dict):
        from mpi4py import MPI
        import dolfinx
        import dolfinx.fem.petsc  # noqa: F401
        import dolfinx.io.gmshio
        import ufl

        self.dolfinx, self.ufl = dolfinx, ufl
        # the JIT (cffi/distutils) logs every compiler call at INFO on the root logger
        logging.disable(logging.INFO)
        msh, ct, ft = dolfinx.io.gmshio.model_to_mesh(gmsh.model, MPI.COMM_WORLD, 0, gdim=2)
        self.msh = msh
        # geometry node -> gmsh node: model_to_mesh orders its input by gmsh tag (tag − 1),
        # so input_global_indices gives the tag (coordinates would be ambiguous where two
        # bodies have distinct nodes at the same place, as in a non-matching pair)
        geo_node = np.array([m.index[int(i) + 1] for i in msh.geometry.input_global_indices])
        scale = np.ptp(m.x, axis=0).max()
        if np.abs(msh.geometry.x[:, :2] - m.x[geo_node]).max() > 1e-12 * scale:
            raise SetupError("dolfinx geometry nodes do not match the gmsh nodes")
        # cells -> gmsh triangles
        key_tri = {tuple(sorted(int(v) for v in tri)): t for t, tri in enumerate(m.tri)}
        gdm = msh.geometry.dofmap
        ncell = msh.topology.index_map(2).size_local
        self.cell_tri = np.empty(ncell, dtype=np.int64)
        for c in range(ncell):
            key = tuple(sorted(int(geo_node[v]) for v in gdm.links(c)))
            if key not in key_tri:
                raise SetupError(f"dolfinx cell {c} is not a triangle of a material surface")
            self.cell_tri[c] = key_tri[key]
        if ncell != len(m.tri):
            raise SetupError(f"dolfinx has {ncell} cells, the material surfaces {len(m.tri)} triangles")
        # facets -> gmsh edges (through cells: topology vertex = geometry node for P1)
        tdim = 2
        msh.topology.create_connectivity(tdim, 0)
        msh.topology.create_connectivity(tdim - 1, 0)
        msh.topology.create_connectivity(tdim - 1, tdim)
        c2v = msh.topology.connectivity(tdim, 0)
        vert_node = np.full(msh.topology.index_map(0).size_local, -1, dtype=np.int64)
        for c in range(ncell):
            for tv, gv in zip(c2v.links(c), gdm.links(c)):
                vert_node[tv] = geo_node[gv]
        f2v = msh.topology.connectivity(tdim - 1, 0)
        nfac = msh.topology.index_map(tdim - 1).size_local
        self.edge_facet = {}
        for f in range(nfac):
            a, b = (int(vert_node[v]) for v in f2v.links(f))
            self.edge_facet[(min(a, b), max(a, b))] = f
        self.f2c = msh.topology.connectivity(tdim - 1, tdim)

        V = dolfinx.fem.VectorFunctionSpace(msh, ("Lagrange", 1))
        self.V = V
        # P1 on a linear mesh: the cell's DOFs follow its geometry nodes
        self.dof_node = np.full(V.dofmap.index_map.size_local, -1, dtype=np.int64)
        for c in range(ncell):
            self.dof_node[V.dofmap.cell_dofs(c)] = geo_node[gdm.links(c)]
        dofx = V.tabulate_dof_coordinates()[:, :2]
        if (self.dof_node < 0).any() or np.abs(dofx - m.x[self.dof_node]).max() > 1e-12 * scale:
            raise SetupError("dolfinx DOF coordinates do not match the gmsh nodes")
        Q = dolfinx.fem.FunctionSpace(msh, ("DG", 0))
        self.mu, self.lam, self.rho = (dolfinx.fem.Function(Q) for _ in range(3))
        self.q_cells = np.arange(ncell)  # DG0: one dof per cell, dof = cell index below
        self.q_dof = np.array([Q.dofmap.cell_dofs(c)[0] for c in range(ncell)])
        plane = cfg.get("model", {}).get("plane", "strain")
        self.plane_stress = plane == "stress"
        th = float(cfg.get("model", {}).get("thickness", 1.0)) if self.plane_stress else 1.0
        self.th = th
        grav = cfg.get("model", {}).get("gravity", [0.0, 0.0])
        C = dolfinx.fem.Constant
        self.t = C(msh, th)
        self.g = C(msh, np.array(grav, dtype=float))
        self.P = C(msh, np.zeros(2))
        self.PN = C(msh, 0.0)
        u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
        eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
        self.axi = plane == "axisymmetric"
        self.omega2 = C(msh, 0.0)  # ω² × the step's load factor (axisymmetric)
        if self.axi:
            # x = r, y = z; every integral carries r (per radian, methods.md §10).
            r = ufl.SpatialCoordinate(msh)[0]
            self.r = r
            # Stiffness: the hoop strain u_r/r at the one-point centroid rule,
            # as signorini's element (r̄|T| B4ᵀD4B4); the in-plane strains are
            # constant on a P1 triangle, so that rule is the element's exactly.
            dx1 = ufl.dx(metadata={"quadrature_degree": 1})
            tr4 = lambda w: ufl.tr(eps(w)) + w[0] / r  # noqa: E731
            self.a = dolfinx.fem.form((2 * self.mu * (ufl.inner(eps(u), eps(v)) + u[0] / r * v[0] / r)
                                       + self.lam * tr4(u) * tr4(v)) * r * dx1)
            # Body loads are polynomials of degree ≤ 3 on a triangle: exact at degree 4.
            dx4 = ufl.dx(metadata={"quadrature_degree": 4})
            self.Lg = dolfinx.fem.form(self.rho * (ufl.dot(self.g, v) + self.omega2 * r * v[0]) * r * dx4)
            self.wr = r
        else:
            self.a = dolfinx.fem.form(self.t * (2 * self.mu * ufl.inner(eps(u), eps(v))
                                                + self.lam * ufl.tr(eps(u)) * ufl.tr(eps(v))) * ufl.dx)
            self.Lg = dolfinx.fem.form(self.t * self.rho * ufl.dot(self.g, v) * ufl.dx)
            self.wr = self.t
        self.v = v
        self.n = ufl.FacetNormal(msh)
        # material data per cell
        mats = cfg["materials"]
        E = np.array([float(mats[nm]["E"]) for nm in m.material_names])
        nu = np.array([float(mats[nm]["nu"]) for nm in m.material_names])
        rho = np.array([float(mats[nm].get("rho", 0.0)) for nm in m.material_names])
        mu = E / (2 * (1 + nu))
        lam = E * nu / ((1 + nu) * (1 - 2 * nu))
        if self.plane_stress:
            lam = 2 * lam * mu / (lam + 2 * mu)
        cm = m.tri_mat[self.cell_tri]
        self.cell_mu, self.cell_lam, self.cell_rho = mu[cm], lam[cm], rho[cm]

    def _set_body(self, mask: np.ndarray) -> None:
        for f, vals in ((self.mu, self.cell_mu), (self.lam, self.cell_lam), (self.rho, self.cell_rho)):
            arr = np.zeros_like(f.x.array)
            arr[self.q_dof] = vals * mask
            f.x.array[:] = arr

    def _matrix(self, form) -> sp.csr_matrix:
        import dolfinx.fem.petsc as dp
        A = dp.assemble_matrix(form)
        A.assemble()
        ip, ii, dd = A.getValuesCSR()
        n = A.getSize()[0]
        M = sp.csr_matrix((dd.copy(), ii.copy(), ip.copy()), shape=(n, n))
        A.destroy()
        return M

    def _vector(self, form) -> np.ndarray:
        b = self.dolfinx.fem.assemble_vector(form)
        return b.array.copy()

    def body_stiffness(self, cell_in_body: np.ndarray) -> sp.csr_matrix:
        self._set_body(cell_in_body.astype(float))
        return self._matrix(self.a)

    def body_gravity(self, cell_in_body: np.ndarray) -> np.ndarray:
        self._set_body(cell_in_body.astype(float))
        return self._vector(self.Lg)

    def traction(self, facets: list[int], p, pn) -> np.ndarray:
        """Load vector of a constant traction on the given exterior facets."""
        dolfinx, ufl = self.dolfinx, self.ufl
        facets = np.array(sorted(set(facets)), dtype=np.int32)
        mt = dolfinx.mesh.meshtags(self.msh, 1, facets, np.ones(len(facets), dtype=np.int32))
        ds = ufl.Measure("ds", domain=self.msh, subdomain_data=mt)
        self.P.value = np.array(p if p is not None else [0.0, 0.0], dtype=float)
        self.PN.value = float(pn if pn is not None else 0.0)
        # wr: thickness t (plane), r (axisymmetric: ∫ N P r ds, exact at degree 2)
        L = dolfinx.fem.form(self.wr * (ufl.dot(self.P, self.v) + self.PN * ufl.dot(self.n, self.v))
                             * ds(1, metadata={"quadrature_degree": 2}))
        return self._vector(L)


# ---------------------------------------------------------------- problem


def eliminate(cs):
    """signorini's per-point elimination: conditions [(r, v)] -> (u0, T columns)."""
    if not cs:
        return np.zeros(2), [np.array([1.0, 0.0]), np.array([0.0, 1.0])]
    r1, v1r = np.asarray(cs[0][0], float), cs[0][1]
    q1 = r1 / np.linalg.norm(r1)
    v1 = v1r / np.linalg.norm(r1)
    second = None
    for r, v in cs[1:]:
        rn = np.asarray(r, float) / np.linalg.norm(r)
        if abs(rn[0] * q1[1] - rn[1] * q1[0]) > 1e-8:
            second = (np.asarray(r, float), v)
            break
    if second is None:
        for r, v in cs[1:]:
            rn = np.asarray(r, float) / np.linalg.norm(r)
            s = rn @ q1
            vv = v / np.linalg.norm(r)
            if abs(vv - s * v1) > 1e-9 * (1 + abs(vv) + abs(v1)):
                raise Conflict("two conditions prescribe different values in one direction")
        return v1 * q1, [np.array([-q1[1], q1[0]])]
    ra, rb = r1, second[0]
    det = ra[0] * rb[1] - ra[1] * rb[0]
    u = np.array([(v1r * rb[1] - second[1] * ra[1]) / det, (ra[0] * second[1] - rb[0] * v1r) / det])
    for r, v in cs:
        res = r[0] * u[0] + r[1] * u[1] - v
        if abs(res) > 1e-9 * (1 + abs(v) + abs(u[0]) + abs(u[1])):
            raise Conflict(f"more than two independent conditions that disagree (residual {res:.3e})")
    return u, []


# The problem-file keys this reference models (docs/problem-format.md); [solver]
# and [output] choose how signorini solves and writes, not the problem.
MODELLED = {
    "mesh": {"file"},
    "model": {"plane", "thickness", "gravity", "omega"},
    "materials": {"E", "nu", "rho"},
    "dirichlet": {"on", "u", "ux", "uy"},
    "slip": {"on"},
    "traction": {"on", "p", "pn"},
    "force": {"on", "f"},
    "contact": {"on", "normals", "slave", "master", "max_gap", "discretization", "interference", "friction",
                "tresca"},
    "steps": {"t", "factor", "load", "displacement", "dirichlet"},
    "solver": None,
    "output": None,
}


def unmodelled(cfg: dict) -> list[str]:
    """Keys of the problem file that the reference does not model."""
    out = []
    for sec, val in cfg.items():
        if sec not in MODELLED:
            out.append(f"[{sec}]")
            continue
        keys = MODELLED[sec]
        if keys is None:
            continue
        entries = val if isinstance(val, list) else (list(val.values()) if sec == "materials" else [val])
        for e in entries:
            if isinstance(e, dict):
                out += [f"{sec}.{k}" for k in e if k not in keys]
    return sorted(set(out))


def at_step(cfg: dict, s: int) -> dict:
    """The problem of load step s (0-based), as README's [[steps]] extension says: loads
    (tractions, point forces, gravity) × load factor, prescribed displacements × displacement
    factor or replaced by the step's dirichlet.NAME = [ux, uy]."""
    import copy

    steps = cfg.get("steps", [])
    if s >= len(steps):
        return cfg
    st = steps[s]
    out = copy.deepcopy(cfg)
    lf = st.get("load", st.get("factor", 1.0))
    df = st.get("displacement", st.get("factor", 1.0))
    for t in out.get("traction", []):
        if "p" in t:
            t["p"] = [t["p"][0] * lf, t["p"][1] * lf]
        if "pn" in t:
            t["pn"] = t["pn"] * lf
    for fo in out.get("force", []):
        fo["f"] = [fo["f"][0] * lf, fo["f"][1] * lf]
    if "gravity" in out.get("model", {}):
        g = out["model"]["gravity"]
        out["model"]["gravity"] = [g[0] * lf, g[1] * lf]
    out.setdefault("model", {})["_load_factor"] = lf  # scales ρω²r (axisymmetric omega)
    explicit = st.get("dirichlet", {})
    for d in out.get("dirichlet", []):
        if d["on"] in explicit:
            u = explicit[d["on"]]
            if "u" in d:
                d["u"] = list(u)
            else:
                if "ux" in d:
                    d["ux"] = u[0]
                if "uy" in d:
                    d["uy"] = u[1]
        else:
            if "u" in d:
                d["u"] = [d["u"][0] * df, d["u"][1] * df]
            for k in ("ux", "uy"):
                if k in d:
                    d[k] = d[k] * df
    return out


class Problem:
    def __init__(self, toml_path: Path, with_contact: bool, gmsh, point_force_thickness: bool = True):
        self.toml_path = toml_path
        self.cfg = tomllib.loads(toml_path.read_text())
        cfg = self.cfg
        self.mesh_path = (toml_path.parent / cfg["mesh"]["file"]).resolve()
        self.m = GmshMesh(gmsh, self.mesh_path, cfg["materials"])
        contacts = cfg.get("contact", []) if with_contact else []
        self.contacts = contacts
        self.topo = Topology(self.m, [c["on"] for c in contacts if "on" in c])
        self.with_contact = with_contact
        self.point_force_thickness = point_force_thickness
        self.axi = cfg.get("model", {}).get("plane", "strain") == "axisymmetric"

    # --- conditions per point (signorini's order: dirichlet entries, then slip lines)
    def conditions(self):
        m, tp, cfg = self.m, self.topo, self.cfg
        conds = [[] for _ in range(tp.np)]

        def group_points(name):
            dim, _ = m.group(name)
            out = []
            if dim == 0:
                for v in m.points(name):
                    out += [(p, None) for p in tp.copies[v]]
            elif dim == 1:
                for a, b in m.lines(name):
                    for t in m.edge_tris.get((min(a, b), max(a, b)), []):
                        body = int(tp.tri_body[t])
                        for v in (a, b):
                            out.append((tp.point_of[(v, body)], (a, b, t)))
            else:
                raise SetupError(f"{name!r}: expected a curve or a point")
            return out

        self.group_points = group_points
        for d in cfg.get("dirichlet", []):
            if "u" in d:
                ux, uy = d["u"]
            else:
                ux, uy = d.get("ux"), d.get("uy")
            for p in sorted({p for p, _ in group_points(d["on"])}):
                if ux is not None:
                    conds[p].append(((1.0, 0.0), float(ux)))
                if uy is not None:
                    conds[p].append(((0.0, 1.0), float(uy)))
        for s in cfg.get("slip", []):
            sums = {}
            for p, seg in group_points(s["on"]):
                if seg is None:
                    continue
                a, b, t = seg
                sums[p] = sums.get(p, np.zeros(2)) + m.outward_normal(t, a, b)
            for p in sorted(sums):
                n = sums[p]
                ln = np.linalg.norm(n)
                if ln > 1e-12:
                    conds[p].append(((n[0] / ln, n[1] / ln), 0.0))
        if self.axi:
            # the axis: u_r = 0 on every point with r ≤ 1e-9 max|r| (problem-format.md §11)
            tol = 1e-9 * np.abs(tp.x[:, 0]).max()
            if (tp.x[:, 0] < -tol).any():
                raise SetupError("axisymmetric: a node lies at x = r < 0")
            for p in np.where(tp.x[:, 0] <= tol)[0]:
                conds[p].append(((1.0, 0.0), 0.0))
        return conds

    def reduction(self):
        """u = u0 + T ξ over all points (2 np) and the rigid-mode check per body."""
        conds = self.conditions()
        rows, cols, vals = [], [], []
        u0 = np.zeros(2 * self.topo.np)
        n = 0
        for p, cs in enumerate(conds):
            try:
                up, tcols = eliminate(cs)
            except Conflict as e:
                tp = self.topo
                raise Conflict(f"node {int(self.m.tags[tp.point_node[p]])} (body {int(tp.point_body[p])}): {e}")
            u0[2 * p:2 * p + 2] = up
            for tc in tcols:
                for k in range(2):
                    if tc[k] != 0.0:
                        rows.append(2 * p + k)
                        cols.append(n)
                        vals.append(tc[k])
                n += 1
        T = sp.csr_matrix((vals, (rows, cols)), shape=(2 * self.topo.np, n))
        # free rigid motions per body (methods.md §1.7)
        floating = []
        tp = self.topo
        for b in range(tp.nbodies):
            pts = np.where(tp.point_body == b)[0]
            xb = tp.x[pts]
            c = (xb.min(0) + xb.max(0)) / 2
            L = max(np.ptp(xb, axis=0).max(), 1e-300)
            G = []
            for p in pts:
                z = np.array([[1.0, 0.0], [0.0, 1.0], [-(tp.x[p, 1] - c[1]) / L, (tp.x[p, 0] - c[0]) / L]])
                for r, _ in conds[p]:
                    r = np.asarray(r) / np.linalg.norm(r)
                    G.append(z @ r)
            if self.axi:
                # a body of revolution moves rigidly along the axis only (methods.md §10)
                G = [[g[1]] for g in G]
            nmodes = 1 if self.axi else 3
            rank = np.linalg.matrix_rank(np.array(G), tol=1e-6) if G else 0
            if rank < nmodes:
                floating.append((b, nmodes - rank))
        return T, u0, floating

    def free_modes(self, T, Kr, floating):
        """The rigid motions the supports leave free (the kernel of the reduced
        K), in the reduced unknowns: each floating body's rigid modes
        (translations and the rotation; the axial translation when
        axisymmetric) projected onto the unknowns (T has orthonormal columns
        per point), and the combinations that K leaves unloaded."""
        if not floating:
            return np.zeros((T.shape[1], 0))
        tp = self.topo
        Z = []
        for b, _ in floating:
            pts = np.where(tp.point_body == b)[0]
            xb = tp.x[pts]
            c = (xb.min(0) + xb.max(0)) / 2
            L = max(np.ptp(xb, axis=0).max(), 1e-300)
            modes = [(0.0, 1.0)] if self.axi else [(1.0, 0.0), (0.0, 1.0), None]
            for md in modes:
                z = np.zeros(2 * tp.np)
                if md is None:
                    z[2 * pts] = -(tp.x[pts, 1] - c[1]) / L
                    z[2 * pts + 1] = (tp.x[pts, 0] - c[0]) / L
                else:
                    z[2 * pts], z[2 * pts + 1] = md
                Z.append(T.T @ z)
        Z = np.array(Z).T
        Z = Z[:, np.linalg.norm(Z, axis=0) > 0]
        if Z.shape[1] == 0:
            return Z
        Z = Z / np.linalg.norm(Z, axis=0)
        # the combinations c with K Z c = 0, relative to the size of the terms
        # that cancel in K Z (|K||Z|): round-off ~1e-16 on a free motion, ~1e-2
        # (the supports' share of the body's nodes) on a held one
        KZ = np.column_stack([Kr @ Z[:, j] for j in range(Z.shape[1])])
        aKZ = np.column_stack([abs(Kr) @ np.abs(Z[:, j]) for j in range(Z.shape[1])])
        scale = max(float(np.linalg.norm(aKZ, axis=0).max()), 1e-300)
        _, sv, vt = np.linalg.svd(KZ / scale, full_matrices=True)
        sv = np.concatenate([sv, np.zeros(vt.shape[0] - len(sv))])
        return Z @ vt[sv < 1e-9].T

    def assemble(self, asm: Assembler):
        """Cut-mesh stiffness K (2np × 2np) and load f."""
        m, tp = self.m, self.topo
        ndof_orig = 2 * len(asm.dof_node)
        cell_body = tp.tri_body[asm.cell_tri]
        K = sp.csr_matrix((2 * tp.np, 2 * tp.np))
        f = np.zeros(2 * tp.np)
        for b in range(tp.nbodies):
            mask = cell_body == b
            # E_b: original dof -> cut dof of body b's copy
            r, c = [], []
            for d, v in enumerate(asm.dof_node):
                p = tp.point_of.get((int(v), b))
                if p is not None:
                    for k in range(2):
                        r.append(2 * p + k)
                        c.append(2 * d + k)
            E = sp.csr_matrix((np.ones(len(r)), (r, c)), shape=(2 * tp.np, ndof_orig))
            Kb = asm.body_stiffness(mask)
            Kc = E @ Kb @ E.T
            lost = abs(Kb).sum() - abs(Kc).sum()
            if abs(lost) > 1e-12 * abs(Kb).sum():
                raise CheckError(f"body {b}: stiffness entries outside the body ({lost:.3e})")
            K = K + Kc
            model = self.cfg.get("model", {})
            asm.g.value = np.array(model.get("gravity", [0.0, 0.0]), dtype=float)
            # centrifugal ρω²r (axisymmetric): a step's load factor scales ρω²r, not ω
            asm.omega2.value = float(model.get("omega", 0.0)) ** 2 * float(model.get("_load_factor", 1.0))
            if any(float(x) != 0.0 for x in asm.g.value) or float(asm.omega2.value) != 0.0:
                f += E @ asm.body_gravity(mask)
        # tractions: each segment loads the copies of the body owning it
        for tr in self.cfg.get("traction", []):
            per_body: dict[int, list[int]] = {}
            for a, b in m.lines(tr["on"]):
                e = (min(a, b), max(a, b))
                ts = m.edge_tris.get(e, [])
                if len(ts) != 1:
                    raise SetupError(f"traction curve {tr['on']!r}: segment {e} is not on the boundary "
                                     "(interior tractions are not supported by this check)")
                per_body.setdefault(int(tp.tri_body[ts[0]]), []).append(asm.edge_facet[e])
            for b, facets in per_body.items():
                fo = asm.traction(facets, tr.get("p"), tr.get("pn"))
                for d, v in enumerate(asm.dof_node):
                    p = tp.point_of.get((int(v), b))
                    if p is not None:
                        f[2 * p:2 * p + 2] += fo[2 * d:2 * d + 2]
        # point forces [N per unit thickness, README]: copy of the lowest body, × thickness
        # (--force-total: f taken as the force on the whole thickness, no factor)
        fscale = asm.th if self.point_force_thickness else 1.0
        for fo in self.cfg.get("force", []):
            for v in m.points(fo["on"]):
                p = tp.copies[v][0]
                f[2 * p:2 * p + 2] += fscale * np.asarray(fo["f"], dtype=float)
        return K.tocsr(), f

    # --- contact rows: list of (coefficients {point: 2-vector}, gap0, kind info)
    def contact_rows(self):
        m, tp = self.m, self.topo
        rows = []
        conf = [c for c in self.contacts if "on" in c]
        if conf:
            kind_of = [c.get("normals", "averaged") for c in conf]
            acc = {}
            for e, cid in sorted(tp.contact_edge.items()):
                ts = m.edge_tris.get(e, [])
                bodies = [int(tp.tri_body[t]) for t in ts]
                if len(ts) != 2 or bodies[0] == bodies[1]:
                    raise SetupError(f"contact curve {conf[cid]['on']!r} is not between two bodies at {e}")
                tk, tl = (ts[0], ts[1]) if bodies[0] < bodies[1] else (ts[1], ts[0])
                k, l = int(tp.tri_body[tk]), int(tp.tri_body[tl])
                n = m.outward_normal(tk, *e)
                for v, o in (e, e[::-1]):
                    ent = acc.setdefault((v, k, l), {"n": [], "w": [], "cid": cid})
                    ent["n"].append(n)
                    ent["w"].append(self.trib_weight(v, o))
            for (v, k, l) in sorted(acc, key=lambda key: (key[1], key[2], int(m.tags[key[0]]))):
                a = acc[(v, k, l)]
                first, second = tp.point_of[(v, k)], tp.point_of[(v, l)]
                normals, tribs = [], []
                if kind_of[a["cid"]] == "segment":
                    for n, w in zip(a["n"], a["w"]):
                        same = [i for i, q in enumerate(normals) if np.abs(q - n).sum() < 1e-12]
                        if same:
                            tribs[same[0]] += w
                        else:
                            normals.append(n)
                            tribs.append(w)
                else:
                    s = np.sum(a["n"], axis=0)
                    normals.append(s / np.linalg.norm(s))
                    tribs.append(sum(a["w"]))
                for n, w in zip(normals, tribs):
                    rows.append({"coef": {first: n, second: -n}, "g": 0.0, "n": n, "first": first, "second": second,
                                 "w": w, "contact": conf[a["cid"]]})
        for c in self.contacts:
            if "slave" not in c:
                continue
            if c.get("discretization", self.default_discretization(c)) == "mortar":
                rows.extend(self.mortar_rows(c))
                continue
            msegs = []
            for a, b in m.lines(c["master"]):
                ts = m.edge_tris.get((min(a, b), max(a, b)), [])
                if len(ts) != 1:
                    raise SetupError(f"master segment {(a, b)} is not on the boundary of one body")
                msegs.append((a, b, int(tp.tri_body[ts[0]]), m.outward_normal(ts[0], a, b)))
            slave = {}  # (node, body) -> tributary weight ∫N ds (∫N r ds axisymmetric)
            for a, b in m.lines(c["slave"]):
                ts = m.edge_tris.get((min(a, b), max(a, b)), [])
                if len(ts) != 1:
                    raise SetupError(f"slave segment {(a, b)} is not on the boundary of one body")
                sb = int(tp.tri_body[ts[0]])
                slave[(a, sb)] = slave.get((a, sb), 0.0) + self.trib_weight(a, b)
                slave[(b, sb)] = slave.get((b, sb), 0.0) + self.trib_weight(b, a)
            for v, sb in sorted(slave, key=lambda s: (s[1], int(m.tags[s[0]]))):
                xs = m.x[v]
                best = None
                for si, (a, b, mb, _) in enumerate(msegs):
                    if mb == sb:
                        continue
                    pa, pb = m.x[a], m.x[b]
                    d = pb - pa
                    xi = ((xs - pa) @ d) / (d @ d)
                    if not (-1e-9 <= xi <= 1 + 1e-9):
                        continue
                    xi = min(max(xi, 0.0), 1.0)
                    dist = np.linalg.norm(xs - (pa + xi * d))
                    if best is None or dist < best[0]:
                        best = (dist, si, xi)
                if best is None:
                    continue
                _, si, xi = best
                a, b, mb, n = msegs[si]
                pp = m.x[a] + xi * (m.x[b] - m.x[a])
                g = float(n @ (xs - pp))
                if "max_gap" in c and g > c["max_gap"]:
                    continue
                coef = {tp.point_of[(v, sb)]: -n}
                for node, w in ((a, 1 - xi), (b, xi)):
                    if w != 0.0:
                        q = tp.point_of[(node, mb)]
                        coef[q] = coef.get(q, 0) + w * n
                # an intended interference keeps its overlap (g < 0, problem-format.md §5)
                if g < -1e-6 * np.linalg.norm(m.x[b] - m.x[a]) and not c.get("interference", False):
                    raise SetupError(f"slave node {int(m.tags[v])} penetrates the master by {-g:.3e}")
                rows.append({"coef": coef, "g": g if c.get("interference", False) else max(g, 0.0), "n": n,
                             "first": tp.point_of[(v, sb)], "second": tp.point_of[(a, mb)],
                             "w": slave[(v, sb)], "contact": c})
        return rows

    def friction(self, rows):
        """The friction of the contact rows (docs/methods.md §9.1): the law
        ("tresca", "coulomb" or None) and per row the tangential row, the
        row's own coefficients with n turned by +90° (t = (−n_y, n_x)) as a
        sparse matrix over the 2·np point DOFs, and the Tresca bound
        s = tresca × tributary weight × thickness (∫N r ds axisymmetric, D on
        a mortar row) or Coulomb's μ."""
        laws = set()
        for c in self.contacts:
            if "tresca" in c:
                laws.add("tresca")
            elif float(c.get("friction", 0.0)) > 0.0:
                laws.add("coulomb")
        if not laws:
            return None, None, None
        if len(laws) > 1:
            raise NotChecked("Tresca and Coulomb pairs in one problem: the reference models one law per "
                             "problem (signorini refuses the mix, methods.md §9)")
        law = laws.pop()
        model = self.cfg.get("model", {})
        te = float(model.get("thickness", 1.0)) if model.get("plane", "strain") == "stress" else 1.0
        ti, tj, tv, bound = [], [], [], []
        for i, r in enumerate(rows):
            n = r["n"]
            t = np.array([-n[1], n[0]])
            for p, cv in r["coef"].items():
                a = float(np.asarray(cv) @ n)  # every coefficient is a multiple of n
                for k in range(2):
                    if a * t[k] != 0.0:
                        ti.append(i)
                        tj.append(2 * p + k)
                        tv.append(a * t[k])
            c = r["contact"]
            trib = r["trib"] if r.get("trib") is not None else r["w"]
            bound.append(float(c.get("tresca", 0.0)) * trib * te if law == "tresca"
                         else float(c.get("friction", 0.0)))
        Tt = sp.csr_matrix((tv, (ti, tj)), shape=(len(rows), 2 * self.topo.np))
        return law, Tt, np.array(bound)

    def held_rows(self, rows, T, u0s):
        """Mortar rows on a line of symmetry (docs/methods.md §9, signorini's
        fem::friction::on_symmetry_line): the slave point cannot move along the
        tangent (no free DOF along t, and t·u0 = 0 in every load step `u0s`:
        a clamped end that a later step moves along the interface, a tube
        pushed out of its fit, is no symmetry line; signorini builds the rows
        once for all steps) and the row ends its run of rows. By symmetry
        they carry no tangential force: no tangential row, bound 0, and they
        stick when in contact."""
        held = np.zeros(len(rows), dtype=bool)
        Tc = T.tocsr()
        for i, r in enumerate(rows):
            if r.get("trib") is None or not r.get("run_end"):
                continue
            n = r["n"]
            t = np.array([-n[1], n[0]])
            p = r["first"]
            free = t[0] * Tc[2 * p] + t[1] * Tc[2 * p + 1]
            if np.abs(free.data).max(initial=0.0) < 1e-12 and all(t @ u0[2 * p:2 * p + 2] == 0.0 for u0 in u0s):
                held[i] = True
        return held

    def trib_weight(self, v, o):
        """∫ N_v ds over the segment (v, o): ℓ/2, or ∫ N_v r ds = ℓ(2r_v + r_o)/6 per
        radian when axisymmetric (methods.md §10)."""
        xv, xo = self.m.x[v], self.m.x[o]
        ln = float(np.linalg.norm(xo - xv))
        return ln * (2 * xv[0] + xo[0]) / 6 if self.axi else ln / 2

    def boundary_segments(self, name):
        """(a, b, body, outward unit normal) of each segment of curve `name`."""
        m, tp = self.m, self.topo
        segs = []
        for a, b in m.lines(name):
            ts = m.edge_tris.get((min(a, b), max(a, b)), [])
            if len(ts) != 1:
                raise SetupError(f"segment {(a, b)} of {name!r} is not on the boundary of one body")
            segs.append((a, b, int(tp.tri_body[ts[0]]), m.outward_normal(ts[0], a, b)))
        return segs

    def default_discretization(self, c):
        """signorini's rows for a pair without `discretization`
        (fem::pairs::default_discretization): mortar, unless the least E of
        the slave's bodies is more than 10 times the largest of the master's."""
        m, tp = self.m, self.topo
        E = {nm: float(self.cfg["materials"][nm]["E"]) for nm in m.material_names}

        def bodies(curve):
            out = set()
            for a, b in m.lines(curve):
                for t in m.edge_tris.get((min(a, b), max(a, b)), []):
                    out.add(int(tp.tri_body[t]))
            return out

        sb, mb = bodies(c["slave"]), bodies(c["master"])
        e_slave = min((E[m.material_names[int(m.tri_mat[t])]] for t in range(len(tp.tri_body))
                       if int(tp.tri_body[t]) in sb), default=math.inf)
        e_master = max((E[m.material_names[int(m.tri_mat[t])]] for t in range(len(tp.tri_body))
                        if int(tp.tri_body[t]) in mb), default=0.0)
        return "nts" if e_slave > 10.0 * e_master else "mortar"

    def mortar_rows(self, c):
        """Mortar rows of a non-matching pair, built here from the formulas of
        docs/methods.md §7.1 (not from signorini's code): dual basis on the part
        of each slave segment that sees the master (Popp et al. 2013), D, M and
        the weighted gap by Gauss-Legendre quadrature (numpy's rule), the
        projections by numpy's polynomial roots and 2x2 solves."""
        m, tp = self.m, self.topo
        ssegs, msegs = self.boundary_segments(c["slave"]), self.boundary_segments(c["master"])
        nsum = {}
        for a, b, body, n in ssegs:
            for v in (a, b):
                nsum[(v, body)] = nsum.get((v, body), np.zeros(2)) + n
        nodal = {k: v / np.linalg.norm(v) for k, v in nsum.items()}
        gx, gw = np.polynomial.legendre.leggauss(5)
        gx, gw = 0.5 * (gx + 1.0), 0.5 * gw
        cross = lambda u, v: u[0] * v[1] - u[1] * v[0]  # noqa: E731
        D, M, G = {}, {}, {}
        for a, b, sb, ns in ssegs:
            x1, x2 = m.x[a], m.x[b]
            n1, n2 = nodal[(a, sb)], nodal[(b, sb)]
            L = np.linalg.norm(x2 - x1)
            X = lambda s: (1 - s) * x1 + s * x2  # noqa: E731
            Nf = lambda s: (1 - s) * n1 + s * n2  # noqa: E731

            def ray(s, y1, y2):
                # x(s) + t n(s) = y1 + xi (y2 - y1): solve for (t, xi)
                n = Nf(s)
                t, xi = np.linalg.solve(np.column_stack([n, -(y2 - y1)]), y1 - X(s))
                return xi, t * np.linalg.norm(n)

            def project(y):
                # (x(s) - y) x n(s) = 0 as a polynomial in s; the real root nearest 1/2
                d, e, dn = x1 - y, x2 - x1, n2 - n1
                coef = [cross(e, dn), cross(d, dn) + cross(e, n1), cross(d, n1)]
                while len(coef) > 1 and abs(coef[0]) <= 1e-14 * max(abs(coef[1]), 1e-300):
                    coef = coef[1:]
                r = [z.real for z in np.roots(coef) if abs(z.imag) <= 1e-12 * max(1.0, abs(z))]
                return min(r, key=lambda z: abs(z - 0.5)) if r else None

            cand = []
            for mi, (ma, mb, mbody, nm) in enumerate(msegs):
                if mbody == sb or nm @ ns >= 0:
                    continue
                sa, sbb = project(m.x[ma]), project(m.x[mb])
                if sa is None or sbb is None:
                    continue
                s0, s1 = max(min(sa, sbb), 0.0), min(max(sa, sbb), 1.0)
                if not s1 - s0 > 1e-12:
                    continue
                cand.append((abs(ray(0.5 * (s0 + s1), m.x[ma], m.x[mb])[1]), mi, s0, s1))
            cand.sort(key=lambda q: (q[0], q[1]))
            covered, pieces = [], []
            for _, mi, s0, s1 in cand:
                free = [(s0, s1)]
                for c0, c1 in covered:
                    free = [q for p0, p1 in free
                            for q in ([(p0, p1)] if c1 <= p0 or c0 >= p1 else
                                      [r for r in ((p0, c0), (c1, p1)) if r[1] > r[0]])]
                pieces += [(p0, p1, mi) for p0, p1 in free if p1 - p0 > 1e-12]
                covered.append((s0, s1))
            if not pieces:
                continue
            # mass matrix and lumped weights on the seen part -> dual basis Phi = A N
            # axisymmetric: every integral carries r (the dual basis is biorthogonal
            # in the r-weighted product, methods.md §10)
            rw = (lambda s: X(s)[0]) if self.axi else (lambda s: 1.0)  # noqa: E731
            quad = [(p0 + t * (p1 - p0), w * (p1 - p0) * L * rw(p0 + t * (p1 - p0)), mi)
                    for p0, p1, mi in pieces for t, w in zip(gx, gw)]
            Nv = np.array([[1 - s, s] for s, _, _ in quad])
            W = np.array([w for _, w, _ in quad])
            Me = (Nv * W[:, None]).T @ Nv
            De = Nv.T @ W
            A = np.linalg.solve(Me.T, np.diag(De)).T  # A = De Me^-1
            for i, key in enumerate(((a, sb), (b, sb))):
                D[key] = D.get(key, 0.0) + De[i]
            for (s, w, mi), nv in zip(quad, Nv):
                ma, mb, mbody, _ = msegs[mi]
                xi, g = ray(s, m.x[ma], m.x[mb])
                if g < -1e-6 * L and not c.get("interference", False):
                    raise SetupError(f"mortar: initial penetration {g:.3e} on slave segment {(a, b)}")
                phi = A @ nv
                for i, key in enumerate(((a, sb), (b, sb))):
                    G[key] = G.get(key, 0.0) + phi[i] * g * w
                    mk = M.setdefault(key, {})
                    for node, nw in ((ma, 1 - xi), (mb, xi)):
                        q = tp.point_of[(node, mbody)]
                        mk[q] = mk.get(q, 0.0) + phi[i] * nw * w
        rows = []
        kept = set()
        for v, sb in sorted(D, key=lambda k: (k[1], int(m.tags[k[0]]))):
            d = D[(v, sb)]
            if not d > 0:
                continue
            g = G.get((v, sb), 0.0) / d
            if "max_gap" in c and g > c["max_gap"]:
                continue
            kept.add((v, sb))
            n = -nodal[(v, sb)]  # outward of the master, as signorini writes it
            coef = {tp.point_of[(v, sb)]: -n}
            for q, w in M.get((v, sb), {}).items():
                coef[q] = coef.get(q, 0) + (w / d) * n
            rows.append({"coef": coef, "g": g, "n": n, "first": tp.point_of[(v, sb)], "second": None,
                         "trib": d, "contact": c, "slave": (v, sb)})
        # a row at the end of its run of rows (one slave segment with rows at both
        # ends): a friction row on a line of symmetry is one of these (friction_rows)
        nseg = {}
        for a, b, sb, _ in ssegs:
            if (a, sb) in kept and (b, sb) in kept:
                for key in ((a, sb), (b, sb)):
                    nseg[key] = nseg.get(key, 0) + 1
        for r in rows:
            r["run_end"] = nseg.get(r["slave"], 0) <= 1
        return rows


# ------------------------------------------------------------------- QP


def solve_qp(K, f, A, g, label, Tm=None, c=None, s=None, warm=None):
    """min ½xᵀKx − fᵀx + Σᵢ sᵢ|(Tm x − c)ᵢ|  s.t.  Ax ≤ g (Tm None: the frictionless QP).

    The Tresca problem of docs/methods.md §9.1 as a QP with one auxiliary
    variable per friction row, wᵢ ≥ ±(Tm x − c)ᵢ and the objective + Σ sᵢwᵢ,
    solved by Clarabel (interior point), then polished by a primal-dual
    active-set iteration on the exact KKT conditions: normal rows active
    (A x = g, λ_n free) or not (λ_n = 0); friction rows stick (Tm x = c,
    λ_t free) or slip (λ_t = sᵢσᵢ, σᵢ = ±1) until A x ≤ g, λ_n ≥ 0,
    |λ_t| ≤ s on sticking rows and σᵢ vᵢ ≥ 0 on slipping ones. The multipliers
    are those of Kx − f + Aᵀλ_n + Tmᵀλ_t = 0 (signorini's signs: λ_n ≥ 0
    compressive, λ_t = s·sign v where a row slips); λ_t = wᵢ's duals z₊ − z₋.
    `warm` = (active, stick, sigma) of a previous solve starts the polish
    there without Clarabel (the Coulomb fixed point); Clarabel runs when that
    polish fails. Returns x, λ_n, λ_t, info."""
    n, m = K.shape[0], A.shape[0]
    if Tm is None:
        Tm, c, s = sp.csr_matrix((0, n)), np.zeros(0), np.zeros(0)
    Tm = sp.csr_matrix(Tm)
    mt = Tm.shape[0]
    # friction rows that act: a bound s > 0 and a tangential row with unknowns
    F = np.where((np.asarray(s) > 0) & (np.diff(Tm.indptr) > 0))[0]
    nf = len(F)
    # Jacobi scaling of the unknowns, row scaling of the constraints
    dk = K.diagonal()
    sc = 1.0 / np.sqrt(np.where(dk > 0, dk, 1.0))
    S = sp.diags(sc)
    Ks = (S @ K @ S).tocsc()
    fs = sc * f
    As = (A @ S).tocsr()
    rn = np.sqrt(abs(As).power(2).sum(axis=1)).A1
    rn[rn == 0] = 1.0
    As = (sp.diags(1.0 / rn) @ As).tocsc()
    gs = g / rn
    Ts = (Tm[F] @ S).tocsr()
    rt = np.sqrt(abs(Ts).power(2).sum(axis=1)).A1 if nf else np.zeros(0)
    Ts = (sp.diags(1.0 / rt) @ Ts).tocsr() if nf else sp.csr_matrix((0, n))
    cs = c[F] / rt if nf else np.zeros(0)
    ss = s[F] * rt if nf else np.zeros(0)  # s|v| = (s·rt)|vs|, vs = v/rt
    # Objective scale: the size of the displacements the data cause, in the
    # scaled unknowns (unit diagonal): the loads, an interference overlap
    # (g < 0) or the slip offset of the previous step; a load-free
    # interference fit has f = 0 and is driven by its negative gaps alone.
    obj = max(np.abs(fs).max(initial=0.0), (-gs).max(initial=0.0), np.abs(cs).max(initial=0.0))
    if not obj > 0:
        obj = 1.0  # nothing drives the problem: x = 0
    t0 = time.time()
    info = dict(status="warm", ip_iter=0, ip_time=0.0, obj=obj)
    state = None
    if warm is not None:
        try:
            state = _polish(Ks, fs, As, gs, Ts, cs, ss, warm[0], warm[1][F], warm[2][F], label)
        except _PolishFailed:
            state = None
    if state is None:
        clarabel = _clarabel()
        settings = clarabel.DefaultSettings()
        settings.verbose = False
        settings.tol_gap_abs = 1e-12
        settings.tol_gap_rel = 1e-12
        settings.tol_feas = 1e-12
        settings.tol_ktratio = 1e-10
        settings.max_iter = 400
        # unknowns [y; ω], y = xs/obj, ω = ws/obj (ws ≥ |Ts y·obj − cs|) for
        # the rows with a finite bound; an infinite bound glues the row
        # (Ts y = cs/obj, a zero cone: the glued start of Coulomb)
        fin = np.isfinite(ss)
        gl, fw = np.where(~fin)[0], np.where(fin)[0]
        nw, ng = len(fw), len(gl)
        P = sp.block_diag([sp.triu(Ks), sp.csc_matrix((nw, nw))]).tocsc()
        q = np.concatenate([-fs / obj, ss[fw] / obj])
        I = sp.identity(nw, format="csc")
        Acon = sp.vstack([sp.hstack([As, sp.csc_matrix((m, nw))]),
                          sp.hstack([Ts[gl], sp.csc_matrix((ng, nw))]),
                          sp.hstack([Ts[fw], -I]), sp.hstack([-Ts[fw], -I])]).tocsc()
        b = np.concatenate([gs / obj, cs[gl] / obj, cs[fw] / obj, -cs[fw] / obj])
        cones = [clarabel.NonnegativeConeT(m)] + ([clarabel.ZeroConeT(ng)] if ng else []) \
            + ([clarabel.NonnegativeConeT(2 * nw)] if nw else [])
        solver = clarabel.DefaultSolver(P, q, Acon, b, cones, settings)
        sol = solver.solve()
        status = str(sol.status)
        info.update(status=status, ip_iter=sol.iterations, ip_time=time.time() - t0)
        if "Solved" not in status:
            raise NotChecked(f"{label}: Clarabel did not solve the reference problem ({status})")
        xs = np.array(sol.x)[:n] * obj
        z = np.array(sol.z) * obj
        lam_s = z[:m]
        lt_s = np.zeros(nf)
        lt_s[gl] = z[m:m + ng]
        lt_s[fw] = z[m + ng:m + ng + nw] - z[m + ng + nw:]
        slack = gs - As @ xs
        sc_g = max(np.abs(As @ xs).max(initial=0.0), np.abs(gs).max(initial=0.0), 1e-300)
        act = (lam_s > 1e-6 * max(lam_s.max(initial=0.0), 1e-300)) | (slack < 1e-8 * sc_g)
        stick = np.abs(lt_s) < (1 - 1e-6) * ss
        sigma = np.where(lt_s >= 0, 1.0, -1.0)
        try:
            state = _polish(Ks, fs, As, gs, Ts, cs, ss, act, stick, sigma, label)
        except _PolishFailed as e:
            # Clarabel's own answer, unpolished: its KKT residuals (below) decide
            # whether it is accurate enough to compare with (geodynamic_steps with
            # Coulomb friction, step 5: a polish that cycled from a Clarabel
            # answer with stationarity 6e-13)
            info["polish_failed"] = str(e)
            state = (xs, np.where(act, lam_s, 0.0), lt_s, act, stick, sigma, 0)
    xs, lam, lts, act, stick_f, sigma_f, it = state
    x = sc * xs
    lam_n = lam / rn  # As = R A S: a multiplier of a scaled row is rn × λ
    lam_t = np.zeros(mt)
    lam_t[F] = lts / rt
    stick = np.ones(mt, dtype=bool)  # rows without friction: λ_t = 0 (see compare)
    stick[F] = stick_f
    sigma = np.ones(mt)
    sigma[F] = sigma_f
    # A bound s > 0 on a tangential row with no unknowns (both sides held along
    # t, e.g. a tube end moved by a prescribed displacement): its slip v = −c is
    # prescribed, λ_t does not enter the balance, and the slip rule alone sets
    # λ_t = s·sign v where v ≠ 0 (0 where v = 0: any value in [−s, s] would do).
    E = np.where((np.asarray(s) > 0) & (np.diff(Tm.indptr) == 0))[0]
    if len(E):
        vE = -c[E]
        moving = np.abs(vE) > 1e-12 * max(np.abs(x).max(initial=0.0), np.abs(c).max(initial=0.0), 1e-300)
        lam_t[E] = np.where(moving & np.isfinite(s[E]), s[E] * np.sign(vE), 0.0)
        stick[E] = ~moving
        sigma[E] = np.where(vE >= 0, 1.0, -1.0)
    # KKT certificate of the reference solution (unscaled)
    # stationarity relative to the size of the terms that cancel in it: with
    # |K||x| in the scale, the round-off of Kx along a rigid motion of a stiff
    # body (a large x, a small Kx) does not count as an error (the deck, ring
    # and slope trust models, stiffness contrast 1e5–1e7: 1.6e-9 … 8.1e-9 of
    # max(‖f‖, ‖Kx‖), ≤ 1e-12 of this scale)
    Kx = K @ x
    r = Kx - f + A.T @ lam_n + Tm.T @ lam_t
    stat = np.linalg.norm(r) / max(np.linalg.norm(f), np.linalg.norm(Kx), np.linalg.norm(abs(K) @ np.abs(x)), 1e-300)
    prim = max(((A @ x - g).clip(min=0)).max(initial=0.0), 0.0) / max(np.abs(x).max(initial=0.0), 1e-300)
    comp = abs(lam_n @ (A @ x - g)) / max(np.abs(lam_n).max(initial=0.0) * np.abs(x).max(initial=0.0), 1e-300)
    dual = (-lam_n).clip(min=0).max(initial=0.0) / max(np.abs(lam_n).max(initial=0.0), 1.0)
    # friction (methods.md §9.4): the bound and the slip rule per row
    v = Tm @ x - c
    Fsc = np.maximum.reduce([np.asarray(s, float), np.abs(lam_t),
                             np.full(mt, max(np.abs(lam_n).max(initial=0.0), np.abs(lam_t).max(initial=0.0), 1e-300))])
    X = max(np.abs(x).max(initial=0.0), (abs(Tm) @ np.abs(x) + np.abs(c)).max(initial=0.0), 1e-300)
    with np.errstate(invalid="ignore"):  # a glued row (s = ∞) is judged by its slip alone
        rule = np.where(np.isfinite(s), np.abs(s - lam_t * np.sign(v)) / Fsc, 1.0)
    fric = max(((np.abs(lam_t) - s).clip(min=0) / Fsc).max(initial=0.0),
               (np.abs(v) / X * rule).max(initial=0.0))
    info.update(polish_iter=it, active=int(act.sum()), stick=int(stick_f.sum()), slip=int(nf - stick_f.sum()),
                stationarity=stat, primal=prim, dual=dual, complementarity=comp, friction=fric,
                warm=(act, stick, sigma))
    return x, lam_n, lam_t, info


class _PolishFailed(Exception):
    pass


def _clarabel():
    try:
        import clarabel
    except ImportError as e:
        raise SetupError(f"clarabel not importable ({e}); install it (python_checks.sh does: "
                         "pip install --target .venv/debian-site clarabel)")
    return clarabel


def _kkt_solve(KKT, rhs, n):
    """Solve the active-set KKT system (sparse LU, two steps of iterative
    refinement). Rows that are linearly dependent (a slave node of two pairs
    with both rows active and sticking: four equations on two unknowns and
    their masters) make it singular with non-unique multipliers: then the
    factor is of the system with −1e-13·I in the multipliers' block (unit
    diagonal K and unit rows: a relative change of ~1e-13) and the refinement
    steps are taken against the exact system. A rigid motion that no row
    holds leaves it singular in the displacements: _PolishFailed."""
    m = KKT.shape[0] - n
    try:
        with np.errstate(all="ignore"):
            lu = spla.splu(KKT)
    except RuntimeError:
        reg = sp.block_diag([sp.csc_matrix((n, n)), -1e-13 * sp.identity(m, format="csc")]).tocsc()
        try:
            with np.errstate(all="ignore"):
                lu = spla.splu((KKT + reg).tocsc())
        except RuntimeError as e:
            raise _PolishFailed(f"singular active-set KKT system ({e})")
    with np.errstate(all="ignore"):
        z = lu.solve(rhs)
        for _ in range(2):
            z = z + lu.solve(rhs - KKT @ z)
    if not np.all(np.isfinite(z)):
        raise _PolishFailed("singular active-set KKT system: a rigid motion that no active or sticking "
                            "row holds (the displacement along it is not unique)")
    return z


def _polish(Ks, fs, As, gs, Ts, cs, ss, act, stick, sigma, label, max_iter=60):
    """Primal-dual active set on the scaled problem (solve_qp), exact KKT solves;
    once a set repeats (a cycle, seen on geodynamic_steps with Coulomb friction)
    one row changes per solve, the largest violation."""
    n, m, nf = Ks.shape[0], As.shape[0], Ts.shape[0]
    act, stick, sigma = act.copy(), stick.copy(), sigma.copy()
    fsc = max(np.abs(fs).max(initial=0.0), 1e-300)
    seen, single = set(), False
    for it in range(1, max_iter + 1):
        ia, ist, isl = np.where(act)[0], np.where(stick)[0], np.where(~stick)[0]
        Aa, Tst = As[ia], Ts[ist]
        KKT = sp.bmat([[Ks, Aa.T, Tst.T], [Aa, None, None], [Tst, None, None]], format="csc")
        rhs = np.concatenate([fs - Ts[isl].T @ (ss[isl] * sigma[isl]), gs[ia], cs[ist]])
        z = _kkt_solve(KKT, rhs, n)
        xs = z[:n]
        lam = np.zeros(m)
        lam[ia] = z[n:n + len(ia)]
        lts = sigma * ss
        lts[ist] = z[n + len(ia):]
        Ax = As @ xs
        sc_g = max(np.abs(Ax).max(initial=0.0), np.abs(gs).max(initial=0.0), 1e-300)
        lmax = max(np.abs(lam).max(initial=0.0), np.abs(lts).max(initial=0.0), fsc * 1e-300)
        v = Ts @ xs - cs
        X = max(np.abs(xs).max(initial=0.0), np.abs(Ts @ xs).max(initial=0.0), np.abs(cs).max(initial=0.0), 1e-300)
        open_viol = ~act & (Ax - gs > 1e-12 * sc_g)
        neg = act & (lam < -1e-12 * lmax)
        over = stick & (np.abs(lts) > ss + 1e-12 * lmax)
        back = ~stick & (sigma * v < -1e-12 * X)
        if not (open_viol.any() or neg.any() or over.any() or back.any()):
            return xs, lam, lts, act, stick, sigma, it
        key = (act.tobytes(), stick.tobytes(), sigma.tobytes())
        if key in seen:
            single = True  # a cycle: from now on change one row per solve
        seen.add(key)
        if single:
            # the largest violation alone, each measured on its own scale
            cand = [(((Ax - gs) / sc_g) * open_viol, "open"), ((-lam / lmax) * neg, "neg"),
                    (((np.abs(lts) - ss) / lmax) * over, "over"), ((-sigma * v / X) * back, "back")]
            worst = max(cand, key=lambda q: q[0].max(initial=0.0))
            j = int(np.argmax(worst[0]))
            open_viol, neg, over, back = (np.zeros_like(open_viol), np.zeros_like(neg), np.zeros_like(over),
                                          np.zeros_like(back))
            {"open": open_viol, "neg": neg, "over": over, "back": back}[worst[1]][j] = True
        act = (act & ~neg) | open_viol
        sigma = np.where(over, np.sign(lts), sigma)
        stick = (stick & ~over) | back
    raise _PolishFailed(f"no consistent active set after {max_iter} solves")


def friction_hand_case():
    """The signs of the friction reference on a hand case: one node of stiffness
    k (both directions) on a rigid floor, pushed by f = (fx, −fy). As a
    conforming row with the floor first: n = (0, 1), the normal row −u_y ≤ 0,
    t = (−1, 0) and the tangential row t·(u_floor − u_node) = u_x, so v = u_x.
    Then λ_n = fy (compressive positive) and, for a bound s: |fx| ≤ s sticks
    (u_x = 0, λ_t = fx), |fx| > s slips, u_x = (fx − s sign fx)/k, λ_t = s sign fx
    = s sign v (Kx − f + Aᵀλ_n + Tᵀλ_t = 0); Coulomb s = μ fy. Returns the
    largest relative error over five cases (Tresca stick and slip both ways,
    Coulomb stick and slip)."""
    k, fy = 2.0, 3.0
    K = sp.csr_matrix(np.diag([k, k]))
    A = sp.csr_matrix(np.array([[0.0, -1.0]]))
    Tm = sp.csr_matrix(np.array([[1.0, 0.0]]))
    worst = 0.0
    for fx, s, mu in ((1.0, 2.0, None), (5.0, 2.0, None), (-5.0, 2.0, None), (1.0, None, 0.5), (4.0, None, 0.5)):
        f = np.array([fx, -fy])
        if mu is None:
            x, ln, lt, _ = solve_qp(K, f, A, np.zeros(1), "hand case", Tm, np.zeros(1), np.array([s]))
        else:
            x, ln, lt, _ = solve_coulomb(K, f, A, np.zeros(1), Tm, np.zeros(1), np.array([mu]), "hand case")
            s = mu * fy
        ux = 0.0 if abs(fx) <= s else (fx - s * np.sign(fx)) / k
        want = np.array([ux, 0.0, fy, fx if abs(fx) <= s else s * np.sign(fx)])
        got = np.array([x[0], x[1], ln[0], lt[0]])
        worst = max(worst, float(np.abs(got - want).max() / np.abs(want).max()))
    return worst


def uniqueness(Zr, A, Tm, x, c, lam_n, lam_t, s, mu, in_contact, law):
    """What of the solution is not unique, from the final states.

    Displacements: a free rigid motion z (Zr, the kernel of K) that no contact
    row in contact (A z = 0) nor sticking row (Tm z = 0) holds: x + t z solves
    too (a ring turning in a ring, frictionless; a block at the sliding limit
    with every row slipping). Returns those motions (reduced unknowns).

    Multipliers: the contact force Aᵀλ_n + Tmᵀλ_t is unique, its split into
    rows is not when the rows' columns are linearly dependent: a normal column
    Aᵢ per row in contact, plus Tmᵢ where the row sticks or could (|vᵢ| ≈ 0),
    or Aᵢ + μσTmᵢ on a Coulomb row that slips (λ_t = μσλ_n); a null vector
    of these columns is a change of the multipliers that changes no force
    (a slave node of two pairs on a shared master corner). Returns the rows
    with a part in such a null vector."""
    m = A.shape[0]
    v = Tm @ x - c
    X = max(np.abs(x).max(initial=0.0), np.abs(c).max(initial=0.0), 1e-300)
    slips = (s > 0) & (np.abs(lam_t) >= (1 - 1e-9) * s)
    moving = np.abs(v) > 1e-9 * X
    sticks = (s > 0) & ~slips & (np.diff(Tm.indptr) > 0)
    # free motions
    motions = np.zeros((Zr.shape[0], 0))
    if Zr.shape[1]:
        H = sp.vstack([A[np.where(in_contact)[0]], Tm[np.where(sticks)[0]]]).tocsr()
        HZ = H @ Zr
        if HZ.shape[0] == 0:
            motions = Zr
        else:
            _, sv, vt = np.linalg.svd(HZ, full_matrices=True)
            sv = np.concatenate([sv, np.zeros(vt.shape[0] - len(sv))])
            motions = Zr @ vt[sv < 1e-9 * max(sv.max(initial=0.0), 1e-300) + 1e-14].T
    # dependent rows
    cols, owner = [], []
    for i in np.where(in_contact)[0]:
        a = A[i]
        if slips[i] and moving[i] and law == "coulomb" and mu[i] > 0:
            a = a + mu[i] * np.sign(lam_t[i]) * Tm[i]
        cols.append(a)
        owner.append(i)
        if (sticks[i] or (slips[i] and not moving[i])) and Tm[i].nnz:
            cols.append(Tm[i])
            owner.append(i)
    bad = set()
    if cols:
        Mt = sp.vstack(cols).tocsc()
        used = np.where(np.diff(Mt.tocsc().indptr) > 0)[0]
        D = Mt[:, used].toarray()
        D = D / np.maximum(np.linalg.norm(D, axis=1), 1e-300)[:, None]
        # connected groups of rows (sharing a DOF) are independent blocks: SVD per group
        G = (abs(sp.csr_matrix(D)) @ abs(sp.csr_matrix(D)).T).tocsr()
        ncomp, lab = sp.csgraph.connected_components(G, directed=False)
        for k in range(ncomp):
            idx = np.where(lab == k)[0]
            if len(idx) < 2:
                continue
            B = D[idx][:, np.abs(D[idx]).sum(axis=0) > 0]
            if B.shape[0] > B.shape[1]:
                null = np.linalg.svd(B.T, full_matrices=True)[2][B.shape[1]:]
            else:
                _, sv, vt = np.linalg.svd(B.T, full_matrices=False)
                null = vt[sv < 1e-9 * sv.max()]
            for vec in null:
                bad |= {owner[idx[j]] for j in np.where(np.abs(vec) > 1e-8)[0]}
    return motions, np.array(sorted(bad), dtype=np.int64)


def solve_coulomb(K, f, A, g, Tm, c, mu, label, tol=1e-12, max_steps=300):
    """Coulomb's s = μ λ_n by the reference's own fixed point: Tresca problems
    (solve_qp) with s from the previous λ_n, s ← s + ω(μλ_n − s), starting from
    the glued solution (s = ∞ where μ > 0: every row sticks, so a body held by
    friction alone is held at the start too); then s¹ = μλ_n, and ω = 1,
    halved (down to 1/64) whenever the residual ‖μλ_n − s‖ grows. Stops when
    ‖μλ_n − s‖∞ ≤ tol·max(μλ_n), or when the change has stalled at the
    round-off of the Tresca solves (no new smallest change in 20 solves, the
    smallest ≤ 1e-9·max μλ_n: a stiffness contrast of 10⁵ leaves 1e-12 …
    1e-9; the iterate with the smallest change is returned and the change
    reported);
    NotChecked after max_steps (the fixed point does not settle)."""
    s = np.where(mu > 0, np.inf, 0.0)
    omega, rprev, warm = 1.0, None, None
    t0 = time.time()
    nclar = 0
    best = None
    for k in range(1, max_steps + 1):
        x, lam_n, lam_t, info = solve_qp(K, f, A, g, label, Tm, c, s, warm)
        nclar += info["status"] != "warm"
        warm = info["warm"]
        target = mu * np.maximum(lam_n, 0.0)
        if k == 1:  # the glued start: s¹ = μλ_n
            s = target
            continue
        r = target - s
        rn = np.abs(r).max(initial=0.0)
        rel_change = rn / max(target.max(initial=0.0), 1e-300)
        if best is None or rel_change < best[0]:
            best = (rel_change, k, (x, lam_n, lam_t, info))
        stalled = k - best[1] >= 20 and best[0] <= 1e-9
        if rel_change <= tol or stalled:
            rel_change, kb, (x, lam_n, lam_t, info) = best
            info.update(fp_steps=k, fp_change=rel_change, fp_clarabel=nclar, fp_time=time.time() - t0,
                        fp_stalled=kb if stalled else None)
            return x, lam_n, lam_t, info
        if rprev is not None and rn > rprev:
            omega = max(omega / 2, 1 / 64)
        rprev = rn
        s = s + omega * r
    raise NotChecked(f"{label}: the reference's Coulomb fixed point did not settle in {max_steps} Tresca "
                     f"solves (last change {rn:.2e} of max μλ_n): the Coulomb problem may have several "
                     "solutions, or this iteration cannot find one")


# ------------------------------------------------------------ comparison


def read_signorini(h5path: Path, step: int):
    import h5py

    with h5py.File(h5path, "r") as f:
        key = f"{step:04d}"
        if key not in f["steps"]:
            raise CheckError(f"{h5path.name}: no /steps/{key} (has {sorted(f['steps'].keys())})")
        st = f["steps"][key]
        out = {
            "nodes": f["mesh/nodes"][:],
            "body": f["mesh/body"][:].astype(np.int64),
            "tags": f["mesh/node_tags"][:].astype(np.int64),
            "triangles": f["mesh/triangles"][:].astype(np.int64),
            "u": st["displacement"][:],
            "stress": st["stress"][:],
            "multipliers": st["multipliers"][:],
            "contact_first": f["mesh/contact_first"][:].astype(np.int64),
            "contact_second": f["mesh/contact_second"][:].astype(np.int64),
            "contact_normal": f["mesh/contact_normal"][:],
            "contact_gap0": f["mesh/contact_gap0"][:],
            "contact_pressure": st["contact_pressure"][:],
            "converged": int(st.attrs["converged"]),
        }
        # friction (methods.md §9.5): absent without friction
        for k in ("multipliers_t", "slip", "state"):
            out[k] = st[k][:] if k in st else None
    return out


def match_points(prob: Problem, sig) -> np.ndarray:
    """signorini point i -> our point index, by coordinates (+ body for node copies)."""
    tp = prob.topo
    L = np.ptp(tp.x, axis=0).max()
    ours = np.column_stack([tp.x, tp.point_body * 10.0 * L])
    theirs = np.column_stack([sig["nodes"], sig["body"] * 10.0 * L])
    if len(theirs) != len(ours):
        raise CheckError(f"signorini has {len(theirs)} points, this model {len(ours)} "
                         f"(bodies: {prob.topo.nbodies} here)")
    dist, idx = cKDTree(ours).query(theirs)
    if dist.max() > 1e-9 * L or len(set(idx.tolist())) != len(idx):
        raise CheckError(f"points do not match by coordinates and body (max distance {dist.max():.3e})")
    if not np.array_equal(prob.m.tags[tp.point_node[idx]], sig["tags"]):
        raise CheckError("matched points have different Gmsh node tags")
    return idx


def stresses(prob: Problem, u: np.ndarray, tris_pts: np.ndarray) -> np.ndarray:
    """(σxx, σyy, σxy, σzz) per triangle (given in our point indices) from P1 displacements."""
    cfg, m, tp = prob.cfg, prob.m, prob.topo
    tri_mat = {}
    for t, tri in enumerate(m.tri):
        tri_mat[(int(tp.tri_body[t]), tuple(sorted(int(v) for v in tri)))] = int(m.tri_mat[t])
    mats = cfg["materials"]
    stress_plane = cfg.get("model", {}).get("plane", "strain") == "stress"
    out = np.zeros((len(tris_pts), 4))
    U = u.reshape(-1, 2)
    for e, tri in enumerate(tris_pts):
        b = int(tp.point_body[tri[0]])
        key = (b, tuple(sorted(int(tp.point_node[p]) for p in tri)))
        mat = mats[m.material_names[tri_mat[key]]]
        E, nu = float(mat["E"]), float(mat["nu"])
        x = tp.x[tri]
        a2 = (x[1, 0] - x[0, 0]) * (x[2, 1] - x[0, 1]) - (x[2, 0] - x[0, 0]) * (x[1, 1] - x[0, 1])
        bb = np.array([x[1, 1] - x[2, 1], x[2, 1] - x[0, 1], x[0, 1] - x[1, 1]]) / a2
        cc = np.array([x[2, 0] - x[1, 0], x[0, 0] - x[2, 0], x[1, 0] - x[0, 0]]) / a2
        ue = U[tri]
        exx, eyy = bb @ ue[:, 0], cc @ ue[:, 1]
        gxy = cc @ ue[:, 0] + bb @ ue[:, 1]
        if prob.axi:
            # (σrr, σzz, σrz, σθθ) at the centroid: hoop strain u_r(c)/r̄ (methods.md §10)
            fct = E / ((1 + nu) * (1 - 2 * nu))
            ett = (ue[:, 0].sum() / 3) / (x[:, 0].sum() / 3)  # u_r(c) / r̄
            sxx = fct * ((1 - nu) * exx + nu * (eyy + ett))
            syy = fct * ((1 - nu) * eyy + nu * (exx + ett))
            sxy = fct * (1 - 2 * nu) / 2 * gxy
            szz = fct * ((1 - nu) * ett + nu * (exx + eyy))
        elif stress_plane:
            fct = E / (1 - nu * nu)
            sxx, syy, sxy = fct * (exx + nu * eyy), fct * (nu * exx + eyy), fct * (1 - nu) / 2 * gxy
            szz = 0.0
        else:
            fct = E / ((1 + nu) * (1 - 2 * nu))
            sxx = fct * ((1 - nu) * exx + nu * eyy)
            syy = fct * (nu * exx + (1 - nu) * eyy)
            sxy = fct * (1 - 2 * nu) / 2 * gxy
            szz = nu * (sxx + syy)
        out[e] = (sxx, syy, sxy, szz)
    return out


def rel(a, b, floor=0.0):
    """max|a - b| relative to max|b|, or to `floor` when that is larger: a
    field that is physically (nearly) zero, such as the stress of a rigid
    translation, holds only round-off, and round-off over round-off is no
    relative error (it gave a false FAIL of 1.47)."""
    scale = max(np.abs(b).max(initial=0.0), floor, 1e-300)
    return float(np.abs(a - b).max(initial=0.0) / scale)


def floors(prob, U):
    """Typical scales of the fields: L the model size, E the largest Young's
    modulus; the stress floor is E·max|u|/L (the stress of a strain |u|/L),
    the force floor that stress times L, the displacement floor 1e-12·L."""
    x = prob.topo.x
    L = float(max(np.ptp(x[:, 0]), np.ptp(x[:, 1]), 1e-300))
    E = max(float(m["E"]) for m in prob.cfg["materials"].values())
    umax = float(np.abs(U).max(initial=0.0))
    return {"u": 1e-12 * L, "stress": E * umax / L, "force": E * umax}


STICK_MARGIN = 1e-6  # a row slips when |λ_t| ≥ (1 − 1e-6) s (problem-format.md §6, methods.md §9.5)


def friction_states(in_contact, held, lam_t, s):
    """0 open, 1 stick, 2 slip by the rule of docs/methods.md §9.5."""
    st = np.where(in_contact, 1, 0).astype(np.int64)
    st[in_contact & ~held & (np.abs(lam_t) >= (1 - STICK_MARGIN) * s)] = 2
    return st


def modulo(d, M):
    """d less its least-squares part in the columns of M."""
    if M is None or M.shape[1] == 0:
        return d
    return d - M @ np.linalg.lstsq(M, d, rcond=None)[0]


def compare(prob, u_ref, sig, tol, label, lam_ref=None, rows=None, fric=None, free_u=None, dep_rows=None,
            Tt=None):
    idx = match_points(prob, sig)
    U = u_ref.reshape(-1, 2)[idx]
    fl = floors(prob, U)
    if free_u is not None and free_u.shape[1]:
        # the displacement modulo the free motions (uniqueness): the difference and
        # the reference both less their parts along the motions
        Mm = free_u.reshape(-1, 2, free_u.shape[1])[idx].reshape(-1, free_u.shape[1])
        d = modulo((sig["u"] - U).ravel(), Mm)
        Up = modulo(U.ravel(), Mm)
        res = {f"displacement (mod {free_u.shape[1]} free motion(s))": rel(d, 0 * d, max(np.abs(Up).max(), fl["u"]))}
    else:
        Mm = None
        res = {"displacement": rel(sig["u"], U, fl["u"])}
    tris = idx[sig["triangles"]]
    res["stress"] = rel(sig["stress"], stresses(prob, u_ref, tris), fl["stress"])
    if lam_ref is not None:
        key = {(r["first"], r["second"]): i for i, r in enumerate(rows)}
        nr = len(sig["multipliers"])
        if nr != len(rows):
            raise CheckError(f"{label}: signorini has {nr} contact rows, this model {len(rows)}")
        # a mortar row is keyed by its slave point alone (its second point is
        # the heaviest of several masters, which ties may pick differently)
        perm = np.array([key.get((int(idx[sig['contact_first'][i]]), int(idx[sig['contact_second'][i, 0]])),
                                 key.get((int(idx[sig['contact_first'][i]]), None)))
                         for i in range(nr)])
        if any(p is None for p in perm):
            raise CheckError(f"{label}: a contact row of signorini has no counterpart here")
        perm = perm.astype(np.int64)
        normals = np.array([rows[j]["n"] for j in perm])
        res["normals"] = rel(sig["contact_normal"], normals)
        # rows whose multipliers are not unique (uniqueness) are left out
        uq = ~np.isin(perm, dep_rows if dep_rows is not None else [])
        res["multipliers"] = rel(sig["multipliers"][uq], lam_ref[perm][uq], 1e-6 * fl["force"])
        mortar = np.array([rows[j].get("trib") is not None for j in perm]) & uq
        L = float(np.ptp(prob.topo.x, axis=0).max())
        model = prob.cfg.get("model", {})
        te = float(model.get("thickness", 1.0)) if model.get("plane", "strain") == "stress" else 1.0
        gref = np.array([rows[j]["g"] for j in perm])
        if mortar.any():
            # mortar rows: the weighted gaps g~/D and the pressure λ/D (the mortar traction)
            res["mortar gap0"] = rel(sig["contact_gap0"][mortar], gref[mortar], 1e-12 * L)
            pref = np.array([lam_ref[j] / (rows[j]["trib"] * te) if rows[j].get("trib") else 0.0
                             for j in perm])
            res["mortar pressure"] = rel(sig["contact_pressure"][mortar], pref[mortar],
                                         1e-6 * fl["force"] / L)
        if (~mortar & uq).any():
            # node-to-segment and conforming rows: the initial gap (negative for an
            # interference fit) and the pressure λ/(trib × thickness), trib = ∫N ds
            # (∫N r ds per radian when axisymmetric)
            nm = ~mortar & uq
            res["gap0"] = rel(sig["contact_gap0"][nm], gref[nm], 1e-12 * L)
            pref = np.array([lam_ref[j] / (rows[j]["w"] * te) if rows[j].get("w") else 0.0 for j in perm])
            res["pressure"] = rel(sig["contact_pressure"][nm], pref[nm], 1e-6 * fl["force"] / L)
    states_line, states_ok = "", True
    if fric is not None:
        if any(sig[k] is None for k in ("multipliers_t", "slip", "state")):
            raise CheckError(f"{label}: a frictional problem, but signorini's checkpoint has no "
                             "multipliers_t / slip / state (problem-format.md §6)")
        lt = fric["lam_t"][perm]
        lmax = max(np.abs(lam_ref).max(initial=0.0), np.abs(fric["lam_t"]).max(initial=0.0), 1e-300)
        res["multipliers_t"] = rel(sig["multipliers_t"][uq], lt[uq], 1e-6 * fl["force"])
        # the slip of the step, v = T x − t0: a difference of displacements,
        # compared relative to the larger of max|v| and 1e-6·max|u| (a step
        # in which every row sticks has v = 0 up to the round-off of u);
        # modulo the free motions, like u
        vfl = max(1e-6 * float(np.abs(U).max(initial=0.0)), fl["u"])
        if free_u is not None and free_u.shape[1]:
            Vm = np.where(fric["held"][:, None], 0.0, Tt @ free_u)[perm]
            res["slip"] = rel(modulo(sig["slip"] - fric["v"][perm], Vm), 0 * lt,
                              max(np.abs(modulo(fric["v"][perm], Vm)).max(initial=0.0), vfl))
        else:
            res["slip"] = rel(sig["slip"], fric["v"][perm], vfl)
        # states: 0 open, 1 stick, 2 slip, the reference's by signorini's rule
        # from its own λ_n, λ_t and s (Coulomb: μ max(λ_n, 0))
        ref_st = friction_states(fric["in_contact"], fric["held"], fric["lam_t"], fric["s"])[perm]
        sig_st = sig["state"].astype(np.int64)
        diff = np.where((ref_st != sig_st) & uq)[0]
        # A row may differ only on the boundary of a state, as the reference
        # sees it, within the comparison tolerance: open/contact where λ_n ≤
        # 10·tol·max|λ| and the gap left is ≤ 10·tol·max|u| (a grazing row),
        # stick/slip where |λ_t| is within 10·tol·max|λ| of (1 − 1e-6)s.
        lam_p, slack_p = lam_ref[perm], fric["slack"][perm]
        s_p, lt_abs = fric["s"][perm], np.abs(lt)
        umax = float(np.abs(U).max(initial=0.0))
        grazing = (lam_p <= 10 * tol * lmax) & (np.abs(slack_p) <= 10 * tol * max(umax, fl["u"]))
        edge = np.abs(lt_abs - (1 - STICK_MARGIN) * s_p) <= 10 * tol * lmax
        boundary = np.array([(grazing[i] if 0 in (ref_st[i], sig_st[i]) else edge[i]) for i in diff], dtype=bool)
        nbad = int((~boundary).sum()) if len(diff) else 0
        counts = lambda st: "/".join(str(int((st == k).sum())) for k in (0, 1, 2))  # noqa: E731
        states_line = (f"  states (open/stick/slip) signorini {counts(sig_st)}, reference {counts(ref_st)}: "
                       f"{len(diff)} differ, {len(diff) - nbad} of them on a state boundary"
                       + (f" ({int((~uq).sum())} rows not unique, not compared)" if (~uq).any() else ""))
        states_ok = nbad == 0
        if not states_ok:
            i = diff[~boundary][0]
            states_line += (f"; e.g. row {i}: signorini {sig_st[i]}, reference {ref_st[i]} (λ_n {lam_p[i]:.3e}, "
                            f"λ_t {lt[i]:.3e}, s {s_p[i]:.3e}, signorini λ_t {sig['multipliers_t'][i]:.3e})")
    worst = max(res.values())
    line = "  ".join(f"{k} {v:.2e}" for k, v in res.items())
    ok = worst <= tol and states_ok
    log(f"{label}: max relative difference {line}{states_line}  -> {'OK' if ok else 'FAIL'} (tol {tol:g})")
    return ok, res


def run_signorini(exe: Path, toml: Path, out: Path, extra: list[str]):
    cmd = [str(exe), "solve", str(toml), "--out", str(out), "--quiet", *extra]
    p = subprocess.run(cmd, capture_output=True, text=True)
    return p.returncode, p.stdout + p.stderr, " ".join(cmd)


# ----------------------------------------------------------------- main


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__.split("\n")[0],
        epilog="exit status: 0 every comparison within --tol; 1 FAIL (a difference above --tol, or signorini "
               "failing on the problem); 2 usage or setup error; 3 NOT CHECKED: the reference cannot check "
               "this problem (a problem-file key it does not model, Tresca and Coulomb pairs in one problem, "
               "its Coulomb fixed point not settling, its own solve failing): the reason is printed, no "
               "verdict on signorini")
    ap.add_argument("toml", type=Path)
    ap.add_argument("--tol", type=float, default=1e-8, help="max relative difference (default 1e-8)")
    ap.add_argument("--signorini", type=Path, default=None,
                    help="binary (default $SIGNORINI or <repo>/target/release/signorini)")
    ap.add_argument("--part", choices=["a", "b", "both"], default="both")
    ap.add_argument("--keep", type=Path, default=None, help="keep signorini's outputs in this directory")
    ap.add_argument("--force-total", dest="force_thickness", action="store_false",
                    help="take [[force]] f as the force on the whole thickness (plane stress) instead of "
                         "N per unit thickness as the README says (a diagnostic switch)")
    args = ap.parse_args(argv)

    exe = args.signorini or Path(os.environ.get("SIGNORINI", REPO / "target/release/signorini"))
    if not exe.is_file():
        raise SetupError(f"signorini binary not found at {exe} (cargo build --release)")
    toml = args.toml.resolve()
    if not toml.is_file():
        raise SetupError(f"no such problem file: {toml}")
    name = toml.stem
    try:
        import gmsh
        import dolfinx  # noqa: F401
        import h5py  # noqa: F401
    except ImportError as e:
        raise SetupError(f"{e} under {sys.executable}: run this script with Debian's /usr/bin/python3 "
                         "(apt-get install python3-dolfinx-real python3-gmsh python3-scipy python3-h5py; "
                         "scripts/python_checks.sh does it)")
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    tmp_ctx = tempfile.TemporaryDirectory(prefix=f"xcheck_{name}_")
    tmp = args.keep.resolve() if args.keep else Path(tmp_ctx.name)
    failures = []
    t_start = time.time()
    log(f"== {name}: {toml}")
    try:
        cfg = tomllib.loads(toml.read_text())
        # A mesh of tetrahedra: the 3D reference (scripts/fenicsx_crosscheck3d.py).
        import fenicsx_crosscheck3d as x3

        msh = (toml.parent / str(cfg.get("mesh", {}).get("file", ""))).resolve()
        if msh.is_file() and x3.mesh_is_3d(gmsh, msh):
            try:
                rc = x3.check(toml, exe, args.tol, tmp, gmsh)
            except x3.NotChecked as e:
                raise NotChecked(str(e))
            except x3.CheckError as e:
                raise CheckError(str(e))
            log(f"{'OK' if rc == 0 else 'FAIL'} {name} ({time.time() - t_start:.1f} s)")
            return rc
        extra = unmodelled(cfg)
        if extra:
            raise NotChecked(f"the reference does not model {', '.join(extra)} (docs/problem-format.md); "
                             "nothing was compared")
        has_contact = bool(cfg.get("contact"))
        parts = ["a", "b"] if args.part == "both" else [args.part]
        nsteps = max(1, len(cfg.get("steps", [])))
        step_cfgs = [at_step(cfg, s) for s in range(nsteps)]
        if nsteps > 1:
            log(f"{nsteps} load steps: each step is compared with /steps/NNNN")

        if "a" in parts:
            t0 = time.time()
            prob = Problem(toml, with_contact=False, gmsh=gmsh, point_force_thickness=args.force_thickness)
            conflict, floating = None, []
            # Any step's prescribed values may conflict (e.g. a plate side that
            # moves while the slip line below it is fixed), so every step is tried.
            base_cfg = prob.cfg
            for cfg_s in step_cfgs:
                prob.cfg = cfg_s
                try:
                    _, _, floating = prob.reduction()
                except Conflict as e:
                    conflict, floating = str(e), []
                    break
            prob.cfg = base_cfg
            outa = tmp / "no_contact"
            outa.mkdir(parents=True, exist_ok=True)
            rc, txt, cmd = run_signorini(exe, toml, outa, ["--no-contact"])
            last = txt.strip().splitlines()[-1] if txt.strip() else ""
            if conflict:
                # e.g. geodynamic: without the contact copies a plate-motion Dirichlet curve and a
                # slip line meet at one node
                if rc == 2 and "conflicting conditions" in txt:
                    log(f"part a: without contact the conditions conflict at {conflict}; signorini "
                        f"refuses as it should (exit 2: {last}) -> OK, no comparison")
                else:
                    failures.append("a")
                    log(f"part a: conflicting conditions at {conflict}, but `{cmd}` exited {rc} -> FAIL")
            elif floating:
                desc = ", ".join(f"body {b} ({k} rigid motion(s))" for b, k in floating)
                if rc == 2:
                    log(f"part a: without contact {desc} is free; signorini refuses as it should "
                        f"(exit 2: {last}) -> OK, no comparison")
                else:
                    failures.append("a")
                    log(f"part a: without contact {desc} is free, but `{cmd}` exited {rc} -> FAIL")
            else:
                if rc != 0:
                    raise CheckError(f"`{cmd}` exited {rc}:\n{txt}")
                log(f"part a: `{cmd}`")
                asm = Assembler(gmsh, prob.m, prob.cfg)
                for s, cfg_s in enumerate(step_cfgs, start=1):
                    prob.cfg = cfg_s
                    T, u0, _ = prob.reduction()
                    K, f = prob.assemble(asm)
                    Kr = (T.T @ K @ T).tocsc()
                    fr = T.T @ (f - K @ u0)
                    xi = spla.spsolve(Kr, fr)
                    u = u0 + T @ xi
                    res = np.linalg.norm(Kr @ xi - fr) / max(np.linalg.norm(fr), 1e-300)
                    tag = f" step {s}" if nsteps > 1 else ""
                    log(f"part a{tag}: FEniCSx linear solve: {T.shape[1]} DOFs, residual {res:.1e} "
                        f"({time.time() - t0:.1f} s)")
                    ok, _ = compare(prob, u, read_signorini(outa / f"{name}.h5", s), args.tol,
                                    f"part a{tag} (no contact)")
                    if not ok:
                        failures.append(f"a{tag}")

        if "b" in parts:
            if not has_contact:
                log("part b: the problem has no [[contact]] -> skipped")
            else:
                outb = tmp / "contact"
                outb.mkdir(parents=True, exist_ok=True)
                rc, txt, cmd = run_signorini(exe, toml, outb, [])
                if rc != 0:
                    raise CheckError(f"`{cmd}` exited {rc}:\n{txt}")
                log(f"part b: `{cmd}`")
                t0 = time.time()
                prob = Problem(toml, with_contact=True, gmsh=gmsh, point_force_thickness=args.force_thickness)
                asm = Assembler(gmsh, prob.m, prob.cfg)
                rows = prob.contact_rows()
                r_i, r_j, r_v, g = [], [], [], []
                for i, r in enumerate(rows):
                    for p, c in r["coef"].items():
                        for k in range(2):
                            if c[k] != 0.0:
                                r_i.append(i)
                                r_j.append(2 * p + k)
                                r_v.append(c[k])
                    g.append(r["g"])
                A = sp.csr_matrix((r_v, (r_i, r_j)), shape=(len(rows), 2 * prob.topo.np))
                g = np.array(g)
                law, Tt, bound = prob.friction(rows)
                if law:
                    hand = friction_hand_case()
                    log(f"part b: {'Tresca' if law == 'tresca' else 'Coulomb'} friction on {len(rows)} rows; "
                        f"the reference's signs on the hand case (a node on a floor): error {hand:.1e}")
                    if hand > 1e-9:
                        raise NotChecked(f"the friction reference fails its hand case (error {hand:.2e})")
                u_prev = np.zeros(2 * prob.topo.np)  # the slip is measured from the previous step
                # every step's prescribed displacements: a row is held (a line of
                # symmetry) only if its point is held along t in all of them
                u0s = []
                if law:
                    for cfg_s in step_cfgs:
                        prob.cfg = cfg_s
                        u0s.append(prob.reduction()[1])
                for s, cfg_s in enumerate(step_cfgs, start=1):
                    prob.cfg = cfg_s
                    T, u0, floating = prob.reduction()
                    K, f = prob.assemble(asm)
                    # rows in the reduced unknowns: A T ξ ≤ g − A u0 (rows with no free DOF dropped)
                    Ar = (A @ T).tocsr()
                    Ar.data[np.abs(Ar.data) <= 1e-14] = 0.0
                    Ar.eliminate_zeros()
                    gr = g - A @ u0
                    keep = np.diff(Ar.indptr) > 0
                    if np.any(gr[~keep] < -1e-12 * (1 + np.abs(g[~keep]))):
                        raise CheckError("a contact row is violated by the prescribed displacements")
                    Kr = (T.T @ K @ T).tocsr()
                    fr = T.T @ (f - K @ u0)
                    tag = f" step {s}" if nsteps > 1 else ""
                    kidx = np.where(keep)[0]
                    fric = None
                    if law:
                        # tangential rows in the reduced unknowns; v = Tt u − Tt u_prev
                        # = Ttr ξ − c with c = Tt (u_prev − u0) (methods.md §9.1)
                        held = prob.held_rows(rows, T, u0s)
                        Ttr = (Tt @ T).tocsr()
                        Ttr.data[np.abs(Ttr.data) <= 1e-14] = 0.0
                        Ttr.eliminate_zeros()
                        Ttr = (sp.diags((~held).astype(float)) @ Ttr).tocsr()[kidx]
                        Ttr.eliminate_zeros()
                        c_off = (Tt @ (u_prev - u0))[kidx]
                        bk = np.where(held, 0.0, bound)[kidx]
                        if law == "tresca":
                            xi, lam_k, lt_k, info = solve_qp(Kr, fr, Ar[keep], gr[keep], f"part b{tag}",
                                                             Ttr, c_off, bk)
                            s_k = bk
                        else:
                            xi, lam_k, lt_k, info = solve_coulomb(Kr, fr, Ar[keep], gr[keep], Ttr, c_off, bk,
                                                                  f"part b{tag}")
                            s_k = bk * np.maximum(lam_k, 0.0)
                    else:
                        xi, lam_k, _, info = solve_qp(Kr, fr, Ar[keep], gr[keep], f"part b{tag}")
                    lam = np.zeros(len(rows))
                    lam[kidx] = lam_k
                    u = u0 + T @ xi
                    # what the problem leaves undetermined (free motions, dependent rows)
                    Zr = prob.free_modes(T, Kr, floating)
                    in_c = info["warm"][0] | (lam_k > 0)
                    if law:
                        motions, dep = uniqueness(Zr, Ar[keep], Ttr, xi, c_off, lam_k, lt_k, s_k, bk, in_c, law)
                    else:
                        nz = np.zeros(int(keep.sum()))
                        motions, dep = uniqueness(Zr, Ar[keep], sp.csr_matrix((len(nz), Kr.shape[0])), xi, nz,
                                                  lam_k, nz, nz, nz, in_c, None)
                    free_u = T @ motions
                    dep_rows = kidx[dep]
                    if free_u.shape[1]:
                        log(f"part b{tag}: {free_u.shape[1]} rigid motion(s) held by no row in contact or "
                            "sticking: the displacement is unique only up to them and is compared modulo them")
                    if len(dep_rows):
                        log(f"part b{tag}: {len(dep_rows)} row(s) with linearly dependent columns (e.g. a slave node "
                            "of two pairs on one master corner): their multipliers and states are not unique and "
                            "are not compared, the forces they make together are (through u)")
                    if law:
                        full = lambda a: np.bincount(kidx, weights=a, minlength=len(rows))  # noqa: E731
                        in_contact = np.zeros(len(rows), dtype=bool)
                        in_contact[kidx] = info["warm"][0] | (lam_k > 0)
                        slack = np.zeros(len(rows))
                        slack[kidx] = gr[keep] - Ar[keep] @ xi
                        # a held row has no tangential row: no slip (signorini writes 0)
                        v_full = np.where(held, 0.0, Tt @ (u - u_prev))
                        fric = {"lam_t": full(lt_k), "s": full(s_k), "v": v_full, "held": held,
                                "in_contact": in_contact, "slack": slack}
                        u_prev = u
                    fl = ", ".join(f"body {b}: {k}" for b, k in floating) or "none"
                    how = (f"Clarabel {info['status']} in {info['ip_iter']} it, "
                           f"active-set polish {info['polish_iter']} solve(s)")
                    if law == "coulomb":
                        how = (f"Coulomb fixed point s <- mu lambda_n: {info['fp_steps']} Tresca solves "
                               f"({info['fp_clarabel']} by Clarabel, the rest polish-only), "
                               + (f"last change {info['fp_change']:.1e}" if info["fp_stalled"] is None else
                                  f"stalled at the round-off of the solves, smallest change "
                                  f"{info['fp_change']:.1e} (solve {info['fp_stalled']})"))
                    fr_txt = ""
                    if law:
                        fr_txt = f", {info['stick']} stick / {info['slip']} slip friction rows"
                    log(f"part b{tag}: reference {'Tresca problem' if law == 'tresca' else 'Coulomb problem' if law else 'QP'}: "
                        f"{Kr.shape[0]} DOFs, {int(keep.sum())} rows, free rigid motions {fl}; {how}, "
                        f"{info['active']} active{fr_txt}; KKT stat {info['stationarity']:.1e} "
                        f"primal {info['primal']:.1e} compl {info['complementarity']:.1e}"
                        + (f" friction {info['friction']:.1e}" if law else "") + f" ({time.time() - t0:.1f} s)")
                    if max(info["stationarity"], info["primal"], info["complementarity"], info["dual"],
                           info["friction"]) > 1e-9:
                        raise NotChecked(f"part b{tag}: the reference solution is not accurate (KKT above 1e-9)")
                    ok, _ = compare(prob, u, read_signorini(outb / f"{name}.h5", s), args.tol,
                                    f"part b{tag} (contact)", lam_ref=lam, rows=rows, fric=fric,
                                    free_u=free_u, dep_rows=dep_rows, Tt=Tt)
                    if not ok:
                        failures.append(f"b{tag}")
    finally:
        gmsh.finalize()
        tmp_ctx.cleanup()
    dt = time.time() - t_start
    if failures:
        m = cfg.get("model", {})
        if (cfg.get("force") and m.get("plane") == "stress" and float(m.get("thickness", 1.0)) != 1.0
                and args.force_thickness):
            log("hint: the problem has [[force]] point loads in plane stress with thickness "
                f"{m.get('thickness')}; this check multiplies them by the thickness (README: f is in "
                "N per unit thickness). Rerun with --force-total to see whether that is the only difference.")
        log(f"FAIL {name}: part(s) {', '.join(failures)} ({dt:.1f} s)")
        return 1
    log(f"OK {name} ({dt:.1f} s)")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except SetupError as e:
        print(f"fenicsx_crosscheck: error: {e}", file=sys.stderr)
        sys.exit(2)
    except NotChecked as e:
        print(f"fenicsx_crosscheck: NOT CHECKED: {e}", file=sys.stderr)
        sys.exit(3)
    except (CheckError, Conflict) as e:
        print(f"fenicsx_crosscheck: FAIL: {e}", file=sys.stderr)
        sys.exit(1)
