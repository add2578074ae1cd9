#!/usr/bin/env python3
"""Checks assets/ur5/ur5.urdf against the standard UR5 DH model.

Usage:  python3 assets/ur5/check_fk.py        (needs numpy)

1. URDF forward kinematics (base_link -> tool0, joint origins composed with Rz(q) about
   each revolute joint's z axis) must equal the DH product
   T_i = Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i) for the test pose and 200 random poses.
2. At q = [-pi, -pi/2, pi/2, -pi/2, -pi/2, 0] tool0 must be at (0.4869, 0.1092, 0.4319)
   in base_link, i.e. (0.4869, 0.1092, 0.8319) with the base at z = 0.4 (the pedestal top).
3. Prints, at that pose and with the base at z = 0.4, every joint origin and every
   collision primitive (centre, and the two end-cap centres of each cylinder) in world
   coordinates, plus each tube's distance from the DH segment it should cover, so one
   can eyeball that the tubes join consecutive joints.
Exits non-zero if 1 or 2 fails.
"""
import math
import os
import sys
import xml.etree.ElementTree as ET

import numpy as np

URDF = os.path.join(os.path.dirname(os.path.abspath(__file__)), "ur5.urdf")
D = [0.089159, 0, 0, 0.10915, 0.09465, 0.0823]
A = [0, -0.425, -0.39225, 0, 0, 0]
ALPHA = [math.pi / 2, 0, 0, math.pi / 2, -math.pi / 2, 0]
Q_TEST = [-math.pi, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0]
TOOL_EXPECTED = np.array([0.4869, 0.1092, 0.4319])
BASE_Z = 0.4


def rot(axis, a):
    c, s = math.cos(a), math.sin(a)
    m = np.eye(4)
    i, j = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}[axis]
    m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
    return m


def trans(x, y, z):
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


def origin(el):
    """4x4 transform of a URDF <origin> (rpy fixed axis: Rz(yaw) Ry(pitch) Rx(roll))."""
    o = el.find("origin") if el is not None else None
    xyz = [float(v) for v in (o.get("xyz", "0 0 0") if o is not None else "0 0 0").split()]
    r, p, y = [float(v) for v in (o.get("rpy", "0 0 0") if o is not None else "0 0 0").split()]
    return trans(*xyz) @ rot("z", y) @ rot("y", p) @ rot("x", r)


def dh_fk(q):
    t = np.eye(4)
    for i in range(6):
        t = t @ rot("z", q[i]) @ trans(0, 0, D[i]) @ trans(A[i], 0, 0) @ rot("x", ALPHA[i])
    return t


def urdf_frames(robot, q):
    """World transform (base_link = identity) of every link, following the joint chain."""
    joints = {j.find("parent").get("link"): j for j in robot.findall("joint")}
    frames, joint_origins = {"base_link": np.eye(4)}, []
    link, qi = "base_link", 0
    while link in joints:
        j = joints[link]
        t = frames[link] @ origin(j)
        joint_origins.append((j.get("name"), t[:3, 3]))
        if j.get("type") == "revolute":
            axis = [float(v) for v in j.find("axis").get("xyz").split()]
            assert axis == [0, 0, 1], j.get("name")
            t = t @ rot("z", q[qi])
            qi += 1
        link = j.find("child").get("link")
        frames[link] = t
    assert qi == 6, "expected 6 revolute joints"
    return frames, joint_origins


def main():
    robot = ET.parse(URDF).getroot()
    ok = True
    rng = np.random.default_rng(0)
    worst = 0.0
    for q in [Q_TEST] + [rng.uniform(-2 * math.pi, 2 * math.pi, 6) for _ in range(200)]:
        frames, _ = urdf_frames(robot, q)
        worst = max(worst, np.abs(frames["tool0"] - dh_fk(q)).max())
    print(f"max |URDF FK - DH FK| over 201 poses: {worst:.2e}")
    ok &= worst < 1e-9

    frames, joint_origins = urdf_frames(robot, Q_TEST)
    tool = frames["tool0"][:3, 3]
    print(f"tool0 at test pose (base frame): {np.round(tool, 4)}  expected {TOOL_EXPECTED}")
    ok &= bool(np.abs(tool - TOOL_EXPECTED).max() < 5e-4)

    lift = trans(0, 0, BASE_Z)
    print(f"\nworld positions at q = [-pi, -pi/2, pi/2, -pi/2, -pi/2, 0], base at z = {BASE_Z}:")
    for name, p in joint_origins:
        print(f"  joint {name:22s} {np.round(p + [0, 0, BASE_Z], 4)}")
    pts = {n: p + [0, 0, BASE_Z] for n, p in joint_origins}
    segments = {  # link -> the DH segment its main tube should cover
        "upper_arm_link": ("shoulder_lift_joint", "elbow_joint"),
        "forearm_link": ("elbow_joint", "wrist_1_joint"),
    }
    for link in robot.findall("link"):
        name = link.get("name")
        for c in link.findall("collision"):
            t = lift @ frames[name] @ origin(c)
            g = c.find("geometry")[0]
            line = f"  {name:15s} {g.tag:8s} centre {np.round(t[:3, 3], 4)}"
            if g.tag == "cylinder":
                h = float(g.get("length")) / 2
                e0, e1 = t[:3, 3] - h * t[:3, 2], t[:3, 3] + h * t[:3, 2]
                line += f" ends {np.round(e0, 3)} {np.round(e1, 3)} r {g.get('radius')}"
                if name in segments and h > 0.15:
                    a, b = (pts[s] for s in segments[name])
                    d = max(np.linalg.norm(np.cross(e - a, b - a)) / np.linalg.norm(b - a) for e in (e0, e1))
                    line += f"  off DH line {d:.3f} m"
            print(line)
    print("\nPASS" if ok else "\nFAIL")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
