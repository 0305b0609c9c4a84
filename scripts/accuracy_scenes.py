"""Scenes on which a ray–triangle test that is not watertight leaks, for
scripts/accuracy_vs_time.py: closed meshes around the camera, tessellated so that the centre
rays of the pixels pass through mesh vertices and along shared edges.

With the camera inside a closed mesh every ray must hit something, so each pixel that misses is
a leak, without any reference. The camera sits at the centre looking down -z with fov_y 90 and a
square image of odd width W, so that pixel x's centre ray points along ((2x + 1 - W) / W, ...,
-1) (conventions.md):
- box: the cube [-1, 1]^3 with every face cut into a 2W x 2W grid; the face z = -1 has a vertex
  at (i - W) / W, and every odd i is a pixel centre: every centre ray meets a vertex shared by
  six triangles.
- sphere: a UV sphere with its pole on the view axis (the middle pixel's ray meets the pole, a
  vertex of 64 triangles) and 64 meridians, 8 of which lie in the planes of the middle row, the
  middle column and the diagonals: those rays run along the meridians' edges.
Each has a copy 1e5 from the origin (scaled up 100 times, so that its triangles stay far larger
than a float's spacing there), where rounding in the ray's frame is larger.
"""
import json
import math
import os


def _box(width):
    """Vertices and faces (0-based) of the cube [-1, 1]^3, each face a (2W)^2 grid of cells."""
    n = 2 * width
    vertices, index, faces = [], {}, []

    def vertex(p):
        key = tuple(p)
        if key not in index:
            index[key] = len(vertices)
            vertices.append(key)
        return index[key]

    # Integer grid coordinates (0..n on each axis) keep the vertices that faces share identical.
    for axis in range(3):
        u_axis, v_axis = (axis + 1) % 3, (axis + 2) % 3
        for side in (0, n):
            for i in range(n):
                for j in range(n):
                    corners = []
                    for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        p = [0, 0, 0]
                        p[axis], p[u_axis], p[v_axis] = side, i + di, j + dj
                        corners.append(vertex(p))
                    faces += [(corners[0], corners[1], corners[2]),
                              (corners[0], corners[2], corners[3])]
    return [tuple((c - width) / width for c in v) for v in vertices], faces


def _sphere(meridians=64, parallels=48):
    """A closed UV sphere of radius 1 with its poles on the z axis."""
    vertices = [(0.0, 0.0, 1.0)]
    for p in range(1, parallels):
        theta = math.pi * p / parallels
        for m in range(meridians):
            phi = 2 * math.pi * m / meridians
            vertices.append((math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi),
                             math.cos(theta)))
    vertices.append((0.0, 0.0, -1.0))
    south = len(vertices) - 1
    ring = lambda p, m: 1 + (p - 1) * meridians + m % meridians  # noqa: E731
    faces = [(0, ring(1, m), ring(1, m + 1)) for m in range(meridians)]
    for p in range(1, parallels - 1):
        for m in range(meridians):
            a, b = ring(p, m), ring(p, m + 1)
            c, d = ring(p + 1, m + 1), ring(p + 1, m)
            faces += [(a, d, c), (a, c, b)]
    faces += [(ring(parallels - 1, m + 1), ring(parallels - 1, m), south)
              for m in range(meridians)]
    return vertices, faces


def _write(folder, case, vertices, faces, width, offset, scale):
    obj = os.path.join(folder, case + ".obj")
    with open(obj, "w") as f:
        f.write(f"# {case}: closed mesh around the camera (scripts/accuracy_scenes.py)\n")
        for v in vertices:
            f.write("v %.9g %.9g %.9g\n" % tuple(offset + scale * c for c in v))
        for a, b, c in faces:
            f.write(f"f {a + 1} {b + 1} {c + 1}\n")
    render = os.path.join(folder, case + ".json")
    centre = [offset] * 3
    with open(render, "w") as f:
        json.dump({"image": {"width": width, "height": width, "spp": 1},
                   "camera": {"position": centre, "look_at": [offset, offset, offset - scale],
                              "up": [0, 1, 0], "fov_y": 90},
                   "lights": [], "background": [0, 0, 0], "max_depth": 1}, f)
    return case, obj, render


def write_hard_scenes(folder, width):
    """Writes the cases into folder; returns (case, obj, render file) for each. width: the
    image's width and height, odd."""
    assert width % 2 == 1, "the middle pixel's centre ray must lie on the view axis"
    os.makedirs(folder, exist_ok=True)
    box, sphere = _box(width), _sphere()
    cases = []
    for name, (vertices, faces) in (("box", box), ("sphere", sphere)):
        cases.append(_write(folder, f"{name}-inside", vertices, faces, width, 0.0, 1.0))
        cases.append(_write(folder, f"{name}-inside-at-1e5", vertices, faces, width, 1e5, 100.0))
    return cases
