#!/usr/bin/env python3
"""The signorini benchmark: families of the three-body, Hertz and rollers
models at ~10 k, 100 k, 400 k and 1 M nodes (and 2 M for the three bodies),
every method, the Cholesky limit, the peers.

Usage (the README's command is `bash scripts/bench`, which installs what the
peers need first):

    python3 scripts/bench.py [--sizes 10k,100k,400k,1m,three_bodies:2m]
                             [--families three_bodies,hertz,rollers] [--methods ssn,mprgp]
                             [--repeats 3] [--budget 600] [--peers clarabel,osqp]
                             [--no-fenicsx] [--work bench] [--out BENCHMARKS.md]

For each family and size it
  1. meshes the shipped .geo with Gmsh (`-clscale`, binary MSH 4.1), calibrated
     so the mesh has the wanted number of nodes within 25 % (cached in --work);
  2. runs `signorini limit` (one sparse Cholesky factorization + solve of C);
  3. runs every method variant (`signorini solve --method M [--preconditioner P]`)
     under /usr/bin/time -v (peak RSS), reading the phase times (read, assemble,
     factor, solve, write) from the JSON summary; a method is skipped at a size
     when its time predicted from the smaller sizes (growth exponent fitted so
     far, at least 1) exceeds --budget, or when it did not converge before:
     the reason is printed and written;
  4. exports the QP (`signorini export --qp`) and solves it with Clarabel and
     OSQP (scripts/bench_peers.py, in .venv), skipped by the same prediction;
  5. three-body family: the linear elastic problem (contact curves glued) with
     FEniCSx (scripts/bench_fenicsx.py, Debian's python3-dolfinx-real) and with
     `signorini solve --no-contact`, timed the same way;
  6. writes --out (BENCHMARKS.md): machine, date, commands, medians, ratios,
     fitted growth exponents, the issue-15 table (best method's whole process
     and peak RSS against the limit's, determinism over the repeats), and the
     raw results as JSON next to it.

Load steps (issue 36): `--steps N` runs, instead of the above, each family and
size as a model with N load steps (`factor = k/N`, loads and prescribed
displacements ramped) by the first of --methods (default ssn), back to back
with `signorini limit` on the same mesh, and writes the steps table (whole
process ÷ limit against 1.5 + 0.15 (N − 1), peak RSS ÷ limit against 1.3, the
per-step assembly / solve / write times from `--log-level debug`) to
--steps-out (default bench/steps.md, raw JSON next to it).

3D (issue 45): `--solid [ARGS]` hands the rest of the command line to
scripts/bench_solid.py (the Hertz sphere on a block and a stack with a
floating cube at 5 k–1 M DOFs, the Cholesky and AMG-PCG yardsticks, FEniCSx's
GAMG-CG on the same mesh; `--solid --check` is the CI run at 5 k DOFs).

The mu scan (issue 42 §1): `--mu-scan 0.05,0.1,...` runs, instead of the
above, meshes/geodynamic_steps.toml with Coulomb friction mu on its three
faults by ssn and mprgp against the frictionless run, written to
--mu-scan-out (default bench/mu_scan.md, raw JSON next to it).

Friction (issue 36): `--friction` runs, instead of the above, the friction
table: a floating punch held tangentially by Coulomb friction alone
(tests/data/friction/floating_punch.geo, mu = 0.3, one load step) and NAFEMS 1
(verification/nafems1, mu = 0.1, 10 load steps) at three mesh sizes each
(--friction-levels, default 0,1,2: about 2 k / 10 k / 50 k and 8 k / 30 k /
80 k nodes), by ssn and mprgp with friction and by ssn on the same model
without it (the punch also without its side load, which nothing would hold):
whole-process time, the solve time and the Newton steps (iterations) and inner
iterations summed over the load steps, written to --friction-out (default
bench/friction.md, raw JSON next to it).

Runs whose median is longer than --long seconds (default 60) are not repeated.
Exit status: 0 if the benchmark ran (whatever the methods did), 2 on a setup
error (no binary, no gmsh).
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import platform
import re
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SIZES = {"10k": 10_000, "100k": 100_000, "400k": 400_000, "1m": 1_000_000, "2m": 2_000_000}
# Empirical: nodes ~ clscale^(-p) for these .geo files (p < 2: points with a
# fixed size and boundary layers).
CLSCALE_EXPONENT = 1.8


def log(msg: str) -> None:
    print(f"[bench {time.strftime('%H:%M:%S')}] {msg}", flush=True)


def run(cmd, timeout=None, env=None, cwd=None):
    """Run cmd; returns (exit code or None on timeout, stdout, stderr, wall s)."""
    t0 = time.perf_counter()
    try:
        p = subprocess.run(
            [str(c) for c in cmd], capture_output=True, text=True, timeout=timeout, env=env, cwd=cwd
        )
        return p.returncode, p.stdout, p.stderr, time.perf_counter() - t0
    except subprocess.TimeoutExpired as e:
        out = e.stdout.decode() if isinstance(e.stdout, bytes) else (e.stdout or "")
        return None, out, "timeout", time.perf_counter() - t0


def median(xs):
    xs = [x for x in xs if x is not None]
    return statistics.median(xs) if xs else None


# ----------------------------------------------------------------- meshes
def msh_nodes(path: Path) -> int:
    """Number of nodes from the $Nodes header (ASCII or binary MSH 4.1)."""
    with open(path, "rb") as f:
        data = f.read(1 << 20)
    i = data.find(b"$Nodes")
    if i < 0:
        raise RuntimeError(f"{path}: no $Nodes section")
    if b"$MeshFormat\n4.1 1" in data:  # binary: numEntityBlocks numNodes min max as size_t
        import struct

        j = data.index(b"\n", i) + 1
        _, n, _, _ = struct.unpack("<4Q", data[j : j + 32])
        return n
    line = data[i:].split(b"\n")[1].split()
    return int(line[1])


def make_mesh(family: str, target: int, work: Path, gmsh: str) -> tuple[Path, int, float]:
    """Mesh family.geo with ~target nodes; returns (msh, nodes, gmsh seconds)."""
    geo = ROOT / "meshes" / f"{family}.geo"
    out = work / f"{family}_{target}.msh"
    info = work / f"{family}_{target}.json"
    if out.exists() and info.exists():
        d = json.loads(info.read_text())
        return out, d["nodes"], d["gmsh_s"]
    shipped = msh_nodes(ROOT / "meshes" / f"{family}.msh")
    s = (shipped / target) ** (1 / CLSCALE_EXPONENT)
    for attempt in range(4):
        tmp = out.with_suffix(".tmp.msh")
        rc, _, err, dt = run([gmsh, "-2", "-format", "msh41", "-bin", "-algo", "del2d",
                              "-clscale", f"{s:.5g}", geo, "-o", tmp])
        if rc != 0:
            raise RuntimeError(f"gmsh failed on {geo}: {err[-500:]}")
        n = msh_nodes(tmp)
        log(f"  gmsh {family} clscale {s:.4g}: {n} nodes ({dt:.1f} s)")
        if 0.75 * target <= n <= 1.25 * target or attempt == 3:
            tmp.rename(out)
            info.write_text(json.dumps({"nodes": n, "clscale": s, "gmsh_s": dt}))
            return out, n, dt
        s *= (n / target) ** (1 / CLSCALE_EXPONENT)
    raise AssertionError


def make_toml(family: str, msh: Path, work: Path) -> Path:
    text = (ROOT / "meshes" / f"{family}.toml").read_text()
    text, k = re.subn(r'(?m)^file\s*=\s*"[^"]*"', f'file = "{msh.name}"', text, count=1)
    if k != 1:
        raise RuntimeError(f"meshes/{family}.toml: no [mesh] file line")
    path = work / f"{msh.stem}.toml"
    path.write_text(text)
    return path


# ----------------------------------------------------------------- signorini
def variants(binary: str):
    rc, out, _, _ = run([binary, "methods"])
    methods, pcs = [], []
    for line in out.splitlines():
        if line.startswith("preconditioners"):
            pcs = [p.strip() for p in line.split(":", 1)[1].split(",")]
        elif line.strip():
            methods.append(line.split()[0])
    vs = []
    for m in methods:
        if m == "cgc":
            vs += [("cgc", p) for p in pcs]
        else:
            vs.append((m, None))
    return vs


def vname(v) -> str:
    return v[0] if v[1] is None else f"{v[0]}+{v[1]}"


def solve_once(binary, toml: Path, v, outdir: Path, timeout, extra=()):
    """One `signorini solve`; returns a dict of times, iterations, RSS, status."""
    if outdir.exists():
        shutil.rmtree(outdir)
    timef = outdir.parent / (outdir.name + ".time")
    cmd = ["/usr/bin/time", "-v", "-o", timef, binary, "solve", toml, "--out", outdir, "--quiet"]
    if v is not None:
        cmd += ["--method", v[0]] + (["--preconditioner", v[1]] if v[1] else [])
    cmd += list(extra)
    rc, _, err, wall = run(cmd, timeout=timeout)
    r = {"exit": rc, "wall": wall}
    if rc is None:
        r["status"] = f"timeout after {timeout:.0f} s"
        return r
    try:
        t = timef.read_text()
        r["rss_mb"] = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", t).group(1)) / 1024
    except (OSError, AttributeError):
        r["rss_mb"] = None
    js = list(outdir.glob("*.json"))
    if rc not in (0, 3) or not js:
        r["status"] = f"exit {rc}: {err.strip().splitlines()[-1] if err.strip() else ''}"
        return r
    d = json.loads(js[0].read_text())
    ts = d["timings_s"]
    ph = ts.get("phases", {})
    r.update(
        status=d["status"],
        converged=d["converged"],
        certified=d["kkt"]["certified"],
        kkt={k: d["kkt"].get(k) for k in ("primal", "dual", "complementarity", "stationarity")},
        iterations=d["iterations"],
        inner=d["inner_iterations"],
        dofs=d["dofs"],
        m=d["constraints"],
        nodes=d["mesh_nodes"],
        energy=d["energy"],
        probes={k: p["u"] for k, p in d.get("probes", {}).items()},
        read=ts["read"],
        assemble=ts["assemble"],
        factor=ph.get("factor", ph.get("precondition", 0.0)),
        solve=ts["solve"],
        write=ts["write"],
        total=ts["total"],
    )
    return r


def repeated(fn, repeats: int, long_s: float):
    """Run fn() up to `repeats` times (once if it takes longer than long_s);
    returns the run with the median total and the list of totals."""
    runs = [fn()]
    key = lambda r: r.get("total", r.get("t_total", r.get("wall", math.inf))) or math.inf
    while len(runs) < repeats and key(runs[0]) <= long_s and runs[0].get("converged", True):
        runs.append(fn())
    totals = sorted(key(r) for r in runs)
    med = statistics.median(totals)
    best = min(runs, key=lambda r: abs(key(r) - med))
    best = dict(best)
    best["repeats"] = len(runs)
    # what must not depend on timing: the path (iterations, inner solves)
    # and the answer (energy, probes), equal over the repeats
    best["fingerprints"] = [json.dumps([r.get(k) for k in ("iterations", "inner", "energy", "probes", "status")])
                            for r in runs]
    best["totals"] = totals
    if len(runs) > 1:
        # medians of every phase, not only of the total
        for f in ("read", "assemble", "factor", "solve", "write", "total", "rss_mb", "wall",
                  "t_read", "t_setup", "t_solve", "t_total", "t_assemble", "t_factor",
                  "t_factor_solve", "t_compile"):
            vals = [r.get(f) for r in runs if isinstance(r.get(f), (int, float))]
            if len(vals) == len(runs):
                best[f] = statistics.median(vals)
    return best


def fit_exponent(points):
    """Least-squares slope of log t against log n."""
    pts = [(math.log(n), math.log(t)) for n, t in points if n and t and t > 0]
    if len(pts) < 2:
        return None
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    if sxx == 0:
        return None
    return sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx


def predict(history, n):
    """Predicted time at size n from (n, t) at smaller sizes, exponent ≥ 1."""
    if not history:
        return None
    p = fit_exponent(history)
    # one point: assume quadratic growth (what CG-type methods show from 10k to 100k)
    p = max(1.0, p if p is not None else 2.0)
    n0, t0 = history[-1]
    return t0 * (n / n0) ** p


# ----------------------------------------------------------------- report
def fmt(x, nd=3):
    if x is None:
        return "–"
    if isinstance(x, str):
        return x
    if x == 0:
        return "0"
    if abs(x) >= 100:
        return f"{x:.0f}"
    if abs(x) >= 1:
        return f"{x:.{nd - 1}f}"
    return f"{x:.{nd}g}"


def machine() -> dict:
    cpu = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    mem = ""
    try:
        kb = int(re.search(r"MemTotal:\s+(\d+)", Path("/proc/meminfo").read_text()).group(1))
        mem = f"{kb / 1024 / 1024:.1f} GiB"
    except (OSError, AttributeError):
        pass
    rc, rev, _, _ = run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"])
    rc2, rustc, _, _ = run(["rustc", "--version"])
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "memory": mem,
        "os": platform.platform(),
        "commit": rev.strip() if rc == 0 else "?",
        "rustc": rustc.strip() if rc2 == 0 else "?",
        "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
    }


def write_report(path: Path, res: dict, args, cmdline: str) -> None:
    mach = res["machine"]
    L = []
    w = L.append
    w("# signorini benchmarks\n")
    w("Generated by `scripts/bench` (scripts/bench.py); every number below is from the one run")
    w("recorded here. Do not edit by hand: rerun the command.\n")
    w(f"- date: {mach['date']}, commit `{mach['commit']}`, {mach['rustc']}")
    w(f"- machine: {mach['cpu']}, {mach['cores']} cores, {mach['memory']}, {mach['os']}")
    w(f"- command: `{cmdline}`")
    w(f"- repeats: {args.repeats} (median reported; runs over {args.long:.0f} s once), "
      f"skip budget {args.budget:.0f} s per run, SIGNORINI_THREADS={os.environ.get('SIGNORINI_THREADS', 'unset (all cores)')}")
    w("- times are wall-clock seconds inside the process (signorini's own phase timers; "
      "peers: perf_counter around their calls); peak RSS from `/usr/bin/time -v`.\n")
    w("Phases: read = TOML + mesh; assemble = topology, elimination, C, d, A, g; "
      "factor = the method's sparse Cholesky (or preconditioner setup); solve = everything the "
      "method does, factor included; write = VTU + HDF5 + JSON. "
      "limit = one sparse Cholesky factorization of C plus one solve (`signorini limit`), "
      "the cost of one linear elastic solve of the same C; ratio = method's solve ÷ limit.\n")

    targets = []
    for fam, fres in res["families"].items():
        w(f"## {fam}\n")
        sizes = fres["sizes"]
        w("| size | nodes | DOFs | contact rows | gmsh [s] | read [s] | assemble [s] | limit factor [s] | limit solve [s] | limit RSS [MB] |")
        w("|---|---|---|---|---|---|---|---|---|---|")
        for s in sizes:
            lim = s.get("limit") or {}
            w(f"| {s['size']} | {s['nodes']} | {lim.get('n', '–')} | {s.get('m', '–')} | {fmt(s['gmsh_s'])} | "
              f"{fmt(lim.get('t_read'))} | {fmt(lim.get('t_assemble'))} | {fmt(lim.get('t_factor'))} | "
              f"{fmt(lim.get('t_solve'))} | {fmt(lim.get('rss_mb'))} |")
        w("")
        for s in sizes:
            lim = s.get("limit") or {}
            lt = lim.get("t_factor_solve")
            w(f"### {fam}, {s['size']} ({s['nodes']} nodes, {lim.get('n', '?')} DOFs)\n")
            w("| method | status | iterations (inner) | read | assemble | factor | solve | write | total | peak RSS [MB] | solve ÷ limit | runs |")
            w("|---|---|---|---|---|---|---|---|---|---|---|---|")
            for name, r in s["methods"].items():
                if "skipped" in r:
                    w(f"| {name} | skipped: {r['skipped']} | | | | | | | | | | |")
                    continue
                st = r.get("status", "?")
                if r.get("converged") and r.get("certified"):
                    st = "converged, certified"
                elif r.get("kkt"):
                    k = r["kkt"]
                    st += (f", not certified (KKT primal {fmt(k.get('primal'))}, compl. "
                           f"{fmt(k.get('complementarity'))}, stat. {fmt(k.get('stationarity'))})")
                ratio = r["solve"] / lt if lt and r.get("solve") is not None else None
                w(f"| {name} | {st} | {r.get('iterations', '–')} ({r.get('inner', '–')}) | {fmt(r.get('read'))} | "
                  f"{fmt(r.get('assemble'))} | {fmt(r.get('factor'))} | {fmt(r.get('solve'))} | {fmt(r.get('write'))} | "
                  f"{fmt(r.get('total'))} | {fmt(r.get('rss_mb'))} | {fmt(ratio)} | {r.get('repeats', 1)} |")
            w("")
            comp = s.get("compress")
            if comp:
                w(f"VTU/HDF5 writing for {comp['method']}: {fmt(comp['write_plain'])} s uncompressed (default), "
                  f"{fmt(comp['write_zlib'])} s with `--compress`; output size {fmt(comp['mb_plain'])} MB vs "
                  f"{fmt(comp['mb_zlib'])} MB.\n")
            peers = s.get("peers")
            if peers:
                w("Peers on the exported QP (`signorini export --qp`, scripts/bench_peers.py):\n")
                w("| solver | status | iterations | setup [s] | solve [s] | total [s] | rel. objective diff | rel. ‖x − x_signorini‖ | max violation | best signorini solve ÷ this |")
                w("|---|---|---|---|---|---|---|---|---|---|")
                best = s.get("best")
                for p in peers:
                    if "skipped" in p:
                        w(f"| {p['solver']} | skipped: {p['skipped']} | | | | | | | | |")
                        continue
                    sp = (best["solve"] / p["t_total"]) if best and p.get("t_total") else None
                    w(f"| {p['solver']} {p.get('version', '')} | {p.get('status')} | {p.get('iterations')} | {fmt(p.get('t_setup'))} | "
                      f"{fmt(p.get('t_solve'))} | {fmt(p.get('t_total'))} | {fmt(p.get('rel_obj_diff'))} | "
                      f"{fmt(p.get('rel_x_diff'))} | {fmt(p.get('violation'))} | {fmt(sp)} |")
                w("")
            fx = s.get("fenicsx")
            lin = s.get("linear")
            if fx or lin:
                w("Linear elastic problem on the same mesh (contact curves glued):\n")
                w("| solver | DOFs | read [s] | compile [s] | assemble [s] | solve [s] | total [s] (no compile) |")
                w("|---|---|---|---|---|---|---|")
                if lin and "total" in lin:
                    w(f"| signorini solve --no-contact ({lin.get('method')}) | {lin.get('dofs')} | {fmt(lin.get('read'))} | – | "
                      f"{fmt(lin.get('assemble'))} | {fmt(lin.get('solve'))} | {fmt(lin.get('read', 0) + lin.get('assemble', 0) + lin.get('solve', 0))} |")
                if fx and "t_total" in fx:
                    w(f"| FEniCSx {fx.get('dolfinx', '')} ({fx.get('solver')}, {fx.get('petsc_lu_package', '')}) | {fx.get('dofs')} | "
                      f"{fmt(fx.get('t_read'))} | {fmt(fx.get('t_compile'))} | {fmt(fx.get('t_assemble'))} | "
                      f"{fmt(fx.get('t_solve'))} | {fmt(fx.get('t_total'))} |")
                elif fx:
                    w(f"| FEniCSx | {fx.get('status', 'failed')} | | | | | |")
                w("")
        # growth exponents
        w(f"### {fam}: growth of the solve time with size\n")
        w("Exponent p of t ∝ n^p fitted by least squares over the sizes run (n = DOFs).\n")
        w("| method | " + " | ".join(f"solve [s] at {s['size']}" for s in sizes) + " | p |")
        w("|---|" + "---|" * len(sizes) + "---|")
        names = list(sizes[0]["methods"].keys()) if sizes else []
        rows = [("limit (factor + solve)", [(s.get("limit") or {}).get("t_factor_solve") for s in sizes])]
        rows += [(nm, [s["methods"].get(nm, {}).get("solve") if s["methods"].get(nm, {}).get("converged") else None
                       for s in sizes]) for nm in names]
        for nm, ts in rows:
            pts = [((s.get("limit") or {}).get("n"), t) for s, t in zip(sizes, ts) if t]
            p = fit_exponent(pts)
            w(f"| {nm} | " + " | ".join(fmt(t) for t in ts) + f" | {fmt(p, 2) if p else '–'} |")
        w("")
        for s in sizes:
            targets.append((fam, s))

    # targets
    w("## Against the targets (issue 4)\n")
    w("| target | family, size | measured | met |")
    w("|---|---|---|---|")
    for fam, s in targets:
        lim = (s.get("limit") or {}).get("t_factor_solve")
        best = s.get("best")
        if best and lim and s["size"] == "1m":
            r = best["solve"] / lim
            w(f"| best method ÷ one Cholesky factor+solve ≤ 1.5 at 1 M | {fam}, {s['size']} | {best['name']}: {fmt(r)} | {'yes' if r <= 1.5 else 'no'} |")
        if best and s["size"] == "100k":
            for p in s.get("peers") or []:
                if p.get("t_total"):
                    sp = p["t_total"] / best["solve"]
                    ok = sp >= 10 or not p.get("converged")
                    w(f"| ≥ 10× faster than {p['solver']} at 100 k | {fam}, {s['size']} | {fmt(sp)}× ({p.get('status')}) | {'yes' if sp >= 10 else 'no'} |")
        fx = s.get("fenicsx")
        if best and fx and fx.get("t_total"):
            r = best["total"] / fx["t_total"]
            w(f"| signorini end to end ≤ 0.5× FEniCSx linear elastic | {fam}, {s['size']} | {best['name']} total {fmt(best['total'])} s ÷ {fmt(fx['t_total'])} s = {fmt(r)} | {'yes' if r <= 0.5 else 'no'} |")
    w("")
    write_issue15(w, res)
    w("Raw results: `" + res["raw"] + "`.\n")
    # The hand-written notes of the file being replaced (everything from
    # "## Notes" on) are kept: measurements behind the methods' parameters.
    if path.exists():
        old = path.read_text()
        k = old.find("\n## Notes\n")
        if k >= 0:
            w(old[k + 1:].rstrip("\n") + "\n")
    path.write_text("\n".join(L))


def whole_best(s):
    """The converged, certified method with the smallest whole-process wall
    time (read, assemble, solve, write; process start to exit) at one size."""
    best = None
    for nm, r in s["methods"].items():
        if "skipped" in r or not (r.get("converged") and r.get("certified")) or r.get("wall") is None:
            continue
        if best is None or r["wall"] < best[1]["wall"]:
            best = (nm, r)
    return best


def write_issue15(w, res) -> None:
    """The ratio table of issue 15: the best method against `signorini limit`
    (one sparse Cholesky factorization and solve of the same C, no output),
    both timed as whole processes, and the peak memory of each."""
    w("## Contact at the price of one linear solve (issue 15)\n")
    w("For each family and size: the converged, certified method with the smallest whole-process "
      "wall time (`signorini solve`: read, assemble, solve, write VTU + HDF5 + JSON; process start to "
      "exit, median of the repeats) against `signorini limit` on the same file (read, assemble, one "
      "sparse Cholesky factorization and solve of C, no output), both timed the same way. "
      "solve ÷ limit compares the solve phase with the limit's factor + solve. "
      "Deterministic: every repeat took the same path and gave the same answer (iterations, inner "
      "solves, energy and probe displacements equal).\n")
    w("| family | size | DOFs | contact rows | best method | iterations (inner) | whole [s] | limit whole [s] | whole ÷ limit | solve ÷ limit | peak RSS ÷ limit | repeats | deterministic |")
    w("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    growth = {}
    for fam, fres in res["families"].items():
        for s in fres["sizes"]:
            lim = s.get("limit") or {}
            b = whole_best(s)
            if not b or not lim.get("wall"):
                w(f"| {fam} | {s['size']} | {lim.get('n', '–')} | {s.get('m', '–')} | – | | | | | | | | |")
                continue
            nm, r = b
            fp = r.get("fingerprints") or []
            det = ("yes" if len(set(fp)) == 1 else "NO") if len(fp) > 1 else "(1 run)"
            rss = r["rss_mb"] / lim["rss_mb"] if r.get("rss_mb") and lim.get("rss_mb") else None
            w(f"| {fam} | {s['size']} | {lim.get('n')} | {s.get('m', '–')} | {nm} | {r.get('iterations')} ({r.get('inner')}) | "
              f"{fmt(r['wall'])} | {fmt(lim['wall'])} | **{fmt(r['wall'] / lim['wall'])}** | "
              f"{fmt(r['solve'] / lim['t_factor_solve'])} | {fmt(rss)} | {r.get('repeats', 1)} | {det} |")
            growth.setdefault((fam, nm), []).append((lim.get("n"), r["solve"], s["size"]))
    w("")
    w("Growth of the best method's solve time, t ∝ n^p, least squares over the sizes from 100k on "
      "(n = DOFs):\n")
    w("| family | method | sizes | p | p of the limit (factor + solve) |")
    w("|---|---|---|---|---|")
    for (fam, nm), pts in growth.items():
        big = [(n, t) for n, t, sz in pts if SIZES[sz] >= 100_000]
        p = fit_exponent(big)
        lim = [((s.get("limit") or {}).get("n"), (s.get("limit") or {}).get("t_factor_solve"))
               for s in res["families"][fam]["sizes"] if SIZES[s["size"]] >= 100_000]
        pl = fit_exponent(lim)
        w(f"| {fam} | {nm} | {', '.join(sz for _, _, sz in pts if SIZES[sz] >= 100_000)} | "
          f"{fmt(p, 2) if p else '–'} | {fmt(pl, 2) if pl else '–'} |")
    w("")


# ----------------------------------------------------------------- load steps
def make_steps_toml(family: str, msh: Path, work: Path, nsteps: int) -> Path:
    """family.toml on msh with nsteps [[steps]], factor k/N (loads and
    prescribed displacements ramped together)."""
    text = make_toml(family, msh, work).read_text()
    if "[[steps]]" in text:
        raise RuntimeError(f"meshes/{family}.toml has [[steps]] already")
    text += "\n" + "".join(f"\n[[steps]]\nt = {k}.0\nfactor = {k / nsteps!r}\n"
                           for k in range(1, nsteps + 1))
    path = work / f"{msh.stem}_steps{nsteps}.toml"
    path.write_text(text)
    return path


STEP_LOG = re.compile(r"step (\d+): assembly ([0-9.]+) s, solve ([0-9.]+) s")
STEP_WRITE = re.compile(r"step (\d+): writing ([0-9.]+) s")


def steps_once(binary, toml: Path, method: str, outdir: Path, timeout):
    """One multi-step `signorini solve --log-level debug`: whole process wall
    time, peak RSS, and each step's assembly, solve and write times."""
    if outdir.exists():
        shutil.rmtree(outdir)
    timef = outdir.parent / (outdir.name + ".time")
    # not --quiet: it silences the debug log the step times are read from
    rc, _, err, wall = run(["/usr/bin/time", "-v", "-o", timef, binary, "solve", toml, "--out", outdir,
                            "--method", method, "--log-level", "debug"], timeout=timeout)
    r = {"exit": rc, "wall": wall}
    if rc not in (0, 3):
        r["status"] = f"exit {rc}: {err.strip().splitlines()[-1] if err.strip() else ''}"
        return r
    r["rss_mb"] = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", timef.read_text()).group(1)) / 1024
    steps = {}
    for m in STEP_LOG.finditer(err):
        steps.setdefault(int(m.group(1)), {}).update(assemble=float(m.group(2)), solve=float(m.group(3)))
    for m in STEP_WRITE.finditer(err):
        steps.setdefault(int(m.group(1)), {})["write"] = float(m.group(2))
    js = list(outdir.glob("*.json"))
    if js:
        d = json.loads(js[0].read_text())
        # the solve times of the JSON's step rows where the log has none
        for row in d.get("steps") or []:
            steps.setdefault(row["step"], {}).setdefault("solve", row["time_solve"])
        r.update(status=d["status"], converged=d["converged"], certified=d["kkt"]["certified"],
                 dofs=d["dofs"], total=d["timings_s"]["total"])
    r["steps"] = [dict(steps[k], step=k) for k in sorted(steps)]
    return r


