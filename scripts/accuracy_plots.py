"""Tables and plots of scripts/accuracy_vs_time.py: Markdown tables of the three sweeps and one
PNG per sweep (matplotlib, installed with apt when missing)."""
import csv
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


def _number(text):
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def read_csv_rows(path):
    """A sweep's CSV as accuracy_vs_time.py wrote it, numbers parsed ("" stays "")."""
    with open(path, newline="") as f:
        return [{k: _number(v) for k, v in r.items()} for r in csv.DictReader(f)]


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


def pareto_front(rows, x, y, higher_is_better=False, min_gain=0.0):
    """The rows no other row beats on both x (less is better) and y, in order of x; a slower row
    must be better in y by more than min_gain (noise) to join the front."""
    better = (lambda a, b: a > b + min_gain) if higher_is_better else \
        (lambda a, b: a < b - min_gain)
    front, best = [], None
    for r in sorted(rows, key=lambda r: (x(r), -y(r) if higher_is_better else y(r))):
        if best is None or better(y(r), best):
            front.append(r)
            best = y(r)
    return front


def _draw_front(ax, rows, x, y, label, higher_is_better, is_default, default_label,
                min_gain=0.0):
    """Every row as a grey dot, the Pareto front as a labelled line, the default as a star."""
    ax.scatter([x(r) for r in rows], [y(r) for r in rows], color="darkgrey", s=18, zorder=2,
               label="off the front")
    front = pareto_front(rows, x, y, higher_is_better, min_gain)
    ax.plot([x(r) for r in front], [y(r) for r in front], "o-", color="tab:blue", ms=5,
            zorder=3, label="Pareto front")
    for k, r in enumerate(front):
        # Alternate above and below the line so that neighbours' labels do not overlap.
        ax.annotate(label(r), (x(r), y(r)), fontsize=7, zorder=5,
                    xytext=(4, 6 if k % 2 == 0 else -11), textcoords="offset points")
    for r in rows:
        if is_default(r):
            ax.scatter([x(r)], [y(r)], marker="*", s=160, color="tab:red", zorder=4,
                       label=default_label)
            break
    xs = [x(r) for r in rows]
    if max(xs) > 5 * min(xs):  # a few settings far slower than the rest: keep the front legible
        ax.set_xscale("log")
    ax.grid(alpha=0.3, which="both")


def frame_ms(r):
    """What a frame costs with this tree setting: build + trace when the scene is rebuilt every
    frame, the trace alone when it is built once."""
    return r["build_ms"] + r["trace_ms"] if r["kind"] == "dynamic" else r["trace_ms"]


def _panels(plt, count):
    """A figure of `count` panels, at most three a row; the unused ones hidden."""
    cols = min(3, count)
    rows = (count + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(5.0 * cols, 4.2 * rows), squeeze=False)
    flat = [ax for row in axes for ax in row]
    for ax in flat[count:]:
        ax.set_visible(False)
    return fig, flat[:count]


def _finish(fig, axes, title, path, plt):
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=8)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_tree_quality(plt, path, tree_rows):
    scenes = list(dict.fromkeys(r["scene"] for r in tree_rows))
    fig, axes = _panels(plt, len(scenes))
    for ax, scene in zip(axes, scenes):
        rows = [r for r in tree_rows if r["scene"] == scene]
        _draw_front(ax, rows, frame_ms, lambda r: r["sah_cost"], lambda r: r["setting"], False,
                    lambda r: r["setting"] == "T=64", "default (T=64, C_e=0.25, 32 bins)",
                    min_gain=0.002 * min(r["sah_cost"] for r in rows))
        kind = rows[0]["kind"]
        ax.set_title(f"{scene} ({kind})", fontsize=9)
        ax.set_xlabel("ms per frame (" + ("build + trace" if kind == "dynamic" else "trace")
                      + ")")
        ax.set_ylabel("SAH cost (C_t 15, C_i 20), lower is better")
    _finish(fig, axes, "Which tree setting? Frame time against tree quality; labelled: the "
            "settings no other beats on both", path, plt)


def plot_image_accuracy(plt, path, image_rows):
    scenes = list(dict.fromkeys(r["scene"] for r in image_rows))
    fig, axes = _panels(plt, len(scenes))
    for ax, scene in zip(axes, scenes):
        rows = [r for r in image_rows if r["scene"] == scene]
        _draw_front(ax, rows, lambda r: r["trace_ms"], lambda r: r["psnr"],
                    lambda r: f"spp {r['spp']}, depth {r['max_depth']}", True,
                    lambda r: r["sweep"] == "spp" and r["spp"] == 1,
                    "render file's default spp 1 (max_depth 8)", min_gain=0.1)
        ax.set_xscale("log")
        ax.set_title(scene, fontsize=9)
        ax.set_xlabel("ms per frame (trace, log scale)")
        ax.set_ylabel("PSNR dB against the reference, higher is better")
    _finish(fig, axes, "Which spp and max_depth? Render time against image error; labelled: "
            "the settings no other beats on both", path, plt)


MODE_COLOURS = {"watertight": "tab:blue", "watertight, packets": "tab:green",
                "moller": "tab:orange", "Embree peer": "tab:grey"}
MODE_LABELS = {"watertight, packets": "watertight, packets (the default on CPU devices)",
               "moller": "Möller–Trumbore"}


def plot_robustness(plt, path, robust_rows):
    ordinary = [r for r in robust_rows if r["pixels"] == ""]
    hard = [r for r in robust_rows if r["pixels"] != ""]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    for ax, rows, key, label in ((axes[0], ordinary, "trace_ms", "ms per frame (trace)"),
                                 (axes[1], hard, "leaks", "leaking pixels (of "
                                  f"{hard[0]['pixels'] if hard else 0} rays)")):
        scenes = list(dict.fromkeys(r["scene"] for r in rows))
        modes = [m for m in MODE_COLOURS if any(r["intersect"] == m for r in rows)]
        width = 0.8 / max(1, len(modes))
        for i, mode in enumerate(modes):
            values = [next((r[key] for r in rows if r["scene"] == s and r["intersect"] == mode),
                           0) for s in scenes]
            bars = ax.bar([x + width * i for x in range(len(scenes))], values, width=width,
                          label=MODE_LABELS.get(mode, mode), color=MODE_COLOURS[mode])
            ax.bar_label(bars, fmt="%.0f", fontsize=7)
        ax.set_xticks([x + 0.4 - width / 2 for x in range(len(scenes))], scenes, rotation=20,
                      fontsize=7, ha="right")
        ax.set_ylabel(label)
        # Room above the bars for the legend, which would hide the tallest.
        ax.set_ylim(0, 1.5 * max([r[key] for r in rows if r[key] != ""] + [1]))
        ax.legend(fontsize=8, loc="upper left")
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
