#!/usr/bin/env python3
"""Sneddon's punch in 3D under refinement (docs/verification_3d.md §7e):
scripts/verify's case sneddon3d (3D quarter model and axisymmetric model at
the same sizes, hc at the punch base growing as hc + 0.1 d) at several hc,
one Markdown table ("3D / axisymmetric (difference)" for the rows against
the axisymmetric model).

    .venv/bin/python verification/sneddon/refine3d.py [--hc 0.01,0.005,0.00333]
"""
import argparse
import os
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "scripts"))
import verify  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--hc", default="0.01,0.005,0.00333")
    ap.add_argument("--work", default="")
    a = ap.parse_args()
    import h5py
    import numpy as np
    verify.h5py, verify.np = h5py, np
    args = argparse.Namespace(exe=os.path.join(verify.ROOT, "target", "release", "signorini"),
                              gmsh="gmsh", plots=False, fine=True)
    work = a.work or tempfile.mkdtemp(prefix="sneddon3d_refine.")
    hcs = [float(v) for v in a.hc.split(",")]
    table, cols = {}, []
    for hc in hcs:
        sub = os.path.join(work, f"hc{hc:g}")
        os.makedirs(sub, exist_ok=True)
        for r in verify.sneddon3d_rows(args, sub, hc, fine=True):
            c = f"{r['case'].replace('sneddon punch ', '')}: {r['quantity']}"
            if c not in table:
                cols.append(c)
                table[c] = []
            err = f"{100 * (r['tool'] / r['reference'] - 1):+.2f} %"
            if r["source"] == "the axisymmetric model":
                table[c].append(f"{r['tool']:.5g} / {r['reference']:.5g} ({err})")
            else:
                table[c].append(f"{r['tool']:.5g} ({err})")
    print("| quantity | " + " | ".join(f"hc = {hc:g} (a/{0.1 / hc:.0f})" for hc in hcs) + " |")
    print("|---|" + "---|" * len(hcs))
    for c in cols:
        print(f"| {c} | " + " | ".join(table[c]) + " |")
    print(f"work directory {work}", file=sys.stderr)


if __name__ == "__main__":
    main()
