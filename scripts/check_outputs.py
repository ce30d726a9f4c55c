#!/usr/bin/env python3
"""Check signorini's output files against the contract (docs/problem-format.md).

Usage:  python scripts/check_outputs.py DIR [NAME ...] [--no-render] [--no-pvpython]

Needs pyvista (with the vtk wheel), h5py and numpy (scripts/python_checks.sh
installs them into .venv).  For every problem NAME in DIR (default: every
NAME.h5 found there) it checks:

* NAME.h5, the checkpoint: /mesh (nodes, node_tags, body, triangles,
  material, contact_points/first/second/weights/normal/gap0/interface/segments
  with shapes, dtypes, index ranges, counter-clockwise triangles, names
  attributes), /steps/NNNN (consecutive from 0001) with displacement,
  multipliers, active, stress, von_mises, principal_stress, contact_pressure,
  gap and the attributes method, preconditioner, iterations, converged,
  kkt_*, energy, time; with friction multipliers_t, tangential_traction,
  slip, state (0/1/2), all four; no NaN/Inf anywhere; NAME.json (if
  present) agrees.
* NAME.vtu (one step) or NAME_NNNN.vtu (load steps), read with pyvista:
  point/cell counts and coordinates/connectivity equal to /mesh; point data
  displacement (3 components, z = 0) and body, cell data stress (4 components
  in plane strain, 3 in plane stress), von_mises (the report's τe of the
  stress), principal_stress (2), material; no NaN; every array equal to the
  HDF5 step's.
* NAME[_NNNN]_contact.vtu: one point per contact row, one line cell per
  contact segment; contact_pressure (≥ 0), gap (≥ 0 up to tolerance),
  active (0/1), normal (3 components, unit) equal to the HDF5 data.
* NAME.pvd (load steps): every DataSet file exists, the times equal the
  steps' `time` attributes, pyvista's PVD reader reads every time step.
* A picture: the last step's mesh warped by `displacement` (scaled so the
  largest displacement is 5 % of the model size), coloured by von_mises,
  rendered off screen to DIR/NAME_von_mises.png, which must not be blank.
  Rendering runs in a child process (a broken GL stack may crash); it tries
  VTK's default window (X, falling back to EGL), EGL, Xvfb (xvfb-run) and
  OSMesa in that order, or the one named by $SIGNORINI_RENDER
  (default|egl|xvfb|osmesa).
* If Debian's `pvpython` (package paraview) is installed, every file is
  also opened with ParaView's readers and the counts and array names are
  compared; otherwise a note says it was skipped.

Prints one OK line per file; exits 1 with the reasons on any failure, 2 on
bad usage or a missing dependency.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

VTK_TRIANGLE, VTK_LINE = 5, 3

MESH_DATASETS = {  # name: (ndim, second dim or None, kind)  kind: f=float, i=integer
    "nodes": (2, 2, "f"),
    "node_tags": (1, None, "i"),
    "body": (1, None, "i"),
    "triangles": (2, 3, "i"),
    "material": (1, None, "i"),
    "contact_points": (2, 2, "f"),
    "contact_first": (1, None, "i"),
    "contact_second": (2, 2, "i"),
    "contact_weights": (2, 2, "f"),
    "contact_normal": (2, 2, "f"),
    "contact_gap0": (1, None, "f"),
    "contact_interface": (1, None, "i"),
    "contact_segments": (2, 2, "i"),
}
STEP_DATASETS = {  # name: (leading size key, second dim, kind)
    "displacement": ("n", 2, "f"),
    "stress": ("m", 4, "f"),
    "von_mises": ("m", None, "f"),
    "principal_stress": ("m", 2, "f"),
    "multipliers": ("r", None, "f"),
    "contact_pressure": ("r", None, "f"),
    "gap": ("r", None, "f"),
    "active": ("r", None, "i"),
}
STEP_ATTRS_FLOAT = ["time", "energy", "kkt_primal", "kkt_dual", "kkt_complementarity", "kkt_stationarity"]


class Failure(Exception):
    pass


class Problems:
    """Collects failures of one file; raises at the end."""

    def __init__(self, what: str):
        self.what = what
        self.errors: list[str] = []

    def check(self, cond, msg: str) -> bool:
        if not cond:
            self.errors.append(msg)
        return bool(cond)

    def done(self, summary: str) -> None:
        if self.errors:
            raise Failure(f"{self.what}:\n    " + "\n    ".join(self.errors))
        print(f"OK {self.what}: {summary}", flush=True)


def finite(a) -> bool:
    a = np.asarray(a)
    return a.dtype.kind not in "fc" or bool(np.isfinite(a).all())


def maxdiff(a, b) -> float:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape != b.shape:
        return float("inf")
    return float(np.abs(a - b).max(initial=0.0))


def close(a, b, rel=1e-12) -> bool:
    scale = max(np.abs(np.asarray(b, dtype=float)).max(initial=0.0), 1e-300)
    return maxdiff(a, b) <= rel * scale


def tau_e(s):
    s = np.asarray(s, dtype=float)
    return np.sqrt(np.maximum(s[:, 0] ** 2 + s[:, 1] ** 2 - s[:, 0] * s[:, 1] + 3 * s[:, 2] ** 2, 0.0))


# ---------------------------------------------------------------- HDF5


def check_h5(path: Path, name: str):
    import h5py

    P = Problems(path.name)
    data = {"steps": {}}
    with h5py.File(path, "r") as f:
        P.check("plane_strain" in f.attrs, "root attribute plane_strain missing")
        data["plane_strain"] = bool(int(f.attrs.get("plane_strain", 1)))
        if not P.check("mesh" in f, "/mesh missing") or not P.check("steps" in f, "/steps missing"):
            P.done("")
        g = f["mesh"]
        for ds, (ndim, second, kind) in MESH_DATASETS.items():
            if not P.check(ds in g, f"/mesh/{ds} missing"):
                continue
            a = g[ds][()]
            P.check(a.ndim == ndim and (second is None or a.shape[1] == second),
                    f"/mesh/{ds} has shape {a.shape}, expected {ndim}-D" + (f" [., {second}]" if second else ""))
            P.check((a.dtype.kind == "f") if kind == "f" else (a.dtype.kind in "iu"),
                    f"/mesh/{ds} has dtype {a.dtype}")
            P.check(finite(a), f"/mesh/{ds} contains NaN/Inf")
            data[ds] = a
        for at in ("material_names", "interface_names"):
            P.check(at in g.attrs, f"/mesh attribute {at} missing")
        if P.errors:
            P.done("")
        n, m, r = len(data["nodes"]), len(data["triangles"]), len(data["contact_points"])
        data.update(n=n, m=m, r=r)
        for ds, want in (("node_tags", n), ("body", n), ("material", m), ("contact_first", r),
                         ("contact_second", r), ("contact_weights", r), ("contact_normal", r),
                         ("contact_gap0", r), ("contact_interface", r)):
            P.check(len(data[ds]) == want, f"/mesh/{ds} has {len(data[ds])} rows, expected {want}")
        tri = data["triangles"]
        P.check(m > 0 and tri.min() >= 0 and tri.max() < n, "/mesh/triangles: point index out of range")
        if m and tri.max() < n:
            x = data["nodes"][tri]
            a2 = (x[:, 1, 0] - x[:, 0, 0]) * (x[:, 2, 1] - x[:, 0, 1]) - (x[:, 2, 0] - x[:, 0, 0]) * (x[:, 1, 1] - x[:, 0, 1])
            P.check((a2 > 0).all(), f"/mesh/triangles: {(a2 <= 0).sum()} triangle(s) not counter-clockwise")
        nmat = len(g.attrs.get("material_names", []))
        P.check(m == 0 or data["material"].max() < nmat, "/mesh/material: index beyond material_names")
        if r:
            P.check(data["contact_first"].max() < n and data["contact_second"].max() < n,
                    "/mesh/contact_first/second: point index out of range")
            nn = np.linalg.norm(data["contact_normal"], axis=1)
            P.check(np.abs(nn - 1).max() < 1e-9, "/mesh/contact_normal: not unit vectors")
            # an initial penetration up to 1e-6 x the segment length is
            # accepted as contact (problem-format.md section 5; a mortar row
            # where a round slave touches a flat master: -6e-11 on hertz)
            pts = data["contact_points"]
            seg = np.median(np.linalg.norm(np.diff(pts, axis=0), axis=1)) if len(pts) > 1 else 1.0
            P.check((data["contact_gap0"] >= -1e-6 * seg).all(), "/mesh/contact_gap0: negative initial gap")
            P.check(np.allclose(data["contact_points"], data["nodes"][data["contact_first"]]),
                    "/mesh/contact_points differ from the nodes of contact_first")
        if len(data["contact_segments"]):
            P.check(data["contact_segments"].max() < r, "/mesh/contact_segments: row index out of range")

        names = sorted(f["steps"].keys())
        P.check(len(names) > 0, "/steps has no step")
        for i, s in enumerate(names, start=1):
            P.check(re.fullmatch(r"\d{4,}", s) and int(s) == i,
                    f"/steps/{s}: expected consecutive 4-digit groups 0001, 0002, … (got {names})")
        if "last_step" in f.attrs:
            P.check(int(f.attrs["last_step"]) == len(names), f"root last_step = {f.attrs['last_step']}, {len(names)} steps")
        sizes = {"n": n, "m": m, "r": r}
        for s in names:
            st = f["steps"][s]
            sd = {}
            for ds, (lead, second, kind) in STEP_DATASETS.items():
                if not P.check(ds in st, f"/steps/{s}/{ds} missing"):
                    continue
                a = st[ds][()]
                want = (sizes[lead],) + ((second,) if second else ())
                P.check(a.shape == want, f"/steps/{s}/{ds} has shape {a.shape}, expected {want}")
                P.check(finite(a), f"/steps/{s}/{ds} contains NaN/Inf")
                sd[ds] = a
            for at in STEP_ATTRS_FLOAT:
                if P.check(at in st.attrs, f"/steps/{s} attribute {at} missing"):
                    P.check(np.isfinite(float(st.attrs[at])), f"/steps/{s} attribute {at} is not finite")
            for at in ("method", "preconditioner"):
                if P.check(at in st.attrs, f"/steps/{s} attribute {at} missing"):
                    v = st.attrs[at]
                    v = v.decode() if isinstance(v, bytes) else str(v)
                    P.check(len(v) > 0, f"/steps/{s} attribute {at} is empty")
            if P.check("iterations" in st.attrs, f"/steps/{s} attribute iterations missing"):
                P.check(np.asarray(st.attrs["iterations"]).dtype.kind in "iu", f"/steps/{s}@iterations is not an integer")
            if P.check("converged" in st.attrs, f"/steps/{s} attribute converged missing"):
                P.check(int(st.attrs["converged"]) in (0, 1), f"/steps/{s}@converged is not 0/1")
            P.check(any(k.startswith("time_") for k in st.attrs), f"/steps/{s}: no time_* (wall time) attribute")
            if "active" in sd:
                P.check(np.isin(sd["active"], (0, 1)).all(), f"/steps/{s}/active: values other than 0/1")
            if "stress" in sd and "von_mises" in sd:
                P.check(close(sd["von_mises"], tau_e(sd["stress"]), 1e-9), f"/steps/{s}/von_mises is not τe(stress)")
            if "stress" in sd and "principal_stress" in sd and m:
                ps = sd["principal_stress"]
                st_ = sd["stress"]
                P.check(close(ps.sum(1), st_[:, 0] + st_[:, 1], 1e-9) and (ps[:, 0] >= ps[:, 1] - 1e-9 * np.abs(ps).max()).all(),
                        f"/steps/{s}/principal_stress inconsistent with stress (trace or order σ1 ≥ σ2)")
                if not data["plane_strain"]:
                    P.check(np.abs(st_[:, 3]).max() == 0, f"/steps/{s}/stress: σzz ≠ 0 in plane stress")
            # [output] reference_step: the *_change datasets are this step's
            # fields minus the reference step's, exactly (h5py's own reading).
            if "displacement_change" in st:
                k = int(st.attrs.get("reference_step", 0))
                ref_name = f"{k:04d}"
                if P.check(ref_name in f["steps"] and k <= int(s),
                           f"/steps/{s}@reference_step = {k}: no such earlier step"):
                    ref = f["steps"][ref_name]
                    for ds, base in (("displacement_change", "displacement"), ("stress_change", "stress"),
                                     ("contact_pressure_change", "contact_pressure")):
                        if P.check(ds in st, f"/steps/{s}/{ds} missing"):
                            P.check(np.array_equal(st[ds][()], st[base][()] - ref[base][()]),
                                    f"/steps/{s}/{ds} is not {base} minus /steps/{ref_name}/{base}")
            # Friction (methods.md §9): all four arrays or none, one per row.
            fr = ("multipliers_t", "tangential_traction", "slip", "state")
            if any(ds in st for ds in fr):
                for ds in fr:
                    if P.check(ds in st, f"/steps/{s}/{ds} missing (the other friction arrays are there)"):
                        a = st[ds][()]
                        P.check(a.shape == (r,), f"/steps/{s}/{ds} has shape {a.shape}, expected {(r,)}")
                        P.check(finite(a), f"/steps/{s}/{ds} contains NaN/Inf")
                        sd[ds] = a
                if "state" in sd:
                    P.check(np.isin(sd["state"], (0, 1, 2)).all(), f"/steps/{s}/state: values other than 0/1/2")
            sd["attrs"] = {k: st.attrs[k] for k in st.attrs}
            data["steps"][int(s)] = sd
    # the JSON summary, when present
    js = path.with_suffix(".json")
    if js.is_file():
        try:
            j = json.loads(js.read_text())
            last = data["steps"][max(data["steps"])]
            P.check(j.get("nodes") == n, f"{js.name}: nodes = {j.get('nodes')}, /mesh has {n}")
            P.check(j.get("triangles") == m, f"{js.name}: triangles = {j.get('triangles')}, /mesh has {m}")
            P.check(j.get("problem") == name, f"{js.name}: problem = {j.get('problem')!r}")
            P.check(bool(j.get("converged")) == bool(int(last["attrs"]["converged"])),
                    f"{js.name}: converged differs from the last HDF5 step")
        except (ValueError, KeyError) as e:
            P.check(False, f"{js.name}: unreadable ({e})")
    conv = [int(sd["attrs"].get("converged", 0)) for sd in data["steps"].values()]
    try:
        P.done(f"{n} points, {m} triangles, {r} contact rows, {len(names)} step(s), converged {conv}")
    except Failure as e:  # usable for the VTU checks all the same
        data["error"] = str(e)
    return data


# ------------------------------------------------------------------ VTU


def check_vtu(path: Path, h5, step: int):
    import pyvista as pv

    P = Problems(path.name)
    g = pv.read(path)
    n, m = h5["n"], h5["m"]
    sd = h5["steps"][step]
    P.check(g.n_points == n, f"{g.n_points} points, /mesh/nodes has {n}")
    P.check(g.n_cells == m, f"{g.n_cells} cells, /mesh/triangles has {m}")
    if g.n_points == n:
        P.check(close(g.points[:, :2], h5["nodes"]) and np.abs(g.points[:, 2]).max(initial=0) == 0,
                "point coordinates differ from /mesh/nodes")
    if g.n_cells == m:
        P.check((g.celltypes == VTK_TRIANGLE).all(), "cells are not all triangles")
        conn = g.cells.reshape(-1, 4) if (g.celltypes == VTK_TRIANGLE).all() else None
        if conn is not None:
            P.check((conn[:, 0] == 3).all() and np.array_equal(conn[:, 1:], h5["triangles"]),
                    "connectivity differs from /mesh/triangles")
    want_pt = {"displacement": 3, "body": 1}
    want_cell = {"stress": 4 if h5["plane_strain"] else 3, "von_mises": 1, "principal_stress": 2, "material": 1}
    for where, arrays, want in (("point", g.point_data, want_pt), ("cell", g.cell_data, want_cell)):
        for name, nc in want.items():
            if not P.check(name in arrays, f"{where} data {name!r} missing (has {list(arrays.keys())})"):
                continue
            a = np.asarray(arrays[name])
            comps = 1 if a.ndim == 1 else a.shape[1]
            P.check(comps == nc, f"{where} data {name!r} has {comps} component(s), expected {nc}")
    for arrays in (g.point_data, g.cell_data):
        for name in arrays.keys():
            P.check(finite(arrays[name]), f"array {name!r} contains NaN/Inf")
    if P.errors:
        P.done("")
    u = np.asarray(g.point_data["displacement"])
    P.check(np.abs(u[:, 2]).max(initial=0) == 0, "displacement z component is not 0")
    P.check(close(u[:, :2], sd["displacement"]), f"displacement differs from /steps/{step:04d}/displacement "
            f"(max {maxdiff(u[:, :2], sd['displacement']):.3e})")
    P.check(np.array_equal(np.asarray(g.point_data["body"]).ravel(), h5["body"]), "body differs from /mesh/body")
    P.check(np.array_equal(np.asarray(g.cell_data["material"]).ravel(), h5["material"]),
            "material differs from /mesh/material")
    nc = want_cell["stress"]
    P.check(close(g.cell_data["stress"], sd["stress"][:, :nc]), f"stress differs from /steps/{step:04d}/stress")
    P.check(close(np.asarray(g.cell_data["von_mises"]).ravel(), sd["von_mises"]), "von_mises differs from the HDF5 step")
    P.check(close(g.cell_data["principal_stress"], sd["principal_stress"]), "principal_stress differs from the HDF5 step")
    umax = float(np.abs(u).max(initial=0))
    P.done(f"{g.n_points} points, {g.n_cells} triangles, max |u| {umax:.4e}, "
           f"max von_mises {float(np.max(g.cell_data['von_mises'], initial=0)):.4e}; equals /steps/{step:04d}")
    return g


def check_contact_vtu(path: Path, h5, step: int):
    import pyvista as pv

    P = Problems(path.name)
    g = pv.read(path)
    r, k = h5["r"], len(h5["contact_segments"])
    sd = h5["steps"][step]
    P.check(g.n_points == r, f"{g.n_points} points, /mesh has {r} contact rows")
    P.check(g.n_cells == k, f"{g.n_cells} cells, /mesh/contact_segments has {k}")
    if g.n_cells:
        P.check((g.celltypes == VTK_LINE).all(), "cells are not all lines")
        if (g.celltypes == VTK_LINE).all():
            conn = g.cells.reshape(-1, 3)
            P.check(np.array_equal(conn[:, 1:], h5["contact_segments"]), "line cells differ from /mesh/contact_segments")
    if g.n_points == r and r:
        P.check(close(g.points[:, :2], h5["contact_points"]), "points differ from /mesh/contact_points")
    want = {"contact_pressure": 1, "gap": 1, "active": 1, "normal": 3}
    for name, nc in want.items():
        if not P.check(name in g.point_data, f"point data {name!r} missing (has {list(g.point_data.keys())})"):
            continue
        a = np.asarray(g.point_data[name])
        comps = 1 if a.ndim == 1 else a.shape[1]
        P.check(comps == nc, f"point data {name!r} has {comps} component(s), expected {nc}")
    for arrays in (g.point_data, g.cell_data):
        for name in arrays.keys():
            P.check(finite(arrays[name]), f"array {name!r} contains NaN/Inf")
    if P.errors or r == 0:
        P.done("no contact rows (empty file)" if not P.errors else "")
        return g
    p = np.asarray(g.point_data["contact_pressure"]).ravel()
    gap = np.asarray(g.point_data["gap"]).ravel()
    act = np.asarray(g.point_data["active"]).ravel()
    nrm = np.asarray(g.point_data["normal"])
    P.check(p.min() >= -1e-8 * max(p.max(), 1e-300), f"negative contact pressure {p.min():.3e}")
    ustep = sd["displacement"]
    gtol = 1e-6 * max(float(np.abs(ustep).max(initial=0)), 1e-300)
    P.check(gap.min() >= -gtol, f"negative gap {gap.min():.3e} (tolerance {gtol:.1e})")
    P.check(np.isin(act, (0, 1)).all(), "active has values other than 0/1")
    P.check(np.abs(np.linalg.norm(nrm, axis=1) - 1).max() < 1e-9 and np.abs(nrm[:, 2]).max() == 0,
            "normal is not a unit vector in the plane")
    P.check(close(p, sd["contact_pressure"]), "contact_pressure differs from the HDF5 step")
    P.check(close(gap, sd["gap"]) or maxdiff(gap, sd["gap"]) <= 1e-15, "gap differs from the HDF5 step")
    P.check(np.array_equal(act, sd["active"]), "active differs from the HDF5 step")
    P.check(close(nrm[:, :2], h5["contact_normal"]), "normal differs from /mesh/contact_normal")
    for name in ("tangential_traction", "slip", "state"):
        if name in sd:
            if P.check(name in g.point_data, f"point data {name!r} missing (the HDF5 step has it)"):
                a = np.asarray(g.point_data[name]).ravel()
                P.check(close(a, sd[name]) or maxdiff(a, sd[name]) == 0, f"{name} differs from the HDF5 step")
    P.done(f"{r} contact points, {k} segments, {int(act.sum())} active, max pressure {p.max():.4e}, "
           f"max gap {gap.max():.3e}; equals /steps/{step:04d}")
    return g


def check_pvd(path: Path, h5, step_files: dict):
    import pyvista as pv

    P = Problems(path.name)
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        raise Failure(f"{path.name}: not XML ({e})")
    P.check(root.tag == "VTKFile" and root.get("type") == "Collection", "not a VTKFile of type Collection")
    entries = [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")]
    times = {s: float(sd["attrs"]["time"]) for s, sd in h5["steps"].items()}
    listed = {f for _, f in entries}
    for _, f in entries:
        P.check((path.parent / f).is_file(), f"DataSet file {f} does not exist")
    for s, files in step_files.items():
        for f in files:
            P.check(f.name in listed, f"{f.name} (step {s}) is not in the collection")
            tf = [t for t, e in entries if e == f.name]
            if tf:
                P.check(abs(tf[0] - times[s]) <= 1e-12 * max(1.0, abs(times[s])),
                        f"{f.name}: timestep {tf[0]} but /steps/{s:04d}@time = {times[s]}")
    if not P.errors:
        reader = pv.get_reader(str(path))
        tv = list(reader.time_values)
        P.check(np.allclose(sorted(set(tv)), sorted(set(times.values()))), f"PVD reader times {tv} != HDF5 times")
        for s, t in sorted(times.items()):
            reader.set_active_time_value(t)
            mb = reader.read()
            blocks = [mb[i] for i in range(mb.n_blocks)]
            npts = sorted(b.n_points for b in blocks if b is not None)
            P.check(h5["n"] in npts, f"time {t}: no block with the {h5['n']} mesh points (got {npts})")
    P.done(f"{len(entries)} data sets, times {sorted(set(t for t, _ in entries))}")


# ------------------------------------------------------------- render

RENDER_CHILD = r"""
import sys, json
import numpy as np
import pyvista as pv
jobs = json.loads(sys.argv[1])
pv.OFF_SCREEN = True
window = "?"
for vtu, png, size in jobs:
    g = pv.read(vtu)
    u = np.asarray(g.point_data["displacement"])
    umax = float(np.linalg.norm(u, axis=1).max(initial=0.0))
    factor = 0.05 * size / umax if umax > 0 else 0.0
    w = g.warp_by_vector("displacement", factor=factor)
    p = pv.Plotter(off_screen=True, window_size=(1200, 900))
    p.set_background("white")
    p.add_mesh(w, scalars="von_mises", cmap="viridis", show_edges=False,
               scalar_bar_args={"title": "von_mises [Pa]", "color": "black", "vertical": True,
                                "position_x": 0.86, "position_y": 0.1, "height": 0.8, "width": 0.06})
    name = vtu.rsplit("/", 1)[-1]
    p.add_text(f"{name}: displacement x {factor:.3g} (max u = {umax:.3e} m)", font_size=10, color="black")
    p.view_xy()
    p.camera.zoom(0.9)
    img = p.screenshot(png, return_img=True)
    window = type(p.ren_win).__name__ if getattr(p, "ren_win", None) is not None else "?"
    p.close()
