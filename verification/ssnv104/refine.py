#!/usr/bin/env python3
"""SSNV104 under refinement (docs/verification_3d.md §7d): scripts/verify's
case ssnv104 (3D quarter model and axisymmetric section at the same element
size hc near the contact) at several sizes, one Markdown table of the tool's
values (3D against the axisymmetric model: "3D / axisymmetric (3D − axi)");
then the axisymmetric model alone on finer meshes (its limit).

    .venv/bin/python verification/ssnv104/refine.py [--hc 2,1,0.667,0.5] [--axi 0.25,0.1]
"""
import argparse
import json
import math
import os
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "scripts"))
import verify  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--hc", default="2,1,0.667,0.5")
    ap.add_argument("--axi", default="0.25,0.1")
    ap.add_argument("--work", default="")
    a = ap.parse_args()
    import h5py
    import numpy as np
    verify.h5py, verify.np = h5py, np
    args = argparse.Namespace(exe=os.path.join(verify.ROOT, "target", "release", "signorini"),
                              gmsh="gmsh", plots=False, fine=False)
    work = a.work or tempfile.mkdtemp(prefix="ssnv104_refine.")
    cols = None
    for hc in [float(v) for v in a.hc.split(",")]:
        sub = os.path.join(work, f"hc{hc:g}")
        os.makedirs(sub, exist_ok=True)
        rows = verify.ssnv104_rows(args, sub, hc, fine=True)
        if cols is None:
            cols = [f"{r['case'].replace('ssnv104 ', '')}: {r['quantity']}" for r in rows]
            print("| quantity | reference | " + " | ".join(f"hc = {float(v):g}" for v in a.hc.split(",")) + " |")
            print("|---|---|" + "---|" * len(a.hc.split(",")))
            table = {c: [f"{r['reference']:.6g}" if r["source"] != "the axisymmetric model"
                         else "axisymmetric, same hc"] for c, r in zip(cols, rows)}
        for c, r in zip(cols, rows):
            err = f"{100 * (r['tool'] / r['reference'] - 1):+.2f} %"
            if r["source"] == "the axisymmetric model":
                table[c].append(f"{r['tool']:.6g} / {r['reference']:.6g} ({err})")
            else:
                table[c].append(f"{r['tool']:.6g} ({err})")
    for c in cols:
        print(f"| {c} | " + " | ".join(table[c]) + " |")
    # the axisymmetric model alone, finer: what the 3D values tend to
    d = os.path.join(verify.VDIR, "ssnv104")
    print("\n| axisymmetric hc | a [mm] (fit) | p0 [MPa] (fit) | total force [N] | u_r rim [mm] |")
    print("|---|---|---|---|---|")
    for hc in [float(v) for v in a.axi.split(",")]:
        sub = os.path.join(work, f"axi{hc:g}")
        os.makedirs(sub, exist_ok=True)
        msh = os.path.join(sub, "ssnv104_axi.msh")
        verify.mesh(args, os.path.join(d, "ssnv104_axi.geo"), {"hc": hc}, msh)
        s, h5 = verify.solve(args, d, "ssnv104_axi.toml", msh, sub)
        with h5py.File(h5) as f:
            ra = f["mesh"]["contact_points"][:, 0]
            pa = verify.last_step(f)["contact_pressure"][:]
            rim = verify.last_step(f)["displacement"][verify.node_at(f, (50.0, 50.0), "upper"), 0]
        aa, p0 = verify.pressure_fit(ra, pa)
        F = 2 * math.pi * abs(s["reactions"]["upper_top"]["force"][1])
        print(f"| {hc:g} | {aa:.6g} | {p0:.6g} | {F:.6g} | {rim:.6g} |")
    print(f"work directory {work}", file=sys.stderr)


if __name__ == "__main__":
    main()
