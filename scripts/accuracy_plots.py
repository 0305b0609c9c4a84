"""Tables and plots of scripts/accuracy_vs_time.py: Markdown tables of the three sweeps and one
PNG per sweep (matplotlib, installed with apt when missing)."""
import os
import shutil
import subprocess
import sys


APT_PYTHON = "/usr/bin/python3"  # the interpreter Debian's python3-matplotlib is installed for


def _importable(python):
    return subprocess.run([python, "-c", "import matplotlib"], capture_output=True).returncode == 0


def ensure_matplotlib(argv):
    """Makes sure this process can import matplotlib, before any sweep costs time: installs
    python3-matplotlib with apt when missing, and re-runs the script under Debian's python3 when
    this interpreter (a pyenv or venv one, say) cannot see the package apt installed."""
    if _importable(sys.executable):
        return
    if not _importable(APT_PYTHON) and shutil.which("apt-get"):
        sudo = [] if os.geteuid() == 0 else ["sudo", "-n"]
        subprocess.run(sudo + ["apt-get", "install", "-y", "-q", "python3-matplotlib"],
                       capture_output=True)
    if _importable(sys.executable):
        return
    if os.path.realpath(sys.executable) != os.path.realpath(APT_PYTHON) and \
            _importable(APT_PYTHON):
        os.execv(APT_PYTHON, [APT_PYTHON, *argv])
    sys.exit("accuracy_vs_time: matplotlib is missing and could not be installed "
             "(apt-get install python3-matplotlib)")


def _pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _table(columns, rows):
    """A Markdown table; columns: (header, function of a row giving the cell text)."""
    lines = ["| " + " | ".join(h for h, _ in columns) + " |",
             "|" + "|".join("---" if i == 0 else "---:" for i in range(len(columns))) + "|"]
    lines += ["| " + " | ".join(cell(r) for _, cell in columns) + " |" for r in rows]
    return "\n".join(lines) + "\n"


def best_tree_settings(tree_rows):
    """Per scene: the setting with the fastest frame (build + trace when dynamic, trace when
    static), and the one with the fastest build + trace and the fastest trace alone."""
    best = []
    for scene in dict.fromkeys(r["scene"] for r in tree_rows):
        rows = [r for r in tree_rows if r["scene"] == scene]
        rebuilt = min(rows, key=lambda r: r["build_ms"] + r["trace_ms"])
        traced = min(rows, key=lambda r: r["trace_ms"])
        default = next((r for r in rows if r["setting"] == "T=64"), rows[0])
        best.append({"scene": scene, "kind": rows[0]["kind"], "triangles": rows[0]["triangles"],
                     "rebuilt": rebuilt, "traced": traced, "default": default})
    return best


