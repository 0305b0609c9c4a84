#!/usr/bin/env python3
"""The Mitsuba 3 half of scripts/compare_mitsuba.py, run by the interpreter of the virtual
environment that script makes (PyPI's `mitsuba`); it is not meant to be run by hand.

    mitsuba_side.py render SPEC.json OUT.exr   # prints {"seconds": ..., "variant": ...}
    mitsuba_side.py compare A.exr B.exr        # prints {"rel_mse": ..., "mean_a": ..., ...}

SPEC: {"obj": PATH, "render_file": {...kdray's render file...}, "spp": N, "max_depth": D,
"rr_depth": R (Mitsuba's; 5, its default, when absent), "variant": "llvm_ad_rgb" | "scalar_rgb",
"work": DIR}. The scene is kdray's, mapped as ../shared/conventions.md says comparisons do: the
camera model (`perspective`, `fov_axis` y), the `path` integrator at the same max_depth (and
Russian roulette after rr_depth segments), `diffuse` (two-sided: kdray shades both sides) for
Lambertian materials with their `map_Kd`, `conductor` for mirrors (illum 3, 5 with Ks),
`dielectric` for glass (illum 4, 6, 7; d < 1; 0 < Tf < 1) with Ni, and one-sided `area` emitters
for triangles with Ke. The render file's point and directional lights become `point` and
`directional` emitters; its background a `constant` emitter. kdray's Phong lobe (Ks, Ns on a
non-mirror) has no counterpart there: such a material is reported in "approximations".
"""
import json
import os
import sys
import time


def parse_mtl(path):
    materials, current = {}, None
    with open(path, errors="replace") as f:
        for raw in f:
            parts = raw.split("#", 1)[0].split()
            if not parts:
                continue
            key, values = parts[0], parts[1:]
            if key == "newmtl":
                current = materials.setdefault(" ".join(values), {})
            elif current is not None and values:
                current[key] = values
    return materials


def parse_obj(path):
    """Positions, texture coordinates, normals, and per material its triangles (fans of the
    faces, as tinyobjloader triangulates them), each corner (v, vt, vn) indices or None."""
    v, vt, vn = [], [], []
    groups, material, libraries = {}, "", []
    with open(path, errors="replace") as f:
        for raw in f:
            parts = raw.split("#", 1)[0].split()
            if not parts:
                continue
            key, values = parts[0], parts[1:]
            if key == "v":
                v.append([float(x) for x in values[:3]])
            elif key == "vt":
                vt.append([float(x) for x in values[:2]] + [0.0] * (2 - len(values[:2])))
            elif key == "vn":
                vn.append([float(x) for x in values[:3]])
            elif key == "usemtl":
                material = " ".join(values)
            elif key == "mtllib":
                libraries.append(" ".join(values))
            elif key == "f":
                corners = []
                for token in values:
                    fields = (token.split("/") + ["", ""])[:3]
                    index = []
                    for field, count in zip(fields, (len(v), len(vt), len(vn))):
                        if not field:
                            index.append(None)
                            continue
                        i = int(field)
                        index.append(i - 1 if i > 0 else count + i)
                    corners.append(index)
                for k in range(1, len(corners) - 1):
                    groups.setdefault(material, []).append((corners[0], corners[k], corners[k + 1]))
    return v, vt, vn, groups, libraries


def write_group_obj(path, v, vt, vn, triangles):
    """One material's triangles as an OBJ of their own; corners keep uv and normal only when all
    three have them (as kdray shades such a face)."""
    counts = {"v": 0, "vt": 0, "vn": 0}
    with open(path, "w") as f:
        for tri in triangles:
            with_uv = all(c[1] is not None for c in tri)
            with_n = all(c[2] is not None for c in tri)
            corners = []
            for c in tri:
                f.write("v %r %r %r\n" % tuple(v[c[0]]))
                counts["v"] += 1
                corner = str(counts["v"])
                if with_uv:
                    f.write("vt %r %r\n" % tuple(vt[c[1]]))
                    counts["vt"] += 1
                if with_n:
                    f.write("vn %r %r %r\n" % tuple(vn[c[2]]))
                    counts["vn"] += 1
                if with_uv or with_n:
                    corner += "/" + (str(counts["vt"]) if with_uv else "")
                if with_n:
                    corner += "/" + str(counts["vn"])
                corners.append(corner)
            f.write("f " + " ".join(corners) + "\n")


def floats(values, n=3):
    out = [float(x) for x in values[:n]]
    return out + [out[-1]] * (n - len(out)) if out else [0.0] * n


