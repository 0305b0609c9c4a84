#!/usr/bin/env python3
"""CTest docs_figures: every generated table of README.md and docs/ is what scripts/update_docs.py
makes of the committed data; and, so that the check can fail, a copy of the docs with one figure
of a generated table changed must be refused with that table's name."""
import os
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCRIPT = os.path.join(ROOT, "scripts", "update_docs.py")


def check(root):
    return subprocess.run([sys.executable, SCRIPT, "--check", "--root", root],
                          capture_output=True, text=True)


def main():
    result = check(ROOT)
    if result.returncode != 0:
        sys.exit("the docs' generated tables differ from their data; run scripts/update_docs.py:\n"
                 + result.stderr)
    with tempfile.TemporaryDirectory(prefix="kdray-docs-") as tmp:
        shutil.copytree(os.path.join(ROOT, "docs"), os.path.join(tmp, "docs"))
        shutil.copy(os.path.join(ROOT, "README.md"), os.path.join(tmp, "README.md"))
        page = os.path.join(tmp, "docs", "performance.md")
        with open(page) as f:
            text = f.read()
        start = text.index("<!-- generated: performance -->")
        row = text.index("\n| build ms", start) + 1
        end = text.index("\n", row)
        cells = text[row:end].split(" | ")
        cells[-1] = "99.99 |"  # the ratio of the table's first row
        with open(page, "w") as f:
            f.write(text[:row] + " | ".join(cells) + text[end:])
        drift = check(tmp)
        if drift.returncode == 0 or "docs/performance.md: table 'performance'" not in drift.stderr:
            sys.exit(f"a changed figure passed the check (exit {drift.returncode}): "
                     f"{drift.stderr}")
    print("generated tables match their data; a changed figure is refused")


if __name__ == "__main__":
    main()
