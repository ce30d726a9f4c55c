#!/usr/bin/env python3
"""Verification cases of signorini against published and analytic references.

Each case of verification/ is meshed with Gmsh at a given element size,
solved with `signorini solve` (default method: auto = ssn), and one or more
quantities are read back from the JSON summary and the HDF5 checkpoint and
compared with their reference. docs/verification.md describes every case,
its reference and its source, and records the measured tables.

Usage:
    scripts/verify [--fine] [--only NAME[,NAME]] [--work DIR] [--plots]
                   [--exe target/release/signorini] [--gmsh gmsh]

    --fine   the fine meshes (minutes); default: the coarse meshes (CI)
    --plots  also draw each checkpoint (`signorini plot`, with and without
             --contact) into the work directory

Prints one Markdown table row per compared quantity. Exit codes:
    0  every error is within its tolerance
    1  an error is outside its tolerance
    2  a usage error (an unknown option or case, --work naming something
       that is not a directory or cannot be created): one line on stderr
    3  a tool is missing (the signorini binary, gmsh) or a mesh or a solve
       failed (a solve must exit 0: converged and certified)

Needs numpy and h5py (scripts/verify runs this file with the project's venv,
.venv, and creates it when it is missing).
"""

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile

# h5py and numpy are imported by main() once the arguments are checked: a
# usage error needs neither (and is exit 2 wherever they are missing).
h5py = None
np = None

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
VDIR = os.path.join(ROOT, "verification")


class Failure(Exception):
    """A mesh or solve that did not finish: exit 3."""


# ---------------------------------------------------------------- running


def mesh(args, geo, params, out_msh, dim=2):
    cmd = [args.gmsh, f"-{dim}", "-format", "msh41", "-v", "1"]
    for k, v in params.items():
        cmd += ["-setnumber", k, repr(float(v))]
    cmd += [geo, "-o", out_msh]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0 or not os.path.exists(out_msh):
        raise Failure(f"gmsh failed on {geo}: {r.stderr.strip()}")


def solve(args, case_dir, toml_name, msh, work):
    """Copy the problem file next to nothing but with its mesh path made
    absolute, solve it, and return (json, h5 file name)."""
    src = os.path.join(case_dir, toml_name)
    text = open(src).read()
    text, n = re.subn(r'(?m)^file\s*=\s*".*"', f'file = "{msh}"', text, count=1)
    if n != 1:
        raise Failure(f"{src}: no [mesh] file line")
    name = os.path.splitext(toml_name)[0]
    dst = os.path.join(work, name + ".toml")
    with open(dst, "w") as f:
        f.write(text)
    r = subprocess.run([args.exe, "solve", dst, "--out", work, "--quiet"],
                       capture_output=True, text=True)
    if r.returncode != 0:
        raise Failure(f"signorini solve {src} exited {r.returncode}: {r.stderr.strip()}")
    with open(os.path.join(work, name + ".json")) as f:
        summary = json.load(f)
    h5 = os.path.join(work, name + ".h5")
    if args.plots:
        for extra, suffix in (([], ""), (["--contact"], "_contact")):
            subprocess.run([args.exe, "plot", h5, "-o",
                            os.path.join(work, name + suffix + ".png"), "--quiet"] + extra,
                           check=False)
    return summary, h5


def last_step(f):
    return f["steps"][sorted(f["steps"])[-1]]


def body_of_material(f, material):
    """Body index (the per-node `body` array) of the triangles of a material."""
    m = f["mesh"]
    names = [str(n) for n in m.attrs["material_names"]]
    mat = m["material"][:]
    tri = m["triangles"][:]
    return int(m["body"][tri[mat == names.index(material), 0][0]])


def node_at(f, xy, material):
    """The output point at xy (to 1e-9) belonging to the body of `material`
    (a contact point carries one copy per body, so a probe is ambiguous)."""
    m = f["mesh"]
    nodes = m["nodes"][:]
    b = body_of_material(f, material)
    d = np.hypot(nodes[:, 0] - xy[0], nodes[:, 1] - xy[1])
    idx = np.where((d < 1e-9 * max(1.0, abs(nodes).max())) & (m["body"][:] == b))[0]
    if len(idx) != 1:
        raise Failure(f"no unique node of {material} at {xy}")
    return int(idx[0])


def hertz_fit(f, xcoord=0):
    """Least-squares fit of p(x)^2 = p0^2 (1 - x^2/a^2) over the active rows:
    p^2 is linear in x^2, so the fit is linear; it averages the node-to-node
    ripple of a node-to-segment pressure instead of reading one node."""
    m = f["mesh"]
    s = last_step(f)
    x = np.abs(m["contact_points"][:, xcoord])
    p = s["contact_pressure"][:]
    act = s["active"][:] > 0
    a, p0 = hertz_fit_rows(x, p, act)
    return a, p0, x[act].max(), x[~act].min()


def hertz_fit_rows(x, p, act):
    """The fit of hertz_fit on given distances x, pressures p and active
    flags: (a, p0)."""
    A = np.vstack([np.ones(act.sum()), x[act] ** 2]).T
    c, *_ = np.linalg.lstsq(A, p[act] ** 2, rcond=None)
    return math.sqrt(-c[0] / c[1]), math.sqrt(c[0])


