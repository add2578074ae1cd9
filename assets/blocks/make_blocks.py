#!/usr/bin/env python3
"""Builds assets/blocks/ from VPG's eight block meshes (Zeng et al., IROS 2018; BSD-2, LICENSE).

    python3 assets/blocks/make_blocks.py DIR_WITH_VPG_OBJ_FILES

Each VPG mesh N.obj becomes BlockN/: block.obj (the mesh, re-framed as VPG's simulator framed
the shape, so that a test case's pose applies to it unchanged), model.urdf (mass, friction) and,
for the grooved 1.obj, collision.obj (convex pieces). The re-framing was measured from VPG's
test cases: with it no two listed objects overlap and all rest on the table.
"""

import math
import pathlib
import sys

# A vertex (x, y, z) of the file goes to these coordinates of the shape's frame.
REFRAME = {
    "0": lambda x, y, z: (z, y, -x),
    # The groove stands upright, as VPG's picture of its case 00 shows it: a cylinder standing
    # in the grooves of two blocks. (y, z, x) gives the same box but lays the groove flat.
    "1": lambda x, y, z: (z, y, -x),
    "2": lambda x, y, z: (x, z, -y),
    "3": lambda x, y, z: (x, y, z),
    "4": lambda x, y, z: (z, x, y),
    "6": lambda x, y, z: (x, y, z),
    "7": lambda x, y, z: (z, x, y),
    "8": lambda x, y, z: (z, x, y),
}

SHAPES = {
    "0": "triangular prism",
    "1": "block with a half-cylinder groove",
    "2": "square tile",
    "3": "flat plank",
    "4": "cube",
    "6": "long block",
    "7": "half cylinder",
    "8": "cylinder",
}

# Painted wooden toy blocks (VPG's real-world set): beech and maple are 650-750 kg/m³.
DENSITY = 700.0
# Painted wood on painted wood or plastic; also Bullet's default, which VPG's V-REP scene keeps.
FRICTION = 0.5
# Segments of the groove's half circle in 1.obj's convex pieces (each chord dips 0.5 mm).
GROOVE_SEGMENTS = 12


def squared(vertices):
    """2.obj's 50 × 50 mm section lies turned by about 15° about x in its file; VPG's simulator
    framed the tile square to its edges, for its cases rest it 1 mm above the table as they rest
    every other block (turned, it would stand 4 mm into it). Turns the section by the angle, to
    0.1°, of the smallest box around it."""
    def turned(degrees):
        a = math.radians(degrees)
        c, s = math.cos(a), math.sin(a)
        return [(x, c * y - s * z, s * y + c * z) for x, y, z in vertices]

    def area(degrees):
        t = turned(degrees)
        return (max(v[1] for v in t) - min(v[1] for v in t)) * (max(v[2] for v in t) - min(v[2] for v in t))

    best = min((k / 10 for k in range(-450, 450)), key=area)
    return turned(best)


def read_obj(path):
    vertices, faces = [], []
    for line in path.read_text().splitlines():
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            vertices.append(tuple(float(p) for p in parts[1:4]))
        elif parts[0] == "f":
            faces.append(tuple(int(p.split("/")[0]) for p in parts[1:]))
    return vertices, faces


def volume(vertices, faces):
    total = 0.0
    for face in faces:
        a = vertices[face[0] - 1]
        for i in range(1, len(face) - 1):
            b, c = vertices[face[i] - 1], vertices[face[i + 1] - 1]
            total += (
                a[0] * (b[1] * c[2] - b[2] * c[1])
                - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0])
            ) / 6.0
    return abs(total)


def fmt(v):
    return f"v {v[0]:.6f} {v[1]:.6f} {v[2]:.6f}"