def tables_markdown(header, tree_rows, image_rows, robust_rows):
    ms = lambda key: lambda r: f"{r[key]:.1f}"  # noqa: E731
    out = [f"# What accuracy costs in time: measured tables\n\n{header}\n"]

    out.append("\n## Which tree setting gives the fastest frame\n\n"
               "Dynamic: rebuilt every frame (frame = build + trace). Static: built once, traced "
               "many times (frame = trace). Primary + shadow rays, one light, max_depth 1. "
               "Dynamic figures are the median frame, static ones the best of the repeats; "
               "each the best of the rounds.\n\n")
    pct = lambda a, b: f"{100.0 * (a / b - 1):+.0f}%"  # noqa: E731
    out.append(_table([
        ("scene", lambda b: f"{b['scene']} ({b['kind']}, {b['triangles']} tris)"),
        ("fastest build + trace", lambda b: f"{b['rebuilt']['setting']}: "
         f"{b['rebuilt']['build_ms']:.0f} + {b['rebuilt']['trace_ms']:.0f} ms"),
        ("default T=64, C_e=0.25, 32 bins", lambda b: f"{b['default']['build_ms']:.0f} + "
         f"{b['default']['trace_ms']:.0f} ms"),
        ("fastest trace", lambda b: f"{b['traced']['setting']}: {b['traced']['trace_ms']:.0f} ms"
         f" ({pct(b['traced']['trace_ms'], b['default']['trace_ms'])} vs default)"),
    ], best_tree_settings(tree_rows)))

    out.append("\n## Tree quality against build time\n\nSAH cost with C_t = 15, C_i = 20. "
               "frame ms: build + trace (dynamic) or trace (static).\n\n")
    out.append(_table([("scene", lambda r: r["scene"]), ("setting", lambda r: r["setting"]),
                       ("build ms", ms("build_ms")), ("SAH cost", ms("sah_cost")),
                       ("nodes", lambda r: str(r["nodes"])), ("trace ms", ms("trace_ms")),
                       ("frame ms", ms("frame_ms"))], tree_rows))

    out.append("\n## Image accuracy against render time\n\nRMSE and PSNR (dB) from "
               "`oiiotool --diff` against a reference render (EXR, linear radiance: emitters "
               "far above 1 dominate the RMSE). spp sweep at max_depth 8; max_depth sweep at a "
               "fixed spp, so its error floor is that spp's.\n\n")
    out.append(_table([("scene", lambda r: f"{r['scene']} {r['width']}x{r['height']}"),
                       ("spp", lambda r: str(r["spp"])),
                       ("max_depth", lambda r: str(r["max_depth"])),
                       ("trace ms", ms("trace_ms")), ("RMSE", lambda r: f"{r['rmse']:.5f}"),
                       ("PSNR dB", lambda r: f"{r['psnr']:.2f}"),
                       ("reference", lambda r: r["reference"])], image_rows))

    if robust_rows:
        out.append("\n## Numerical robustness against speed\n\nOrdinary scenes: trace ms of "
                   "primary + shadow rays (best of 3). Closed meshes with the camera inside, "
                   "centre rays through mesh vertices: every ray must hit, so each miss is a "
                   "leak through a shared edge or vertex.\n\n")
        out.append(_table([("scene", lambda r: r["scene"]), ("case", lambda r: r["case"]),
                           ("intersect", lambda r: r["intersect"]),
                           ("trace ms", ms("trace_ms")),
                           ("leaks (pixels)", lambda r: f"{r['leaks']} of {r['pixels']}"
                            if r["pixels"] != "" else ""),
                           ("Embree hit/miss mismatches", lambda r: str(r["embree_hit_miss"]))],
                          robust_rows))
    return "".join(out)


