#!/usr/bin/env python3
"""CTest compare_embree_failures: scripts/compare_embree.py skips (77) only when the shared folder
is absent; a shared folder without a scene, or whose Embree peer does not build, fails (1) and
says which (through KDRAY_SHARED_DIR, on folders made here)."""
import os
import subprocess
import sys
import tempfile

SCRIPT = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts",
                      "compare_embree.py")


def run(shared):
    r = subprocess.run([sys.executable, SCRIPT, "--kdray", "/nonexistent/kdray"],
                       capture_output=True, text=True, env={**os.environ, "KDRAY_SHARED_DIR": shared})
    return r.returncode, r.stdout + r.stderr


def expect(shared, code, words):
    got, text = run(shared)
    if got != code or words not in text:
        sys.exit(f"{shared}: exit {got} (want {code}), output {text!r} (want {words!r})")


with tempfile.TemporaryDirectory() as tmp:
    expect(os.path.join(tmp, "absent"), 77, "skipped")
    shared = os.path.join(tmp, "shared")
    os.makedirs(os.path.join(shared, "scenes", "empty"))
    expect(shared, 1, "has no scene folder")
    scene = os.path.join(shared, "scenes", "box")
    os.makedirs(scene)
    for name in ("render.json", "box.obj"):
        open(os.path.join(scene, name), "w").close()
    expect(shared, 1, "Embree peer")
    os.makedirs(os.path.join(shared, "peers", "embree"))
    with open(os.path.join(shared, "peers", "embree", "build.sh"), "w") as f:
        f.write("echo the peer does not build >&2; exit 3\n")
    expect(shared, 1, "does not build")
print("compare_embree: skips only without ../shared, fails on no scene and on a broken peer")