def row(case, quantity, ref, tool, tol, kind="rel", source=""):
    if kind == "rel":
        err = abs(tool - ref) / abs(ref) if ref != 0 else abs(tool)
    elif kind in ("below", "above"):
        # a bound, not a value: the row passes when tool < ref (below) or
        # tool > ref (above); err is 0 or 1 against the tolerance 0.5
        ok = tool < ref if kind == "below" else tool > ref
        err, tol = (0.0 if ok else 1.0), 0.5
    else:  # absolute error of a quantity whose reference is 0 (scaled already)
        err = abs(tool - ref)
    return {"case": case, "quantity": quantity, "reference": ref, "tool": tool,
            "error": err, "tol": tol, "kind": kind, "source": source}


# ------------------------------------------------------------------ cases


def case_nafems1(args, work):
    d = os.path.join(VDIR, "nafems1")
    hc = 0.15 if args.fine else 0.6
    msh = os.path.join(work, "nafems1.msh")
    mesh(args, os.path.join(d, "nafems1.geo"), {"hc": hc}, msh)
    rows = []
    # Hertz (Johnson 1985, §4.2): F = 35000 N/mm, R = 50 mm
    E1, E2, nu = 210000.0, 70000.0, 0.3
    Es = 1.0 / ((1 - nu**2) / E1 + (1 - nu**2) / E2)
    F, R = 35000.0, 50.0
    a_ref = math.sqrt(4 * F * R / (math.pi * Es))
    p0_ref = 2 * F / (math.pi * a_ref)
    tol = 0.01 if args.fine else 0.02
    for toml, uy_ref, label in (("nafems1.toml", -1.27423, "mu = 0"),
                                ("nafems1_mu.toml", -1.27031, "mu = 0.1")):
        summary, h5 = solve(args, d, toml, msh, work)
        with h5py.File(h5) as f:
            if label == "mu = 0":
                a, p0, _, _ = hertz_fit(f)
                rows.append(row("nafems1 " + label, "a [mm] (fit)", a_ref, a, tol,
                                source="Hertz, Johnson (1985) §4.2"))
                rows.append(row("nafems1 " + label, "p0 [MPa] (fit)", p0_ref, p0, tol,
                                source="Hertz, Johnson (1985) §4.2"))
            b = node_at(f, (0.0, 0.0), "block")
            uy = float(last_step(f)["displacement"][b, 1])
        src = "Code_Aster SSNP154" + ("B" if label == "mu = 0" else "D")
        rows.append(row("nafems1 " + label, "u_y(B) [mm]", uy_ref, uy, 0.02, source=src))
    return rows


def case_patch(args, work):
    d = os.path.join(VDIR, "patch")
    params = {"hu": 1 / 23, "hl": 1 / 31} if args.fine else {"hu": 0.14, "hl": 0.1}
    msh = os.path.join(work, "patch.msh")
    mesh(args, os.path.join(d, "patch.geo"), params, msh)
    p = 1.0e7
    rows = []
    # mortar passes the patch test: round-off; NTS has an O(1) error that
    # does not shrink with the mesh (docs/verification.md, section 3)
    for toml, tol_p, tol_s in (("patch_mortar.toml", 1e-10, 1e-10),
                               ("patch_nts.toml", 0.15, 0.50)):
        summary, h5 = solve(args, d, toml, msh, work)
        with h5py.File(h5) as f:
            s = last_step(f)
            pr = s["contact_pressure"][:]
            act = s["active"][:]
            sig = s["stress"][:]
        label = "patch " + toml.split("_")[1].split(".")[0]
        if act.min() == 0:
            raise Failure(f"{label}: an interface row is open")
        rows.append(row(label, "max abs(p_row/p - 1)", 0.0, float(np.abs(pr / p - 1).max()),
                        tol_p, kind="abs", source="uniform pressure p"))
        dev = max(float(np.abs(sig[:, 1] / -p - 1).max()),
                  float(np.abs(sig[:, 0]).max() / p), float(np.abs(sig[:, 2]).max() / p))
        rows.append(row(label, "max abs(sigma - sigma_exact)/p", 0.0, dev, tol_s, kind="abs",
                        source="uniform stress sigma_yy = -p"))
    return rows


def case_nonmatching(args, work):
    """Two blocks on a flat 5:4 non-matching interface under a uniform
    pressure (docs/verification.md §3): the default rows of a non-matching
    pair (mortar) against node-to-segment rows on request, on meshes refined
    by halving (h_m = 0.5 -> 0.0625 mm fine, 0.5 and 0.25 mm coarse)."""
    d = os.path.join(VDIR, "nonmatching")
    p = 100.0
    rows = []
    for k in ((5, 10, 20, 40) if args.fine else (5, 10)):
        msh = os.path.join(work, f"blocks54_{k}.msh")
        mesh(args, os.path.join(d, "blocks54.geo"), {"k": k}, msh)
        h = f"h_m = {2.5 / k:g} mm"
        for toml in ("blocks54.toml", "blocks54_nts.toml"):
            summary, h5 = solve(args, d, toml, msh, work)
            disc = summary["contact"]["interfaces"]["upper_bottom->lower_top"]["discretization"]
            with h5py.File(h5) as f:
                s = last_step(f)
                x = f["mesh"]["contact_points"][:, 0]
                pr = s["contact_pressure"][:]
                act = s["active"][:]
                sig = s["stress"][:]
            if act.min() == 0:
                raise Failure(f"nonmatching {toml} k = {k}: an interface row is open")
            e = pr / p - 1
            # interior rows whose slave node lands on a master node: x = 10 j / k
            on = (np.abs(x * k / 10 - np.round(x * k / 10)) < 1e-6) & (x > 1e-9) & (x < 10 - 1e-9)
            if toml == "blocks54.toml":
                if disc != "mortar":
                    raise Failure(f"nonmatching: the default pair ran {disc}, not mortar")
                dev = max(float(np.abs(sig[:, 1] / -p - 1).max()),
                          float(np.abs(sig[:, 0]).max() / p), float(np.abs(sig[:, 2]).max() / p))
                rows.append(row(f"5:4 default (mortar), {h}", "max abs(p_row/p - 1)", 0.0,
                                float(np.abs(e).max()), 1e-10, kind="abs",
                                source="uniform pressure p"))
                rows.append(row(f"5:4 default (mortar), {h}", "max abs(sigma - sigma_exact)/p",
                                0.0, dev, 1e-10, kind="abs", source="uniform stress"))
            else:
                # a known defect, recorded: the tolerance guards its size
                rows.append(row(f"5:4 nts, {h}", "mean p_row/p - 1 where slave meets master",
                                0.0, float(e[on].mean()), 0.10, kind="abs",
                                source="uniform pressure p"))
    return rows


