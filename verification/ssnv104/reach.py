#!/usr/bin/env python3
"""A failing check of the 3D mortar rows' reach (docs/verification_3d.md
§7d): SSNV104's 3D model at hc = 1 mm WITHOUT `max_gap`. methods.md §11.6
widens each slave triangle's box by its own longest edge when there is no
max_gap, so slave triangles whose initial gap to the master exceeds their
size get no mortar row; SSNV104's contact zone reaches r ≈ 10.3 mm, where
the initial gap is ≈ 2.1 mm, so on 1 mm triangles the rows stop short and
the caps overlap. Exits 1 while that is so, 0 once the rows reach past
the contact zone (r > 11 mm) and the caps do not overlap by more than the
small-displacement contact's own 0.15 mm (measured with max_gap = 5:
0.11 mm), 3 if a tool fails.

    .venv/bin/python verification/ssnv104/reach.py [--hc 1]
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
    ap.add_argument("--hc", type=float, default=1.0)
    a = ap.parse_args()
    import h5py
    import numpy as np
    import matplotlib.tri as mtri
    verify.h5py, verify.np = h5py, np
    args = argparse.Namespace(exe=os.path.join(verify.ROOT, "target", "release", "signorini"),
                              gmsh="gmsh", plots=False, fine=True)
    work = tempfile.mkdtemp(prefix="ssnv104_reach.")
    msh = os.path.join(work, "ssnv104_3d.msh")
    try:
        verify.mesh(args, os.path.join(HERE, "ssnv104_3d.geo"), {"hc": a.hc}, msh, dim=3)
        text = open(os.path.join(HERE, "ssnv104_3d.toml")).read()
        if "max_gap = 5.0\n" not in text:
            raise verify.Failure("ssnv104_3d.toml has no 'max_gap = 5.0' line to remove")
        with open(os.path.join(work, "nogap.toml"), "w") as f:
            f.write(text.replace("max_gap = 5.0\n", ""))
        summary, h5 = verify.solve(args, work, "nogap.toml", msh, work)
    except verify.Failure as e:
        print(f"reach: {e}", file=sys.stderr)
        return 3
    R = 50.0
    with h5py.File(h5) as f:
        m, st = f["mesh"], verify.last_step(f)
        X = m["nodes"][:]
        Y = X + st["displacement"][:]
        xyz = X[m["contact_slave"][:]]
        r_rows = np.hypot(xyz[:, 0], xyz[:, 1])
        p = st["contact_pressure"][:]
    try:
        a_txt = f"{verify.pressure_fit(r_rows, p)[0]:.2f} mm"
    except ValueError:
        a_txt = "no Hertz fit (p^2 is not falling with r^2)"
    # The overlap: the deformed upper cap against the deformed lower cap
    # interpolated at the same (x, y), near the contact (r < 14 mm).
    r = np.hypot(X[:, 0], X[:, 1])
    up = (np.abs(np.linalg.norm(X - [0, 0, R], axis=1) - R) < 1e-6) & (r < 14)
    lo = (np.abs(np.linalg.norm(X - [0, 0, -R], axis=1) - R) < 1e-6) & (r < 14)
    tri = mtri.Triangulation(Y[lo][:, 0], Y[lo][:, 1])  # Delaunay in (x, y)
    zl = np.ma.filled(mtri.LinearTriInterpolator(tri, Y[lo][:, 2])(Y[up][:, 0], Y[up][:, 1]),
                      np.nan)
    gap = Y[up][:, 2] - zl
    overlap = float(-np.nanmin(gap))
    reach = float(r_rows.max())
    print(f"hc = {a.hc:g} mm without max_gap: {len(p)} rows out to r = {reach:.2f} mm, "
          f"{int((p > 0).sum())} active; a (fit): {a_txt}; max pressure {p.max():.4g} MPa; "
          f"the caps overlap by up to {overlap:.3f} mm")
    # the contact radius is 10.3 mm (docs/verification_3d.md §7d); rows must reach past it
    ok = reach > 11.0 and overlap <= 0.15
    print("reach: " + ("OK" if ok else "FAIL: the mortar rows stop short of the contact zone"))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
