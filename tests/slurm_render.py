#!/usr/bin/env python3
"""scripts/slurm-render.sh on a real, one-node Slurm cluster made for the test.

As root: starts munged with a fresh key and slurmctld + slurmd with a slurm.conf generated in a
temporary folder (their own ports, sockets, state and logs: nothing of the machine's is used),
submits testdata/anim as a job array of 3 tasks (`sbatch --array=0-2 --wait`) into one folder,
and checks that the stats.json the shards merged there holds the frames of one `kdray render` of
the whole animation on this machine: the same frames, inputs, images (byte for byte), rays, hit
pixels, effects, scenes and trees (everything but times and device bytes, which depend on the
run), each shard a run of its own, and that `kdray stats OUT --json` sums up the same frames.

Exits 77 (CTest's SKIP_RETURN_CODE), saying why, when the cluster cannot be had: not root, Slurm
or munge not installed (scripts/install-deps.sh --slurm), or a daemon that does not come up.

    slurm_render.py --kdray build/kdray
"""
import argparse
import json
import os
import pathlib
import shutil
import socket
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
SKIP = 77
SHARDS = 3
SIZE = "64x48"
# What a frame's record holds that depends on the run, not on the frame: times, and device bytes
# (buffers left by the previous build are reused, docs/performance.md).
# "run": the index of the run (here, the shard) that rendered the frame into the folder.
# Round trips (device_syncs, ...) follow the device's compute units, which shards may not share.
RUN_DEPENDENT = {"mrays_per_s", "device_bytes", "device_bytes_per_triangle", "timings_ms", "run",
                 "device_syncs", "kernel_launches", "device_transfers"}


class Skip(Exception):
    pass


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def stable(record):
    """A frame record without what depends on the run."""
    if isinstance(record, dict):
        return {k: stable(v) for k, v in record.items()
                if not k.endswith("_ms") and k not in RUN_DEPENDENT}
    if isinstance(record, list):
        return [stable(v) for v in record]
    return record


def tail(path, lines=15):
    try:
        return "\n".join(pathlib.Path(path).read_text(errors="replace").splitlines()[-lines:])
    except OSError:
        return "(no log)"


