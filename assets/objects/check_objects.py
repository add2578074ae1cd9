#!/usr/bin/env python3
"""Checks the primitive YCB object models in assets/objects (stdlib only).

Usage:  python3 assets/objects/check_objects.py

The reference's objects are ../ycb-meshes/SIZES.md: each one's true size (the smallest box
around its collision mesh in any orientation, sides sorted), mass and friction. For every
<Name>/model.urdf listed there this script measures the same true size of the collision
primitives (boxes, cylinders along their local z, spheres, each after its <origin xyz rpy>):
every side must be within max(10 %, 5 mm) of the table's. Mass and
<contact><lateral_friction> must equal the table. It also checks: robot name, a single link
`base_link`, axis-aligned bounding-box centre within 5 mm of the link origin, at most 8
primitives, every visual matched by an identical collision, every visual has a uniquely named
material with a colour, and no primitive thinner than 8 mm. Finally split.json must hold the
table's train/test lists. The same size, mass and friction check runs in the Rust unit tests
(src/assets/true_size.rs). Prints one row per object and exits non-zero on any failure.
"""
import json
import math
import os
import sys
import xml.etree.ElementTree as ET

HERE = os.path.dirname(os.path.abspath(__file__))
SIZES_MD = os.path.join(HERE, "..", "ycb-meshes", "SIZES.md")


def reference_table():
    """name: (true size in mm sorted, mass kg, mu, split), from SIZES.md."""
    table = {}
    with open(SIZES_MD, encoding="utf-8") as fh:
        for line in fh:
            if line.startswith("| Ycb"):
                cells = [c.strip() for c in line.split("|")]
                size = tuple(float(v) for v in cells[4].split("×"))
                table[cells[1]] = (size, float(cells[6]), float(cells[7]), cells[2])
    return table


TARGETS = reference_table()
MIN_THICKNESS_MM = 8.0
MAX_PRIMITIVES = 8


def rpy_matrix(r, p, y):
    """URDF fixed-axis roll-pitch-yaw: R = Rz(y) Ry(p) Rx(r), as a row-major 3x3 list."""
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]


def floats(s, n):
    v = [float(x) for x in s.split()]
    assert len(v) == n, s
    return v


def primitive(el):
    """(kind, dims, centre, rotation) of a <visual>/<collision> element."""
    o = el.find("origin")
    xyz = floats(o.get("xyz", "0 0 0"), 3) if o is not None else [0.0] * 3
    rpy = floats(o.get("rpy", "0 0 0"), 3) if o is not None else [0.0] * 3
    g = el.find("geometry")[0]
    if g.tag == "box":
        dims = floats(g.get("size"), 3)
    elif g.tag == "cylinder":
        dims = [float(g.get("radius")), float(g.get("length"))]
    elif g.tag == "sphere":
        dims = [float(g.get("radius"))]
    else:
        raise ValueError(f"unsupported geometry <{g.tag}>")
    return g.tag, dims, xyz, rpy_matrix(*rpy)


def half_extent(kind, dims, rot):
    """Exact half extents of the primitive's world AABB."""
    if kind == "box":
        return [sum(abs(rot[i][j]) * dims[j] / 2 for j in range(3)) for i in range(3)]
    if kind == "sphere":
        return [dims[0]] * 3
    r, length = dims  # cylinder: axis = third column of rot
    return [abs(rot[i][2]) * length / 2 + r * math.sqrt(max(0.0, 1 - rot[i][2] ** 2)) for i in range(3)]


