"""The Cattaneo-Mindlin footprint in 3D (docs/verification_3d.md §7g): the
contact VTU of the shear step drawn from above, three panels: the contact
pressure, the friction state (0 open, 1 stick, 2 slip) with the circles
r = a and r = c of the reference, and |q| the tangential traction.

    .venv/bin/python verification/cattaneo3d/render.py WORK/cattaneo3d OUT.png

    .venv/bin/python verification/cattaneo3d/render.py WORK/cattaneo3d OUT.png cattaneo3d_mu0

WORK/cattaneo3d: the work directory of `scripts/verify --only cattaneo3d
--work WORK` (its cattaneo3d_0002_contact.vtu and cattaneo3d.json).
"""
import json
import math
import os
import sys

import numpy as np
import pyvista as pv


def main():
    work, out = sys.argv[1], sys.argv[2]
    name = sys.argv[3] if len(sys.argv) > 3 else "cattaneo3d"  # cattaneo3d_mu0: mu = 0
    grid = pv.read(os.path.join(work, name + "_0002_contact.vtu"))
    s = json.load(open(os.path.join(work, name + ".json")))
    fx, fy, fz = s["reactions"]["ball_top"]["force"]
    P, Q, mu, R = -fz, math.hypot(fx, fy), 0.5, 1.0
    Es = 2.0e11 / (2 * (1 - 0.3**2))
    a = (3 * P * R / (4 * Es)) ** (1 / 3)
    c = a * (1 - Q / (mu * P)) ** (1 / 3)
    names = grid.point_data.keys()
    st = next((k for k in ("friction_state", "state") if k in names), None)
    panels = [("contact_pressure", "contact pressure [Pa]", None)]
    if st is not None:
        panels.append((st, "friction state (0 open, 1 stick, 2 slip)", (0, 2)))
    if "tangential_traction" in names:
        q = np.asarray(grid.point_data["tangential_traction"])
        grid.point_data["|q|"] = np.linalg.norm(q.reshape(len(q), -1), axis=1)
        panels.append(("|q|", "|q| tangential traction [Pa]", None))
    if os.environ.get("DISPLAY") is None:
        try:
            pv.start_xvfb()
        except Exception:
            pass
    pl = pv.Plotter(shape=(1, len(panels)), off_screen=True, window_size=(600 * len(panels), 620))
    phi = np.linspace(0, 2 * np.pi, 200)
    for i, (name, title, clim) in enumerate(panels):
        pl.subplot(0, i)
        pl.add_mesh(grid.copy(), scalars=name, show_edges=True, edge_color="grey",
                    clim=clim, cmap="viridis", n_colors=3 if clim else 256,
                    scalar_bar_args={"title": title, "vertical": False})
        for rr, col in ((a, "red"), (c, "white")):
            pts = np.c_[rr * np.cos(phi), rr * np.sin(phi), np.full_like(phi, 1e-4)]
            pl.add_mesh(pv.lines_from_points(pts, close=True), color=col, line_width=3)
        pl.view_xy()
        pl.camera.parallel_projection = True
        pl.camera.parallel_scale = 1.3 * a
        pl.camera.focal_point = (0, 0, 0)
        pl.camera.position = (0, 0, 1)
        pl.add_text(title, font_size=10)
    pl.screenshot(out)
    print(f"{out}: a = {a:.5g} m (red), c = {c:.5g} m (white), Q/muP = {Q / (mu * P):.4f}")


if __name__ == "__main__":
    main()