print("RENDER " + json.dumps({"window": window}))
"""

BACKENDS = ["default", "egl", "xvfb", "osmesa"]


def backend_cmd(backend: str, jobs_json: str):
    env = dict(os.environ)
    cmd = [sys.executable, "-c", RENDER_CHILD, jobs_json]
    if backend == "egl":
        env["VTK_DEFAULT_OPENGL_WINDOW"] = "vtkEGLRenderWindow"
    elif backend == "osmesa":
        env["VTK_DEFAULT_OPENGL_WINDOW"] = "vtkOSOpenGLRenderWindow"
    elif backend == "xvfb":
        xr = shutil.which("xvfb-run")
        if not xr:
            return None, None
        env.pop("VTK_DEFAULT_OPENGL_WINDOW", None)
        cmd = [xr, "-a", "-s", "-screen 0 1280x1024x24", *cmd]
    return cmd, env


def render(jobs: list[tuple[Path, Path, float]]) -> str:
    """Render every (vtu, png, model size) in one child process; returns the backend used."""
    forced = os.environ.get("SIGNORINI_RENDER")
    order = [forced] if forced else BACKENDS
    jobs_json = json.dumps([[str(v), str(p), s] for v, p, s in jobs])
    notes = []
    for b in order:
        if b not in BACKENDS:
            raise Failure(f"SIGNORINI_RENDER={b!r}: expected one of {BACKENDS}")
        cmd, env = backend_cmd(b, jobs_json)
        if cmd is None:
            notes.append(f"{b}: xvfb-run not installed")
            continue
        for _, png, _ in jobs:
            if png.exists():
                png.unlink()
        try:
            p = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=300)
        except subprocess.TimeoutExpired:
            notes.append(f"{b}: timed out")
            continue
        line = [ln for ln in p.stdout.splitlines() if ln.startswith("RENDER ")]
        if p.returncode == 0 and line and all(png.is_file() for _, png, _ in jobs):
            return f"{b} ({json.loads(line[-1][7:])['window']})"
        tail = re.sub(r"\x1b\[[0-9;]*m", "", (p.stderr.strip().splitlines() or [""])[-1])[:200]
        notes.append(f"{b}: exit {p.returncode} {tail}")
    raise Failure("no off-screen rendering backend works here (" + "; ".join(notes) + "). "
                  "Install xvfb (apt-get install xvfb) or Mesa's EGL/OSMesa (libegl1 libegl-mesa0 / libosmesa6); "
                  "scripts/python_checks.sh does this")


def check_png(png: Path, backend: str):
    import pyvista as pv

    P = Problems(png.name)
    img = pv.read(png)
    arr = np.asarray(img.point_data[img.point_data.keys()[0]])
    dims = img.dimensions
    rgb = arr[:, :3].astype(float)
    bg = np.array([255.0, 255.0, 255.0])
    nonbg = (np.abs(rgb - bg).sum(1) > 30).mean()
    packed = (arr[:, 0].astype(np.int64) << 16) | (arr[:, 1].astype(np.int64) << 8) | arr[:, 2].astype(np.int64)
    colours = len(np.unique(packed))
    P.check(nonbg > 0.01, f"image is (nearly) blank: {100 * nonbg:.2f} % non-background pixels")
    P.check(colours > 20, f"image has only {colours} distinct colours")
    P.check(rgb.std() > 5, f"image has no contrast (std {rgb.std():.2f})")
    P.done(f"{dims[0]}x{dims[1]}, {100 * nonbg:.1f} % drawn, {colours} colours, rendered with {backend}")


# ------------------------------------------------------------ pvpython

PV_CHILD = r"""
import json, sys
from paraview import simple
out = {}
for f in sys.argv[1:]:
    if f.endswith(".pvd"):
        r = simple.PVDReader(FileName=f)
        times = list(r.TimestepValues) if hasattr(r.TimestepValues, "__iter__") else [r.TimestepValues]
        r.UpdatePipeline(times[-1] if times else 0.0)
        info = r.GetDataInformation()
        out[f] = {"times": times, "points": info.GetNumberOfPoints(), "cells": info.GetNumberOfCells()}
    else:
        r = simple.XMLUnstructuredGridReader(FileName=[f])
        r.UpdatePipeline()
        info = r.GetDataInformation()
        out[f] = {"points": info.GetNumberOfPoints(), "cells": info.GetNumberOfCells(),
                  "point_arrays": list(r.PointData.keys()), "cell_arrays": list(r.CellData.keys())}
