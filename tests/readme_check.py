#!/usr/bin/env python3
"""CTest readme: the front page keeps its promises.

- README.md starts with exactly the two commands, scripts/demo.sh and scripts/test.sh, and stays
  a front page (at most 200 lines); the details live in docs/.
- Every relative link and picture of README.md and docs/*.md names a file that exists, and every
  link to a README heading (#anchor) names a heading that exists.
- Every `build/kdray` command in the README's code blocks runs, from the repository root, with
  the built kdray (its output folders or files moved under a temporary folder, images made
  small), and the demo's picture (docs/demo.json) was made by the README's own commands.
- No help text points at ../shared, which a clone does not have.

    readme_check.py --kdray build/kdray
"""
import argparse
import json
import os
import re
import shlex
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")


def fail(message):
    sys.exit(f"readme_check: {message}")


def anchor(heading):
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces as hyphens."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def check_links(path):
    with open(path) as f:
        text = f.read()
    headings = {anchor(h) for h in re.findall(r"^#+ (.*)$", text, re.M)}
    folder = os.path.dirname(path)
    for target in LINK.findall(text):
        if re.match(r"[a-z]+:", target):
            continue  # a URL
        file, _, fragment = target.partition("#")
        if file and not os.path.exists(os.path.normpath(os.path.join(folder, file))):
            fail(f"{os.path.relpath(path, ROOT)}: link to {target}, which does not exist")
        if not file and fragment not in headings:
            fail(f"{os.path.relpath(path, ROOT)}: link to #{fragment}, which is no heading")


def code_blocks(text):
    return re.findall(r"^```(?:sh)?\n(.*?)^```", text, re.M | re.S)


def run_commands(kdray, commands, tmp):
    for line in commands:
        words = shlex.split(line.split(" #")[0])
        words[0] = kdray
        # Output under the temporary folder; renders small, so that the check takes seconds.
        words = [os.path.join(tmp, w) if w.startswith("out/") else w for w in words]
        if words[1] == "render":
            words += ["--size", "64x48", "-q"]
        result = subprocess.run(words, cwd=ROOT, capture_output=True, text=True, timeout=300)
        if result.returncode != 0:
            fail(f"the README's `{line}` failed (exit {result.returncode}): {result.stderr}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--kdray", required=True)
    args = parser.parse_args()
    with open(os.path.join(ROOT, "README.md")) as f:
        readme = f.read()
    blocks = code_blocks(readme)
    first = [l.split("#")[0].strip() for l in blocks[0].splitlines()] if blocks else []
    if first != ["scripts/demo.sh", "scripts/test.sh"] or readme.index("```") > readme.index("\n\n") + 2:
        fail(f"README.md must start with the two commands scripts/demo.sh and scripts/test.sh, "
             f"found {first}")
    if readme.count("\n") > 200:
        fail(f"README.md has {readme.count(chr(10))} lines: a front page has at most 200")
    check_links(os.path.join(ROOT, "README.md"))
    docs = os.path.join(ROOT, "docs")
    for folder, _, files in os.walk(docs):
        for name in files:
            if name.endswith(".md"):
                check_links(os.path.join(folder, name))

    commands = [l.strip() for b in blocks[1:] for l in b.splitlines()
                if l.strip().startswith("build/kdray ")]
    if not commands:
        fail("README.md shows no build/kdray command")
    with open(os.path.join(docs, "demo.json")) as f:
        demo = json.load(f)
    for c in demo["commands"]:
        if c not in commands:
            fail(f"docs/demo.png was made by `{c}`, which the README does not show")
    with tempfile.TemporaryDirectory(prefix="kdray-readme-") as tmp:
        run_commands(os.path.abspath(args.kdray), commands, tmp)

    for command in ([], ["build"], ["render"], ["stats"], ["compare"]):
        result = subprocess.run([args.kdray, *command, "--help"], capture_output=True, text=True)
        if "../shared" in result.stdout:
            fail(f"`kdray {' '.join(command)} --help` points at ../shared, which a clone lacks")
    print(f"README: the two commands first, {len(commands)} commands run, links resolve")


if __name__ == "__main__":
    main()
