#!/usr/bin/env python3
"""The deterministic part of a runs.csv, and a comparison of it with a golden file.

    rows.py normalize RUNS_CSV OUT_CSV    write RUNS_CSV's deterministic columns, sorted by point_key
    rows.py compare GOLDEN_CSV RUNS_CSV   exit 1 naming every point and column that differs

scripts/check-rows.sh runs the CI suites and calls this; the golden files live in tests/golden/.
Python 3 standard library only (CI has no extra packages).

What is left out, and why. Found by running every suite twice on one build (lavapipe, the base
commit of the house move) and listing the columns that differed, then completed by name with
the columns a faster or slower machine would change that two runs here happened to agree on:
- the run, the moment and the host: run_id, git_rev, timestamp_utc, adapter, driver,
  driver_info, device_type, adapter_features (the golden files are lavapipe's; the host's
  Mesa names itself in these);
- anything read off a clock, and what follows from one: every gpu_ms_* and cpu_ms_* column,
  every *_ms time (pass, frame, prepare, measure, judge, reference, the deferred CPU phases,
  the pre-pass latencies), the rates (*_per_s, shade_ns_per_light_quad), ratios of times
  (x_floor, x_blend, speedup_vs_*, gpu_wall_ratio, raster_bound_ratio, peak_bandwidth_frac),
  what the stopping rule decided (samples, warmup_frames, stop_reason, target_reached, the
  canary and clock-lift columns, session_spread), the clocks (NVML: none on lavapipe), and
  lit_within_frame (a comparison of two wall times);
- gpu_time_trusted, and the flags set from timing (timestamps_incomplete: GPU time under 5 %
  of wall time, which lavapipe's compute passes trip or not from run to run; noisy;
  throttled): removed from `flag`, the rest of the flag set kept;
- in `notes`, the milliseconds the CPU-lit pre-pass writes into its note (`… median 0.676 ms`):
  the number is masked, the words kept.
No racy method's error columns differed between the two runs on lavapipe (mlab, adaptive,
kbuffer_rmw: their races did not change a pixel at these sizes), so RACY is empty: a method
whose errors turn out to vary goes there with its columns, never the whole row.
"""

import csv
import fnmatch
import re
import sys

EXCLUDED = [
    # the run, the moment, the host
    "run_id", "git_rev", "timestamp_utc", "adapter", "driver", "driver_info", "device_type",
    "adapter_features",
    # which physical GPU and job ran it, and who else held the GPU
    "gpu_uuid", "gpu_serial", "pci_bus_id", "slurm_*", "gpu_other_processes",
    # clocks and what follows from them
    "gpu_ms_*", "cpu_ms_*", "*_ms", "*_per_s", "shade_ns_per_light_quad*",
    "x_floor", "x_blend", "speedup_vs_*", "gpu_wall_ratio", "raster_bound_ratio",
    "peak_bandwidth_frac", "samples", "samples_discarded", "warmup_frames", "stop_reason",
    "target_reached", "canary_*", "clock_lift_*", "session_spread", "sm_clock_*",
    "mem_clock_*", "gpu_temp_*", "gpu_power_*", "throttle_reasons", "clock_source",
    "lit_within_frame", "gpu_time_trusted", "pass_ms_ci", "l2_resident",
]

# Flags set by the timing rules (how fast the adapter was, not what the point computed).
TIMING_FLAGS = {"timestamps_incomplete", "noisy", "throttled"}

# A time written into a note (masked, the note kept).
NOTE_TIME = re.compile(r"[0-9]+(\.[0-9]+)? ms\b")

# Racy methods whose error columns vary between identical runs: method -> column patterns
# blanked for that method only. Empty: none varied (see above).
RACY = {}


def excluded(name):
    return any(fnmatch.fnmatchcase(name, p) for p in EXCLUDED)


def clean_flags(value):
    parts = [f for f in value.split("|") if f and f not in TIMING_FLAGS]
    return "|".join(parts)


def normalize_rows(path):
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        header = [c for c in reader.fieldnames if not excluded(c)]
        rows = []
        for r in reader:
            racy = RACY.get(r.get("method", ""), [])
            out = {}
            for c in header:
                v = r[c]
                if c == "flag":
                    v = clean_flags(v)
                if c == "notes":
                    v = NOTE_TIME.sub("<t> ms", v)
                if any(fnmatch.fnmatchcase(c, p) for p in racy):
                    v = "<racy>"
                out[c] = v
            rows.append(out)
    # A floor row's key repeats when two study tables of a suite share a scene: the key, then
    # the whole row, orders them.
    rows.sort(key=lambda r: (r.get("point_key", ""), [r[c] for c in header]))
    return header, rows


def write(header, rows, out):
    with open(out, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=header, lineterminator="\n")
        w.writeheader()
        w.writerows(rows)


def read(path):
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        return list(reader.fieldnames), list(reader)


def compare(golden, runs):
    gh, grows = read(golden)
    nh, nrows = normalize_rows(runs)
    problems = []
    if gh != nh:
        missing = [c for c in gh if c not in nh]
        extra = [c for c in nh if c not in gh]
        problems.append(f"columns differ: missing {missing}, new {extra}"
                        + ("" if missing or extra else " (order)"))
    def by_key(rows):
        out = {}
        for r in rows:
            out.setdefault(r["point_key"], []).append(r)
        return out

    g, n = by_key(grows), by_key(nrows)
    for k in sorted(set(g) - set(n)):
        problems.append(f"missing point {k}")
    for k in sorted(set(n) - set(g)):
        problems.append(f"new point {k}")
    for k in sorted(set(g) & set(n)):
        if len(g[k]) != len(n[k]):
            problems.append(f"{k}: {len(g[k])} rows in the golden file, {len(n[k])} now")
            continue
        for gr, nr in zip(g[k], n[k]):
            diffs = [f"{c}: {gr.get(c)!r} -> {nr.get(c)!r}"
                     for c in gh if c in nh and gr.get(c) != nr.get(c)]
            if diffs:
                problems.append(f"{k}: " + "; ".join(diffs))
    for p in problems[:200]:
        print(f"  {p}")
    if len(problems) > 200:
        print(f"  … and {len(problems) - 200} more")
    return not problems


def main(argv):
    if len(argv) == 4 and argv[1] == "normalize":
        h, rows = normalize_rows(argv[2])
        write(h, rows, argv[3])
        return 0
    if len(argv) == 4 and argv[1] == "compare":
        return 0 if compare(argv[2], argv[3]) else 1
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))