def case_hertz(args, work):
    d = os.path.join(VDIR, "hertz")
    hc = 0.00125 if args.fine else 0.005
    msh = os.path.join(work, "hertz2.msh")
    mesh(args, os.path.join(d, "hertz2.geo"), {"hc": hc}, msh)
    summary, h5 = solve(args, d, "hertz2.toml", msh, work)
    E, nu, R1, R2 = 2.0e11, 0.3, 1.0, 2.0
    Es = E / (2 * (1 - nu**2))
    R = R1 * R2 / (R1 + R2)
    F = 2 * 1.6182654e8 * R1  # full model: twice the half model's load
    a_ref = math.sqrt(4 * F * R / (math.pi * Es))
    p0_ref = 2 * F / (math.pi * a_ref)
    with h5py.File(h5) as f:
        a, p0, _, _ = hertz_fit(f)
    tol = 0.01 if args.fine else 0.02
    return [row("hertz 2 cylinders", "a [m] (fit)", a_ref, a, tol,
                source="Johnson (1985) §4.2"),
            row("hertz 2 cylinders", "p0 [Pa] (fit)", p0_ref, p0, tol,
                source="Johnson (1985) §4.2")]


def case_hertz_sphere(args, work):
    """Two spheres, axisymmetric (docs/verification.md §7): the section of
    case_hertz revolved; forces are per radian, so F = 2 pi q R1^2 / 2."""
    d = os.path.join(VDIR, "hertz_sphere")
    hc = 0.00125 if args.fine else 0.005
    msh = os.path.join(work, "hertz_sphere.msh")
    mesh(args, os.path.join(d, "hertz_sphere.geo"), {"hc": hc}, msh)
    summary, h5 = solve(args, d, "hertz_sphere.toml", msh, work)
    E, nu, R1, R2, q = 2.0e11, 0.3, 1.0, 2.0, 8.744777e6
    Es = E / (2 * (1 - nu**2))
    R = R1 * R2 / (R1 + R2)
    F = q * math.pi * R1**2
    a_ref = (3 * F * R / (4 * Es)) ** (1 / 3)
    p0_ref = 3 * F / (2 * math.pi * a_ref**2)
    with h5py.File(h5) as f:
        a, p0, _, _ = hertz_fit(f)
    tol = 0.01 if args.fine else 0.02
    return [row("hertz sphere (axisymmetric)", "a [m] (fit)", a_ref, a, tol,
                source="Johnson (1985) §4.2"),
            row("hertz sphere (axisymmetric)", "p0 [Pa] (fit)", p0_ref, p0, tol,
                source="Johnson (1985) §4.2"),
            row("hertz sphere (axisymmetric)", "axial contact force [N/rad]", F / (2 * math.pi),
                next(iter(summary["contact"]["interfaces"].values()))["force"][1], 1e-6,
                source="load q pi R1^2 / (2 pi)")]


def case_punch(args, work):
    d = os.path.join(VDIR, "punch")
    hc = 0.001 if args.fine else 0.005
    msh = os.path.join(work, "punch.msh")
    mesh(args, os.path.join(d, "punch.geo"), {"hc": hc}, msh)
    summary, h5 = solve(args, d, "punch.toml", msh, work)
    a, F = 0.1, 2.0e7
    with h5py.File(h5) as f:
        x = f["mesh"]["contact_points"][:, 0]
        s = last_step(f)
        lam = s["multipliers"][:]
        pr = s["contact_pressure"][:]
    # nodal force on the central half |x| < a/2 (the node at a/2 counts half)
    w = np.where(np.abs(x - a / 2) < 1e-9, 0.5, np.where(x < a / 2, 1.0, 0.0))
    frac = float((w * lam).sum() / lam.sum())
    p_axis = float(pr[np.argmin(np.abs(x))])
    tol = 0.01 if args.fine else 0.03
    return [row("flat punch", "force share of abs(x) < a/2", 1.0 / 3.0, frac, tol,
                source="Johnson (1985) §2.8"),
            row("flat punch", "p(0) [Pa]", F / (math.pi * a), p_axis, tol,
                source="Johnson (1985) §2.8")]


