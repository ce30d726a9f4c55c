#!/usr/bin/env python3
"""Pictures of SSNV104 (docs/verification_3d.md §7d), off-screen with pyvista:

    .venv/bin/python verification/ssnv104/render.py [OUTDIR]   (default docs/)

ssnv104_3d.png: the 3D and the axisymmetric model at hc = 0.667 mm, von
Mises on the section y = 0 and on the r-z section, and the contact pressure
on the 3D slave cap. ssnv104_reach.png: the 3D model at hc = 1 mm without
and with max_gap (the section y = 0 deformed at scale 1: without it the
mortar rows stop short of the contact zone's edge and the caps overlap).
"""
import argparse
import os
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "scripts"))
import verify  # noqa: E402


def save(plotter, path):
    """A screenshot as a 256-colour PNG (a fraction of the size)."""
    from PIL import Image
    plotter.screenshot(path)
    Image.open(path).convert("RGB").quantize(256).save(path, optimize=True)


def run(args, work, name, toml_text, msh):
    path = os.path.join(work, name + ".toml")
    with open(path, "w") as f:
        f.write(toml_text)
    verify.solve(args, work, name + ".toml", msh, work)
    return os.path.join(work, name)


def main():
    import pyvista as pv
    pv.OFF_SCREEN = True
    out = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(verify.ROOT, "docs"))
    args = argparse.Namespace(exe=os.path.join(verify.ROOT, "target", "release", "signorini"),
                              gmsh="gmsh", plots=False, fine=True)
    import h5py
    import numpy as np
    verify.h5py, verify.np = h5py, np
    work = tempfile.mkdtemp(prefix="ssnv104_render.")
    t3 = open(os.path.join(HERE, "ssnv104_3d.toml")).read()
    ta = open(os.path.join(HERE, "ssnv104_axi.toml")).read()
    meshes = {}
    for hc in (0.667, 1.0):
        meshes[hc] = os.path.join(work, f"s3_{hc:g}.msh")
        verify.mesh(args, os.path.join(HERE, "ssnv104_3d.geo"), {"hc": hc}, meshes[hc], dim=3)
    ma = os.path.join(work, "sa.msh")
    verify.mesh(args, os.path.join(HERE, "ssnv104_axi.geo"), {"hc": 0.667}, ma)
    b3 = run(args, work, "fine3d", t3, meshes[0.667])
    ba = run(args, work, "fineaxi", ta, ma)
    if "max_gap = 5.0\n" not in t3:
        sys.exit("render.py: ssnv104_3d.toml has no 'max_gap = 5.0' line")
    bn = run(args, work, "nogap", t3.replace("max_gap = 5.0\n", ""), meshes[1.0])
    bg = run(args, work, "gap", t3, meshes[1.0])

    clim = [0, 2000]
    p = pv.Plotter(shape=(1, 3), window_size=(1800, 650))
    g = pv.read(b3 + ".vtu")
    s = g.slice(normal="y", origin=(0, 1e-3, 0)).clip_box(bounds=(0, 20, -1, 1, -15, 15), invert=False)
    p.subplot(0, 0)
    p.add_mesh(s, scalars="von_mises", show_edges=True, edge_color="gray", cmap="viridis", clim=clim,
               scalar_bar_args={"title": "von Mises [MPa]"})
    p.add_text("3D, hc = 0.667 mm: section y = 0", font_size=9)
    p.view_xz()
    a = pv.read(ba + ".vtu").clip_box(bounds=(0, 20, -15, 15, -1, 1), invert=False)
    p.subplot(0, 1)
    p.add_mesh(a, scalars="von_mises", show_edges=True, edge_color="gray", cmap="viridis", clim=clim,
               show_scalar_bar=False)
    p.add_text("axisymmetric, hc = 0.667 mm: r-z section", font_size=9)
    p.view_xy()
    c = pv.read(b3 + "_contact.vtu")
    p.subplot(0, 2)
    p.add_mesh(c, scalars="contact_pressure", show_edges=True, cmap="plasma",
               scalar_bar_args={"title": "contact pressure [MPa]"})
    p.add_text("3D: pressure on the upper cap (slave), view along z", font_size=9)
    p.view_xy()
    save(p, os.path.join(out, "ssnv104_3d.png"))

    p = pv.Plotter(shape=(1, 2), window_size=(1600, 700))
    for k, (b, t) in enumerate(((bn, "hc = 1 mm, no max_gap"), (bg, "hc = 1 mm, max_gap = 5 mm"))):
        s = pv.read(b + ".vtu").slice(normal="y", origin=(0, 1e-3, 0))
        s = s.clip_box(bounds=(4, 14, -1, 1, -1.5, 1.5), invert=False).warp_by_vector("displacement", factor=1.0)
        p.subplot(0, k)
        p.add_mesh(s, scalars="body", show_edges=True, edge_color="black", cmap=["tan", "lightblue"],
                   show_scalar_bar=False, opacity=0.6)
        p.add_text(t + ": section y = 0, 4 < x < 14 mm, deformed (scale 1)", font_size=9)
        p.view_xz()
    save(p, os.path.join(out, "ssnv104_reach.png"))
    print(f"wrote {out}/ssnv104_3d.png, {out}/ssnv104_reach.png (work {work})")


if __name__ == "__main__":
    main()
