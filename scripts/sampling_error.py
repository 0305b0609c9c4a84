#!/usr/bin/env python3
"""Less noise per sample: the image error of renders at equal spp against a 4096-spp render of the
same scene, for two kdray binaries (the sampler before and after a change), side by side.

    scripts/sampling_error.py --before OLD/kdray [--after build/kdray] [--reference-spp 4096]
                              [--out docs/sampling-error] [--integrators whitted,path]
                              [--change "what differs between the two binaries"]

Scenes: testdata's Cornell room (glass, mirror, an area light) with the path integrator at
max_depth 5 and with Whitted's, and ../shared's CornellBox-Original with the path integrator when
../shared is there; 128x128 (160x120 for the room) at spp 1, 4, 16, 64 and 256. The reference is
the --after binary at --reference-spp, seeded apart from both sides (another frame number); error is RMSE as `oiiotool --diff` prints it
(scripts/accuracy_vs_time.py's image_error). "spp for the same error" is the after side's error
interpolated on a log-log line between its measured spps, the target being a quarter of the
before side's spp. Writes OUT.json and OUT.md.
"""
import argparse
import json
import math
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from accuracy_vs_time import image_error, kdray_render, link_copies, write_render_file  # noqa
from bench_common import ROOT, SHARED, run_record, write_json, write_markdown  # noqa: E402

SPPS = [1, 4, 16, 64, 256]
# The change docs/sampling-error.md measures: #30's sampler as a whole, from the independent hashes
# it replaced (commit 7c7ed41) to the sampler kdray has now, against one reference.
CHANGE = ("Before: commit 7c7ed41, independent hashes per sample and dimension, Whitted's area-light "
          "samples hashes of the shading point; after: each pixel's samples low-discrepancy (the R2 "
          "sequence, rotated per pixel), each pair of dimensions taking the pixel's points in an "
          "order of its own (a hash permutation of the sample indices), each path vertex's light "
          "sample (emitter and point) and lobe (choice and direction) from a pair of their own, "
          "and Whitted's area-light samples following the pixel's sequence (docs/path-tracing.md, "
          "kd_shading.h).")


def scenes():
    room = os.path.join(ROOT, "testdata", "cornell")
    room_obj = next(os.path.join(room, f) for f in sorted(os.listdir(room)) if f.endswith(".obj"))
    room_render = os.path.join(room, "render.json")
    out = [("testdata/cornell path", room_obj, room_render, "path", 160, 120),
           ("testdata/cornell whitted", room_obj, room_render, "whitted", 160, 120)]
    box = os.path.join(SHARED, "scenes", "cornell-box")
    if os.path.isdir(box):
        out.append(("cornell-box/CornellBox-Original path",
                    os.path.join(box, "CornellBox-Original.obj"),
                    os.path.join(box, "render.json"), "path", 128, 128))
    return out


def spp_for_error(points, error):
    """The spp at which the (spp, rmse) points reach `error`, on log-log lines between them
    (None when outside them)."""
    for (s0, e0), (s1, e1) in zip(points, points[1:]):
        if e1 <= error <= e0 and e0 > e1:
            t = (math.log(e0) - math.log(error)) / (math.log(e0) - math.log(e1))
            return math.exp(math.log(s0) + t * (math.log(s1) - math.log(s0)))
    return None


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--before", required=True)
    parser.add_argument("--after", default=os.path.join(ROOT, "build", "kdray"))
    parser.add_argument("--reference-spp", type=int, default=4096)
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "sampling-error"))
    parser.add_argument("--integrators", default="path,whitted",
                        help="the scenes of these integrators only (a change to one leaves the "
                             "other's images as they were)")
    parser.add_argument("--change", default=CHANGE,
                        help="what differs between the binaries, for the page's text")
    args = parser.parse_args()
    integrators = args.integrators.split(",")
    rows = []
    with tempfile.TemporaryDirectory(prefix="kdray-sampling-") as tmp:
        for name, obj, render, integrator, width, height in scenes():
            if integrator not in integrators:
                continue
            tag = name.replace("/", "_").replace(" ", "_")

            def render_at(kdray, spp, side, frame_number=0):
                changes = {"image": {"width": width, "height": height, "spp": spp},
                           "max_depth": 5, "freeze_camera": True}
                if integrator == "path":
                    changes["integrator"] = "path"
                render_file = write_render_file(
                    render, os.path.join(tmp, f"{tag}-{side}-{spp}.json"), **changes)
                out = os.path.join(tmp, tag, f"{side}-{spp}")
                # A frame's number seeds its samples: the reference is frame 7 of eight copies,
                # so that no side's samples are a subset of the reference's (a side whose spp
                # samples the reference averaged in would show less error than it has).
                objs = link_copies(obj, os.path.join(tmp, tag, "copies"), 8) \
                    if frame_number else [obj]
                frames = ["--frames", f"{frame_number}:{frame_number}"] if frame_number else []
                frame = kdray_render(kdray, objs, render_file, out,
                                     ["--format", "exr", *frames])["frames"][0]
                name = os.path.basename(objs[frame_number] if frame_number else obj)
                return frame, os.path.join(out, os.path.splitext(name)[0] + ".exr")

            _, reference = render_at(args.after, args.reference_spp, "reference", 7)
            row = {"scene": name, "integrator": integrator, "width": width, "height": height,
                   "reference_spp": args.reference_spp}
            for side, kdray in (("before", args.before), ("after", args.after)):
                row[side] = []
                for spp in SPPS:
                    frame, image = render_at(kdray, spp, side)
                    row[side].append({"spp": spp, "rmse": image_error(image, reference)["rmse"],
                                      "trace_ms": frame["trace_ms"]})
                    print(f"{name:40s} {side:6s} spp {spp:4d} RMSE {row[side][-1]['rmse']:.5f}")
            after_points = [(p["spp"], p["rmse"]) for p in row["after"]]
            row["after_spp_for_before_error"] = [
                {"spp": p["spp"], "after_spp": spp_for_error(after_points, p["rmse"])}
                for p in row["before"]]
            rows.append(row)
    record = {**run_record(args.after), "before": args.before, "change": args.change,
              "scenes": rows}
    write_json(args.out + ".json", record)
    lines = ["# Less noise per sample", "",
             f"Generated by `scripts/sampling_error.py` from `{os.path.basename(args.out)}.json`: "
             f"commit {record['commit']}, {record['date']}, {record['machine']}. RMSE (`oiiotool "
             f"--diff`) of linear EXRs against the after binary at {args.reference_spp} spp, "
             f"max_depth 5. {args.change}", "",
             "| scene | spp | RMSE before | RMSE after | after / before | after's spp for before's "
             "error |", "|---|---:|---:|---:|---:|---:|"]
    for row in rows:
        for b, a, s in zip(row["before"], row["after"], row["after_spp_for_before_error"]):
            reach = f"{s['after_spp']:.1f}" if s["after_spp"] else "-"
            lines.append(f"| {row['scene']} | {b['spp']} | {b['rmse']:.5f} | {a['rmse']:.5f} | "
                         f"{a['rmse'] / b['rmse']:.2f} | {reach} |")
    write_markdown(args.out, lines)
    return 0


if __name__ == "__main__":
    sys.exit(main())