def case_cattaneo(args, work):
    d = os.path.join(VDIR, "cattaneo")
    hc = 0.0015 if args.fine else 0.006
    msh = os.path.join(work, "cattaneo.msh")
    mesh(args, os.path.join(d, "cattaneo.geo"), {"hc": hc}, msh)
    summary, h5 = solve(args, d, "cattaneo.toml", msh, work)
    mu, E, nu, R = 0.5, 2.0e11, 0.3, 1.0
    Es = E / (2 * (1 - nu**2))
    fx, fy = summary["reactions"]["cyl_top"]["force"]
    P, Q = -fy, abs(fx)
    if not Q < mu * P:
        raise Failure(f"cattaneo: Q = {Q} is not below mu P = {mu * P}")
    a = math.sqrt(4 * P * R / (math.pi * Es))
    c_ref = a * math.sqrt(1 - Q / (mu * P))
    with h5py.File(h5) as f:
        x = f["mesh"]["contact_points"][:, 0]
        st = last_step(f)["state"][:]
        q = last_step(f)["tangential_traction"][:]
        pr = last_step(f)["contact_pressure"][:]
    o = np.argsort(x)
    x, st, q, pr = x[o], st[o], q[o], pr[o]
    # Cattaneo's shear traction (Johnson 1985, §7.2):
    # q = mu p0 (sqrt(1 - x^2/a^2) - (c/a) sqrt(1 - x^2/c^2)), the second
    # term only in the stick zone; compared in magnitude (its sign follows
    # the tangent's orientation), as an rms over the rows in contact
    p0 = 2 * P / (math.pi * a)
    q_cm = mu * p0 * (np.sqrt(np.clip(1 - (x / a) ** 2, 0, None))
                      - (c_ref / a) * np.sqrt(np.clip(1 - (x / c_ref) ** 2, 0, None)))
    on = pr > 0
    q_rms = float(np.sqrt(np.mean((np.abs(q[on]) - q_cm[on]) ** 2)) / (mu * p0))
    stick = np.where(st == 1)[0]
    i0, i1 = stick.min(), stick.max()
    if not (st[i0:i1 + 1] == 1).all() or st[i0 - 1] != 2 or st[i1 + 1] != 2:
        raise Failure("cattaneo: the stick rows are not one zone between two slip zones")
    # each end of the stick zone: halfway between the last stick row and
    # the first slip row
    left = 0.5 * (x[i0] + x[i0 - 1])
    right = 0.5 * (x[i1] + x[i1 + 1])
    c = 0.5 * (right - left)
    tol = 0.05 if args.fine else 0.10
    return [row("cattaneo-mindlin", f"c [m] (Q/muP = {Q / (mu * P):.3f})", c_ref, c, tol,
                source="Johnson (1985) §7.2"),
            row("cattaneo-mindlin", "rms(abs(q) - q_CM)/(mu p0)", 0.0, q_rms,
                0.08, kind="abs", source="Johnson (1985) §7.2")]


def case_sneddon(args, work):
    """Sneddon's rigid flat cylindrical punch on a half-space, axisymmetric
    (docs/verification.md §7): the punch's settlement and the pressure's
    shape; forces per radian (F / 2 pi in the outputs)."""
    d = os.path.join(VDIR, "sneddon")
    hc = 0.001 if args.fine else 0.005
    msh = os.path.join(work, "sneddon.msh")
    mesh(args, os.path.join(d, "sneddon.geo"), {"hc": hc}, msh)
    summary, h5 = solve(args, d, "sneddon.toml", msh, work)
    a, E, nu, q = 0.1, 2.0e11, 0.3, 1.0e8
    F = q * math.pi * a**2
    delta_ref = F * (1 - nu**2) / (2 * a * E)
    with h5py.File(h5) as f:
        x = f["mesh"]["contact_points"][:, 0]
        s = last_step(f)
        lam = s["multipliers"][:]
        pr = s["contact_pressure"][:]
        # the block's copy of the point on the axis under the punch
        uy = float(s["displacement"][node_at(f, (0.0, 0.0), "block"), 1])
    # force on the central disk r < a/2 (the node at a/2 counts half):
    # the multipliers are nodal forces per radian, the weight r inside
    w = np.where(np.abs(x - a / 2) < 1e-9, 0.5, np.where(x < a / 2, 1.0, 0.0))
    frac = float((w * lam).sum() / lam.sum())
    p_axis = float(pr[np.argmin(np.abs(x))])
    tol_d = 0.015 if args.fine else 0.03
    tol_p = 0.01 if args.fine else 0.05
    c = "sneddon punch (axisymmetric)"
    return [row(c, "delta [m]", delta_ref, -uy, tol_d, source="Sneddon (1946)"),
            row(c, "force share of r < a/2", 1 - math.sqrt(0.75), frac, tol_p,
                source="Sneddon (1946)"),
            row(c, "p(0) [Pa]", F / (2 * math.pi * a**2), p_axis, tol_p,
                source="Sneddon (1946)"),
            row(c, "axial contact force [N/rad]", F / (2 * math.pi),
                summary["contact"]["interfaces"]["punch_base"]["force"][1], 1e-6,
                source="load q pi a^2 / (2 pi)")]


def nodal_stress(f, step, node, material):
    """sigma at a node as Code_Aster's SIEF_NOEU takes it: the mean of the
    element values (constant per P1 triangle) of the triangles of
    `material` that have the node as a vertex."""
    m = f["mesh"]
    names = [str(n) for n in m.attrs["material_names"]]
    tri = m["triangles"][:]
    sel = (m["material"][:] == names.index(material)) & (tri == node).any(axis=1)
    if not sel.any():
        raise Failure(f"no triangle of {material} at node {node}")
    return step["stress"][:][sel].mean(axis=0)


