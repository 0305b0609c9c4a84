#!/usr/bin/env python3
"""Compiles every OpenCL program kdray can build on a GPU for NVIDIA (nvptx64-nvidia-cuda) and AMD
(amdgcn-amd-amdhsa, gfx1030) with Debian's clang-14 and libclc's built-ins, and checks that no
symbol is left unresolved and that each kernel stays inside the budgets of docs/gpu-kernels.md.

The programs and their options come from kdray itself (build/kdray_programs, from
cl/program_catalogue.cpp): this script keeps no list. Each program is compiled twice per target:
at -O2 (then linked with libclc, optimised and lowered by llc, whose output gives the kernel's
private and local memory and, on AMD, its registers) and at -O0, where nothing is inlined, as a
driver at -cl-opt-disable would compile it: every called function must have a definition.

  scripts/gpu_compile.py --programs build/kdray_programs                 # check (CTest gpu_compile)
  scripts/gpu_compile.py --programs build/kdray_programs --out docs/gpu-kernels.json
                                                          # then scripts/update_docs.py
"""
import argparse
import concurrent.futures
import datetime
import json
import os
import re
import shlex
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LIBCLC = "/usr/lib/clc"

# Target: the triple, the clang flags, libclc's library and llc's CPU.
TARGETS = {
    "nvptx": {"triple": "nvptx64-nvidia-cuda", "clang": [], "libclc": "nvptx64--nvidiacl.bc",
              "mcpu": "sm_80"},
    "amdgcn": {"triple": "amdgcn-amd-amdhsa", "clang": ["-mcpu=gfx1030", "-nogpulib"],
               "libclc": "amdgcn--amdhsa.bc", "mcpu": "gfx1030"},
}

# Budgets (docs/gpu-kernels.md says why): private memory per work-item, and local memory per
# work-group as compiled in (the limit kdray's tighter Oclgrind run, 32 KiB, gives every device).
PRIVATE_BUDGET = 4096
LOCAL_BUDGET = 32768
# Kernels a GPU runs only when asked for, with their own budget: the small stage's
# subtree-per-work-item shape (CPU devices' default; on a GPU only with --small-stage per-root,
# cl/builder/opencl_builder.cpp) keeps a whole subtree's build state per work-item.
PRIVATE_BUDGET_OF = {"kd_build_small_subtrees": 12288}


def tool(name):
    return os.environ.get("KDRAY_" + name.upper().replace("-", "_"), name + "-14")


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({r.returncode}):\n{r.stderr[-4000:]}")
    return r.stdout


def undefined(bitcode):
    """The symbols `bitcode` uses and does not define (LLVM intrinsics are not symbols)."""
    out = run([tool("llvm-nm"), "--undefined-only", bitcode])
    return sorted(line.split()[-1] for line in out.splitlines() if line.strip())


def ptx_resources(ptx):
    """Per kernel: its .local bytes (its depot plus the deepest chain of callees' depots) and the
    .shared bytes of the module-level variables it or its callees name."""
    ptx = re.sub(r"//.*", "", ptx)  # llc's comments name the next function
    shared = {m[1]: int(m[2]) for m in re.finditer(
        r"^\s*\.(?:visible |extern )?\.?shared \.align \d+ \.b8 ([\w.$]+)\[(\d+)\]", ptx, re.M)}
    heads = list(re.finditer(r"^(?:\.visible |\.weak )?\.(entry|func)\s+(?:\([^)]*\)\s*)?(\w+)\(",
                             ptx, re.M))
    funcs = {}
    for i, m in enumerate(heads):
        body = ptx[m.end():heads[i + 1].start() if i + 1 < len(heads) else len(ptx)]
        depot = sum(int(d) for d in re.findall(r"\.local \.align \d+ \.b8 \t?__local_depot\d+\[(\d+)\]",
                                               body))
        funcs[m[2]] = {"kernel": m[1] == "entry", "depot": depot, "body": body}
    for f in funcs.values():
        words = set(re.findall(r"[\w.$]+", f["body"]))
        f["calls"] = [g for g in funcs if g in words]
        f["shared"] = [s for s in shared if s in words]

    def walk(name, seen=()):
        f = funcs[name]
        inner = [walk(c, seen + (name,)) for c in f["calls"] if c not in seen + (name,)]
        return (f["depot"] + max((p for p, _ in inner), default=0),
                set(f["shared"]).union(*(s for _, s in inner)))

    result = {}
    for name, f in funcs.items():
        if f["kernel"]:
            private, used = walk(name)
            result[name] = {"private": private, "local": sum(shared[s] for s in used)}
    return result


