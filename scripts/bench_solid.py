#!/usr/bin/env python3
"""The 3D benchmark (issue 45): the Hertz sphere on a block and a stack of two cubes whose
upper cube is held by the contact alone, at sizes from ~5 k to ~1 M DOFs.

Usage (also `python3 scripts/bench.py --solid ...`):

    python3 scripts/bench_solid.py [--families hertz,stack] [--sizes 50k,300k,1m]
        [--repeats 3] [--long 60] [--cholesky-max 400000] [--no-fenicsx] [--work bench/solid]
        [--out bench/solid.md] [--binary target/release/signorini] [--check]

For each family and size it meshes the .geo of tests/data/solid_contact with Gmsh
(`-3 -order 1 -format msh22`, the size parameter of SIZES; cached in --work), writes the
model and runs, each under /usr/bin/time -f %M (peak RSS):
  * `signorini limit` (one Cholesky of C; skipped above --cholesky-max DOFs),
  * `signorini limit --path iterative` (one AMG-PCG solve of the iterative path's operator),
  * `signorini solve --ssn-path iterative` and, up to --cholesky-max, `signorini solve`
    (the default path: direct below ssn::ITERATIVE_3D_FROM = 100 k unknowns, iterative
    from there; the table of BENCHMARKS.md "3D contact: speed" was measured with a binary
    whose threshold was 400 k, so its "solve direct" column is the direct path throughout),
  * FEniCSx (scripts/bench_fenicsx3d.py under /usr/bin/python3): the linear elasticity of
    the same mesh without contact by CG + GAMG (the Hertz ball held by a prescribed u_z on
    its top instead of the pressure, the stack glued through its conforming interface).
Times are medians of --repeats (runs longer than --long once). Writes a markdown table to
--out and the raw rows as JSON next to it. --check: the 5k size of both families, one
repeat; exit 1 unless every solve is certified and FEniCSx ran (CI).
"""

from __future__ import annotations

import argparse
import json
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
GEO = ROOT / "tests" / "data" / "solid_contact"

# family → size label → the .geo's size parameter (measured DOFs in BENCHMARKS.md)
SIZES = {
    "hertz": {"5k": 0.02, "50k": 0.008, "160k": 0.005, "300k": 0.004, "1m": 0.0027, "3m": 0.00187},
    "stack": {"5k": 0.11, "50k": 0.05, "300k": 0.028, "1m": 0.019},
}
PARAM = {"hertz": "hc", "stack": "h"}

TOML = {
    "hertz": """[mesh]
file = "{msh}"

[materials.ball]
E = 2.0e11
nu = 0.3

[materials.block]
E = 2.0e11
nu = 0.3

[[slip]]
on = "x0"

[[slip]]
on = "y0"

[[slip]]
on = "block_bottom"

[[traction]]
on = "ball_top"
pn = -4.6629e7

[[contact]]
slave = "ball"
master = "block_top"
discretization = "nts"
""",
    "stack": """[mesh]
file = "{msh}"

[materials.lower]
E = 2.0e11
nu = 0.3

[materials.upper]
E = 7.0e10
nu = 0.33

[[slip]]
on = "x0"

[[slip]]
on = "y0"

[[slip]]
on = "bottom"

[[traction]]
on = "top"
pn = -1.0e8

[[contact]]
on = "interface"
""",
}

FENICSX = {
    "hertz": ["--material", "ball:2e11:0.3", "--material", "block:2e11:0.3", "--fix", "x0:0:0",
              "--fix", "y0:1:0", "--fix", "block_bottom:2:0", "--fix", "ball_top:2:-1e-4"],
    "stack": ["--material", "lower:2e11:0.3", "--material", "upper:7e10:0.33", "--fix", "x0:0:0",
              "--fix", "y0:1:0", "--fix", "bottom:2:0", "--pressure", "top:-1e8"],
}


def log(msg: str) -> None:
    print(f"[{time.strftime('%H:%M:%S')}] {msg}", file=sys.stderr, flush=True)