def case_nafems2(args, work):
    """NAFEMS contact benchmark 2 (punch with rounded edges), axisymmetric,
    against Code_Aster SSNA122 modelling A (docs/verification.md §7)."""
    d = os.path.join(VDIR, "nafems2")
    hc = 0.5 if args.fine else 2.0
    msh = os.path.join(work, "nafems2.msh")
    mesh(args, os.path.join(d, "nafems2.geo"), {"hc": hc}, msh)
    rows = []
    # VALE_CALC of astest/ssna122a.comm at M. Tolerances (docs/verification.md
    # §7): the spread of Code_Aster's own SSNA122 modellings (u_y(M) 1.7 %,
    # sigma_yy(M) 7.7 %) plus this P1 mesh's own error, measured by
    # refinement to hc = 0.125 mm (coarse 1.8 % and 2.1 %, fine 0.2 % and 0.4 %)
    tol_u = 0.02 if args.fine else 0.035
    tol_s = 0.08 if args.fine else 0.10
    for toml, uy_ref, syy_ref, label in (
            ("nafems2.toml", -0.130734196, -91.100611838, "mu = 0"),
            ("nafems2_mu.toml", -0.128580159, -88.665558926, "mu = 0.1")):
        summary, h5 = solve(args, d, toml, msh, work)
        with h5py.File(h5) as f:
            mnode = node_at(f, (0.0, 0.0), "foundation")
            s = last_step(f)
            uy = float(s["displacement"][mnode, 1])
            syy = float(nodal_stress(f, s, mnode, "foundation")[1])
        c = "nafems2 " + label
        rows.append(row(c, "u_y(M) [mm]", uy_ref, uy, tol_u, source="Code_Aster SSNA122A"))
        rows.append(row(c, "sigma_yy(M) [MPa]", syy_ref, syy, tol_s,
                        source="Code_Aster SSNA122A"))
    return rows


def shrink_fit_pressure(a, c, b, delta, E, nu):
    """Lame's shrink-fit pressure (plane strain, one material; Timoshenko &
    Goodier 1970, section 28): delta is the outer tube's expansion at c under
    an internal pressure p less the inner tube's (negative) under an external
    p, both linear in p: u_r(r) = (1 + nu)/E ((1 - 2 nu) A r + B / r) for
    sigma_rr = A - B / r^2."""
    def u(A, B, r):
        return (1 + nu) / E * ((1 - 2 * nu) * A * r + B / r)
    ao = c * c / (b * b - c * c)
    ai = -c * c / (c * c - a * a)
    return delta / (u(ao, ao * b * b, c) - u(ai, ai * a * a, c))


def case_shrinkfit(args, work):
    """Shrink fit of two tubes, then the inner one pushed out axially under
    Coulomb friction, axisymmetric (docs/verification.md §7)."""
    d = os.path.join(VDIR, "shrinkfit")
    n = 24 if args.fine else 8
    msh = os.path.join(work, "shrinkfit.msh")
    mesh(args, os.path.join(d, "shrinkfit.geo"), {"n": n}, msh)
    summary, h5 = solve(args, d, "shrinkfit.toml", msh, work)
    a, c, b, L, delta, E, nu, mu = 0.5, 1.0, 1.5, 0.5, 1.0e-3, 2.0e11, 0.3, 0.2
    p = shrink_fit_pressure(a, c, b, delta, E, nu)
    limit = mu * p * c * L  # full-slip friction force per radian
    with h5py.File(h5) as f:
        steps = [f["steps"][k] for k in sorted(f["steps"])]
        if len(steps) != 3:
            raise Failure(f"shrinkfit: {len(steps)} steps in the checkpoint, want 3")
        s1, s2, s3 = steps
        lam = s1["multipliers"][:]
        if (s1["active"][:] == 0).any():
            raise Failure("shrinkfit: an interface row is open after the fit")
        # mean pressure: total normal force over the rows' total weight
        # (the tributary weight of a row is lambda / p)
        p_mean = float(lam.sum() / (lam / s1["contact_pressure"][:]).sum())
        q2 = abs(float(s2["multipliers_t"][:].sum()))  # friction force, step 2
        st2 = s2["state"][:]
        st3 = s3["state"][:]
        # the rows at the tube ends: their slave node is pushed with the
        # end, their master node held, so they slip whatever the push
        zr = f["mesh"]["contact_points"][:, 1]
        inner_rows = (zr > 1e-9) & (zr < L - 1e-9)
    # the push force at full slip: the axial reactions of the inner tube's
    # ends (last step; equilibrium of the inner tube, not the contact's books)
    rz = summary["reactions"]
    push = abs(rz["inner_bottom"]["force"][1] + rz["inner_top"]["force"][1])
    tol = 0.0025 if args.fine else 0.005
    cs = "shrink fit (axisymmetric)"
    return [row(cs, "mean contact pressure, step 1 [Pa]", p, p_mean, tol,
                source="Lame, Timoshenko & Goodier (1970) §28"),
            row(cs, "push force, push 1e-4 m: mu p c L [N/rad]", limit, push, tol,
                source="Coulomb, mu x Lame"),
            row(cs, "share of rows slipping, push 1e-4 m", 1.0,
                float((st3 == 2).mean()), 0.0, source="full slip"),
            row(cs, "friction force / (mu p c L), push 1e-7 m", 1.0, q2 / limit, 0.0,
                kind="below", source="below sliding"),
            row(cs, "share of the rows off the ends sticking, push 1e-7 m", 1.0,
                float((st2[inner_rows] == 1).mean()), 0.0, source="below sliding")]


def pressure_fit(r, p):
    """Least-squares fit of p^2 = p0^2 (1 - r^2/a^2) over the rows with
    p > 0.3 max p (the fit of the 3D Hertz test, docs/verification.md §7c):
    (a, p0)."""
    sel = p > 0.3 * p.max()
    A = np.vstack([np.ones(sel.sum()), r[sel] ** 2]).T
    c, *_ = np.linalg.lstsq(A, p[sel] ** 2, rcond=None)
    return math.sqrt(-c[0] / c[1]), math.sqrt(c[0])


