#!/usr/bin/env python3
"""The 3D friction benchmark (issue 46, "Fast"): frictional ÷ frictionless whole-process
time on two 3D families at three sizes, and ssn's Newton steps per load step.

Usage:

    python3 scripts/bench_friction3d.py [--families cattaneo,stack] [--sizes s,m,l]
        [--repeats 3] [--long 60] [--work bench/friction3d] [--out bench/friction3d.md]
        [--binary target/release/signorini]

Families (meshed with Gmsh, `-3 -order 1 -format msh22`, cached in --work):
  * cattaneo: the Cattaneo–Mindlin sphere on a block of verification/cattaneo3d (its .geo
    and .toml: pressed by a prescribed displacement, then sheared, mu = 0.5, mortar-free
    node-to-surface rows), at hc = 0.03, 0.015 (the verification's coarse mesh) and 0.0075
    (its fine one), and 0.005 (size xl, 163 k DOFs: past ITERATIVE_3D_FROM, where ssn_path
    = "auto" solves on AMG-PCG);
  * stack: the quarter model of two cubes of tests/data/solid_contact/stack.geo (the upper
    one held by the contact alone, 1e8 Pa on its top, aluminium on steel, so the Poisson
    expansions differ and the interface has stick and slip zones), Coulomb mu = 0.3, at
    h = 0.11, 0.07, 0.05 (and 0.035, size xl, 119 k DOFs; 0.025, size xxl, 301 k DOFs).
A size a family does not define is skipped with a message.
Each model runs `signorini solve -q` twice, under /usr/bin/time -f %M: with its friction
and with the friction key removed (the same mesh and loads). Wall times are medians of
--repeats (runs longer than --long once). The ratio is the two medians' ratio, measured in
the same run. Writes a markdown table to --out and the raw rows as JSON next to it; exits 1
if a run is not certified.
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_solid import ROOT, TOML, fmt, log, repeated, timed  # noqa: E402

SIZES = {
    "cattaneo": {"s": 0.03, "m": 0.015, "l": 0.0075, "xl": 0.005},
    "stack": {"s": 0.11, "m": 0.07, "l": 0.05, "xl": 0.035, "xxl": 0.025},
}
GEO = {
    "cattaneo": (ROOT / "verification" / "cattaneo3d" / "cattaneo3d.geo", "hc"),
    "stack": (ROOT / "tests" / "data" / "solid_contact" / "stack.geo", "h"),
}

# bench_solid's stack (the 3D benchmark's family) with Coulomb friction on its interface.
STACK = TOML["stack"] + "friction = 0.3\n"


def model(fam: str, msh: Path) -> str:
    """The frictional problem file of a family on mesh `msh`."""
    if fam == "stack":
        return STACK.format(msh=msh.name)
    src = (ROOT / "verification" / "cattaneo3d" / "cattaneo3d.toml").read_text()
    return re.sub(r'file = "[^"]*"', f'file = "{msh.name}"', src, count=1)


def frictionless(text: str) -> str:
    out = re.sub(r"(?m)^friction = .*\n", "", text)
    if out == text:
        raise SystemExit("bench_friction3d: the model has no friction key")
    return out


def mesh(fam: str, size: str, work: Path) -> Path:
    geo, param = GEO[fam]
    val = SIZES[fam][size]
    msh = work / f"{fam}_{val}.msh"
    if not msh.exists():
        log(f"{fam} {size}: gmsh {param} = {val}")
        subprocess.run(["gmsh", "-3", "-order", "1", "-format", "msh22", "-setnumber", param, str(val),
                        str(geo), "-o", str(msh)], check=True, capture_output=True)
    return msh


def run_size(args, fam: str, size: str, work: Path) -> dict:
    msh = mesh(fam, size, work)
    text = model(fam, msh)
    rec: dict = {"family": fam, "size": size, "param": SIZES[fam][size]}
    tf = work / "time.txt"
    for key, body in (("frictionless", frictionless(text)), ("friction", text)):
        toml = work / f"{fam}_{size}_{key}.toml"
        toml.write_text(body)

        def once(toml=toml):
            od = work / "out"
            rc, out, err, wall, rss = timed([args.binary, "solve", toml, "-o", od, "-q"], tf)
            js = od / f"{toml.stem}.json"
            if not js.exists():
                return {"error": f"exit {rc}: {err.strip()[-300:]}", "wall": wall}
            d = json.loads(js.read_text())
            js.unlink()
            steps = d.get("steps") or []
            return {"wall": wall, "rss_mb": rss, "status": d["status"], "dofs": d["dofs"],
                    "newton": d["iterations"], "certified": (d.get("kkt") or {}).get("certified"),
                    "step_newton": [s.get("iterations") for s in steps],
                    "timings": d["timings_s"], "contact": d.get("contact")}
        log(f"{fam} {size}: {key}")
        rec[key] = repeated(once, args.repeats, args.long)
        r = rec[key]
        log(f"  wall={r.get('wall')} status={r.get('status')} newton={r.get('newton')} "
            f"steps={r.get('step_newton')} {r.get('error', '')}")
    return rec


def table(rows: list, cmdline: str) -> str:
    out = [f"Command: `{cmdline}`", "",
           "| model | DOFs | frictionless [s] (Newton) | frictional [s] (Newton per step) | "
           "frictional ÷ frictionless | stick / slip rows | RSS frictional (per DOF) | status |",
           "|---" * 8 + "|"]
    for r in rows:
        f0, f1 = r.get("frictionless", {}), r.get("friction", {})
        n = f1.get("dofs") or f0.get("dofs")
        pairs = (f1.get("contact") or {}).values()
        c = {k: sum(p.get(k) or 0 for p in pairs) for k in ("stick", "slip")} if pairs else {}
        ratio = fmt(f1["wall"] / f0["wall"], 3) if f0.get("wall") and f1.get("wall") else "–"
        per = (f"{fmt(f1['rss_mb'] / 1024, 3)} GB ({fmt(f1['rss_mb'] * 1024 / n, 3)} kB)"
               if f1.get("rss_mb") and n else "–")
        st = "certified" if f1.get("certified") and f0.get("certified") else (
            f1.get("status") or f1.get("error", "")[:60])
        steps = "/".join(str(s) for s in f1.get("step_newton") or []) or fmt(f1.get("newton"))
        out.append(f"| {r['family']} {r['param']} | {n} | {fmt(f0.get('wall'))} ({f0.get('newton', '–')}) | "
                   f"{fmt(f1.get('wall'))} ({steps}) | {ratio} | {c.get('stick', '–')} / {c.get('slip', '–')} | "
                   f"{per} | {st} |")
    return "\n".join(out) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--families", default="cattaneo,stack")
    ap.add_argument("--sizes", default="s,m,l")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--long", type=float, default=60.0)
    ap.add_argument("--work", default=str(ROOT / "bench" / "friction3d"))
    ap.add_argument("--out", default=str(ROOT / "bench" / "friction3d.md"))
    ap.add_argument("--binary", default=str(ROOT / "target" / "release" / "signorini"))
    args = ap.parse_args(argv)
    cmdline = "python3 scripts/bench_friction3d.py " + " ".join(argv if argv is not None else sys.argv[1:])
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    rows = []
    for fam in [f for f in args.families.split(",") if f]:
        for size in [s for s in args.sizes.split(",") if s]:
            if size not in SIZES[fam]:
                log(f"{fam}: no size {size} (sizes {', '.join(SIZES[fam])})")
                continue
            rows.append(run_size(args, fam, size, work))
            Path(args.out).write_text(table(rows, cmdline))
            Path(args.out).with_suffix(".json").write_text(json.dumps(rows, indent=1))
    print(table(rows, cmdline))
    bad = [f"{r['family']} {r['size']} {k}" for r in rows for k in ("frictionless", "friction")
           if not r.get(k, {}).get("certified")]
    if bad:
        print("bench_friction3d: not certified: " + "; ".join(bad), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