def amdgcn_resources(asm):
    """Per kernel: scratch (private) and group segment (local) bytes from its kernel descriptor,
    VGPRs and SGPRs, llc's occupancy (waves per SIMD) and its spills."""
    result = {}
    for m in re.finditer(r"\.amdhsa_kernel (\w+)\n(.*?)\.end_amdhsa_kernel", asm, re.S):
        fields = dict(re.findall(r"\.amdhsa_(\w+) (\d+)", m[2]))
        result[m[1]] = {"private": int(fields["private_segment_fixed_size"]),
                        "local": int(fields["group_segment_fixed_size"]),
                        "vgprs": int(fields["next_free_vgpr"]),
                        "sgprs": int(fields["next_free_sgpr"])}
    current = None
    for line in asm.splitlines():
        if m := re.match(r"^(\w+):\s+; @(\w+)", line):
            current = m[1]
        elif (m := re.match(r"^; Occupancy: (\d+)", line)) and current in result:
            result[current]["occupancy"] = int(m[1])
    current = None
    for line in asm.splitlines():
        if m := re.match(r"^\s+\.name:\s+(\w+)", line):
            current = m[1]
        elif (m := re.match(r"^\s+\.([vs]gpr)_spill_count:\s+(\d+)", line)) and current in result:
            result[current][m[1] + "_spills"] = int(m[2])
    return result


def compile_program(index, program, target, tmp):
    """One program for one target: its kernels' resources and the symbols left unresolved."""
    t = TARGETS[target]
    src = os.path.join(tmp, f"p{index}.cl")
    base = os.path.join(tmp, f"p{index}.{target}")
    options = [o for o in shlex.split(program["options"]) if o != "-w"]
    clang = [tool("clang"), "-x", "cl", "-target", t["triple"], *t["clang"], "-Xclang",
             "-finclude-default-header", "-emit-llvm", "-c", "-w", *options, src]
    libclc = os.path.join(LIBCLC, t["libclc"])
    unresolved = {}
    for level in ("-O0", "-O2"):
        run(clang + [level, "-o", f"{base}{level}.bc"])
        run([tool("llvm-link"), "--only-needed", "--suppress-warnings", f"{base}{level}.bc", libclc,
             "-o", f"{base}{level}.linked.bc"])
        if missing := undefined(f"{base}{level}.linked.bc"):
            unresolved[level] = missing
    run([tool("opt"), "-O2", f"{base}-O2.linked.bc", "-o", f"{base}.opt.bc"])
    out = f"{base}.s"
    llc = [tool("llc"), "-O2", f"-mcpu={t['mcpu']}", f"{base}.opt.bc", "-o", out]
    if target == "amdgcn":
        llc.insert(1, "-mtriple=amdgcn-amd-amdhsa")
    run(llc)
    with open(out) as f:
        text = f.read()
    kernels = ptx_resources(text) if target == "nvptx" else amdgcn_resources(text)
    return {"unresolved": unresolved, "kernels": kernels}


