#!/usr/bin/env python3
"""Same bits before and after a refactoring: every shipped example, every test
model and the verification manual's models, solved by two binaries, must give
bit-identical answers.

Usage:
    scripts/same_bits.py --base OLD_BINARY [--new target/release/signorini]
                         [--work DIR] [--only SUBSTRING] [--gmsh gmsh]

For every problem file of meshes/, tests/data/, tests/hard/ and
verification/ (the verification models are meshed first with their .geo's
default parameters), both binaries run `solve` with the same flags. Compared:
- every dataset of the HDF5 checkpoint, byte for byte (dtype, shape, values),
  and every attribute except the timings (`time*`) and `program`;
- the JSON summary, every key except timings (`time*`, `seconds`, `*_s`);
- the exit codes;
- the VTU files byte for byte.
A model whose base run fails is reported and must fail the same way.

Prints one line per model; exit 0 when every model matches, 1 otherwise,
2 on a usage error. Needs h5py and numpy (the project's .venv).
"""

import argparse
import glob
import json
import os
import re
import shutil
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def problems(only):
    pats = [
        "meshes/*.toml",
        "meshes/3d/*.toml",
        "tests/data/*/*.toml",
        "tests/data/solid/xcheck/*.toml",
        "tests/hard/*.toml",
        "verification/*/*.toml",
    ]
    out = []
    for p in pats:
        out += sorted(glob.glob(os.path.join(ROOT, p)))
    if only:
        out = [p for p in out if any(o in p for o in only.split(","))]
    return out


def prepared(path, work, gmsh):
    """The problem file to run: verification models get their mesh made."""
    rel = os.path.relpath(path, ROOT)
    if not rel.startswith("verification"):
        return path
    text = open(path).read()
    m = re.search(r'^file\s*=\s*"([^"]+)"', text, re.M)
    if not m:
        return path
    msh = m.group(1)
    d = os.path.dirname(path)
    if os.path.exists(os.path.join(d, msh)):
        return path
    geo = os.path.join(d, os.path.splitext(os.path.basename(msh))[0] + ".geo")
    if not os.path.exists(geo):
        geos = glob.glob(os.path.join(d, "*.geo"))
        if len(geos) != 1:
            return None
        geo = geos[0]
    dst = os.path.join(work, "models", rel.replace("/", "_")[:-5])
    os.makedirs(dst, exist_ok=True)
    out_msh = os.path.join(dst, os.path.basename(msh))
    if not os.path.exists(out_msh):
        # A .geo with a Physical Volume is a 3D model (as `signorini mesh`).
        src = re.sub(r"//[^\n]*", "", open(geo).read())
        dim = "-3" if "Physical Volume" in src else "-2"
        r = subprocess.run([gmsh, dim, "-format", "msh41", "-v", "1", geo, "-o", out_msh],
                           capture_output=True, text=True)
        if r.returncode != 0:
            return None
    toml = os.path.join(dst, os.path.basename(path))
    open(toml, "w").write(text.replace(m.group(0), f'file = "{out_msh}"'))
    return toml


def run(exe, toml, out):
    shutil.rmtree(out, ignore_errors=True)
    r = subprocess.run([exe, "solve", toml, "-o", out, "-qq"], capture_output=True, text=True)
    return r.returncode, r.stderr


TIME = re.compile(r"(^time|seconds|_s$|^program$)")


def strip(obj):
    if isinstance(obj, dict):
        return {k: strip(v) for k, v in obj.items() if not TIME.search(k)}
    if isinstance(obj, list):
        return [strip(v) for v in obj]
    return obj


