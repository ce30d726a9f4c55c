#!/usr/bin/python3
"""FEniCSx (dolfinx 0.5.2) linear elasticity of a 3D signorini mesh by CG + GAMG, timed.

Usage:
    /usr/bin/python3 scripts/bench_fenicsx3d.py MESH.msh --material NAME:E:nu [...]
        [--fix SURFACE:COMP:VALUE ...] [--pressure SURFACE:PN ...] [--json OUT.json]

The side-by-side yardstick of the 3D benchmark (scripts/bench_solid.py, issue 45): the
LINEAR ELASTIC problem without contact on the same mesh (P1 vector Lagrange on the
tetrahedra, E and nu per physical volume), u_COMP = VALUE on the nodes of a physical
surface (a slip plane normal to an axis is `NAME:k:0`), a normal pressure PN (N/m²,
negative pushes) on a surface. Bodies meshed apart that touch only through contact must
be held by --fix (e.g. the Hertz ball by a prescribed u_z on its top). CG + GAMG (PETSc's
defaults) with the six rigid modes as near-null space, rtol 1e-10.

Phases (time.perf_counter): read (gmsh.open + gmshio.model_to_mesh), assemble (spaces,
forms incl. the FFCx JIT, which is cached after the first run, matrix, vector, BCs),
solve (KSP setup + solve). JSON: {dofs, t_read, t_assemble, t_solve, t_total,
ksp_iterations, ksp_reason, rel_residual}. Exit 1 when KSP does not converge.
"""

from __future__ import annotations

import argparse
import json
import sys
import time


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("msh")
    ap.add_argument("--material", action="append", default=[])
    ap.add_argument("--fix", action="append", default=[])
    ap.add_argument("--pressure", action="append", default=[])
    ap.add_argument("--json")
    a = ap.parse_args(argv)

    import numpy as np
    import gmsh
    from mpi4py import MPI
    from petsc4py import PETSc
    import dolfinx
    import dolfinx.fem.petsc as fp
    import dolfinx.io.gmshio  # noqa: F401
    import ufl

    t0 = time.perf_counter()
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.open(a.msh)
    msh, ct, ft = dolfinx.io.gmshio.model_to_mesh(gmsh.model, MPI.COMM_WORLD, 0, gdim=3)
    groups = {}
    for dim, tag in gmsh.model.getPhysicalGroups():
        groups[gmsh.model.getPhysicalName(dim, tag)] = (dim, tag)
    t_read = time.perf_counter() - t0

    t1 = time.perf_counter()
    V = dolfinx.fem.VectorFunctionSpace(msh, ("Lagrange", 1))
    Q = dolfinx.fem.FunctionSpace(msh, ("DG", 0))
    mu, lam = dolfinx.fem.Function(Q), dolfinx.fem.Function(Q)
    for spec in a.material:
        name, E, nu = spec.split(":")
        E, nu = float(E), float(nu)
        cells = ct.indices[ct.values == groups[name][1]]
        dofs = Q.dofmap.list.array[cells]
        mu.x.array[dofs] = E / (2 * (1 + nu))
        lam.x.array[dofs] = E * nu / ((1 + nu) * (1 - 2 * nu))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    ds = ufl.Measure("ds", domain=msh, subdomain_data=ft)
    n = ufl.FacetNormal(msh)
    zero = dolfinx.fem.Constant(msh, PETSc.ScalarType(0.0))
    L_ufl = zero * v[0] * ufl.dx
    for spec in a.pressure:
        name, pn = spec.split(":")
        PN = dolfinx.fem.Constant(msh, PETSc.ScalarType(float(pn)))
        L_ufl = L_ufl + PN * ufl.dot(n, v) * ds(groups[name][1])
    a_ufl = (2 * mu * ufl.inner(eps(u), eps(v)) + lam * ufl.tr(eps(u)) * ufl.tr(eps(v))) * ufl.dx
    af, Lf = dolfinx.fem.form(a_ufl), dolfinx.fem.form(L_ufl)
    bcs = []
    for spec in a.fix:
        name, comp, val = spec.split(":")
        facets = ft.indices[ft.values == groups[name][1]]
        dofs = dolfinx.fem.locate_dofs_topological(V.sub(int(comp)), 2, facets)
        bcs.append(dolfinx.fem.dirichletbc(PETSc.ScalarType(float(val)), dofs, V.sub(int(comp))))
    A = fp.assemble_matrix(af, bcs=bcs)
    A.assemble()
    b = fp.assemble_vector(Lf)
    fp.apply_lifting(b, [af], bcs=[bcs])
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    fp.set_bc(b, bcs)
    t_asm = time.perf_counter() - t1

    t2 = time.perf_counter()
    # the six rigid modes as near-null space (dolfinx's elasticity demo)
    bs = V.dofmap.index_map_bs
    nloc = V.dofmap.index_map.size_local
    x = V.tabulate_dof_coordinates()[:nloc]
    vecs = [dolfinx.la.create_petsc_vector(V.dofmap.index_map, bs) for _ in range(6)]
    arrs = [vv.array for vv in vecs]
    for k in range(3):
        arrs[k][k::3] = 1.0
    arrs[3][0::3], arrs[3][1::3] = -x[:, 1], x[:, 0]
    arrs[4][0::3], arrs[4][2::3] = x[:, 2], -x[:, 0]
    arrs[5][2::3], arrs[5][1::3] = x[:, 1], -x[:, 2]
    dolfinx.la.orthonormalize(vecs)
    A.setNearNullSpace(PETSc.NullSpace().create(vectors=vecs))
    ksp = PETSc.KSP().create(msh.comm)
    ksp.setOperators(A)
    ksp.setType("cg")
    ksp.getPC().setType("gamg")
    ksp.setTolerances(rtol=1e-10, atol=1e-300, max_it=10000)
    ksp.setFromOptions()
    sol = A.createVecRight()
    ksp.solve(b, sol)
    t_solve = time.perf_counter() - t2

    r = b.duplicate()
    A.mult(sol, r)
    r.axpy(-1.0, b)
    rec = {
        "dofs": int(V.dofmap.index_map.size_global * bs),
        "t_read": t_read, "t_assemble": t_asm, "t_solve": t_solve,
        "t_total": t_read + t_asm + t_solve,
        "ksp_iterations": int(ksp.getIterationNumber()),
        "ksp_reason": int(ksp.getConvergedReason()),
        "rel_residual": float(r.norm() / max(b.norm(), 1e-300)),
    }
    print(json.dumps(rec))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(rec, f)
    return 0 if rec["ksp_reason"] > 0 else 1


if __name__ == "__main__":
    sys.exit(main())