class Cluster:
    """munged, slurmctld and slurmd in `work`, stopped (by the ids this started) on exit."""

    def __init__(self, work):
        self.work = work
        self.processes = []
        self.munged_pid = None
        self.conf = work / "slurm.conf"
        self.socket = work / "munge" / "munge.socket.2"
        self.env = dict(os.environ, SLURM_CONF=str(self.conf))

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        for p in reversed(self.processes):
            if p.poll() is None:
                p.terminate()
                try:
                    p.wait(timeout=20)
                except subprocess.TimeoutExpired:
                    p.kill()
                    p.wait()
        if self.munged_pid:
            try:
                os.kill(self.munged_pid, 15)
            except ProcessLookupError:
                pass

    def start_munge(self):
        munge = self.work / "munge"
        munge.mkdir(mode=0o700)
        key = munge / "munge.key"
        key.write_bytes(os.urandom(1024))
        key.chmod(0o600)
        log = munge / "munged.log"
        pid_file = munge / "munged.pid"
        result = subprocess.run(
            ["munged", "--force", "--socket=%s" % self.socket, "--key-file=%s" % key,
             "--log-file=%s" % log, "--pid-file=%s" % pid_file,
             "--seed-file=%s" % (munge / "munged.seed")],
            capture_output=True, text=True, timeout=30)
        if result.returncode != 0:
            raise Skip("munged did not start (exit %d): %s %s" %
                       (result.returncode, result.stderr.strip(), tail(log)))
        for _ in range(50):
            if pid_file.exists() and pid_file.read_text().strip():
                self.munged_pid = int(pid_file.read_text().strip())
                break
            time.sleep(0.1)
        # A credential made and read back proves the daemon serves the socket.
        check = subprocess.run("munge -n -S %s | unmunge -S %s" % (self.socket, self.socket),
                               shell=True, capture_output=True, text=True, timeout=30)
        if check.returncode != 0:
            raise Skip("munge does not answer on %s: %s %s" %
                       (self.socket, check.stderr.strip(), tail(log)))

    def write_conf(self):
        host = socket.gethostname().split(".")[0]
        # The node as slurmd sees the hardware (`NodeName=... CPUs=... RealMemory=...`).
        probe = subprocess.run(["slurmd", "-C"], capture_output=True, text=True, timeout=60)
        node = next((l for l in probe.stdout.splitlines() if l.startswith("NodeName=")), None)
        if probe.returncode != 0 or node is None:
            raise Skip("slurmd -C cannot describe this machine: %s" % probe.stderr.strip())
        host = node.split()[0][len("NodeName="):]
        for d in ("state", "spool"):
            (self.work / d).mkdir()
        self.conf.write_text("\n".join([
            "# One-node cluster of tests/slurm_render.py",
            "ClusterName=kdraytest",
            "SlurmctldHost=%s" % host,
            "SlurmctldPort=%d" % free_port(),
            "SlurmdPort=%d" % free_port(),
            "SlurmUser=root",
            "SlurmdUser=root",
            "AuthType=auth/munge",
            "CredType=cred/munge",
            "AuthInfo=socket=%s" % self.socket,
            "StateSaveLocation=%s" % (self.work / "state"),
            "SlurmdSpoolDir=%s" % (self.work / "spool"),
            "SlurmctldPidFile=%s" % (self.work / "slurmctld.pid"),
            "SlurmdPidFile=%s" % (self.work / "slurmd.pid"),
            "SlurmctldLogFile=%s" % (self.work / "slurmctld.log"),
            "SlurmdLogFile=%s" % (self.work / "slurmd.log"),
            "SlurmctldDebug=info",
            "SlurmdDebug=info",
            # Nothing that needs cgroups, systemd or a database: a container has none of them.
            "ProctrackType=proctrack/linuxproc",
            "TaskPlugin=task/none",
            "JobAcctGatherType=jobacct_gather/none",
            "AccountingStorageType=accounting_storage/none",
            "MpiDefault=none",
            "SwitchType=switch/none",
            "SchedulerType=sched/builtin",
            "SelectType=select/cons_tres",
            "SelectTypeParameters=CR_CPU",
            "ReturnToService=2",
            "%s State=UNKNOWN" % node,
            "PartitionName=kdray Nodes=ALL Default=YES MaxTime=INFINITE State=UP",
            ""]))

    def start_slurm(self):
        for daemon, args in (("slurmctld", ["-D", "-i", "-f", str(self.conf)]),
                             ("slurmd", ["-D", "-f", str(self.conf)])):
            log = open(self.work / (daemon + ".out"), "w")
            self.processes.append(subprocess.Popen([daemon] + args, stdout=log,
                                                   stderr=subprocess.STDOUT, env=self.env))
        deadline = time.time() + 90
        while time.time() < deadline:
            for p, name in zip(self.processes, ("slurmctld", "slurmd")):
                if p.poll() is not None:
                    raise Skip("%s exited with %d:\n%s\n%s" % (
                        name, p.returncode, tail(self.work / (name + ".out")),
                        tail(self.work / (name + ".log"))))
            state = subprocess.run(["sinfo", "--noheader", "-o", "%t"], capture_output=True,
                                   text=True, env=self.env, timeout=30).stdout.split()
            if state and all(s in ("idle", "mix", "alloc") for s in state):
                return
            time.sleep(1)
        raise Skip("the node did not become idle in 90 s (sinfo: %s):\n%s\n%s" % (
            state, tail(self.work / "slurmctld.log"), tail(self.work / "slurmd.log")))


