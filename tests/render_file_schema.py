#!/usr/bin/env python3
"""docs/render-file.schema.json against kdray's own render-file reader (core/render/render_file.cpp).

1. Every render file of testdata/, scripts/render-files/ and of ../shared/scenes (that part skipped, saying so, when
   ../shared is absent) is valid under the schema.
2. Good and bad render files made here are run through `kdray render` (a one-triangle scene, the
   reference builder and tracer, 8x8 pixels) and through the schema: a good file renders (exit 0)
   and is valid; a bad file makes kdray exit non-zero with a `kdray: error:` line naming the
   render file, and is invalid. Any disagreement fails the test, naming the case.
3. What a JSON Schema cannot say (the schema's description lists it) is pinned too: kdray refuses
   these files and the schema accepts them, so a change on either side shows here.

    render_file_schema.py --kdray build/kdray [--schema docs/render-file.schema.json]
"""
import argparse
import json
import pathlib
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent

try:
    import jsonschema
except ImportError:
    sys.exit("render_file_schema: python module jsonschema missing: install python3-jsonschema "
             "(scripts/install-deps.sh)")

# A camera that sees the triangle of TRIANGLE_OBJ.
CAMERA = {"position": [0, 0, 3], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov_y": 45}
TRIANGLE_OBJ = "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n"

# (name, render file): both kdray and the schema accept these.
GOOD = [
    ("empty object", {}),
    ("conventions.md's example", {
        "image": {"width": 640, "height": 480, "spp": 1},
        "camera": CAMERA,
        "lights": [
            {"type": "point", "position": [2, 4, 2], "intensity": [30, 30, 30]},
            {"type": "directional", "direction": [-1, -1, -1], "irradiance": [1, 1, 1]},
        ],
        "background": [0.05, 0.05, 0.08], "ambient": [0, 0, 0], "exposure": 0, "max_depth": 4}),
    ("$schema hint for editors", {"$schema": "../docs/render-file.schema.json", "camera": CAMERA}),
    ("every field null", {"image": None, "camera": None, "lights": None, "background": None,
                          "ambient": None, "exposure": None, "display": None,
                          "max_depth": None}),
    ("display clamp", {"display": "clamp"}),
    ("display filmic", {"display": "filmic"}),
    ("null inside objects", {"image": {"width": None, "height": None, "spp": None},
                             "camera": {"position": [0, 0, 3], "look_at": None, "up": None,
                                        "fov_y": None},
                             "lights": [{"type": None, "position": None, "intensity": None},
                                        {"type": "directional", "direction": None,
                                         "irradiance": None}]}),
    ("ambient grey", {"ambient": 0.25}),
    ("limits", {"image": {"width": 1, "height": 65536, "spp": 65536}, "max_depth": 16,
                "exposure": -64}),
    ("limits 2", {"image": {"width": 65536, "height": 1, "spp": 1}, "max_depth": 1,
                  "exposure": 64}),
    ("point light without type, huge intensity", {"lights": [{"intensity": [1e300, 0, 0]}]}),
    ("empty lights", {"lights": []}),
    ("keyframes", {"camera": [dict(CAMERA, frame=10), dict(CAMERA, frame=0, fov_y=30),
                              {"frame": 2147483647, "position": [0, 0, 5]}]}),
    ("integer and real vectors", {"background": [0, 1, 0.5], "camera": {
        "position": [0.0, 0, 3e0], "up": [0, 2, 0]}}),
    ("float range", {"background": [3.4e38, 0, 0], "lights": [{"position": [-3.4e38, 0, 0]}]}),
    ("directional light, default direction", {"lights": [{"type": "directional"}]}),
    ("integrator whitted", {"integrator": "whitted", "max_depth": 16}),
    ("integrator null, Whitted's depth", {"integrator": None, "max_depth": 3}),
    ("integrator path, default depth", {"integrator": "path"}),
    ("integrator path, unbounded", {"integrator": "path", "max_depth": -1}),
    ("integrator path, deep", {"integrator": "path", "max_depth": 65536}),
    ("integrator path, emitters only", {"integrator": "path", "max_depth": 1}),
]

# (name, render file as JSON text): both kdray and the schema refuse these.
BAD_OBJECTS = [
    ("not an object", [1, 2]),
    ("unknown top-level key", {"imagee": {}}),
    ("unknown image key", {"image": {"widht": 10}}),
    ("unknown camera key", {"camera": dict(CAMERA, fov=40)}),
    ("unknown keyframe key", {"camera": [dict(CAMERA, frame=0, time=1)]}),
    ("point light with a directional key", {"lights": [{"type": "point", "direction": [0, 1, 0]}]}),
    ("light without type with irradiance", {"lights": [{"irradiance": [1, 1, 1]}]}),
    ("directional light with a position", {"lights": [{"type": "directional",
                                                       "position": [0, 1, 0]}]}),
    ("image not an object", {"image": [640, 480]}),
    ("width a string", {"image": {"width": "640"}}),
    ("width 0", {"image": {"width": 0}}),
    ("height negative", {"image": {"height": -1}}),
    ("width too large", {"image": {"width": 65537}}),
    ("spp 0", {"image": {"spp": 0}}),
    ("spp too large", {"image": {"spp": 65537}}),
    ("spp real", {"image": {"spp": 1.5}}),
    ("width a bool", {"image": {"width": True}}),
    ("camera a string", {"camera": "front"}),
    ("camera empty array", {"camera": []}),
    ("keyframe without frame", {"camera": [CAMERA]}),
    ("keyframe with null frame", {"camera": [dict(CAMERA, frame=None)]}),
    ("keyframe frame negative", {"camera": [dict(CAMERA, frame=-1)]}),
    ("keyframe frame too large", {"camera": [dict(CAMERA, frame=2147483648)]}),
    ("keyframe frame a string", {"camera": [dict(CAMERA, frame="0")]}),
    ("keyframe not an object", {"camera": [dict(CAMERA, frame=0), None]}),
    ("position of 2", {"camera": dict(CAMERA, position=[0, 3])}),
    ("position of 4", {"camera": dict(CAMERA, position=[0, 0, 3, 1])}),
    ("position a number", {"camera": dict(CAMERA, position=3)}),
    ("position with a string", {"camera": dict(CAMERA, position=[0, "0", 3])}),
    ("position with a null", {"camera": dict(CAMERA, position=[0, None, 3])}),
    ("position beyond float", {"camera": dict(CAMERA, position=[0, 0, 1e39])}),
    ("fov_y 0", {"camera": dict(CAMERA, fov_y=0)}),
    ("fov_y 180", {"camera": dict(CAMERA, fov_y=180)}),
    ("fov_y negative", {"camera": dict(CAMERA, fov_y=-10)}),
    ("fov_y a string", {"camera": dict(CAMERA, fov_y="45")}),
    ("lights an object", {"lights": {"type": "point"}}),
    ("light not an object", {"lights": [[0, 1, 0]]}),
    ("light type unknown", {"lights": [{"type": "spot"}]}),
    ("light type a number", {"lights": [{"type": 1}]}),
    ("point intensity negative", {"lights": [{"position": [0, 1, 0], "intensity": [1, -1, 1]}]}),
    ("irradiance negative", {"lights": [{"type": "directional", "irradiance": [-1, 1, 1]}]}),
    ("irradiance beyond float", {"lights": [{"type": "directional", "irradiance": [1e39, 1, 1]}]}),
    ("direction zero", {"lights": [{"type": "directional", "direction": [0, 0, 0]}]}),
    ("direction zero, reals", {"lights": [{"type": "directional", "direction": [0.0, -0.0, 0]}]}),
    ("background negative", {"background": [0, -0.1, 0]}),
    ("background a number", {"background": 0.5}),
    ("background of 2", {"background": [0.5, 0.5]}),
    ("ambient negative grey", {"ambient": -0.5}),
    ("ambient negative", {"ambient": [0, 0, -1]}),
    ("ambient a string", {"ambient": "grey"}),
    ("ambient beyond float", {"ambient": 1e39}),
    ("display unknown", {"display": "aces"}),
    ("display a number", {"display": 1}),
    ("exposure too high", {"exposure": 64.5}),
    ("exposure too low", {"exposure": -65}),
    ("exposure a string", {"exposure": "1"}),
    ("max_depth 0", {"max_depth": 0}),
    ("max_depth too large", {"max_depth": 17}),
    ("max_depth real", {"max_depth": 2.5}),
    ("integrator unknown", {"integrator": "bdpt"}),
    ("integrator a number", {"integrator": 1}),
    ("max_depth -1 with Whitted", {"max_depth": -1}),
    ("max_depth 17 with Whitted", {"integrator": "whitted", "max_depth": 17}),
    ("path max_depth 0", {"integrator": "path", "max_depth": 0}),
    ("path max_depth -2", {"integrator": "path", "max_depth": -2}),
    ("path max_depth too large", {"integrator": "path", "max_depth": 65537}),
    ("$schema not a string", {"$schema": 1}),
]
BAD_TEXTS = [
    ("truncated JSON", '{"image": {"width": 64'),
    ("not JSON", "image: 64"),
    ("number overflowing a double", '{"exposure": 1e400}'),
]

# What the schema cannot express: kdray refuses these, the schema accepts them. Each is listed in
# the schema's description.
BEYOND_SCHEMA = [
    ("integer written as a real", '{"image": {"width": 64.0}}'),
    ("integer written with an exponent", '{"max_depth": 1e1}'),
    ("fov_y that rounds to 180 in float", '{"camera": {"fov_y": 179.999999999}}'),
    ("fov_y that rounds to 0 in float", '{"camera": {"fov_y": 1e-50}}'),
    ("look_at at the position", json.dumps({"camera": dict(CAMERA, look_at=[0, 0, 3])})),
    ("up zero", json.dumps({"camera": dict(CAMERA, up=[0, 0, 0])})),
    ("up parallel to the view", json.dumps({"camera": dict(CAMERA, up=[0, 0, 1])})),
    ("up too short", json.dumps({"camera": dict(CAMERA, up=[1e-200, 0, 0])})),
    ("two keys of one frame", json.dumps({"camera": [dict(CAMERA, frame=1),
                                                     dict(CAMERA, frame=1)]})),
    ("camera too far from the scene for floats",
     json.dumps({"camera": dict(CAMERA, position=[0, 0, 3.4e38])})),
    ("direction too short", json.dumps({"lights": [{"type": "directional",
                                                    "direction": [1e-200, 0, 0]}]})),
]


def run_kdray(kdray, scene, work, name, text):
    """kdray render's exit status and stderr for a render file holding `text`."""
    path = work / (name.replace(" ", "_").replace("$", "") + ".json")
    path.write_text(text)
    out = work / "out"
    result = subprocess.run(
        [kdray, "render", str(scene), "-o", str(out), "--camera", str(path), "--size", "8x8",
         "--builder", "reference", "--tracer", "reference", "--quiet",
         "--overwrite"],  # one folder: each file's settings replace the last's
        capture_output=True, text=True, timeout=120)
    return result.returncode, result.stderr, path


def schema_errors(validator, text):
    """The schema's verdict on `text`: None when valid, else the first error's message."""
    try:
        document = json.loads(text)
    except ValueError as e:
        return "not JSON: %s" % e
    error = jsonschema.exceptions.best_match(validator.iter_errors(document))
    return None if error is None else "%s at %s" % (error.message, list(error.absolute_path))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kdray", required=True)
    parser.add_argument("--schema", default=str(ROOT / "docs" / "render-file.schema.json"))
    parser.add_argument("--shared", default=str(ROOT.parent / "shared"))
    args = parser.parse_args()

    schema = json.loads(pathlib.Path(args.schema).read_text())
    jsonschema.Draft202012Validator.check_schema(schema)
    validator = jsonschema.Draft202012Validator(schema)
    failures = []

    # 1. The render files that exist.
    files = sorted((ROOT / "testdata").rglob("render*.json"))
    if not files:
        failures.append("no render file under testdata/")
    # The render files kept for the shared scenes (scripts/render-files/README.md).
    files += sorted((ROOT / "scripts" / "render-files").glob("*.json"))
    scenes = pathlib.Path(args.shared) / "scenes"
    if scenes.is_dir():
        shared = sorted(scenes.rglob("render*.json"))
        print("%d render files under %s" % (len(shared), scenes))
        files += shared
    else:
        print("SKIP the shared scenes: %s is absent" % scenes)
    for f in files:
        problem = schema_errors(validator, f.read_text())
        print("%-8s %s%s" % ("valid" if problem is None else "INVALID", f,
                             "" if problem is None else ": " + problem))
        if problem is not None:
            failures.append("%s: %s" % (f, problem))

    # 2. and 3. kdray and the schema on the same files.
    cases = ([(n, json.dumps(d), "good") for n, d in GOOD] +
             [(n, json.dumps(d), "bad") for n, d in BAD_OBJECTS] +
             [(n, t, "bad") for n, t in BAD_TEXTS] +
             [(n, t, "beyond") for n, t in BEYOND_SCHEMA])
    with tempfile.TemporaryDirectory(prefix="kdray-schema-") as tmp:
        work = pathlib.Path(tmp)
        scene = work / "triangle.obj"
        scene.write_text(TRIANGLE_OBJ)
        for name, text, kind in cases:
            status, stderr, path = run_kdray(args.kdray, scene, work, name, text)
            problem = schema_errors(validator, text)
            kdray_ok = status == 0
            error_line = next((l for l in stderr.splitlines() if l.startswith("kdray: error:")), "")
            if kind == "good":
                ok = kdray_ok and problem is None
                want = "kdray renders it, the schema accepts it"
            elif kind == "bad":
                ok = (not kdray_ok and str(path) in error_line and problem is not None)
                want = "kdray refuses it naming the file, the schema refuses it"
            else:
                ok = (not kdray_ok and str(path) in error_line and problem is None)
                want = "kdray refuses it naming the file, the schema accepts it (beyond a schema)"
            got = "kdray: exit %d%s; schema: %s" % (
                status, " (" + error_line + ")" if error_line else "",
                "valid" if problem is None else problem)
            print("%-4s %-6s %-40s %s" % ("ok" if ok else "FAIL", kind, name, got))
            if not ok:
                failures.append("%s (%s): want: %s; got: %s; stderr: %s" %
                                (name, kind, want, got, stderr.strip()[-300:]))

    if failures:
        print("\n%d failures:" % len(failures))
        for f in failures:
            print("  " + f)
        return 1
    print("\nall %d render files and %d cases agree" % (len(files), len(cases)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