def node_at3(f, xyz, material):
    """The output point at xyz (to 1e-9 of the model's size) of the body of
    `material`, in a 3D checkpoint."""
    m = f["mesh"]
    nodes = m["nodes"][:]
    names = [str(n) for n in m.attrs["material_names"]]
    tets = m["tetrahedra"][:]
    b = int(m["body"][tets[m["material"][:] == names.index(material), 0][0]])
    d = np.linalg.norm(nodes - np.asarray(xyz, float), axis=1)
    idx = np.where((d < 1e-9 * abs(nodes).max()) & (m["body"][:] == b))[0]
    if len(idx) != 1:
        raise Failure(f"no unique node of {material} at {xyz}")
    return int(idx[0])


def case_ssnv104(args, work):
    """Code_Aster SSNV104 (V6.04.104): two hemispheres crushed together, in
    3D (quarter model, slip planes) and axisymmetric on the same section and
    element sizes (docs/verification_3d.md §7d). Rows: the 3D model against
    the manual's Hertz reference, and the 3D model against the axisymmetric
    one (contact radius, pressure at matched radii, total force, a
    displacement)."""
    return ssnv104_rows(args, work, 0.667 if args.fine else 2.0, args.fine)


def ssnv104_rows(args, work, hc, fine):
    """case_ssnv104 at element size hc (mm) near the contact, with the fine
    or the coarse tolerances (verification/ssnv104/refine.py runs it at
    several sizes)."""
    d = os.path.join(VDIR, "ssnv104")
    msh3 = os.path.join(work, "ssnv104_3d.msh")
    msha = os.path.join(work, "ssnv104_axi.msh")
    mesh(args, os.path.join(d, "ssnv104_3d.geo"), {"hc": hc}, msh3, dim=3)
    mesh(args, os.path.join(d, "ssnv104_axi.geo"), {"hc": hc}, msha)
    s3, h3 = solve(args, d, "ssnv104_3d.toml", msh3, work)
    sa, ha = solve(args, d, "ssnv104_axi.toml", msha, work)
    E, nu, R, h = 2.0e4, 0.3, 50.0, 4.0
    Es = E / (2 * (1 - nu**2))            # two equal spheres
    Rs = R / 2                            # 1/R* = 1/R + 1/R
    a_ref = math.sqrt(R * h / 2)          # V6.04.104 §2.1: 10 mm
    p0_ref = E / (math.pi * (1 - nu**2)) * math.sqrt(2 * h / R)  # 2798.3 MPa
    with h5py.File(h3) as f:
        m, st = f["mesh"], last_step(f)
        xyz = m["nodes"][:][m["contact_slave"][:]]
        r3 = np.hypot(xyz[:, 0], xyz[:, 1])
        p3 = st["contact_pressure"][:]
        rim3 = st["displacement"][node_at3(f, (R, 0.0, R), "upper"), 0]
    with h5py.File(ha) as f:
        ra = f["mesh"]["contact_points"][:, 0]
        pa = last_step(f)["contact_pressure"][:]
        rima = last_step(f)["displacement"][node_at(f, (R, R), "upper"), 0]
    a3, p03 = pressure_fit(r3, p3)
    aa, _ = pressure_fit(ra, pa)
    F3 = 4 * abs(s3["reactions"]["upper_top"]["force"][2])          # quarter model
    Fa = 2 * math.pi * abs(sa["reactions"]["upper_top"]["force"][1])  # per radian
    aF = (3 * F3 * Rs / (4 * Es)) ** (1 / 3)  # Hertz for the force carried
    c, src = "ssnv104 3D", "Code_Aster SSNV104, V6.04.104 §2.1"
    tol_a, tol_p = (0.05, 0.10) if fine else (0.08, 0.12)
    rows = [row(c, "a [mm] (fit)", a_ref, a3, tol_a, source=src),
            row(c, "p0 [MPa] (fit)", p0_ref, p03, tol_p, source=src),
            row(c, "Hertz approach for the force carried [mm]", h, aF**2 / Rs, 0.10,
                source="crush imposed, Hertz"),
            row(c, "a [mm] (fit) against Hertz for the force carried", aF, a3,
                0.02 if fine else 0.03, source="Johnson (1985) §4.2")]
    # 3D against axisymmetric: the pressure averaged over rings of the 3D
    # slave nodes against the axisymmetric pressure at the same radii
    o = np.argsort(ra)
    c = "ssnv104 3D vs axisymmetric"
    tol_r = 0.03 if fine else 0.08
    for lo, hi in ((0.0, 3.0), (3.0, 6.0), (6.0, 8.0)):
        k = (r3 >= lo) & (r3 < hi)
        pm = float(np.interp(r3[k], ra[o], pa[o]).mean())
        rows.append(row(c, f"mean p, {lo:g} <= r < {hi:g} mm [MPa]", pm, float(p3[k].mean()),
                        tol_r, source="the axisymmetric model"))
    rows += [row(c, "a [mm] (fit)", aa, a3, 0.02 if fine else 0.05,
                 source="the axisymmetric model"),
             row(c, "total force [N]", Fa, F3, 0.01 if fine else 0.03,
                 source="the axisymmetric model"),
             row(c, "u_r at the upper rim (R, R) [mm]", rima, rim3, 0.02 if fine else 0.05,
                 source="the axisymmetric model")]
    return rows


def case_sneddon3d(args, work):
    """Sneddon's punch in 3D (docs/verification_3d.md §7e): a quarter of
    case_sneddon's model with slip planes, against Sneddon and against the
    axisymmetric model meshed with the same sizes (hc at the punch base,
    growing as hc + 0.1 d in both)."""
    return sneddon3d_rows(args, work, 0.005 if args.fine else 0.01, args.fine)