# A shim for shard A of namespaces_case: every rename of a kdray temporary waits, so that the
# temporary is live (written, not yet renamed into place) for long enough that shard B starts,
# and cleans up the folder, while it is there. Without it the window is a millisecond.
RENAME_DELAY_C = r"""
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
int rename(const char* from, const char* to) {
    static int (*real)(const char*, const char*);
    if (!real) real = (int (*)(const char*, const char*))dlsym(RTLD_NEXT, "rename");
    const char* ms = getenv("KDRAY_TEST_RENAME_DELAY_MS");
    if (ms && strstr(from, ".kdray.tmp@")) usleep((useconds_t)atoi(ms) * 1000);
    return real(from, to);
}
"""
NAMESPACE_SHARDS = 2


def unshare_command():
    """The unshare that gives a command a PID namespace of its own here, or Skip."""
    if not shutil.which("unshare"):
        raise Skip("unshare (util-linux) not installed")
    tried = []
    for command in (["unshare", "--pid", "--fork", "--mount-proc"],
                    ["unshare", "-r", "--pid", "--fork", "--mount-proc"]):
        probe = subprocess.run(command + ["sh", "-c", "echo $$"], capture_output=True,
                               text=True, timeout=60)
        if probe.returncode == 0 and probe.stdout.strip() == "1":
            return command
        tried.append("%s: %s" % (" ".join(command), probe.stderr.strip() or probe.stdout.strip()))
    raise Skip("no PID namespace may be made here (%s)" % "; ".join(tried))


def namespaces_case(kdray, work, failures):
    """Two shards of scripts/slurm-render.sh, each in a PID namespace of its own on this host,
    rendering into one folder at once: as two Slurm nodes' shards do into a shared folder when
    they run in containers, or under Slurm's job_container plugins. Both share the host name, and
    a process id in one means nothing in the other: shard B, starting, took shard A's live
    temporary for a dead process's and deleted it, and A's frame failed ("cannot rename the
    finished file into place"). Checks that both shards' frames and stats land, that nothing is
    left behind, and that nothing of the user's is deleted."""
    unshare = unshare_command()
    compiler = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
    if not compiler:
        raise Skip("no C compiler for the rename-delay shim")
    work.mkdir()
    shim = work / "rename_delay.so"
    (work / "rename_delay.c").write_text(RENAME_DELAY_C)
    subprocess.run([compiler, "-shared", "-fPIC", "-o", str(shim), str(work / "rename_delay.c"),
                    "-ldl"], check=True, timeout=120)

    out = work / "out"
    out.mkdir()
    # What is not this run's, and stays: a user's file named like an old temporary, and another
    # node's temporary (whose lock, on a shared folder, may be one only that node sees).
    users = {".holiday.tmp2023.tar": "the user's",
             ".frame_099.png.kdray.tmp@another-node@7@0123456789abcdef.png": "another node's"}
    for name, text in users.items():
        (out / name).write_text(text)
    frames = str(ROOT / "testdata" / "anim" / "*.obj")
    render_json = str(ROOT / "testdata" / "anim" / "render.json")
    script = str(ROOT / "scripts" / "slurm-render.sh")

    def shard(index, prelude="", delay_ms=None):
        env = dict(os.environ, KDRAY=kdray, SLURM_ARRAY_TASK_ID=str(index),
                   SLURM_ARRAY_TASK_COUNT=str(NAMESPACE_SHARDS))
        if delay_ms:
            env.update(LD_PRELOAD=str(shim), KDRAY_TEST_RENAME_DELAY_MS=str(delay_ms))
        # Not exec'd by sh: the shard is not process 1 of its namespace.
        command = '%sbash "$0" "$@"; exit $?' % prelude
        return subprocess.Popen(
            unshare + ["sh", "-c", command, script, frames, render_json, str(out), "--size", SIZE,
                       "--quiet"],
            cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)

    # Shard A's kdray runs as process ~300 of its namespace, one that B's namespace does not
    # have (in both as process 2, the same number would have hidden the problem), and each of
    # its temporaries lives 3 s.
    a = shard(0, prelude="seq 300 | xargs -n1 true; ", delay_ms=3000)
    deadline = time.time() + 300
    while not any(".kdray.tmp@" in n and n not in users for n in os.listdir(out)):
        if a.poll() is not None or time.time() > deadline:
            failures.append("namespaces: shard A wrote no temporary (exit %s): %s" %
                            (a.poll(), a.communicate()[0].strip() if a.poll() is not None
                             else "timed out"))
            if a.poll() is None:
                a.kill()
                a.wait()
            return
        time.sleep(0.01)
    live = sorted(n for n in os.listdir(out) if ".kdray.tmp@" in n and n not in users)
    print("shard A is writing %s; shard B starts" % live)
    b = shard(1)
    outputs = {}
    for name, p in (("B", b), ("A", a)):
        try:
            text = p.communicate(timeout=600)[0].strip()
        except subprocess.TimeoutExpired:
            p.kill()
            text = p.communicate()[0].strip() + " (killed after 600 s)"
        outputs[name] = text
        print("shard %s (exit %d)%s" % (name, p.returncode, ": " + text if text else ""))
        if p.returncode != 0:
            failures.append("namespaces: shard %s exited %d: %s" % (name, p.returncode, text))

    names = set(os.listdir(out))
    for name, whose in users.items():
        if name not in names or (out / name).read_text() != whose:
            failures.append("namespaces: %s file %s was deleted or changed" % (whose, name))
    left = sorted(n for n in names if ".kdray.tmp@" in n and n not in users)
    if left:
        failures.append("namespaces: temporaries left behind: %s" % left)
    want = len(list((ROOT / "testdata" / "anim").glob("*.obj")))
    try:
        stats = json.loads((out / "stats.json").read_text())
    except (OSError, ValueError) as e:
        failures.append("namespaces: no stats.json: %s" % e)
        return
    recorded = sorted(f["frame"] for f in stats.get("frames", []))
    if recorded != list(range(want)):
        failures.append("namespaces: stats.json records frames %s; the shards render 0..%d" %
                        (recorded, want - 1))
    if len(stats.get("runs", [])) != NAMESPACE_SHARDS:
        failures.append("namespaces: stats.json lists %d runs, not %d" %
                        (len(stats.get("runs", [])), NAMESPACE_SHARDS))
    if stats.get("failed_frames"):
        failures.append("namespaces: failed frames %s" % stats["failed_frames"])
    for f in stats.get("frames", []):
        if not (out / f["image"]).is_file():
            failures.append("namespaces: frame %d's %s is missing" % (f["frame"], f["image"]))
    if not any(x.startswith("namespaces") for x in failures):
        print("two shards in two PID namespaces rendered frames %s into one folder; runs %s" %
              (recorded, [r.get("frames_rendered") for r in stats["runs"]]))


