#!/usr/bin/env python3
"""`cmake --install BUILD --prefix TMP` into a temporary prefix, then:

- bin/kdray, share/man/man1/kdray.1 and share/bash-completion/completions/kdray exist (the man
  page only with --man: the build makes it only when help2man was found);
- the man page names every command and every option of `kdray <command> --help`;
- the completion file holds every command and every option, and completes: it is sourced in bash
  after bash-completion and _kdray is called with COMP_WORDS set as bash would, e.g.
  `kdray ren` -> render, `kdray render --qu` -> --quality, `kdray render --camera d/` -> the
  .json file in d/ and not the .obj.

    install_check.py --build-dir build [--man]
"""
import argparse
import pathlib
import shutil
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts"))
import cli_docs  # noqa: E402

BASH_COMPLETION = pathlib.Path("/usr/share/bash-completion/bash_completion")

# (words on the line, the last being completed; words COMPREPLY must hold; words it must not).
CASES = [
    (["kdray", "ren"], ["render"], []),
    (["kdray", "st"], ["stats"], []),
    (["kdray", ""], ["build", "render", "stats"], []),
    (["kdray", "--ver"], ["--version"], []),
    (["kdray", "render", "--qu"], ["--quality", "--quiet"], []),
    (["kdray", "render", "--quality", ""], ["low", "medium", "high"], []),
    (["kdray", "render", "--quality=me"], ["medium"], []),
    (["kdray", "build", "--builder", "r"], ["reference"], []),
    (["kdray", "render", "--tracer", ""], ["opencl", "reference"], []),
    (["kdray", "render", "--format", ""], ["png", "exr"], []),
    (["kdray", "render", "--packets", "o"], ["on", "off"], []),
    (["kdray", "render", "--intersect", ""], ["watertight", "moller"], []),
    (["kdray", "build", "--fo"], [], ["--format"]),  # render's option, not build's
    (["kdray", "stats", "--j"], ["--json"], []),
    (["kdray", "render", "--camera", "d/"], ["d/render.json"], ["d/scene.obj", "d/notes.txt"]),
    (["kdray", "render", "--camera=d/"], ["d/render.json"], ["d/scene.obj"]),
    (["kdray", "render", "d/"], ["d/scene.obj"], ["d/render.json", "d/notes.txt"]),
    (["kdray", "build", "d/s"], ["d/scene.obj"], []),
    (["kdray", "stats", "d/"], ["d/scene.obj", "d/tree.kdt", "d/out"], ["d/notes.txt"]),
    (["kdray", "render", "d/scene.obj", "-o", "d/"], ["d/out"], ["d/scene.obj"]),
    (["kdray", "render", "--spp", ""], [], ["d"]),  # a number: no files offered
]


def comp_words(words):
    """COMP_WORDS as bash makes them: `=` (of COMP_WORDBREAKS) is a word of its own."""
    out = []
    for w in words:
        parts = w.split("=")
        for i, part in enumerate(parts):
            if i > 0:
                out.append("=")
            if part or i == len(parts) - 1:
                out.append(part)
    return out


