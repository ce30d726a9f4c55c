"""The contact pressure footprint of the 3D Hertz test (tests/solid_contact.rs,
docs/verification.md): reads the (x, y, p) lines HERTZ3D_DUMP wrote and draws
the quarter footprint (mirrored to the full disc) and p(r) against Hertz's
p0 sqrt(1 - r^2/a^2) (K. L. Johnson, Contact Mechanics, 1985, eq. 4.22-4.23).

usage: .venv/bin/python scripts/hertz3d_footprint.py DUMP OUT.png [ROWS]
(ROWS: the label of the rows, "NTS rows" by default)
"""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import matplotlib.tri as mtri
import numpy as np

E, NU, R, A_NOMINAL = 2.0e11, 0.3, 1.0, 0.1


def main(dump, out, rows="NTS rows"):
    d = np.loadtxt(dump)
    x, y, p = d[:, 0], d[:, 1], d[:, 2]
    keep = np.hypot(x, y) < 2.0 * A_NOMINAL
    x, y, p = x[keep], y[keep], p[keep]
    # Mirror the quarter to the full footprint (the symmetry planes' nodes
    # appear twice; harmless for a picture).
    X = np.concatenate([x, -x, -x, x])
    Y = np.concatenate([y, y, -y, -y])
    P = np.concatenate([p, p, p, p])
    estar = 1.0 / (2.0 * (1.0 - NU**2) / E)
    load = 4.0 * estar * A_NOMINAL**3 / (3.0 * R)
    a = A_NOMINAL
    p0 = 3.0 * load / (2.0 * np.pi * a * a)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 5.0))
    tri = mtri.Triangulation(X, Y)
    cs = ax1.tricontourf(tri, P / 1e9, levels=20, cmap="viridis")
    ax1.add_patch(plt.Circle((0, 0), a, fill=False, color="w", ls="--", lw=1))
    ax1.set_aspect("equal")
    ax1.set_xlabel("x [m]")
    ax1.set_ylabel("y [m]")
    ax1.set_title("contact pressure [GPa] (quarter model mirrored)\ndashed: Hertz radius a")
    fig.colorbar(cs, ax=ax1)
    r = np.hypot(x, y)
    rr = np.linspace(0, a, 200)
    ax2.plot(rr, p0 * np.sqrt(1 - (rr / a) ** 2) / 1e9, "k-", label="Hertz (nominal load)")
    ax2.plot(r, p / 1e9, "o", ms=3, label="signorini, " + rows)
    ax2.set_xlabel("r [m]")
    ax2.set_ylabel("p [GPa]")
    ax2.set_title("pressure against radius")
    ax2.legend()
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main(*sys.argv[1:4])