def plot_tree_quality(plt, path, tree_rows):
    scenes = list(dict.fromkeys(r["scene"] for r in tree_rows))
    fig, axes = plt.subplots(2, len(scenes), figsize=(4.2 * len(scenes), 7.5), squeeze=False)
    for col, scene in enumerate(scenes):
        rows = [r for r in tree_rows if r["scene"] == scene]
        top, bottom = axes[0][col], axes[1][col]
        for r in rows:
            colour = "tab:red" if r["builder"] == "reference" else (
                "tab:blue" if r["setting"].startswith("T=") else
                "tab:green" if r["setting"].startswith("C_e=") else "tab:purple")
            top.scatter(r["build_ms"], r["sah_cost"], color=colour)
            top.annotate(r["setting"], (r["build_ms"], r["sah_cost"]), fontsize=7,
                         xytext=(3, 3), textcoords="offset points")
            bottom.scatter(r["build_ms"], r["trace_ms"], color=colour)
            bottom.annotate(r["setting"], (r["build_ms"], r["trace_ms"]), fontsize=7,
                            xytext=(3, 3), textcoords="offset points")
        # Lines of equal build + trace: for a dynamic scene the best setting touches the lowest.
        worst = max(r["build_ms"] + r["trace_ms"] for r in rows)
        best = min(r["build_ms"] + r["trace_ms"] for r in rows)
        for total in (best, (best + worst) / 2):
            bottom.plot([0, total], [total, 0], ls=":", color="grey", lw=0.8)
        bottom.set_xlim(0, max(r["build_ms"] for r in rows) * 1.25)
        bottom.set_ylim(0, max(r["trace_ms"] for r in rows) * 1.25)
        top.set_title(f"{scene} ({rows[0]['kind']})", fontsize=9)
        top.set_xlabel("build ms")
        top.set_ylabel("SAH cost (C_t 15, C_i 20)")
        bottom.set_xlabel("build ms")
        bottom.set_ylabel("trace ms (primary + shadow)")
    fig.suptitle("Tree quality against build time\nblue: large-node threshold T (C_e 0.25), "
                 "green: empty-space ratio C_e (T 64), purple: large-node split (median or "
                 "SAH bins), red: reference full SAH; "
                 "dotted: equal build + trace", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_image_accuracy(plt, path, image_rows):
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    for sweep, ax, key in (("spp", axes[0], "spp"), ("max_depth", axes[1], "max_depth")):
        for scene in dict.fromkeys(r["scene"] for r in image_rows):
            rows = [r for r in image_rows if r["scene"] == scene and r["sweep"] == sweep]
            ax.plot([r["trace_ms"] for r in rows], [r["psnr"] for r in rows], marker="o",
                    label=scene)
            for r in rows:
                ax.annotate(str(r[key]), (r["trace_ms"], r["psnr"]), fontsize=7,
                            xytext=(3, -9), textcoords="offset points")
        if sweep == "spp":
            ax.set_xscale("log")
        ax.set_xlabel("trace ms" + (" (log)" if sweep == "spp" else ""))
        ax.set_ylabel("PSNR dB against the reference")
        ax.set_title(f"{sweep} sweep" + (" (max_depth 8)" if sweep == "spp" else
                                         f" (spp {rows[0]['spp'] if rows else ''})"),
                     fontsize=10)
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
    fig.suptitle("Image accuracy against render time (labels: spp, max_depth)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


MODE_COLOURS = {"watertight": "tab:blue", "watertight, packets": "tab:green",
                "moller": "tab:orange", "Embree peer": "tab:grey"}


def plot_robustness(plt, path, robust_rows):
    ordinary = [r for r in robust_rows if r["pixels"] == ""]
    hard = [r for r in robust_rows if r["pixels"] != ""]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    for ax, rows, key, label in ((axes[0], ordinary, "trace_ms", "trace ms"),
                                 (axes[1], hard, "leaks", "leaking pixels")):
        scenes = list(dict.fromkeys(r["scene"] for r in rows))
        modes = [m for m in MODE_COLOURS if any(r["intersect"] == m for r in rows)]
        width = 0.8 / max(1, len(modes))
        for i, mode in enumerate(modes):
            values = [next((r[key] for r in rows if r["scene"] == s and r["intersect"] == mode),
                           0) for s in scenes]
            bars = ax.bar([x + width * i for x in range(len(scenes))], values, width=width,
                          label=mode, color=MODE_COLOURS[mode])
            ax.bar_label(bars, fmt="%.0f", fontsize=7)
        ax.set_xticks([x + 0.4 - width / 2 for x in range(len(scenes))], scenes, rotation=20,
                      fontsize=7, ha="right")
        ax.set_ylabel(label)
        ax.legend(fontsize=8)
    axes[0].set_title("Speed: primary + shadow rays", fontsize=10)
    axes[1].set_title("Leaks: closed meshes, camera inside, rays through vertices", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_all(out_dir, tree_rows, image_rows, robust_rows):
    plt = _pyplot()
    plot_tree_quality(plt, os.path.join(out_dir, "tree_quality.png"), tree_rows)
    plot_image_accuracy(plt, os.path.join(out_dir, "image_accuracy.png"), image_rows)
    if robust_rows:
        plot_robustness(plt, os.path.join(out_dir, "robustness.png"), robust_rows)
