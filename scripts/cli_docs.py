#!/usr/bin/env python3
"""What `kdray --help` and `kdray <command> --help` say, turned into the bash completion and the
man page's COMMANDS section at build time (CMakeLists.txt), so that neither can go stale.

    cli_docs.py --kdray build/kdray completion TEMPLATE OUTPUT  # scripts/kdray.bash-completion.in
    cli_docs.py --kdray build/kdray man-include OUTPUT          # help2man --include file
    cli_docs.py --kdray build/kdray options [COMMAND]          # every option, one a line

The help is CLI11's: an option line is two spaces, the option's names joined by ',', then either
one space and its type (an upper-case word such as TEXT or INT, followed by `:{a,b}` when the
values are enumerated, `=default` when it has one) or at least two spaces and its description.
"""
import argparse
import os
import re
import subprocess
import sys

OPTION = re.compile(r"^  (-\S+)(?: (\S.*?))?(?:\s{2,}(.*))?$")
COMMAND = re.compile(r"^  ([a-z][a-z0-9-]*)\s{2,}(.*)$")
SECTION = re.compile(r"^([A-Z][A-Za-z ]*):$")


def help_text(kdray, *args):
    """`kdray ARGS --help` run as `kdray`, so that the usage line names the program, not its path."""
    return subprocess.run(["kdray", *args, "--help"], executable=kdray, capture_output=True,
                          text=True, check=True).stdout


def parse(text):
    """(description, usage, sections): sections maps a heading ("Options", "Tree", ...) to its
    entries, each a dict with names, type (None for a flag), choices and description."""
    lines = text.splitlines()
    description = lines[0] if lines and not lines[0].startswith("Usage:") else ""
    usage = next((l[len("Usage: "):] for l in lines if l.startswith("Usage: ")), "")
    sections, heading, entry = {}, None, None
    for line in lines:
        if SECTION.match(line):
            heading = SECTION.match(line).group(1)
            sections[heading] = []
            entry = None
            continue
        if heading is None or not line.strip():
            continue
        option = OPTION.match(line) if heading != "Subcommands" else None
        command = COMMAND.match(line) if heading in ("Subcommands", "Positionals") else None
        if heading == "Positionals" and line.startswith("  ") and not line.startswith("   "):
            name, _, rest = line.strip().partition(" ")
            entry = {"names": [name], "type": rest.split("  ")[0].strip(), "choices": [],
                     "description": rest.partition("  ")[2].strip()}
            sections[heading].append(entry)
        elif option:
            names, kind, desc = option.groups()
            choices = re.search(r":\{([^}]*)\}", kind or "")
            entry = {"names": names.split(","), "type": kind.strip() if kind else None,
                     "choices": choices.group(1).split(",") if choices else [],
                     "description": (desc or "").strip()}
            sections[heading].append(entry)
        elif command:
            entry = {"names": [command.group(1)], "type": None, "choices": [],
                     "description": command.group(2).strip()}
            sections[heading].append(entry)
        elif entry is not None and line.startswith("   "):
            entry["description"] = (entry["description"] + " " + line.strip()).strip()
    return description, usage, sections


def commands(kdray):
    _, _, sections = parse(help_text(kdray))
    return [e["names"][0] for e in sections.get("Subcommands", [])]


def options(sections):
    return [e for heading, entries in sections.items() if heading not in ("Positionals",
                                                                           "Subcommands")
            for e in entries]


def completion(kdray, template, output):
    _, _, top = parse(help_text(kdray))
    names = commands(kdray)
    top_options = [n for e in options(top) for n in e["names"]]
    out = ["_kdray_commands='%s'" % " ".join(names),
           "_kdray_top_options='%s'" % " ".join(top_options)]
    choices = []
    for command in names:
        _, _, sections = parse(help_text(kdray, command))
        every = [n for e in options(sections) for n in e["names"]]
        valued = [n for e in options(sections) if e["type"] for n in e["names"]]
        out.append("_kdray_options_%s='%s'" % (command.replace("-", "_"), " ".join(every)))
        out.append("_kdray_valued_%s='%s'" % (command.replace("-", "_"), " ".join(valued)))
        for e in options(sections):
            if e["choices"]:
                patterns = "|".join("'%s %s'" % (command, n) for n in e["names"])
                choices.append("        %s) printf '%%s\\n' %s ;;" %
                               (patterns, " ".join(e["choices"])))
    out.append("# The values of an enumerated option: _kdray_choices COMMAND OPTION")
    out.append("_kdray_choices() {\n    case \"$1 $2\" in\n%s\n    esac\n}" % "\n".join(choices))
    text = open(template).read()
    if "@KDRAY_GENERATED@" not in text:
        sys.exit("cli_docs: %s has no @KDRAY_GENERATED@" % template)
    write_output(output, text.replace("@KDRAY_GENERATED@", "\n".join(out)))


def write_output(output, text):
    """Writes a generated file, making its folder: a fresh build folder has none."""
    os.makedirs(os.path.dirname(os.path.abspath(output)), exist_ok=True)
    with open(output, "w") as f:
        f.write(text)


def roff(text):
    """Plain text for a roff line: backslashes and leading dots or quotes escaped, dashes literal."""
    text = text.replace("\\", "\\e").replace("-", "\\-")
    return "\\&" + text if text[:1] in (".", "'") else text


def man_include(kdray, output):
    """help2man's --include file: a COMMANDS section with every command's usage and options."""
    out = ["[COMMANDS]"]
    for command in commands(kdray):
        description, usage, sections = parse(help_text(kdray, command))
        out.append('.SS "%s"' % roff(usage))
        out.append(roff(description))
        for heading, entries in sections.items():
            if heading == "Options":
                entries = [e for e in entries if "--help" not in e["names"]]
            if not entries:
                continue
            out.append(".PP\n%s:" % roff(heading))
            for e in entries:
                out.append(".TP\n\\fB%s\\fR%s" % (roff(", ".join(e["names"])),
                                                   " \\fI" + roff(e["type"]) + "\\fR"
                                                   if e["type"] else ""))
                out.append(roff(e["description"]))
    write_output(output, "\n".join(out) + "\n")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kdray", required=True)
    sub = parser.add_subparsers(dest="what", required=True)
    c = sub.add_parser("completion")
    c.add_argument("template")
    c.add_argument("output")
    m = sub.add_parser("man-include")
    m.add_argument("output")
    o = sub.add_parser("options")
    o.add_argument("command", nargs="?")
    args = parser.parse_args()
    if args.what == "completion":
        completion(args.kdray, args.template, args.output)
    elif args.what == "man-include":
        man_include(args.kdray, args.output)
    else:
        cmd = [args.command] if args.command else []
        _, _, sections = parse(help_text(args.kdray, *cmd))
        for e in options(sections):
            print(" ".join(e["names"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