def run_steps(args, binary, work: Path, size_spec) -> int:
    """The steps table (issue 36): N-step runs against `signorini limit`."""
    n = args.steps
    method = (args.methods.split(",")[0].strip() if args.methods else "ssn") or "ssn"
    rows = []
    for fam in [f.strip() for f in args.families.split(",") if f.strip()]:
        for _, size in sorted([fs for fs in size_spec if fs[0] in (None, fam)], key=lambda fs: SIZES[fs[1]]):
            msh, nodes, _ = make_mesh(fam, SIZES[size], work, args.gmsh)
            toml = make_steps_toml(fam, msh, work, n)
            limit_toml = make_toml(fam, msh, work)
            for rep in range(args.repeats):
                # back to back: the limit, then the N-step run
                tf = work / "limit.time"
                rc, out, err, lwall = run(["/usr/bin/time", "-v", "-o", tf, binary, "limit", limit_toml])
                lrss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", tf.read_text()).group(1)) / 1024 if rc == 0 else None
                r = steps_once(binary, toml, method, work / "out_steps", max(4 * args.budget, 120.0))
                row = {"family": fam, "size": size, "nodes": nodes, "nsteps": n, "method": method, "repeat": rep + 1,
                       "limit_wall": lwall if rc == 0 else None, "limit_rss_mb": lrss, **r}
                rows.append(row)
                log(f"steps {fam} {size} #{rep + 1}: whole {fmt(r.get('wall'))} s, limit {fmt(lwall)} s, "
                    f"RSS {fmt(r.get('rss_mb'))} / {fmt(lrss)} MB, {r.get('status')}")
    out = Path(args.steps_out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps({"machine": machine(), "cmdline": "python3 scripts/bench.py " + " ".join(sys.argv[1:]),
                                                    "rows": rows}, indent=1, default=str))
    target = 1.5 + 0.15 * (n - 1)
    L = [f"Load steps: {n} steps, `--method {method}`, each run back to back with `signorini limit` "
         f"(whole processes; target whole ÷ limit ≤ 1.5 + 0.15 (N − 1) = {target:.2f}, peak RSS ÷ limit ≤ 1.3).\n",
         "| family | size | nodes | run | whole [s] | limit [s] | whole ÷ limit | met | RSS [MB] | limit RSS [MB] | RSS ÷ limit | met | step 1 asm / solve / write [s] | steps 2–N asm / solve / write, median [s] |",
         "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        wl = r["wall"] / r["limit_wall"] if r.get("limit_wall") and r.get("wall") and r.get("converged") else None
        rl = r["rss_mb"] / r["limit_rss_mb"] if r.get("limit_rss_mb") and r.get("rss_mb") else None
        st = r.get("steps") or []
        first = st[0] if st else {}
        later = st[1:]
        med = lambda k: median([s.get(k) for s in later])
        L.append(f"| {r['family']} | {r['size']} | {r['nodes']} | {r['repeat']} | {fmt(r.get('wall'))} | {fmt(r.get('limit_wall'))} | "
                 f"{fmt(wl)} | {'yes' if wl is not None and wl <= target else 'no'} | {fmt(r.get('rss_mb'))} | {fmt(r.get('limit_rss_mb'))} | "
                 f"{fmt(rl)} | {'yes' if rl is not None and rl <= 1.3 else 'no'} | "
                 f"{fmt(first.get('assemble'))} / {fmt(first.get('solve'))} / {fmt(first.get('write'))} | "
                 f"{fmt(med('assemble'))} / {fmt(med('solve'))} / {fmt(med('write'))} |")
    out.write_text("\n".join(L) + "\n")
    print("\n".join(L))
    log(f"wrote {out} and {out.with_suffix('.json')}")
    return 0


# ----------------------------------------------------------------- friction
PUNCH_TOML = """# A floating punch held tangentially by Coulomb friction alone (bench.py --friction).
[mesh]
file = "MESH"
[model]
plane = "strain"
[materials.foundation]
E = 2.0e10
nu = 0.3
[materials.punch]
E = 2.0e11
nu = 0.3
[[dirichlet]]
on = "found_bottom"
u = [0.0, 0.0]
[[dirichlet]]
on = "found_sides"
ux = 0.0
[[traction]]
on = "punch_top"
pn = -1.0e6
SIDE[[contact]]
slave = "punch_bottom"
master = "found_top"
FRICTION
[solver]
tol = 1.0e-10
"""
PUNCH_SIDE = '[[traction]]\non = "punch_left"\np = [2.0e5, 0.0]\n'
SHEARED_TOML = """# meshes/two_blocks with the upper block held only by the contact, pressed
# and sheared by a traction on top in four load steps (bench.py --friction-scale).
[mesh]
file = "MESH"
[model]
plane = "strain"
[materials.lower]
E = 2.0e9
nu = 0.25
[materials.upper]
E = 2.0e9
nu = 0.25
[[dirichlet]]
on = "bottom"
u = [0.0, 0.0]
[[slip]]
on = "left_lower"
[[slip]]
on = "right_lower"
[[traction]]
on = "top"
p = [1.0e5, -1.0e6]
[[contact]]
on = "interface"
FRICTION
[[steps]]
factor = 0.25
[[steps]]
factor = 0.5
[[steps]]
factor = 0.75
[[steps]]
factor = 1.0
"""
# model: (geo, gmsh arguments per level). The first three levels of punch
# and nafems1 are those of --friction; --friction-scale runs the families
# of FRICTION_SCALE at about 10 k, 50 k and 200 k nodes.
FRICTION_MODELS = {
    "punch": ("tests/data/friction/floating_punch.geo", [["-clscale", "1.0"], ["-clscale", "0.45"], ["-clscale", "0.2"]]),
    "nafems1": ("verification/nafems1/nafems1.geo",
                [["-clscale", "0.5"], ["-clscale", "0.25"], ["-clscale", "0.15"],
                 ["-clscale", "0.43"], ["-clscale", "0.19"], ["-clscale", "0.097"]]),
    "shrinkfit": ("scripts/bench_models/shrinkfit_push.geo",
                  [None, None, None, ["-setnumber", "nz", "400", "-setnumber", "nr", "12"],
                   ["-setnumber", "nz", "800", "-setnumber", "nr", "31"],
                   ["-setnumber", "nz", "1600", "-setnumber", "nr", "62"]]),
    "sheared": ("meshes/two_blocks.geo", [None, None, None, ["-clscale", "0.2"], ["-clscale", "0.1"], ["-clscale", "0.05"]]),
}
FRICTION_SCALE = ("shrinkfit", "nafems1", "sheared")


def friction_toml(model: str, msh: Path, frictional: bool) -> str:
    if model == "punch":
        return (PUNCH_TOML.replace("MESH", msh.name)
                .replace("SIDE", PUNCH_SIDE if frictional else "")
                .replace("FRICTION", "friction = 0.3" if frictional else ""))
    if model == "sheared":
        # Frictionless: the upper block's sides slip instead of friction holding it.
        return (SHEARED_TOML.replace("MESH", msh.name)
                .replace("FRICTION", "friction = 0.12" if frictional else
                         '[[slip]]\non = "left_upper"\n[[slip]]\non = "right_upper"'))
    if model == "shrinkfit":
        text = (ROOT / "scripts" / "bench_models" / "shrinkfit_push.toml").read_text()
        text = text.replace('file = "shrinkfit_push.msh"', f'file = "{msh.name}"')
        return text if frictional else text.replace("friction = 0.2\n", "")
    text = (ROOT / "verification" / "nafems1" / "nafems1_mu.toml").read_text()
    text = text.replace('file = "nafems1.msh"', f'file = "{msh.name}"')
    text = text[: text.index("[[steps]]")] + "".join(f"[[steps]]\nfactor = {k / 10!r}\n\n" for k in range(1, 11))
    if not frictional:
        text = text.replace("friction = 0.1\n", "")
    return text


def friction_once(binary, toml: Path, method: str, outdir: Path, timeout):
    """One `signorini solve`: whole-process wall time, and the solve time,
    Newton steps and inner iterations summed over the load steps."""
    if outdir.exists():
        shutil.rmtree(outdir)
    rc, _, err, wall = run([binary, "solve", toml, "--out", outdir, "--method", method, "--quiet"], timeout=timeout)
    r = {"exit": rc, "wall": wall}
    js = list(outdir.glob("*.json")) if outdir.exists() else []
    if rc not in (0, 3) or not js:
        r["status"] = "timeout" if rc is None else f"exit {rc}: {err.strip().splitlines()[-1] if err.strip() else ''}"
        return r
    d = json.loads(js[0].read_text())
    steps = d.get("steps") or [{"iterations": d["iterations"], "inner_iterations": d["inner_iterations"],
                                "time_solve": d["timings_s"]["solve"]}]
    r.update(status=d["status"], converged=d["converged"], certified=d["kkt"]["certified"],
             friction_residual=d["kkt"].get("friction"), dofs=d["dofs"], m=d["constraints"], nodes=d["mesh_nodes"],
             nsteps=len(steps), newton=sum(s["iterations"] for s in steps),
             inner=sum(s["inner_iterations"] for s in steps), solve=sum(s["time_solve"] for s in steps),
             total=d["timings_s"]["total"], energy=d["energy"])
    return r


def run_friction(args, binary, work: Path) -> int:
    """The friction table (issue 36): ssn vs mprgp vs frictionless ssn."""
    levels = [int(v) for v in args.friction_levels.split(",") if v.strip()]
    models = FRICTION_SCALE if args.friction_scale else ("punch", "nafems1")
    if args.friction_models:
        models = [m for m in args.friction_models.split(",") if m]
    if args.friction_scale:
        levels = [3 + lv for lv in levels]
    methods = [m for m in args.friction_methods.split(",") if m]
    rows = []
    for model in models:
        geo, scales = FRICTION_MODELS[model]
        for lv in levels:
            s = scales[lv]
            if s is None:
                continue
            msh = work / f"friction_{model}_{lv}.msh"
            if not msh.exists():
                rc, _, err, _ = run([args.gmsh, "-2", "-format", "msh41", "-bin", *s, ROOT / geo, "-o", msh])
                if rc != 0:
                    raise RuntimeError(f"gmsh failed on {geo}: {err[-500:]}")
            for method, frictional in [(m, True) for m in methods] + [("ssn", False)]:
                toml = work / f"friction_{model}_{lv}_{'mu' if frictional else 'nomu'}.toml"
                toml.write_text(friction_toml(model, msh, frictional))
                variant = method if frictional else "ssn, frictionless"
                r = repeated(lambda: friction_once(binary, toml, method, work / "out_friction", max(4 * args.budget, 120.0)),
                             args.repeats, args.long)
                row = {"model": model, "level": lv, "gmsh": " ".join(s), "variant": variant, **r}
                rows.append(row)
                log(f"friction {model} level {lv} ({r.get('nodes')} nodes) {variant}: {fmt(r.get('wall'))} s, "
                    f"Newton {r.get('newton')}, inner {r.get('inner')}, {r.get('status')}")
    out = Path(args.friction_out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps({"machine": machine(), "cmdline": "python3 scripts/bench.py " + " ".join(sys.argv[1:]),
                                                    "rows": rows}, indent=1, default=str))
    head = ("Friction at scale (issue 42 §2): the shrink fit pushed out (scripts/bench_models/shrinkfit_push.toml: "
            "axisymmetric, NTS 5:4, mu 0.2, 6 load steps), NAFEMS 1 (mu 0.1, 10 load steps) and the sheared blocks "
            "(two_blocks, the upper block held by friction mu 0.12 alone, 4 load steps; frictionless: its sides slip "
            "instead) at about 10 k, 50 k and 200 k nodes"
            if args.friction_scale else
            "Friction (issue 36): a floating punch held by Coulomb friction alone (mu 0.3, 1 step) and NAFEMS 1 "
            "(mu 0.1, 10 load steps)")
    L = [head + "; whole process wall time (median of the repeats), solve time, Newton steps and "
         "inner iterations summed over the steps; ratio = wall ÷ the frictionless ssn run on the same mesh "
         "(target ssn ≤ 3, and ssn never slower than mprgp).\n",
         "| model | nodes | DOFs | rows | variant | wall [s] | solve [s] | Newton | inner | ÷ frictionless | status |",
         "|---|---|---|---|---|---|---|---|---|---|---|"]
    base = {(r["model"], r["level"]): r.get("wall") for r in rows if r["variant"] == "ssn, frictionless"}
    for r in rows:
        b = base.get((r["model"], r["level"]))
        ratio = r["wall"] / b if b and r.get("wall") and r.get("converged") else None
        st = r.get("status", "")
        if r.get("converged"):
            st = "certified" if r.get("certified") else "uncertified"
        L.append(f"| {r['model']} | {r.get('nodes', '–')} | {r.get('dofs', '–')} | {r.get('m', '–')} | {r['variant']} | "
                 f"{fmt(r.get('wall'))} | {fmt(r.get('solve'))} | {r.get('newton', '–')} | {r.get('inner', '–')} | "
                 f"{fmt(ratio, 2) if ratio else '–'} | {st} |")
    out.write_text("\n".join(L) + "\n")
    print("\n".join(L))
    log(f"wrote {out} and {out.with_suffix('.json')}")
    return 0


# ----------------------------------------------------------------- mu scan
FAULTS = ("fault_cont_base", "fault_subduction", "fault_ocean_base")


def mu_scan_toml(mu) -> str:
    """meshes/geodynamic_steps.toml with Coulomb friction mu on its three
    faults (None: frictionless), the mesh path made absolute."""
    text = (ROOT / "meshes" / "geodynamic_steps.toml").read_text()
    text = text.replace('file = "geodynamic.msh"', f'file = "{ROOT / "meshes" / "geodynamic.msh"}"')
    if mu is not None:
        for f in FAULTS:
            text = text.replace(f'on = "{f}"\n', f'on = "{f}"\nfriction = {mu}\n')
    return text


def run_mu_scan(args, binary, work: Path) -> int:
    """The mu scan (issue 42 §1): the geodynamic load-step model with Coulomb
    friction on its faults, by ssn and mprgp, against the frictionless run."""
    mus = [float(v) for v in args.mu_scan.split(",") if v.strip()]
    rows = []
    work.mkdir(parents=True, exist_ok=True)
    for mu in [None] + mus:
        toml = work / f"mu_scan_{mu}.toml"
        toml.write_text(mu_scan_toml(mu))
        for method in (("ssn",) if mu is None else ("ssn", "mprgp")):
            r = repeated(lambda: friction_once(binary, toml, method, work / "out_mu_scan", max(4 * args.budget, 120.0)),
                         args.repeats, args.long)
            rows.append({"mu": mu, "method": method, **r})
            log(f"mu scan mu = {mu} {method}: {fmt(r.get('wall'))} s, Newton {r.get('newton')}, {r.get('status')}")
    out = Path(args.mu_scan_out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps({"machine": machine(), "cmdline": "python3 scripts/bench.py " + " ".join(sys.argv[1:]),
                                                    "rows": rows}, indent=1, default=str))
    base = next((r.get("wall") for r in rows if r["mu"] is None), None)
    L = ["Coulomb friction on the geodynamic step model (meshes/geodynamic_steps.toml, 5 load steps, friction = mu on "
         "its three faults; issue 42 §1): whole-process wall time (median of the repeats), iterations summed over the "
         "steps, ratio = wall ÷ the frictionless ssn run (target ≤ 15), status over every step.\n",
         "| mu | method | wall [s] | iterations | ÷ frictionless | status |",
         "|---|---|---|---|---|---|"]
    for r in rows:
        ratio = r["wall"] / base if base and r.get("wall") else None
        st = r.get("status", "")
        if "converged" in r:
            st = "every step certified" if r.get("converged") and r.get("certified") else "NOT certified"
        L.append(f"| {r['mu'] if r['mu'] is not None else '0 (frictionless)'} | {r['method']} | {fmt(r.get('wall'))} | "
                 f"{r.get('newton', '–')} | {fmt(ratio, 2) if ratio else '–'} | {st} |")
    out.write_text("\n".join(L) + "\n")
    print("\n".join(L))
    log(f"wrote {out} and {out.with_suffix('.json')}")
    return 0


# ----------------------------------------------------------------- main
def main() -> int:
    if "--solid" in sys.argv[1:]:
        sys.path.insert(0, str(Path(__file__).resolve().parent))
        import bench_solid
        return bench_solid.main([a for a in sys.argv[1:] if a != "--solid"])
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="10k,100k,400k,1m,three_bodies:2m",
                    help="comma list of sizes (" + ",".join(SIZES) + "); FAMILY:SIZE runs that size for that family only")
    ap.add_argument("--families", default="three_bodies,hertz,rollers")
    ap.add_argument("--methods", default="", help="comma list of variants (e.g. mprgp,ssn,cgc+cholesky); default all")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--long", type=float, default=60.0, help="runs longer than this are not repeated")
    ap.add_argument("--budget", type=float, default=600.0, help="skip a run predicted to take longer [s]")
    ap.add_argument("--peers", default="clarabel,osqp",
                    help="peer solvers on the exported QP, comma-separated; 'none' (or '') for none")
    ap.add_argument("--no-fenicsx", action="store_true")
    ap.add_argument("--work", default=str(ROOT / "bench"))
    ap.add_argument("--out", default=str(ROOT / "BENCHMARKS.md"))
    ap.add_argument("--binary", default=str(ROOT / "target" / "release" / "signorini"))
    ap.add_argument("--gmsh", default="gmsh")
    ap.add_argument("--steps", type=int, default=0, metavar="N",
                    help="run the load-step table instead (N steps per model; see the module doc)")
    ap.add_argument("--steps-out", default=str(ROOT / "bench" / "steps.md"))
    ap.add_argument("--friction", action="store_true",
                    help="run the friction table instead (see the module doc)")
    ap.add_argument("--friction-levels", default="0,1,2",
                    help="mesh levels of the friction table (0, 1, 2: coarse to fine)")
    ap.add_argument("--friction-out", default=str(ROOT / "bench" / "friction.md"))
    ap.add_argument("--friction-scale", action="store_true",
                    help="with --friction: the families of issue 42 §2 (shrink fit push-out, NAFEMS 1, sheared "
                         "blocks) at about 10 k, 50 k, 200 k nodes (--friction-levels 0,1,2)")
    ap.add_argument("--friction-models", default="",
                    help="comma list of friction models to run (default: punch,nafems1; with --friction-scale "
                         "shrinkfit,nafems1,sheared)")
    ap.add_argument("--friction-methods", default="ssn,mprgp",
                    help="frictional variants of --friction (frictionless ssn always runs)")
    ap.add_argument("--mu-scan", default="",
                    help="comma list of mu: run the geodynamic mu scan (issue 42 §1) instead, e.g. 0.05,0.1,0.15,0.2,0.3,0.6")
    ap.add_argument("--mu-scan-out", default=str(ROOT / "bench" / "mu_scan.md"))
    ap.add_argument("--report-only", metavar="JSON",
                    help="run nothing: rewrite --out from the raw results of an earlier run (its JSON)")
    ap.add_argument("--check", action="store_true",
                    help="exit 1 unless every method run converged with a certificate and every peer and FEniCSx ran (CI)")
    args = ap.parse_args()
    cmdline = "python3 scripts/bench.py " + " ".join(sys.argv[1:])
    if args.report_only:
        res = json.loads(Path(args.report_only).read_text())
        old = argparse.Namespace(**res["args"])
        write_report(Path(args.out), res, old, res.get("cmdline", cmdline))
        log(f"wrote {args.out} from {args.report_only}")
        return 0

    binary = args.binary
    if not Path(binary).is_file():
        print(f"bench: {binary} not found; build with cargo build --release", file=sys.stderr)
        return 2
    if shutil.which(args.gmsh) is None:
        print("bench: gmsh not found (apt-get install gmsh)", file=sys.stderr)
        return 2
    if not Path("/usr/bin/time").exists():
        print("bench: /usr/bin/time not found (apt-get install time)", file=sys.stderr)
        return 2
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    venv_py = ROOT / ".venv" / "bin" / "python"
    size_spec = []  # (family or None, size)
    for s in [s.strip() for s in args.sizes.split(",") if s.strip()]:
        fam_only, _, s = s.rpartition(":")
        s = s.lower()
        size_spec.append((fam_only or None, s))
        if s not in SIZES:
            print(f"bench: unknown size {s}; known: {', '.join(SIZES)}", file=sys.stderr)
            return 2
    if args.steps > 0:
        return run_steps(args, binary, work, size_spec)
    if args.friction:
        return run_friction(args, binary, work)
    if args.mu_scan:
        return run_mu_scan(args, binary, work)
    vs = variants(binary)
    if args.methods:
        want = [m.strip() for m in args.methods.split(",")]
        vs = [v for v in vs if vname(v) in want or v[0] in want]
    peers = [p for p in args.peers.split(",") if p and p != "none"]
    res = {"machine": machine(), "families": {}, "args": vars(args), "cmdline": cmdline}
    raw = Path(args.out).with_suffix(".json")
    res["raw"] = raw.name

    for fam in [f.strip() for f in args.families.split(",") if f.strip()]:
        fres = {"sizes": []}
        res["families"][fam] = fres
        history = {vname(v): [] for v in vs}
        failed = {}
        peer_hist = {p: [] for p in peers}
        sizes = [s for f, s in sorted(size_spec, key=lambda fs: SIZES[fs[1]]) if f in (None, fam)]
        for size in sizes:
            target = SIZES[size]
            log(f"{fam} {size}: meshing")
            msh, nodes, gmsh_s = make_mesh(fam, target, work, args.gmsh)
            toml = make_toml(fam, msh, work)
            srec = {"size": size, "nodes": nodes, "gmsh_s": gmsh_s, "methods": {}}
            fres["sizes"].append(srec)

            log(f"{fam} {size}: limit")

            def limit_once():
                tf = work / "limit.time"
                rc, out, err, wall = run(["/usr/bin/time", "-v", "-o", tf, binary, "limit", toml])
                if rc != 0:
                    return {"status": f"exit {rc}: {err.strip()[-300:]}"}
                d = json.loads(out.strip().splitlines()[-1])
                d["rss_mb"] = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", tf.read_text()).group(1)) / 1024
                d["total"] = d["t_factor_solve"]
                d["wall"] = wall
                return d

            srec["limit"] = repeated(limit_once, args.repeats, args.long)
            n = srec["limit"].get("n", nodes * 2)
            log(f"  limit: factor {fmt(srec['limit'].get('t_factor'))} s, solve {fmt(srec['limit'].get('t_solve'))} s")

            best = None
            for v in vs:
                nm = vname(v)
                if nm in failed:
                    srec["methods"][nm] = {"skipped": failed[nm]}
                    log(f"  {nm}: skipped ({failed[nm]})")
                    continue
                pr = predict(history[nm], n)
                if pr is not None and pr > args.budget:
                    why = f"predicted {pr:.0f} s > budget {args.budget:.0f} s (from smaller sizes)"
                    srec["methods"][nm] = {"skipped": why}
                    log(f"  {nm}: skipped ({why})")
                    continue
                timeout = max(2 * args.budget, 60.0)
                r = repeated(lambda: solve_once(binary, toml, v, work / "out", timeout), args.repeats, args.long)
                srec["methods"][nm] = r
                srec["m"] = r.get("m", srec.get("m"))
                log(f"  {nm}: {r.get('status')} it {r.get('iterations')} solve {fmt(r.get('solve'))} s total {fmt(r.get('total'))} s RSS {fmt(r.get('rss_mb'))} MB")
                if r.get("converged"):
                    history[nm].append((n, r["solve"]))
                    if best is None or r["solve"] < best["solve"]:
                        best = dict(r, name=nm)
                else:
                    failed[nm] = f"did not converge at {size} ({r.get('status')})"
            srec["best"] = best

            if best and best.get("total", math.inf) <= args.budget:
                # output writing, compressed vs not (two more solves: not
                # when one is longer than the budget)
                bv = next(v for v in vs if vname(v) == best["name"])
                plain = solve_once(binary, toml, bv, work / "out_plain", None)
                mb_plain = sum(f.stat().st_size for f in (work / "out_plain").iterdir()) / 2**20
                zl = solve_once(binary, toml, bv, work / "out_zlib", None, extra=["--compress"])
                mb_zlib = sum(f.stat().st_size for f in (work / "out_zlib").iterdir()) / 2**20
                srec["compress"] = {"method": best["name"], "write_plain": plain.get("write"), "write_zlib": zl.get("write"),
                                    "mb_plain": mb_plain, "mb_zlib": mb_zlib}
                log(f"  write: {fmt(plain.get('write'))} s plain, {fmt(zl.get('write'))} s zlib")

            # peers
            if peers and best:
                qpdir = work / f"qp_{fam}_{size}"
                if qpdir.exists():
                    shutil.rmtree(qpdir)
                rc, out, err, wall = run([binary, "export", "--qp", qpdir, toml, "--solution", "--method", best["name"].split("+")[0]]
                                         + (["--preconditioner", best["name"].split("+")[1]] if "+" in best["name"] else []))
                plist = []
                if rc != 0:
                    log(f"  export failed: {err.strip()[-300:]}")
                else:
                    for p in peers:
                        pr = predict(peer_hist[p], n)
                        if pr is not None and pr > args.budget:
                            plist.append({"solver": p, "skipped": f"predicted {pr:.0f} s > budget {args.budget:.0f} s"})
                            log(f"  {p}: skipped (predicted {pr:.0f} s)")
                            continue
                        pj = work / f"peer_{p}.json"
                        if pj.exists():
                            pj.unlink()
                        reps = args.repeats if not peer_hist[p] or peer_hist[p][-1][1] * (n / peer_hist[p][-1][0]) < args.long else 1
                        rc, out, err, wall = run([venv_py, ROOT / "scripts" / "bench_peers.py", qpdir, "--solvers", p,
                                                  "--time-limit", str(args.budget), "--repeats", str(reps), "--json", pj],
                                                 timeout=reps * (2 * args.budget + 60) + 180)
                        if pj.exists():
                            d = json.loads(pj.read_text())
                            d = d[0] if isinstance(d, list) and d else d
                            plist.append(d)
                            if d.get("t_total"):
                                peer_hist[p].append((n, d["t_total"]))
                            log(f"  {p}: {d.get('status')} {fmt(d.get('t_total'))} s")
                        else:
                            plist.append({"solver": p, "status": f"failed (exit {rc}): {(err or '').strip()[-200:]}"})
                            log(f"  {p}: failed {(err or '').strip()[-200:]}")
                    shutil.rmtree(qpdir, ignore_errors=True)
                srec["peers"] = plist

            # linear elastic: signorini --no-contact and FEniCSx (glued contact curves)
            if fam == "three_bodies":
                lin = repeated(lambda: solve_once(binary, toml, ("ssn", None), work / "out_lin", None, extra=["--no-contact"]),
                               args.repeats, args.long)
                lin["method"] = "ssn"
                srec["linear"] = lin
                if not args.no_fenicsx:
                    fj = work / "fenicsx.json"
                    if fj.exists():
                        fj.unlink()
                    # once when the previous size already took longer than --long
                    fx_prev = fres.get("fenicsx_prev")
                    fx_reps = 1 if fx_prev and fx_prev[1] * (n / fx_prev[0]) > args.long else args.repeats
                    rc, out, err, wall = run(["/usr/bin/python3", ROOT / "scripts" / "bench_fenicsx.py", toml,
                                              "--repeats", str(fx_reps), "--json", fj],
                                             timeout=args.budget * (args.repeats + 1) + 300)
                    if fj.exists():
                        srec["fenicsx"] = json.loads(fj.read_text())
                        if srec["fenicsx"].get("t_total"):
                            fres["fenicsx_prev"] = (n, srec["fenicsx"]["t_total"])
                        log(f"  fenicsx: total {fmt(srec['fenicsx'].get('t_total'))} s")
                    else:
                        srec["fenicsx"] = {"status": f"failed (exit {rc}): {(err or '').strip()[-300:]}"}
                        log(f"  fenicsx failed: {(err or '').strip()[-300:]}")
            raw.write_text(json.dumps(res, indent=1, default=str))
            write_report(Path(args.out), res, args, cmdline)
    raw.write_text(json.dumps(res, indent=1, default=str))
    write_report(Path(args.out), res, args, cmdline)
    log(f"wrote {args.out} and {raw}")
    if args.check:
        bad = []
        for fam, fres in res["families"].items():
            for s in fres["sizes"]:
                if not (s.get("limit") or {}).get("t_factor"):
                    bad.append(f"{fam} {s['size']}: limit failed")
                for nm, r in s["methods"].items():
                    if "skipped" in r:
                        continue
                    if nm == "penalty":
                        # Inexact by definition: λ = (Ax − g)⁺/ε_p is
                        # stationary, feasibility and complementarity are
                        # O(ε_p) (README, methods table), as in tests/compare.rs.
                        st = (r.get("kkt") or {}).get("stationarity")
                        if not (r.get("converged") and st is not None and st <= 1e-6):
                            bad.append(f"{fam} {s['size']} {nm}: {r.get('status')}, KKT {r.get('kkt')}")
                    elif not (r.get("converged") and r.get("certified")):
                        bad.append(f"{fam} {s['size']} {nm}: {r.get('status')}")
                for p in s.get("peers") or []:
                    if "skipped" not in p and not p.get("converged"):
                        bad.append(f"{fam} {s['size']} {p.get('solver')}: {p.get('status')}")
                fx = s.get("fenicsx")
                if fam == "three_bodies" and not args.no_fenicsx and not (fx and fx.get("t_total")):
                    bad.append(f"{fam} {s['size']} fenicsx: {(fx or {}).get('status')}")
        for b in bad:
            print(f"bench --check: {b}", file=sys.stderr)
        return 1 if bad else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