def surface_points(kind, dims, xyz, rot):
    """Points that bound a primitive: a box's corners, two 64-point rings, a sphere's lattice."""
    if kind == "box":
        hx, hy, hz = [d / 2 for d in dims]
        local = [(sx * hx, sy * hy, sz * hz) for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
    elif kind == "cylinder":
        r, length = dims
        local = [(r * math.cos(a), r * math.sin(a), z)
                 for a in (2 * math.pi * k / 64 for k in range(64)) for z in (-length / 2, length / 2)]
    else:
        r, n = dims[0], 200
        local = []
        for k in range(n):
            z = 1 - 2 * (k + 0.5) / n
            ring, a = math.sqrt(1 - z * z), k * math.pi * (3 - math.sqrt(5))
            local.append((r * ring * math.cos(a), r * ring * math.sin(a), r * z))
    return [tuple(xyz[i] + sum(rot[i][j] * p[j] for j in range(3)) for i in range(3)) for p in local]


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def about(axis, angle):
    c, s = math.cos(angle), math.sin(angle)
    return [[[1, 0, 0], [0, c, -s], [0, s, c]], [[c, 0, s], [0, 1, 0], [-s, 0, c]],
            [[c, -s, 0], [s, c, 0], [0, 0, 1]]][axis]


def extents(points, rot):
    out = []
    for row in rot:
        d = [row[0] * p[0] + row[1] * p[1] + row[2] * p[2] for p in points]
        out.append(max(d) - min(d))
    return out


def true_size(prims):
    """Sides (m, sorted) of the smallest box around the primitives in any orientation: a greedy
    descent over rotations from many starts, as src/assets/true_size.rs does it."""
    points = [p for kind, dims, xyz, rot in prims for p in surface_points(kind, dims, xyz, rot)]
    starts = [about(2, 0.0)] + [[list(r) for r in zip(*rot)] for _, _, _, rot in prims]
    starts += [matmul(about(2, math.radians(y)), about(0, math.radians(p)))
               for y in range(0, 180, 30) for p in range(0, 180, 45)]
    best = None
    for rot in starts:
        sides = extents(points, rot)
        step = math.radians(10)
        while step > math.radians(0.1):
            improved = False
            for axis in range(3):
                for sign in (1, -1):
                    turned = matmul(about(axis, sign * step), rot)
                    turned_sides = extents(points, turned)
                    if math.prod(turned_sides) < math.prod(sides) - 1e-15:
                        rot, sides, improved = turned, turned_sides, True
            if not improved:
                step /= 2
        if best is None or math.prod(sides) < math.prod(best):
            best = sides
    return sorted(best)


def thickness(kind, dims):
    if kind == "box":
        return min(dims)
    if kind == "sphere":
        return 2 * dims[0]
    return min(2 * dims[0], dims[1])


def check(name, target):
    size_ref, mass_ref, mu_ref, _ = target
    problems = []
    root = ET.parse(os.path.join(HERE, name, "model.urdf")).getroot()
    if root.get("name") != name:
        problems.append(f"robot name {root.get('name')!r}")
    links = root.findall("link")
    if [l.get("name") for l in links] != ["base_link"]:
        problems.append("expected exactly one link named base_link")
    link = links[0]
    mass = float(link.find("inertial/mass").get("value"))
    fr = link.find("contact/lateral_friction")
    mu = float(fr.get("value")) if fr is not None else float("nan")
    if abs(mass - mass_ref) > 1e-9:
        problems.append(f"mass {mass} != {mass_ref}")
    if not abs(mu - mu_ref) <= 1e-9:
        problems.append(f"mu {mu} != {mu_ref}")

    visuals, collisions = link.findall("visual"), link.findall("collision")
    if len(collisions) > MAX_PRIMITIVES:
        problems.append(f"{len(collisions)} primitives > {MAX_PRIMITIVES}")
    if [primitive(v) for v in visuals] != [primitive(c) for c in collisions]:
        problems.append("visuals and collisions differ")
    names = []
    for v in visuals:
        m = v.find("material")
        if m is None or m.find("color") is None:
            problems.append("visual without material colour")
        else:
            names.append(m.get("name"))
    if len(set(names)) != len(names):
        problems.append("material names not unique")

    lo, hi = [math.inf] * 3, [-math.inf] * 3
    for c in collisions:
        kind, dims, xyz, rot = primitive(c)
        h = half_extent(kind, dims, rot)
        lo = [min(lo[i], xyz[i] - h[i]) for i in range(3)]
        hi = [max(hi[i], xyz[i] + h[i]) for i in range(3)]
        if thickness(kind, dims) * 1000 < MIN_THICKNESS_MM - 1e-6:
            problems.append(f"{kind} {dims} thinner than {MIN_THICKNESS_MM} mm")
    centre = [(hi[i] + lo[i]) / 2 * 1000 for i in range(3)]
    size = [v * 1000 for v in true_size([primitive(c) for c in collisions])]
    for s, ref in zip(size, size_ref):
        if abs(s - ref) > max(0.1 * ref, 5.0):
            problems.append(f"true size {[round(v) for v in size]} mm vs {list(size_ref)} mm")
            break
    if max(abs(c) for c in centre) > 5.0:
        problems.append(f"bbox centre {[round(c, 1) for c in centre]} mm off the origin")
    return size, centre, mass, mu, len(collisions), problems


def main():
    failed = False
    print(f"{'object':18s} {'true size (mm)':>23s}   {'target (mm)':>15s}  {'centre off':>10s}  "
          f"{'mass':>6s} {'mu':>4s}  prims  result")
    for name, target in TARGETS.items():
        try:
            size, centre, mass, mu, n, problems = check(name, target)
        except Exception as e:  # missing file, malformed XML, ...
            print(f"{name:18s} ERROR {e}")
            failed = True
            continue
        s = " x ".join(f"{v:5.1f}" for v in size)
        t = " x ".join(f"{v:3.0f}" for v in target[0])
        off = max(abs(c) for c in centre)
        print(f"{name:18s} {s:>23s}   {t:>15s}  {off:7.1f} mm  {mass:6.3f} {mu:4.1f}  {n:5d}  "
              f"{'ok' if not problems else 'FAIL: ' + '; '.join(problems)}")
        failed |= bool(problems)

    expected = {k: [n for n, t in TARGETS.items() if t[3] == k] for k in ("train", "test")}
    try:
        with open(os.path.join(HERE, "split.json")) as fh:
            split = json.load(fh)
        ok = split == expected
    except Exception as e:
        split, ok = e, False
    print(f"split.json: {'ok' if ok else 'FAIL: ' + str(split)}")
    failed |= not ok
    print("ALL OK" if not failed else "FAILED")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