def h5diff(a, b):
    import h5py
    import numpy as np
    diffs = []
    fa, fb = h5py.File(a, "r"), h5py.File(b, "r")

    def attrs(x, y, name):
        ka = {k for k in x.attrs if not TIME.search(k)}
        kb = {k for k in y.attrs if not TIME.search(k)}
        if ka != kb:
            diffs.append(f"{name}: attributes {sorted(ka ^ kb)}")
        for k in ka & kb:
            va, vb = np.asarray(x.attrs[k]), np.asarray(y.attrs[k])
            if va.dtype != vb.dtype or va.shape != vb.shape or va.tobytes() != vb.tobytes():
                if not (va.dtype == object and list(va.ravel()) == list(vb.ravel())):
                    diffs.append(f"{name}@{k}")

    names_a, names_b = [], []
    fa.visit(names_a.append)
    fb.visit(names_b.append)
    if set(names_a) != set(names_b):
        diffs.append(f"objects {sorted(set(names_a) ^ set(names_b))}")
    attrs(fa, fb, "/")
    for n in sorted(set(names_a) & set(names_b)):
        x, y = fa[n], fb[n]
        attrs(x, y, n)
        if isinstance(x, h5py.Dataset):
            va, vb = x[()], y[()]
            va, vb = np.asarray(va), np.asarray(vb)
            if va.dtype != vb.dtype or va.shape != vb.shape:
                diffs.append(f"{n}: {va.dtype}{va.shape} vs {vb.dtype}{vb.shape}")
            elif va.dtype == object:
                if list(va.ravel()) != list(vb.ravel()):
                    diffs.append(n)
            elif va.tobytes() != vb.tobytes():
                d = np.max(np.abs(va.astype(float) - vb.astype(float))) if va.size else 0
                diffs.append(f"{n} (max |diff| {d:.3e})")
    return diffs


def compare(a, b):
    diffs = []
    fa = sorted(os.listdir(a)) if os.path.isdir(a) else []
    fb = sorted(os.listdir(b)) if os.path.isdir(b) else []
    if fa != fb:
        diffs.append(f"files {sorted(set(fa) ^ set(fb))}")
    for f in sorted(set(fa) & set(fb)):
        pa, pb = os.path.join(a, f), os.path.join(b, f)
        if f.endswith(".h5"):
            diffs += [f"{f}: {d}" for d in h5diff(pa, pb)]
        elif f.endswith(".json"):
            ja, jb = strip(json.load(open(pa))), strip(json.load(open(pb)))
            if ja != jb:
                keys = [k for k in set(ja) | set(jb) if ja.get(k) != jb.get(k)]
                diffs.append(f"{f}: keys {sorted(keys)}")
        elif os.path.isfile(pa):
            if open(pa, "rb").read() != open(pb, "rb").read():
                diffs.append(f"{f}: bytes")
    return diffs


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--base", required=True)
    ap.add_argument("--new", default=os.path.join(ROOT, "target/release/signorini"))
    ap.add_argument("--work", default="/tmp/same_bits")
    ap.add_argument("--only")
    ap.add_argument("--gmsh", default="gmsh")
    args = ap.parse_args()
    for exe in (args.base, args.new):
        if not os.access(exe, os.X_OK):
            print(f"same_bits: {exe}: not an executable", file=sys.stderr)
            return 2
    os.makedirs(args.work, exist_ok=True)
    bad = 0
    n = 0
    for p in problems(args.only):
        rel = os.path.relpath(p, ROOT)
        toml = prepared(p, args.work, args.gmsh)
        if toml is None:
            print(f"SKIP  {rel}: no mesh")
            continue
        tag = rel.replace("/", "_")[:-5]
        oa, ob = os.path.join(args.work, "base", tag), os.path.join(args.work, "new", tag)
        ca, ea = run(args.base, toml, oa)
        cb, eb = run(args.new, toml, ob)
        n += 1
        diffs = []
        if ca != cb:
            diffs.append(f"exit {ca} vs {cb}")
        diffs += compare(oa, ob)
        if diffs:
            bad += 1
            print(f"DIFF  {rel}: " + "; ".join(diffs[:6]))
        else:
            print(f"SAME  {rel} (exit {ca})")
        sys.stdout.flush()
    print(f"{n - bad} of {n} models give the same bits")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