def timed(cmd: list, tf: Path) -> tuple[int, str, str, float, float]:
    """Run under /usr/bin/time -f %M: (exit code, stdout, stderr, wall s, peak RSS MB)."""
    t0 = time.perf_counter()
    p = subprocess.run(["/usr/bin/time", "-f", "%M", "-o", str(tf)] + [str(c) for c in cmd],
                       capture_output=True, text=True)
    wall = time.perf_counter() - t0
    m = re.search(r"(\d+)\s*$", tf.read_text()) if tf.exists() else None
    return p.returncode, p.stdout, p.stderr, wall, (int(m.group(1)) / 1024 if m else float("nan"))


def repeated(f, repeats: int, long: float) -> dict:
    """f() `repeats` times (once if the first run takes longer than `long` s); the median wall."""
    runs = [f()]
    while len(runs) < repeats and runs[0].get("wall", 0) <= long and "error" not in runs[0]:
        runs.append(f())
    out = dict(runs[len(runs) // 2] if len(runs) > 2 else runs[0])
    walls = [r["wall"] for r in runs if "wall" in r]
    if walls:
        out["wall"] = statistics.median(walls)
        out["walls"] = walls
    return out


def mesh(fam: str, size: str, work: Path) -> Path:
    val = SIZES[fam][size]
    msh = work / f"{fam}_{val}.msh"
    if not msh.exists():
        log(f"{fam} {size}: gmsh {PARAM[fam]} = {val}")
        subprocess.run(["gmsh", "-3", "-order", "1", "-format", "msh22", "-setnumber", PARAM[fam], str(val),
                        str(GEO / f"{fam}.geo"), "-o", str(msh)], check=True, capture_output=True)
    return msh


def run_size(args, fam: str, size: str, work: Path) -> dict:
    msh = mesh(fam, size, work)
    toml = work / f"{fam}_{size}.toml"
    toml.write_text(TOML[fam].format(msh=msh.name))
    tf = work / "time.txt"
    rec: dict = {"family": fam, "size": size, "param": SIZES[fam][size]}

    def limit(path: str):
        def once():
            rc, out, err, wall, rss = timed([args.binary, "limit", toml, "--path", path], tf)
            if rc != 0:
                return {"error": err.strip()[-300:], "wall": wall}
            d = json.loads(out.strip().splitlines()[-1])
            d.update(wall=wall, rss_mb=rss)
            return d
        return once

    def solve(extra: list):
        def once():
            od = work / "out"
            rc, out, err, wall, rss = timed([args.binary, "solve", toml, "-o", od, "-q"] + extra, tf)
            js = od / f"{toml.stem}.json"
            if not js.exists():
                return {"error": f"exit {rc}: {err.strip()[-300:]}", "wall": wall}
            d = json.loads(js.read_text())
            js.unlink()
            return {"wall": wall, "rss_mb": rss, "status": d["status"], "dofs": d["dofs"],
                    "newton": d["iterations"], "cg": d["inner_iterations"], "kkt": d.get("kkt"),
                    "timings": d["timings_s"], "active": d.get("active")}
        return once

    n = None
    log(f"{fam} {size}: limit --path iterative")
    rec["limit_iterative"] = repeated(limit("iterative"), args.repeats, args.long)
    n = rec["limit_iterative"].get("n")
    if n is not None and n <= args.cholesky_max:
        log(f"{fam} {size}: limit (Cholesky)")
        rec["limit"] = repeated(limit("cholesky"), args.repeats, args.long)
        log(f"{fam} {size}: solve (default path)")
        rec["solve_default"] = repeated(solve([]), args.repeats, args.long)
    log(f"{fam} {size}: solve --ssn-path iterative")
    rec["solve_iterative"] = repeated(solve(["--ssn-path", "iterative"]), args.repeats, args.long)
    if not args.no_fenicsx:
        log(f"{fam} {size}: FEniCSx GAMG-CG")

        def fx():
            rc, out, err, wall, rss = timed(["/usr/bin/python3", ROOT / "scripts" / "bench_fenicsx3d.py", msh]
                                            + FENICSX[fam], tf)
            if rc != 0:
                return {"error": err.strip()[-300:], "wall": wall}
            d = json.loads(out.strip().splitlines()[-1])
            d.update(wall=wall, rss_mb=rss)
            return d
        rec["fenicsx"] = repeated(fx, args.repeats, args.long)
    for k, v in rec.items():
        if isinstance(v, dict):
            log(f"  {k}: " + ", ".join(f"{a}={v[a]}" for a in ("wall", "status", "newton", "cg", "iterations",
                                                                 "ksp_iterations", "error") if a in v))
    return rec


def fmt(x, d=3) -> str:
    if x is None or (isinstance(x, float) and x != x):
        return "–"
    if isinstance(x, float):
        return f"{x:.{d}g}"
    return str(x)


def table(rows: list, cmdline: str) -> str:
    out = [f"Command: `{cmdline}`", "",
           "| model | DOFs | rows | Cholesky limit [s] | AMG limit [s] (CG) | solve direct [s] (Newton) | "
           "solve iterative [s] (Newton, CG) | iterative ÷ AMG limit | direct ÷ Cholesky | "
           "FEniCSx GAMG [s] (solve, CG) | iterative ÷ FEniCSx | RSS iterative (per DOF) | RSS direct (per DOF) |",
           "|---" * 13 + "|"]
    for r in rows:
        li, lc = r.get("limit_iterative", {}), r.get("limit", {})
        si, sd, fx = r.get("solve_iterative", {}), r.get("solve_default", {}), r.get("fenicsx", {})
        n = li.get("n") or si.get("dofs")
        per = lambda s: (f"{fmt(s.get('rss_mb') / 1024, 3)} GB ({fmt(s['rss_mb'] * 1024 / n, 3)} kB)"  # noqa: E731
                         if s.get("rss_mb") and n else "–")
        ratio = lambda a, b: fmt(a / b, 3) if a and b else "–"  # noqa: E731
        st = lambda s: "" if s.get("status") in (None, "converged") else f" {s.get('status') or s.get('error', '')[:40]}"  # noqa: E731
        out.append(
            f"| {r['family']} {r['size']} | {n} | {li.get('springs', '–')} | {fmt(lc.get('wall'))} | "
            f"{fmt(li.get('wall'))} ({li.get('iterations', '–')}) | "
            f"{fmt(sd.get('wall'))} ({sd.get('newton', '–')}){st(sd)} | "
            f"{fmt(si.get('wall'))} ({si.get('newton', '–')}, {si.get('cg', '–')}){st(si)} | "
            f"{ratio(si.get('wall'), li.get('wall'))} | {ratio(sd.get('wall'), lc.get('wall'))} | "
            f"{fmt(fx.get('wall'))} ({fmt(fx.get('t_solve'))}, {fx.get('ksp_iterations', '–')}) | "
            f"{ratio(si.get('wall'), fx.get('wall'))} | {per(si)} | {per(sd)} |")
    return "\n".join(out) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--families", default="hertz,stack")
    ap.add_argument("--sizes", default="50k,300k,1m")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--long", type=float, default=60.0)
    ap.add_argument("--cholesky-max", type=int, default=400_000)
    ap.add_argument("--no-fenicsx", action="store_true")
    ap.add_argument("--work", default=str(ROOT / "bench" / "solid"))
    ap.add_argument("--out", default=str(ROOT / "bench" / "solid.md"))
    ap.add_argument("--binary", default=str(ROOT / "target" / "release" / "signorini"))
    ap.add_argument("--check", action="store_true")
    args = ap.parse_args(argv)
    cmdline = "python3 scripts/bench_solid.py " + " ".join(argv if argv is not None else sys.argv[1:])
    if args.check:
        args.sizes, args.repeats = "5k", 1
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    rows = []
    for fam in [f for f in args.families.split(",") if f]:
        for size in [s for s in args.sizes.split(",") if s]:
            if size in SIZES[fam]:
                rows.append(run_size(args, fam, size, work))
                # written after every size, so a long run that is stopped keeps what it measured
                md = table(rows, cmdline)
                Path(args.out).write_text(md)
                Path(args.out).with_suffix(".json").write_text(json.dumps(rows, indent=1))
    md = table(rows, cmdline)
    print(md)
    if args.check:
        bad = [f"{r['family']} {r['size']} {k}" for r in rows for k in ("solve_iterative", "solve_default")
               if k in r and r[k].get("status") != "converged"]
        bad += [f"{r['family']} {r['size']} FEniCSx" for r in rows
                if not args.no_fenicsx and "error" in r.get("fenicsx", {"error": 1})]
        if bad:
            print("bench_solid --check: failed: " + "; ".join(bad), file=sys.stderr)
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