def cluster_case(kdray, work, failures):
    """The job array on the one-node cluster, in `work`; raises Skip when it cannot be had."""
    if os.geteuid() != 0:
        raise Skip("the one-node Slurm cluster needs root (its daemons run as root)")
    missing = [t for t in ("munged", "munge", "unmunge", "slurmctld", "slurmd", "sbatch",
                           "sinfo") if not shutil.which(t)]
    if missing:
        raise Skip("%s not installed (scripts/install-deps.sh --slurm)" % ", ".join(missing))
    work.mkdir()
    work.chmod(0o755)  # slurmd's job steps read the scripts' output folders as root anyway
    try:
        with Cluster(work) as cluster:
            cluster.start_munge()
            cluster.write_conf()
            cluster.start_slurm()
            print("cluster up: %s" % cluster.conf)

            frames = str(ROOT / "testdata" / "anim" / "*.obj")
            render_json = str(ROOT / "testdata" / "anim" / "render.json")
            out = work / "out"
            env = dict(cluster.env, KDRAY=kdray)
            job = subprocess.run(
                ["sbatch", "--wait", "--array=0-%d" % (SHARDS - 1), "--cpus-per-task=1",
                 "--output=%s" % (work / "task-%A_%a.log"), "--chdir=%s" % ROOT,
                 str(ROOT / "scripts" / "slurm-render.sh"), frames, render_json, str(out),
                 "--size", SIZE],
                capture_output=True, text=True, env=env, timeout=1200)
            print(job.stdout.strip(), job.stderr.strip())
            for log in sorted(work.glob("task-*.log")):
                text = log.read_text(errors="replace").strip()
                if text:
                    print("%s:\n%s" % (log.name, text))
            if job.returncode != 0:
                failures.append("sbatch --wait exited %d" % job.returncode)

        single = work / "single"
        run = subprocess.run([kdray, "render", frames, "--camera", render_json, "-o",
                              str(single), "--size", SIZE, "--quiet"],
                             capture_output=True, text=True, cwd=ROOT, timeout=1200)
        if run.returncode != 0:
            failures.append("the single-machine run exited %d: %s" % (run.returncode,
                                                                        run.stderr.strip()))
        if failures:
            raise RuntimeError()

        # The shards merged their frames into the folder's one stats.json.
        reference = json.loads((single / "stats.json").read_text())["frames"]
        merged_stats = json.loads((out / "stats.json").read_text())
        runs = merged_stats.get("runs", [])
        for i, run_record in enumerate(runs):
            print("run %d: frames %s" % (i, run_record.get("frames_rendered")))
        if len(runs) != SHARDS:
            failures.append("stats.json lists %d runs; the array had %d shards" %
                            (len(runs), SHARDS))
        merged = {}
        for f in merged_stats["frames"]:
            if f["frame"] in merged:
                failures.append("frame %d recorded twice" % f["frame"])
            merged[f["frame"]] = f
        want = [f["frame"] for f in reference]
        if sorted(merged) != want:
            failures.append("the shards recorded frames %s; one run renders %s" %
                            (sorted(merged), want))
        for f in reference:
            if f["frame"] not in merged:
                continue
            g = merged[f["frame"]]
            if stable(f) != stable(g):
                a, b = stable(f), stable(g)
                keys = sorted(k for k in set(a) | set(b) if a.get(k) != b.get(k))
                failures.append("frame %d differs from the single run in %s" % (f["frame"], keys))
            if (single / f["image"]).read_bytes() != (out / g["image"]).read_bytes():
                failures.append("frame %d: %s differs from the single run's" %
                                (f["frame"], out / g["image"]))

        # kdray stats reads the folder as the run.
        stats = subprocess.run([kdray, "stats", str(out), "--json"],
                               capture_output=True, text=True, timeout=300)
        if stats.returncode != 0:
            failures.append("kdray stats of the folder exited %d: %s" %
                            (stats.returncode, stats.stderr.strip()))
        else:
            summary = json.loads(stats.stdout).get("render", {})
            numbers = summary.get("frame_numbers")
            if numbers is None or sorted(numbers) != want or summary.get("frames") != len(want):
                failures.append("kdray stats' summary: frames %s, frame_numbers %s; "
                                "want %d frames %s" % (summary.get("frames"), numbers,
                                                       len(want), want))
            else:
                print("kdray stats: %d frames %s" % (summary["frames"], numbers))
    except RuntimeError:
        pass
    if not failures:
        print("the job array's %d shards rendered the frames of one run" % SHARDS)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kdray", required=True)
    parser.add_argument("--keep", action="store_true", help="keep the temporary folder")
    args = parser.parse_args()
    kdray = str(pathlib.Path(args.kdray).resolve())

    work = pathlib.Path(tempfile.mkdtemp(prefix="kdray-slurm-"))
    work.chmod(0o755)
    failures, skipped = [], []
    try:
        for name, case in (("two PID namespaces", namespaces_case),
                           ("the Slurm job array", cluster_case)):
            print("== %s" % name)
            try:
                case(kdray, work / name.replace(" ", "-"), failures)
            except Skip as e:
                print("SKIP: %s: %s" % (name, e))
                skipped.append(name)
    finally:
        if args.keep:
            print("kept %s" % work)
        else:
            shutil.rmtree(work, ignore_errors=True)

    if failures:
        print("\n%d failures:" % len(failures))
        for f in failures:
            print("  " + f)
        return 1
    # A case that could not run is said, and the test reported skipped rather than passed.
    return SKIP if skipped else 0


if __name__ == "__main__":
    sys.exit(main())