def bsdf_for(m, folder, approximations, name):
    illum = int(float(m.get("illum", ["2"])[0]))
    kd = floats(m.get("Kd", ["0.8"]))
    ks = floats(m.get("Ks", ["0"]))
    ni = float(m.get("Ni", ["1.5"])[0])
    d = float(m.get("d", ["1"])[0]) if "d" in m else 1.0 - float(m.get("Tr", ["0"])[0])
    tf = floats(m.get("Tf", ["1"]))
    if illum in (4, 6, 7) or d < 1.0 or 0.0 < max(tf) < 1.0:
        return {"type": "dielectric", "int_ior": ni if ni > 1.0 else 1.5, "ext_ior": 1.0}
    if illum in (3, 5) and max(ks) > 0.0:
        return {"type": "conductor", "material": "none",
                "specular_reflectance": {"type": "rgb", "value": ks}}
    if max(ks) > 0.0:
        approximations.append(f"{name}: Phong lobe Ks {ks} left out (no Mitsuba counterpart)")
    reflectance = {"type": "rgb", "value": kd}
    if "map_Kd" in m:
        texture = os.path.join(folder, m["map_Kd"][-1])
        if os.path.isfile(texture):
            # kdray multiplies Kd by the texel; Mitsuba's bitmap has no factor, so only Kd = 1
            # maps exactly.
            if kd != [1.0, 1.0, 1.0]:
                approximations.append(f"{name}: map_Kd with Kd {kd} != 1 uses the texture alone")
            reflectance = {"type": "bitmap", "filename": texture, "filter_type": "bilinear",
                           "wrap_mode": "repeat"}
    return {"type": "twosided", "material": {"type": "diffuse", "reflectance": reflectance}}


def scene_dict(spec, mi):
    obj = spec["obj"]
    folder = os.path.dirname(os.path.abspath(obj))
    rf = spec["render_file"]
    v, vt, vn, groups, libraries = parse_obj(obj)
    materials = {}
    for lib in libraries:
        path = lib if os.path.isabs(lib) else os.path.join(folder, lib)
        if os.path.isfile(path):
            materials.update(parse_mtl(path))
    cam = rf.get("camera", {})
    image = rf.get("image", {})
    width, height = int(image.get("width", 640)), int(image.get("height", 480))
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": int(spec["max_depth"]),
                       "rr_depth": int(spec.get("rr_depth", 5))},
        "sensor": {
            "type": "perspective",
            "fov_axis": "y",
            "fov": float(cam.get("fov_y", 45)),
            "to_world": mi.ScalarTransform4f.look_at(origin=cam.get("position", [0, 1, 3]),
                                                     target=cam.get("look_at", [0, 0, 0]),
                                                     up=cam.get("up", [0, 1, 0])),
            "film": {"type": "hdrfilm", "width": width, "height": height,
                     "pixel_format": "rgb", "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": int(spec["spp"])},
        },
    }
    approximations = []
    os.makedirs(spec["work"], exist_ok=True)
    for k, (name, triangles) in enumerate(sorted(groups.items())):
        m = materials.get(name, {})
        path = os.path.join(spec["work"], f"group_{k}.obj")
        write_group_obj(path, v, vt, vn, triangles)
        shape = {"type": "obj", "filename": path, "bsdf": bsdf_for(m, folder, approximations, name)}
        ke = floats(m.get("Ke", ["0"]))
        if max(ke) > 0.0:
            shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": ke}}
        scene[f"shape_{k}"] = shape
    for k, light in enumerate(rf.get("lights", [])):
        if light.get("type") == "point":
            scene[f"light_{k}"] = {"type": "point", "position": light["position"],
                                   "intensity": {"type": "rgb", "value": light["intensity"]}}
        elif light.get("type") == "directional":
            scene[f"light_{k}"] = {"type": "directional", "direction": light["direction"],
                                   "irradiance": {"type": "rgb", "value": light["irradiance"]}}
    background = rf.get("background", [0, 0, 0])
    if max(background) > 0:
        scene["background"] = {"type": "constant",
                               "radiance": {"type": "rgb", "value": background}}
    if max(rf.get("ambient", [0, 0, 0])) > 0:
        approximations.append("the render file's ambient term has no Mitsuba counterpart")
    return scene, approximations


def render(spec_path, out):
    with open(spec_path) as f:
        spec = json.load(f)
    import mitsuba as mi
    mi.set_variant(spec["variant"])
    scene_desc, approximations = scene_dict(spec, mi)
    scene = mi.load_dict(scene_desc)
    # Two timed parts, as kdray's frame figures have: the first render includes the JIT's
    # compilation (llvm variants), so a warm-up render at 1 spp runs first, untimed.
    mi.render(scene, spp=1)
    start = time.perf_counter()
    image = mi.render(scene, spp=int(spec["spp"]))
    mi.Bitmap(image).write(out)
    seconds = time.perf_counter() - start
    print(json.dumps({"seconds": seconds, "variant": spec["variant"],
                      "approximations": approximations}))


def compare(a_path, b_path):
    import numpy as np
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    a = np.array(mi.Bitmap(a_path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32,
                                           False), dtype=np.float64)
    b = np.array(mi.Bitmap(b_path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32,
                                           False), dtype=np.float64)
    if a.shape != b.shape:
        print(json.dumps({"error": f"sizes differ: {a.shape} and {b.shape}"}))
        return 1
    # Relative MSE as the rendering literature reports it (e.g. Mitsuba's and pbrt's papers):
    # the squared difference over the reference's square, with 1e-2 keeping dark pixels finite.
    rel_mse = float(np.mean((a - b) ** 2 / (b ** 2 + 1e-2)))
    print(json.dumps({"rel_mse": rel_mse, "mean_a": float(a.mean()), "mean_b": float(b.mean()),
                      "pixels": int(a.shape[0] * a.shape[1])}))
    return 0


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[1] == "render":
        render(sys.argv[2], sys.argv[3])
    elif len(sys.argv) == 4 and sys.argv[1] == "compare":
        sys.exit(compare(sys.argv[2], sys.argv[3]))
    else:
        sys.exit(__doc__)
