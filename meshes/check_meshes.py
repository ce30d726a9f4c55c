#!/usr/bin/env python3
"""Consistency check of the shipped example models (pure standard library).

Usage:  python3 check_meshes.py [model.toml ...]      (default: all *.toml here)

For each problem file it reads the ASCII Gmsh 4.1 mesh it names and checks:
  * only first-order elements (points, 2-node lines, 3-node triangles);
  * every triangle lies in a physical surface, and every physical surface
    name is a [materials.NAME] key (and vice versa);
  * no orphan nodes (nodes not used by any triangle), no two distinct nodes
    at the same coordinates inside one body, positive triangle orientation;
  * every name used by the TOML exists with a suitable dimension;
  * bodies = connected triangle sets after cutting along the conforming
    contact curves; each conforming curve has exactly two triangles on each
    segment, from two different bodies (so both sides share its nodes);
  * non-matching pairs: slave and master are boundary curves of two
    different bodies without shared nodes; the initial normal gap of the
    slave nodes is reported;
  * boundary-condition curves lie on the boundary of the mesh;
  * probes lie inside the mesh.
Prints a summary per model and exits non-zero if any check failed.
"""
import math
import os
import sys
import tomllib

HERE = os.path.dirname(os.path.abspath(__file__))


class Msh:
    def __init__(self, path):
        self.names = {}        # (dim, tag) -> name
        self.ent_phys = {}     # (dim, entity tag) -> [phys tags]
        self.nodes = {}        # tag -> (x, y)
        self.elems = []        # (type, entity dim, entity tag, [node tags])
        with open(path) as f:
            lines = f.read().split("\n")
        i = 0
        while i < len(lines):
            s = lines[i].strip()
            if s == "$MeshFormat":
                ver, ftype = lines[i + 1].split()[:2]
                if ver != "4.1" or ftype != "0":
                    raise ValueError(f"{path}: not ASCII msh 4.1 ({ver}, {ftype})")
                i += 2
            elif s == "$PhysicalNames":
                n = int(lines[i + 1])
                for k in range(n):
                    parts = lines[i + 2 + k].split(maxsplit=2)
                    self.names[(int(parts[0]), int(parts[1]))] = parts[2].strip('"')
                i += 2 + n
            elif s == "$Entities":
                counts = [int(v) for v in lines[i + 1].split()]
                i += 2
                for dim in range(4):
                    for _ in range(counts[dim]):
                        v = lines[i].split()
                        tag = int(v[0])
                        k = 4 if dim == 0 else 7
                        nphys = int(v[k])
                        self.ent_phys[(dim, tag)] = [abs(int(t)) for t in v[k + 1:k + 1 + nphys]]
                        i += 1
            elif s == "$Nodes":
                nblocks = int(lines[i + 1].split()[0])
                i += 2
                for _ in range(nblocks):
                    _, _, param, n = (int(v) for v in lines[i].split())
                    if param:
                        raise ValueError("parametric nodes not supported by this check")
                    tags = [int(lines[i + 1 + k]) for k in range(n)]
                    for k in range(n):
                        x, y, _z = (float(v) for v in lines[i + 1 + n + k].split())
                        self.nodes[tags[k]] = (x, y)
                    i += 1 + 2 * n
            elif s == "$Elements":
                nblocks = int(lines[i + 1].split()[0])
                i += 2
                for _ in range(nblocks):
                    edim, etag, etype, n = (int(v) for v in lines[i].split())
                    for k in range(n):
                        v = [int(t) for t in lines[i + 1 + k].split()]
                        self.elems.append((etype, edim, etag, v[1:]))
                    i += 1 + n
            else:
                i += 1

    def phys_names(self, dim, etag):
        return [self.names.get((dim, p), f"#{p}") for p in self.ent_phys.get((dim, etag), [])]


class UF:
    def __init__(self, n):
        self.p = list(range(n))

    def find(self, a):
        while self.p[a] != a:
            self.p[a] = self.p[self.p[a]]
            a = self.p[a]
        return a

    def union(self, a, b):
        a, b = self.find(a), self.find(b)
        if a != b:
            self.p[max(a, b)] = min(a, b)


def seg_point_dist(p, a, b):
    ax, ay = a
    bx, by = b
    dx, dy = bx - ax, by - ay
    L2 = dx * dx + dy * dy
    t = 0.0 if L2 == 0 else max(0.0, min(1.0, ((p[0] - ax) * dx + (p[1] - ay) * dy) / L2))
    qx, qy = ax + t * dx, ay + t * dy
    return math.hypot(p[0] - qx, p[1] - qy), (qx, qy)