def sneddon3d_rows(args, work, hc, fine):
    d = os.path.join(VDIR, "sneddon")
    msh3 = os.path.join(work, "sneddon_3d.msh")
    msha = os.path.join(work, "sneddon.msh")
    mesh(args, os.path.join(d, "sneddon_3d.geo"), {"hc": hc, "k": 0.1}, msh3, dim=3)
    mesh(args, os.path.join(d, "sneddon.geo"), {"hc": hc, "k": 0.1}, msha)
    s3, h3 = solve(args, d, "sneddon_3d.toml", msh3, work)
    sa, ha = solve(args, d, "sneddon.toml", msha, work)
    a, E, nu = 0.1, 2.0e11, 0.3
    # the load the mesh carries: the faceted quarter disc is up to 0.6 %
    # smaller than pi a^2 / 4
    F3 = 4 * abs(s3["loads"]["force"][2])
    with h5py.File(h3) as f:
        m, st = f["mesh"], last_step(f)
        xyz = m["nodes"][:][m["contact_slave"][:]]
        r3 = np.hypot(xyz[:, 0], xyz[:, 1])
        p3 = st["contact_pressure"][:]
        d3 = -float(st["displacement"][node_at3(f, (0.0, 0.0, 0.0), "block"), 2])
        fc = 4 * float(st["multipliers"][:].sum())
    with h5py.File(ha) as f:
        ra = f["mesh"]["contact_points"][:, 0]
        pa = last_step(f)["contact_pressure"][:]
        da = -float(last_step(f)["displacement"][node_at(f, (0.0, 0.0), "block"), 1])
    c, src = "sneddon punch 3D", "Sneddon (1946)"
    rows = [row(c, "delta [m]", F3 * (1 - nu**2) / (2 * a * E), d3, 0.05 if fine else 0.08,
                source=src),
            row(c, "p(0) [Pa]", F3 / (2 * math.pi * a**2), float(p3[np.argmin(r3)]),
                0.06 if fine else 0.12, source=src),
            row(c, "contact force, 4 sum(lambda) [N]", F3, fc, 1e-6, source="the load carried")]
    c = "sneddon punch 3D vs axisymmetric"
    o = np.argsort(ra)
    rows.append(row(c, "delta [m]", da, d3, 0.025 if fine else 0.04, source="the axisymmetric model"))
    for lo, hi in ((0.0, 0.25), (0.25, 0.5), (0.5, 0.75)):
        k = (r3 >= lo * a) & (r3 < hi * a)
        pm = float(np.interp(r3[k], ra[o], pa[o]).mean())
        rows.append(row(c, f"mean p, {lo:g} a <= r < {hi:g} a [Pa]", pm, float(p3[k].mean()),
                        0.04 if fine else 0.08, source="the axisymmetric model"))
    return rows


def case_cylinder3d(args, work):
    """A cylinder on a block in 3D under plane strain (docs/verification.md,
    "Cylinder on a block"): Hertz line contact, on the multigrid path."""
    d = os.path.join(VDIR, "cylinder3d")
    hf = 0.001 if args.fine else 0.0015
    msh = os.path.join(work, "cylinder3d.msh")
    mesh(args, os.path.join(d, "cylinder3d.geo"), {"hf": hf}, msh, dim=3)
    summary, h5 = solve(args, d, "cylinder3d.toml", msh, work)
    E, nu, R, pn = 2.0e11, 0.3, 0.05, 1.726e9
    Es = E / (2 * (1 - nu**2))
    P = pn * 2 * R  # load per unit length on the whole cylinder
    b_ref = math.sqrt(4 * P * R / (math.pi * Es))
    p0_ref = 2 * P / (math.pi * b_ref)
    with h5py.File(h5) as f:
        m, st = f["mesh"], last_step(f)
        x = np.abs(m["nodes"][:][m["contact_slave"][:]][:, 0])
        p = st["contact_pressure"][:]
        act = st["active"][:] > 0
    # The fit of hertz_fit: p^2 linear in x^2 (p = p0 sqrt(1 - x^2/b^2)),
    # over every active row along the cylinder.
    b, p0 = hertz_fit_rows(x, p, act)
    tol = 0.01 if args.fine else 0.02
    force = summary["contact"]["cyl_surf/block_top"]["force"][2]
    src = "Johnson (1985) §4.3"
    return [row("cylinder on a block (3D, iterative path)", "b [m] (fit)", b_ref, b, tol, source=src),
            row("cylinder on a block (3D, iterative path)", "p0 [Pa] (fit)", p0_ref, p0, tol, source=src),
            row("cylinder on a block (3D, iterative path)", "contact force [N]", pn * R * 0.01,
                abs(force), 1e-6, source="load pn R L")]