def groove_pieces():
    """1.obj in its file frame: 100 × 50 × 50 mm (x, y, z) less a half cylinder of radius
    25 mm along y, centred on the bottom face z = −25 mm. Convex pieces: the two solid ends and
    one slab over each chord of the groove's arc."""
    half = (0.05, 0.025, 0.025)
    r = 0.025
    pieces = [
        [(x, y, z) for x in (-half[0], -r) for y in (-half[1], half[1]) for z in (-half[2], half[2])],
        [(x, y, z) for x in (r, half[0]) for y in (-half[1], half[1]) for z in (-half[2], half[2])],
    ]
    for k in range(GROOVE_SEGMENTS):
        a0 = math.pi * k / GROOVE_SEGMENTS
        a1 = math.pi * (k + 1) / GROOVE_SEGMENTS
        arc = [(-r * math.cos(a), -half[2] + r * math.sin(a)) for a in (a0, a1)]
        piece = []
        for x, z in arc:
            for y in (-half[1], half[1]):
                piece.append((x, y, z))
                piece.append((x, y, half[2]))
        pieces.append(piece)
    return pieces


def hexahedron_faces(first):
    """The 12 triangles of a hexahedron whose 8 corners are numbered 4·i + 2·j + k from
    `first` (i, j, k in {0, 1}), as every piece of groove_pieces() is: the loader keeps only
    the vertices that faces use."""
    corner = lambda i, j, k: first + 4 * i + 2 * j + k
    quads = []
    for fixed in range(3):
        for side in (0, 1):
            quad = []
            for a, b in ((0, 0), (0, 1), (1, 1), (1, 0)):
                ijk = [a, b]
                ijk.insert(fixed, side)
                quad.append(corner(*ijk))
            quads.append(quad)
    return [f"f {q[0]} {q[1]} {q[2]}\nf {q[0]} {q[2]} {q[3]}" for q in quads]


def main(source):
    out = pathlib.Path(__file__).resolve().parent
    for stem, reframe in REFRAME.items():
        vertices, faces = read_obj(source / f"{stem}.obj")
        if stem == "2":
            vertices = squared(vertices)
        framed = [reframe(*v) for v in vertices]
        folder = out / f"Block{stem}"
        folder.mkdir(exist_ok=True)
        lines = [
            f"# VPG's blocks/{stem}.obj ({SHAPES[stem]}), re-framed as VPG's simulator framed it;",
            "# BSD-2, see ../LICENSE. Made by assets/blocks/make_blocks.py.",
        ]
        lines += [fmt(v) for v in framed]
        lines += ["f " + " ".join(str(i) for i in f) for f in faces]
        (folder / "block.obj").write_text("\n".join(lines) + "\n")
        collision = "block.obj"
        if stem == "1":
            collision = "collision.obj"
            lines = [
                "# Convex pieces of Block1 (the groove cannot be one hull). Made by",
                "# assets/blocks/make_blocks.py; BSD-2, see ../LICENSE.",
            ]
            first = 1
            for n, piece in enumerate(groove_pieces()):
                lines.append(f"o piece_{n}")
                lines += [fmt(reframe(*p)) for p in piece]
                lines += hexahedron_faces(first)
                first += len(piece)
            (folder / "collision.obj").write_text("\n".join(lines) + "\n")
        mass = DENSITY * volume(vertices, faces)
        (folder / "model.urdf").write_text(
            f"""<?xml version="1.0"?>
<!-- Block{stem}: VPG's {stem}.obj, a {SHAPES[stem]}. Mass: the mesh's volume at {DENSITY:.0f} kg/m³;
     friction {FRICTION} (assets/blocks/README.md). Made by assets/blocks/make_blocks.py. -->
<robot name="Block{stem}">
  <link name="base_link">
    <contact><lateral_friction value="{FRICTION}"/></contact>
    <inertial>
      <mass value="{mass:.4f}"/>
      <inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0" izz="1e-5"/>
    </inertial>
    <visual>
      <geometry><mesh filename="block.obj"/></geometry>
      <material name="wood"><color rgba="0.8 0.65 0.45 1"/></material>
    </visual>
    <collision>
      <geometry><mesh filename="{collision}"/></geometry>
    </collision>
  </link>
</robot>
"""
        )
        print(f"Block{stem}: {SHAPES[stem]}, {mass * 1000:.1f} g")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(pathlib.Path(sys.argv[1]))