def check(toml_path):
    errors, notes = [], []
    with open(toml_path, "rb") as f:
        prob = tomllib.load(f)
    msh_path = os.path.join(os.path.dirname(toml_path), prob["mesh"]["file"])
    m = Msh(msh_path)
    name = os.path.basename(toml_path)

    bad_types = {e[0] for e in m.elems} - {1, 2, 15}
    if bad_types:
        errors.append(f"element types other than point/line/triangle: {sorted(bad_types)}")

    # physical groups by name
    groups = {}  # name -> dim
    for (dim, _tag), nm in m.names.items():
        if nm in groups and groups[nm] != dim:
            errors.append(f"name '{nm}' used for two dimensions")
        groups[nm] = dim
    curve_segs = {}   # name -> list of (a, b)
    point_nodes = {}  # name -> list of node tags
    tris, tri_mat = [], []
    for etype, edim, etag, conn in m.elems:
        names = m.phys_names(edim, etag)
        if etype == 2:
            if not names:
                errors.append(f"triangle in surface {etag} without physical surface")
            tris.append(conn)
            tri_mat.append(names[0] if names else None)
        elif etype == 1:
            for nm in names:
                curve_segs.setdefault(nm, []).append(tuple(conn))
        elif etype == 15:
            for nm in names:
                point_nodes.setdefault(nm, []).extend(conn)

    # materials <-> physical surfaces
    surf_names = {nm for (d, _), nm in m.names.items() if d == 2}
    mats = set(prob.get("materials", {}).keys())
    if surf_names - mats:
        errors.append(f"physical surfaces without material: {sorted(surf_names - mats)}")
    if mats - surf_names:
        errors.append(f"materials without physical surface: {sorted(mats - surf_names)}")

    # nodes
    used = set(n for t in tris for n in t)
    orphans = set(m.nodes) - used
    if orphans:
        errors.append(f"{len(orphans)} orphan nodes (not in any triangle), e.g. {sorted(orphans)[:5]}")
    neg = 0
    for t in tris:
        (x1, y1), (x2, y2), (x3, y3) = (m.nodes[n] for n in t)
        a2 = (x2 - x1) * (y3 - y1) - (x3 - x1) * (y2 - y1)
        if a2 <= 0:
            neg += 1
    if neg:
        notes.append(f"{neg} triangles clockwise / degenerate")

    # edges -> triangles
    edge_tris = {}
    for k, t in enumerate(tris):
        for a, b in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0])):
            edge_tris.setdefault(frozenset((a, b)), []).append(k)
    for e, ts in edge_tris.items():
        if len(ts) > 2:
            errors.append(f"edge {sorted(e)} shared by {len(ts)} triangles")

    # names used in the TOML
    def need(nm, dims, what):
        if nm not in groups:
            errors.append(f"{what}: physical group '{nm}' not in mesh")
            return False
        if groups[nm] not in dims:
            errors.append(f"{what}: '{nm}' has dimension {groups[nm]}, expected {dims}")
            return False
        return True

    conf_curves, nm_pairs = [], []
    for c in prob.get("contact", []):
        if "on" in c:
            if need(c["on"], (1,), "contact"):
                conf_curves.append(c["on"])
        else:
            if need(c["slave"], (1,), "contact slave") and need(c["master"], (1,), "contact master"):
                nm_pairs.append((c["slave"], c["master"]))
    for sec, dims in (("dirichlet", (0, 1)), ("traction", (1,)), ("slip", (1,)), ("force", (0,))):
        for c in prob.get(sec, []):
            need(c["on"], dims, sec)

    # bodies: cut along conforming contact curves
    cut = set()
    for nm in conf_curves:
        for a, b in curve_segs.get(nm, []):
            cut.add(frozenset((a, b)))
    uf = UF(len(tris))
    for e, ts in edge_tris.items():
        if len(ts) == 2 and e not in cut:
            uf.union(ts[0], ts[1])
    roots = sorted({uf.find(k) for k in range(len(tris))},
                   key=lambda r: min(n for k in range(len(tris)) if uf.find(k) == r for n in tris[k]))
    # number bodies by lowest node tag (as the solver does)
    body_of_root = {r: i + 1 for i, r in enumerate(roots)}
    tri_body = [body_of_root[uf.find(k)] for k in range(len(tris))]
    body_nodes = {}
    for k, t in enumerate(tris):
        body_nodes.setdefault(tri_body[k], set()).update(t)
    body_mats = {}
    for k in range(len(tris)):
        body_mats.setdefault(tri_body[k], set()).add(tri_mat[k])

    # duplicated coordinates inside a body (would mean a non-conforming seam)
    for b, ns in body_nodes.items():
        seen = {}
        for n in ns:
            key = (round(m.nodes[n][0], 9), round(m.nodes[n][1], 9))
            if key in seen:
                errors.append(f"body {b}: nodes {seen[key]} and {n} at the same point {key}")
            seen[key] = n

    def seg_body(seg):
        return [tri_body[k] for k in edge_tris.get(frozenset(seg), [])]

    contact_info = []
    for nm in conf_curves:
        pairs = set()
        for seg in curve_segs.get(nm, []):
            bs = seg_body(seg)
            if len(bs) != 2 or bs[0] == bs[1]:
                errors.append(f"contact '{nm}': segment {seg} has adjacent bodies {bs}")
                break
            pairs.add(tuple(sorted(bs)))
        nn = len({n for s in curve_segs.get(nm, []) for n in s})
        contact_info.append(f"'{nm}': {len(curve_segs.get(nm, []))} segs, {nn} shared nodes, bodies {sorted(pairs)}")
    for sl, ma in nm_pairs:
        sb = {b for s in curve_segs[sl] for b in seg_body(s)}
        mb = {b for s in curve_segs[ma] for b in seg_body(s)}
        for s in curve_segs[sl] + curve_segs[ma]:
            if len(seg_body(s)) != 1:
                errors.append(f"non-matching curve segment {s} is not on the boundary")
                break
        if len(sb) != 1 or len(mb) != 1 or sb == mb:
            errors.append(f"pair {sl}/{ma}: slave bodies {sb}, master bodies {mb}")
        sn = {n for s in curve_segs[sl] for n in s}
        mn = {n for s in curve_segs[ma] for n in s}
        if sn & mn:
            errors.append(f"pair {sl}/{ma}: shared nodes {sorted(sn & mn)[:5]}")
        gaps = []
        for n in sn:
            p = m.nodes[n]
            d = min(seg_point_dist(p, m.nodes[a], m.nodes[b])[0] for a, b in curve_segs[ma])
            gaps.append(d)
        hs = [math.dist(m.nodes[a], m.nodes[b]) for a, b in curve_segs[sl]]
        hm = [math.dist(m.nodes[a], m.nodes[b]) for a, b in curve_segs[ma]]
        contact_info.append(
            f"'{sl}'->'{ma}': {len(sn)} slave nodes, {len(mn)} master nodes, gap min {min(gaps):.3g} "
            f"max {max(gaps):.3g}, slave h {min(hs):.3g}..{max(hs):.3g}, master h {min(hm):.3g}..{max(hm):.3g}")

    # BC curves on the boundary (or on a contact curve)
    supports = {}  # body -> set of kinds
    for sec in ("dirichlet", "slip", "traction"):
        for c in prob.get(sec, []):
            nm = c["on"]
            if groups.get(nm) == 1:
                for seg in curve_segs.get(nm, []):
                    bs = seg_body(seg)
                    if len(bs) == 2 and frozenset(seg) not in cut:
                        errors.append(f"{sec} '{nm}': segment {seg} is interior")
                        break
                    for b in bs:
                        supports.setdefault(b, set()).add(sec)
            elif groups.get(nm) == 0:
                for n in point_nodes.get(nm, []):
                    for b, ns in body_nodes.items():
                        if n in ns:
                            supports.setdefault(b, set()).add(sec + "(point)")

    # probes
    probe_info = []
    for pn, (px, py) in prob.get("output", {}).get("probes", {}).items():
        inside = None
        for k, t in enumerate(tris):
            (x1, y1), (x2, y2), (x3, y3) = (m.nodes[n] for n in t)
            d = (y2 - y3) * (x1 - x3) + (x3 - x2) * (y1 - y3)
            l1 = ((y2 - y3) * (px - x3) + (x3 - x2) * (py - y3)) / d
            l2 = ((y3 - y1) * (px - x3) + (x1 - x3) * (py - y3)) / d
            if min(l1, l2, 1 - l1 - l2) >= -1e-9:
                inside = tri_body[k]
                break
        nearest = min(m.nodes, key=lambda n: math.dist(m.nodes[n], (px, py)))
        dn = math.dist(m.nodes[nearest], (px, py))
        if inside is None:
            errors.append(f"probe {pn} outside the mesh")
        probe_info.append(f"{pn}=({px:g},{py:g}) body {inside}, nearest node {nearest} at {dn:.3g}")

    # report
    print(f"== {name}  (mesh {os.path.basename(msh_path)})")
    print(f"   nodes {len(m.nodes)}, triangles {len(tris)}, bodies {len(body_nodes)}")
    for b in sorted(body_nodes):
        print(f"   body {b}: {len(body_nodes[b])} nodes, materials {sorted(body_mats[b])}, "
              f"supports {sorted(supports.get(b, []))}")
    for s in contact_info:
        print(f"   contact {s}")
    for s in probe_info:
        print(f"   probe {s}")
    for s in notes:
        print(f"   note: {s}")
    for s in errors:
        print(f"   ERROR: {s}")
    return not errors


def main():
    files = sys.argv[1:] or sorted(
        os.path.join(HERE, f) for f in os.listdir(HERE) if f.endswith(".toml"))
    ok = True
    for f in files:
        try:
            ok &= check(f)
        except Exception as exc:  # noqa: BLE001
            print(f"== {os.path.basename(f)}\n   ERROR: {exc}")
            ok = False
    print("all checks passed" if ok else "SOME CHECKS FAILED")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