def summarise(programs, results):
    """Per kernel and target, the worst over the programs that hold it (and which program)."""
    rows = {}
    for (index, target), r in results.items():
        program = programs[index]
        for name, res in r["kernels"].items():
            key = (program["file"], name, target)
            row = rows.setdefault(key, {"file": program["file"], "kernel": name, "target": target,
                                        "programs": 0, "private_min": res["private"]})
            row["programs"] += 1
            row["private_min"] = min(row["private_min"], res["private"])
            if res["private"] > row.get("private", -1):
                row["private"] = res["private"]
                row["private_options"] = program["options"]
            for k in ("local", "vgprs", "sgprs", "vgpr_spills", "sgpr_spills"):
                if k in res:
                    row[k] = max(row.get(k, 0), res[k])
            if "occupancy" in res:
                row["occupancy"] = min(row.get("occupancy", 99), res["occupancy"])
    return [rows[k] for k in sorted(rows)]


def breaches(rows):
    out = []
    for r in rows:
        budget = PRIVATE_BUDGET_OF.get(r["kernel"], PRIVATE_BUDGET)
        if r["private"] > budget:
            out.append(f"{r['kernel']} ({r['target']}): {r['private']} bytes of private memory "
                       f"per work-item, over the budget of {budget} "
                       f"(options: {r['private_options']})")
        if r.get("local", 0) > LOCAL_BUDGET:
            out.append(f"{r['kernel']} ({r['target']}): {r['local']} bytes of local memory per "
                       f"work-group, over the budget of {LOCAL_BUDGET}")
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--programs", required=True, help="the kdray_programs binary")
    parser.add_argument("--out", help="write the JSON here (docs/gpu-kernels.json)")
    parser.add_argument("--jobs", type=int, default=os.cpu_count())
    parser.add_argument("--limit", type=int, help="only the first N programs (script work)")
    args = parser.parse_args()

    catalogue = json.loads(run([args.programs, "--device", "gpu"]))
    programs = catalogue["programs"][:args.limit]
    results, unresolved = {}, []
    with tempfile.TemporaryDirectory(prefix="kdray-gpu-compile-") as tmp, \
            concurrent.futures.ThreadPoolExecutor(args.jobs) as pool:
        for i, p in enumerate(programs):
            with open(os.path.join(tmp, f"p{i}.cl"), "w") as f:
                f.write(p["source"])
        jobs = {pool.submit(compile_program, i, p, t, tmp): (i, t)
                for i, p in enumerate(programs) for t in TARGETS}
        for job in concurrent.futures.as_completed(jobs):
            i, t = jobs[job]
            r = job.result()
            results[(i, t)] = r
            for level, names in r["unresolved"].items():
                unresolved.append(f"{programs[i]['file']} '{programs[i]['options']}' ({t}, "
                                  f"{level}): unresolved {', '.join(names)}")
    rows = summarise(programs, results)
    problems = sorted(unresolved) + breaches(rows)
    if args.out:
        clang_version = run([tool("clang"), "--version"]).splitlines()[0]
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        from bench_common import git_commit
        value = {"date": str(datetime.date.today()), "commit": git_commit(),
                 "machine": f"{clang_version}, libclc from {LIBCLC}",
                 "command": " ".join([os.path.relpath(sys.argv[0], ROOT), *sys.argv[1:]]),
                 "targets": {k: {"triple": v["triple"], "cpu": v["mcpu"], "libclc": v["libclc"]}
                             for k, v in TARGETS.items()},
                 "budgets": {"private_bytes": PRIVATE_BUDGET, "local_bytes": LOCAL_BUDGET,
                             "private_bytes_of": PRIVATE_BUDGET_OF},
                 "programs": len(programs), "problems": problems, "rows": rows}
        with open(args.out, "w") as f:
            json.dump(value, f, indent=1)
            f.write("\n")
    for r in rows:
        extra = (f", {r['vgprs']} VGPRs, occupancy {r.get('occupancy')}" if "vgprs" in r else "")
        print(f"{r['target']:7} {r['kernel']:28} private {r['private_min']}-{r['private']} B, "
              f"local {r.get('local', 0)} B{extra} ({r['programs']} programs)")
    print(f"{len(programs)} programs x {len(TARGETS)} targets compiled")
    for p in problems:
        print("gpu_compile: " + p, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