def case_patch3d(args, work):
    """The 3D contact patch test through the binary (docs/verification_3d.md
    §7f): stacked cubes with non-matching faces under a uniform pressure;
    mortar rows exact to round-off, node-to-surface rows not (a guard)."""
    d = os.path.join(VDIR, "patch3d")
    params = {"h1": 0.1, "h2": 0.073} if args.fine else {"h1": 0.3, "h2": 0.22}
    msh = os.path.join(work, "patch3d.msh")
    mesh(args, os.path.join(d, "patch3d.geo"), params, msh, dim=3)
    p = 1.0e7
    exact = np.array([0.0, 0.0, -p, 0.0, 0.0, 0.0])
    rows = []
    for toml, tol_p, tol_s in (("patch3d_mortar.toml", 1e-10, 1e-10),
                               ("patch3d_nts.toml", 0.15, 0.50)):
        summary, h5 = solve(args, d, toml, msh, work)
        with h5py.File(h5) as f:
            s = last_step(f)
            pr = s["contact_pressure"][:]
            act = s["active"][:]
            sig = s["stress"][:]
        label = "patch 3D " + toml.split("_")[1].split(".")[0]
        if act.min() == 0:
            raise Failure(f"{label}: an interface row is open")
        rows.append(row(label, f"max abs(p_row/p - 1) ({len(pr)} rows)", 0.0,
                        float(np.abs(pr / p - 1).max()), tol_p, kind="abs",
                        source="uniform pressure p"))
        rows.append(row(label, "max abs(sigma - sigma_exact)/p", 0.0,
                        float(np.abs(sig - exact).max() / p), tol_s, kind="abs",
                        source="uniform stress sigma_zz = -p"))
    return rows


CASES = {"nafems1": case_nafems1, "patch": case_patch, "nonmatching": case_nonmatching,
         "hertz": case_hertz,
         "punch": case_punch, "cattaneo": case_cattaneo, "hertz_sphere": case_hertz_sphere,
         "sneddon": case_sneddon, "nafems2": case_nafems2, "shrinkfit": case_shrinkfit,
         "ssnv104": case_ssnv104, "sneddon3d": case_sneddon3d, "patch3d": case_patch3d,
         "cylinder3d": case_cylinder3d}
# the 3D friction cases (issue 46): scripts/verify3d_friction.py
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import verify3d_friction  # noqa: E402
CASES.update(verify3d_friction.cases(sys.modules[__name__]))


EXIT_USAGE = 2
EXIT_FAILED = 3


class OneLineParser(argparse.ArgumentParser):
    """argparse whose usage errors are one line on stderr and exit 2."""

    def error(self, message):
        print(f"verify: {message} (scripts/verify --help)", file=sys.stderr)
        sys.exit(EXIT_USAGE)


def main():
    ap = OneLineParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--fine", action="store_true")
    ap.add_argument("--only", default="")
    ap.add_argument("--work", default="")
    ap.add_argument("--plots", action="store_true")
    ap.add_argument("--exe", default=os.path.join(ROOT, "target", "release", "signorini"))
    ap.add_argument("--gmsh", default="gmsh")
    args = ap.parse_args()
    # Relative paths are the caller's (scripts/verify runs this from the root).
    caller = os.environ.get("VERIFY_CALLER_DIR", os.getcwd())
    if args.work:
        args.work = os.path.abspath(os.path.join(caller, args.work))
    args.exe = os.path.abspath(os.path.join(caller, args.exe))
    names = [n for n in args.only.split(",") if n] or list(CASES)
    for n in names:
        if n not in CASES:
            print(f"verify: unknown case '{n}' (cases: {', '.join(CASES)})", file=sys.stderr)
            return EXIT_USAGE
    if args.work and os.path.exists(args.work) and not os.path.isdir(args.work):
        print(f"verify: --work {args.work}: exists and is not a directory", file=sys.stderr)
        return EXIT_USAGE
    global h5py, np
    try:
        import h5py
        import numpy as np
    except ImportError as e:
        print(f"verify: {e} (scripts/verify installs h5py and numpy into .venv)", file=sys.stderr)
        return EXIT_FAILED
    if not os.path.exists(args.exe):
        print(f"verify: {args.exe} not found (cargo build --release)", file=sys.stderr)
        return EXIT_FAILED
    if shutil.which(args.gmsh) is None:
        print(f"verify: {args.gmsh} not found", file=sys.stderr)
        return EXIT_FAILED
    try:
        work = args.work or tempfile.mkdtemp(prefix="signorini_verify.")
        os.makedirs(work, exist_ok=True)
    except OSError as e:
        print(f"verify: --work {args.work}: cannot create the directory: {e.strerror}",
              file=sys.stderr)
        return EXIT_USAGE
    level = "fine" if args.fine else "coarse"
    print(f"verify: {level} meshes, work directory {work}", file=sys.stderr)
    print("| case | quantity | reference | tool | error | tolerance | pass |")
    print("|---|---|---|---|---|---|---|")
    failed = 0
    for n in names:
        sub = os.path.join(work, n)
        os.makedirs(sub, exist_ok=True)
        try:
            rows = CASES[n](args, sub)
        except Failure as e:
            print(f"verify: {n}: {e}", file=sys.stderr)
            return EXIT_FAILED
        for r in rows:
            ok = r["error"] <= r["tol"]
            failed += not ok
            ref = "0" if r["kind"] == "abs" else f"{r['reference']:.6g}"
            err = f"{r['error']:.2e}" if r["kind"] == "abs" else f"{100 * r['error']:.2f} %"
            tol = f"{r['tol']:.2g}" if r["kind"] == "abs" else f"{100 * r['tol']:.2g} %"
            if r["kind"] in ("below", "above"):
                ref = ("< " if r["kind"] == "below" else "> ") + f"{r['reference']:.6g}"
                err, tol = "-", "bound"
            print(f"| {r['case']} | {r['quantity']} | {ref} | {r['tool']:.6g} | {err} | {tol} | "
                  f"{'yes' if ok else 'NO'} |", flush=True)
    if not args.work and not args.plots:
        shutil.rmtree(work, ignore_errors=True)
    if failed:
        print(f"verify: {failed} quantity(ies) outside tolerance", file=sys.stderr)
        return 1
    print("verify: all within tolerance", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