print("PVJSON " + json.dumps(out))
"""


def check_pvpython(files: list[Path], expect: dict) -> None:
    exe = shutil.which("pvpython")
    if not exe:
        print("note: pvpython (Debian package paraview) not found: the ParaView reader check is skipped", flush=True)
        return
    env = dict(os.environ)
    with tempfile.NamedTemporaryFile("w", suffix=".py", delete=False) as t:
        t.write(PV_CHILD)
    try:
        cmd = [exe, "--force-offscreen-rendering", t.name, *map(str, files)]
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=300, env=env)
        if p.returncode != 0 or "PVJSON " not in p.stdout:
            # older pvpython builds do not know --force-offscreen-rendering
            cmd = [exe, t.name, *map(str, files)]
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=300, env=env)
    finally:
        os.unlink(t.name)
    lines = [ln for ln in p.stdout.splitlines() if ln.startswith("PVJSON ")]
    if p.returncode != 0 or not lines:
        raise Failure(f"pvpython failed (exit {p.returncode}): {(p.stderr.strip().splitlines() or [''])[-1]}")
    got = json.loads(lines[-1][7:])
    for f in files:
        P = Problems(f"{f.name} (pvpython)")
        r, e = got.get(str(f)), expect[f]
        if not P.check(r is not None, "not read"):
            P.done("")
        for key in ("points", "cells"):
            if key in e:
                P.check(r[key] == e[key], f"{key}: ParaView reads {r[key]}, expected {e[key]}")
        for key in ("point_arrays", "cell_arrays"):
            for a in e.get(key, []):
                P.check(a in r.get(key, []), f"{key[:-7]} array {a!r} missing in ParaView ({r.get(key)})")
        if "times" in e:
            P.check(np.allclose(sorted(set(r["times"])), sorted(set(e["times"]))), f"times {r['times']} != {e['times']}")
        P.done(", ".join(f"{k} {r[k]}" for k in ("points", "cells") if k in r)
               + (f", times {r['times']}" if "times" in r else ""))


# ---------------------------------------------------------------- main


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Check signorini's outputs (VTU, PVD, HDF5) and render a picture.")
    ap.add_argument("dir", type=Path)
    ap.add_argument("names", nargs="*", help="problem names (default: every NAME.h5 in DIR)")
    ap.add_argument("--no-render", action="store_true", help="skip the PNG")
    ap.add_argument("--no-pvpython", action="store_true", help="skip the ParaView check even if pvpython exists")
    args = ap.parse_intermixed_args(argv)
    try:
        import h5py  # noqa: F401
        import pyvista  # noqa: F401
    except ImportError as e:
        print(f"check_outputs: error: {e} (run scripts/python_checks.sh, or pip install pyvista h5py)", file=sys.stderr)
        return 2
    d = args.dir
    if not d.is_dir():
        print(f"check_outputs: error: {d} is not a directory", file=sys.stderr)
        return 2
    # A run with load steps splits its checkpoint: NAME.h5 (the index) links
    # NAME_mesh.h5 and NAME_NNNN.h5, which are parts of NAME, not problems.
    stems = {p.stem for p in d.glob("*.h5")}
    part = re.compile(r"(.+)_(mesh|\d{4,})")
    names = args.names or sorted(
        s for s in stems if not ((m := part.fullmatch(s)) and m.group(1) in stems)
    )
    if not names:
        print(f"check_outputs: error: no NAME.h5 in {d}", file=sys.stderr)
        return 2
    failures: list[str] = []
    claimed: set[Path] = set()
    pv_files: list[Path] = []
    pv_expect: dict = {}
    render_jobs: list = []
    for name in names:
        h5path = d / f"{name}.h5"
        try:
            if not h5path.is_file():
                raise Failure(f"{h5path.name}: missing (every solve writes the checkpoint)")
            h5 = check_h5(h5path, name)
        except Exception as e:
            msg = str(e) if isinstance(e, Failure) else f"{h5path.name}: {type(e).__name__}: {e}"
            failures.append(msg + " (the VTU/PVD files of this problem are not checked)")
            print(f"FAIL {failures[-1]}", flush=True)
            claimed |= {f for f in d.iterdir() if re.fullmatch(re.escape(name) + r"(_\d{4,})?(_contact)?\.vtu|" + re.escape(name) + r"\.pvd", f.name)}
            continue
        if "error" in h5:
            failures.append(h5["error"])
            print(f"FAIL {h5['error']}", flush=True)
        claimed.add(h5path)
        steps = sorted(h5["steps"])
        single = (d / f"{name}.vtu").is_file()
        step_files = {}
        if single:
            step_files[steps[-1]] = [d / f"{name}.vtu", d / f"{name}_contact.vtu"]
        else:
            for s in steps:
                step_files[s] = [d / f"{name}_{s:04d}.vtu", d / f"{name}_{s:04d}_contact.vtu"]
        if single and len(steps) > 1:
            failures.append(f"{name}: {len(steps)} steps in the checkpoint but a single {name}.vtu")
        last_vtu = None
        for s, (vtu, cvtu) in step_files.items():
            for f, fn in ((vtu, check_vtu), (cvtu, check_contact_vtu)):
                claimed.add(f)
                try:
                    if not f.is_file():
                        raise Failure(f"{f.name}: missing")
                    fn(f, h5, s)
                    pv_files.append(f)
                    pv_expect[f] = ({"points": h5["n"], "cells": h5["m"],
                                     "point_arrays": ["displacement", "body"],
                                     "cell_arrays": ["stress", "von_mises", "principal_stress", "material"]}
                                    if fn is check_vtu else
                                    {"points": h5["r"], "cells": len(h5["contact_segments"]),
                                     "point_arrays": ["contact_pressure", "gap", "active", "normal"] if h5["r"] else []})
                except Failure as e:
                    failures.append(str(e))
                    print(f"FAIL {e}", flush=True)
                except Exception as e:  # an unreadable file: report it, go on
                    failures.append(f"{f.name}: {type(e).__name__}: {e}")
                    print(f"FAIL {failures[-1]}", flush=True)
            last_vtu = vtu
        pvd = d / f"{name}.pvd"
        if pvd.is_file() or not single:
            claimed.add(pvd)
            try:
                if not pvd.is_file():
                    raise Failure(f"{pvd.name}: missing (load steps need the collection)")
                check_pvd(pvd, h5, step_files)
                pv_files.append(pvd)
                # ParaView merges the two parts (mesh + contact boundary) of a time step
                pv_expect[pvd] = {"times": [float(h5["steps"][s]["attrs"]["time"]) for s in steps],
                                  "points": h5["n"] + h5["r"], "cells": h5["m"] + len(h5["contact_segments"])}
            except Failure as e:
                failures.append(str(e))
                print(f"FAIL {e}", flush=True)
        if not args.no_render and last_vtu is not None and last_vtu.is_file():
            render_jobs.append((last_vtu, d / f"{name}_von_mises.png", float(np.ptp(h5["nodes"], axis=0).max())))
    if render_jobs:
        try:
            backend = render(render_jobs)
            for _, png, _ in render_jobs:
                try:
                    check_png(png, backend)
                except Failure as e:
                    failures.append(str(e))
                    print(f"FAIL {e}", flush=True)
        except Failure as e:
            failures.append(str(e))
            print(f"FAIL {e}", flush=True)
    if not args.names:
        for f in sorted(d.iterdir()):
            if f.suffix in (".vtu", ".pvd") and f not in claimed:
                failures.append(f"{f.name}: no matching NAME.h5 checkpoint / not a file of a solved problem")
                print(f"FAIL {failures[-1]}", flush=True)
    if not args.no_pvpython:
        try:
            check_pvpython(pv_files, pv_expect)
        except Failure as e:
            failures.append(str(e))
            print(f"FAIL {e}", flush=True)
    if failures:
        print(f"\ncheck_outputs: {len(failures)} failure(s):", file=sys.stderr)
        for f in failures:
            print(f"  - {f}", file=sys.stderr)
        return 1
    print(f"check_outputs: all files of {', '.join(names)} in {d} OK", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