def complete(completion, cwd, words):
    """COMPREPLY of _kdray for `words`, the cursor at the end of the last one."""
    script = """
source {bc} || exit 3
source {file} || exit 4
COMP_WORDS=({words})
COMP_CWORD=$(( ${{#COMP_WORDS[@]}} - 1 ))
COMP_LINE={line}
COMP_POINT=${{#COMP_LINE}}
COMPREPLY=()
_kdray kdray "${{COMP_WORDS[COMP_CWORD]}}" "${{COMP_WORDS[COMP_CWORD-1]}}"
printf '%s\\n' "${{COMPREPLY[@]}}"
""".format(bc=BASH_COMPLETION, file=completion,
           words=" ".join("'%s'" % w for w in comp_words(words)),
           line="'%s'" % " ".join(words))
    result = subprocess.run(["bash", "--norc", "--noprofile", "-c", script], cwd=cwd,
                            capture_output=True, text=True, timeout=60)
    if result.returncode != 0:
        raise RuntimeError("bash exited %d: %s" % (result.returncode, result.stderr.strip()))
    return [w for w in result.stdout.splitlines() if w]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build-dir", required=True)
    parser.add_argument("--man", action="store_true", help="the build made the man page")
    parser.add_argument("--cmake", default="cmake")
    args = parser.parse_args()
    failures = []

    with tempfile.TemporaryDirectory(prefix="kdray-install-") as tmp:
        prefix = pathlib.Path(tmp) / "prefix"
        result = subprocess.run([args.cmake, "--install", args.build_dir, "--prefix", str(prefix)],
                                capture_output=True, text=True)
        print(result.stdout.strip())
        if result.returncode != 0:
            print(result.stderr)
            return 1
        kdray = prefix / "bin" / "kdray"
        man = prefix / "share" / "man" / "man1" / "kdray.1"
        completion = prefix / "share" / "bash-completion" / "completions" / "kdray"
        for f in [kdray, completion] + ([man] if args.man else []):
            if not f.is_file():
                failures.append("not installed: %s" % f)
        if not args.man:
            print("SKIP the man page: the build found no help2man")
        if failures:
            print("\n".join(failures))
            return 1
        version = subprocess.run([str(kdray), "--version"], capture_output=True, text=True)
        if version.returncode != 0 or not version.stdout.startswith("kdray "):
            failures.append("installed kdray --version: %r" % version.stdout)

        # Every command and option, in the man page and in the completion file.
        commands = cli_docs.commands(str(kdray))
        if not {"build", "render", "stats"} <= set(commands):
            failures.append("kdray --help lists the commands %s" % commands)
        man_text = man.read_text().replace("\\-", "-") if args.man else ""
        completion_text = completion.read_text()
        for command in commands:
            _, _, sections = cli_docs.parse(cli_docs.help_text(str(kdray), command))
            names = [n for e in cli_docs.options(sections) for n in e["names"]]
            for name in names:
                if args.man and name not in man_text:
                    failures.append("the man page lacks %s %s" % (command, name))
                if " %s " % name not in " %s " % completion_text.replace("'", " "):
                    failures.append("the completion lacks %s %s" % (command, name))
            if args.man and ("kdray %s" % command) not in man_text:
                failures.append("the man page lacks the command %s" % command)
            print("%s: %d option names checked" % (command, len(names)))
        if args.man and ".TH KDRAY" not in man_text:
            failures.append("the man page has no .TH header")

        # The completion completes.
        if not BASH_COMPLETION.is_file():
            failures.append("%s missing: install bash-completion (scripts/install-deps.sh)" %
                            BASH_COMPLETION)
        else:
            work = pathlib.Path(tmp) / "work"
            (work / "d" / "out").mkdir(parents=True)
            for name in ("scene.obj", "render.json", "tree.kdt", "notes.txt"):
                (work / "d" / name).write_text("")
            for words, want, unwanted in CASES:
                try:
                    got = complete(completion, work, words)
                except RuntimeError as e:
                    failures.append("%s: %s" % (" ".join(words), e))
                    continue
                ok = all(w in got for w in want) and not any(w in got for w in unwanted)
                print("%-4s %-40s -> %s" % ("ok" if ok else "FAIL", "'" + " ".join(words) + "'",
                                            " ".join(got)))
                if not ok:
                    failures.append("completing '%s' gave %s; want %s%s" % (
                        " ".join(words), got, want,
                        ", none of %s" % unwanted if unwanted else ""))

    if failures:
        print("\n%d failures:" % len(failures))
        for f in failures:
            print("  " + f)
        return 1
    print("\ninstalled files, man page and completion check out")
    return 0


if __name__ == "__main__":
    sys.exit(main())
