#!/usr/bin/env python3
"""Checks the primitive YCB-like object models in assets/objects (stdlib only).

Usage:  python3 assets/objects/check_objects.py

For every <Name>/model.urdf listed in TARGETS it computes the exact axis-aligned bounding
box of the collision primitives (boxes, cylinders along their local z, spheres, each after
its <origin xyz rpy>) and compares it with the reference size: every dimension must be
within max(10 %, 5 mm). Mass and <contact><lateral_friction> must equal the table.
It also checks: robot name, a single link `base_link`, bounding-box centre within 5 mm of
the link origin, at most 8 primitives, every visual matched by an identical collision,
every visual has a uniquely named material with a colour, and no primitive thinner than
8 mm. Finally split.json must hold the expected train/test lists.
Prints one row per object and exits non-zero on any failure.
"""
import json
import math
import os
import sys
import xml.etree.ElementTree as ET

HERE = os.path.dirname(os.path.abspath(__file__))
# name: (size x, y, z in mm, mass kg, mu, split)
TARGETS = {
    "YcbHammer": ((129, 334, 34), 0.665, 1.0, "train"),
    "YcbMediumClamp": ((87, 77, 29), 0.059, 0.6, "train"),
    "YcbMustardBottle": ((99, 59, 191), 0.603, 0.8, "train"),
    "YcbPowerDrill": ((165, 124, 189), 0.895, 0.9, "train"),
    "YcbTomatoSoupCan": ((66, 66, 102), 0.349, 0.8, "train"),
    "YcbBanana": ((192, 80, 40), 0.066, 0.8, "test"),
    "YcbChipsCan": ((75, 75, 230), 0.205, 0.5, "test"),
    "YcbFoamBrick": ((77, 92, 55), 0.028, 0.5, "test"),
    "YcbGelatinBox": ((73, 69, 87), 0.097, 0.3, "test"),
    "YcbMasterChefCan": ((70, 70, 99), 0.404, 0.5, "test"),
    "YcbPear": ((66, 104, 66), 0.049, 0.6, "test"),
    "YcbPottedMeatCan": ((101, 88, 84), 0.370, 0.6, "test"),
    "YcbScissors": ((205, 88, 20), 0.082, 0.8, "test"),
    "YcbStrawberry": ((41, 53, 45), 0.018, 0.5, "test"),
    "YcbTennisBall": ((64, 64, 64), 0.058, 0.8, "test"),
}
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
    size = [(hi[i] - lo[i]) * 1000 for i in range(3)]
    centre = [(hi[i] + lo[i]) / 2 * 1000 for i in range(3)]
    for axis, s, ref in zip("xyz", size, size_ref):
        if abs(s - ref) > max(0.1 * ref, 5.0):
            problems.append(f"{axis} size {s:.1f} mm vs {ref} mm")
    if max(abs(c) for c in centre) > 5.0:
        problems.append(f"bbox centre {[round(c, 1) for c in centre]} mm off the origin")
    return size, centre, mass, mu, len(collisions), problems


def main():
    failed = False
    print(f"{'object':18s} {'bbox size (mm)':>23s}   {'target (mm)':>15s}  {'centre off':>10s}  "
          f"{'mass':>6s} {'mu':>4s}  prims  result")
    for name, target in TARGETS.items():
        try:
            size, centre, mass, mu, n, problems = check(name, target)
        except Exception as e:  # missing file, malformed XML, ...
            print(f"{name:18s} ERROR {e}")
            failed = True
            continue
        s = " x ".join(f"{v:5.1f}" for v in size)
        t = " x ".join(f"{v:3d}" for v in target[0])
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
