#!/usr/bin/env python3
"""Compares two runs.csv files point by point, ignoring timing, timestamps and run metadata:
the check that a refactor changed no point, status, error or judged value.

  scripts/compare-points.py BEFORE.csv AFTER.csv [--rename old=new ...]

Points are matched by (scene_label, WxH, method, the axis values both files record), so a
renamed axis (e.g. schema 1's `variant=tiebreak` → `tiebreak=true`) is mapped with --rename
old_column:old_value=new_column:new_value. Columns only one file has are listed, not compared.
Exit 1 on any difference."""
import csv, sys

IGNORE = {"schema", "run_id", "git_rev", "timestamp_utc", "point_key", "reps", "warmup",
          "gpu_ms_median", "gpu_ms_min", "gpu_ms_max", "gpu_ms_rel_noise", "cpu_ms_median",
          "cpu_ms_min", "cpu_ms_max", "pass_ms", "triangles_per_s", "vertices_per_s",
          "x_floor", "speedup_vs_depth_peel", "cpu_light_ms", "frame_ms", "latency_ms",
          "reference_ms", "prep_ms", "gpu_ms_small_viewport", "raster_bound_ratio", "adapter_features",
          "driver_info"}
# Identity: where the point ran and what it was.
KEY = ["study", "scene_label", "width", "height", "method"]
FLOAT_TOL = 1e-9

def load(path):
    with open(path) as f:
        return list(csv.DictReader(f))

def main():
    args = sys.argv[1:]
    renames = []
    while "--rename" in args:
        i = args.index("--rename")
        old, new = args[i + 1].split("=")
        renames.append((old.split(":"), new.split(":")))
        del args[i:i + 2]
    a, b = load(args[0]), load(args[1])
    for r in a:
        for (oc, ov), (nc, nv) in renames:
            if r.get(oc) == ov:
                r[oc] = ""
                r[nc] = nv
    cols_a, cols_b = set(a[0]) if a else set(), set(b[0]) if b else set()
    only_a, only_b = sorted(cols_a - cols_b), sorted(cols_b - cols_a)
    shared = sorted((cols_a & cols_b) - IGNORE - set(KEY))
    # Axis columns: those either file sets on some row and that name configuration, compared
    # via identity of the row's full cell set below; here, identity uses KEY + every shared
    # column whose name the schema lists as an axis.
    axes = [c for c in ["layers", "max_layers", "payload", "occlusion_stop", "specialisation",
                        "heuristics", "tiebreak", "thickness", "bucket_count", "bucket_mode",
                        "bucket_pairing", "hist_bins", "small_max", "effect", "sigma", "csg_a",
                        "csg_b", "dof_near", "dof_far", "stability_case", "stiffness"] if c in cols_a | cols_b]
    def ident(r):
        return tuple(r.get(k, "") for k in KEY) + tuple(r.get(k, "") for k in axes)
    ia, ib = {}, {}
    for r in a:
        ia.setdefault(ident(r), []).append(r)
    for r in b:
        ib.setdefault(ident(r), []).append(r)
    bad = 0
    # A column the new file fills with a default where the old one left it empty is a renamed
    # meaning, not a change: compare only cells the old file set.
    def same(x, y):
        if x == y:
            return True
        try:
            fx, fy = float(x), float(y)
            return abs(fx - fy) <= FLOAT_TOL * max(1.0, abs(fx), abs(fy))
        except ValueError:
            return False
    unmatched_a = [k for k in ia if k not in ib]
    unmatched_b = [k for k in ib if k not in ia]
    # Retry unmatched new rows ignoring axis cells the old file left empty (defaults now written).
    for ka in list(unmatched_a):
        base = ka[:len(KEY)]
        cand = [kb for kb in unmatched_b if kb[:len(KEY)] == base and all(
            va == "" or va == vb for va, vb in zip(ka[len(KEY):], kb[len(KEY):]))]
        if len(cand) == 1:
            ib[ka] = ib.pop(cand[0])
            unmatched_a.remove(ka)
            unmatched_b.remove(cand[0])
    for k in unmatched_a:
        print("only in BEFORE:", k); bad += 1
    for k in unmatched_b:
        print("only in AFTER:", k); bad += 1
    for k, ra in ia.items():
        rb = ib.get(k)
        if not rb:
            continue
        if len(ra) != len(rb):
            print(f"{k}: {len(ra)} rows before, {len(rb)} after"); bad += 1
            continue
        for x, y in zip(ra, rb):
            for c in shared:
                if x.get(c, "") == "" and c in axes:
                    continue
                if not same(x.get(c, ""), y.get(c, "")):
                    print(f"{k}: {c}: {x.get(c)!r} -> {y.get(c)!r}"); bad += 1
    print(f"{len(a)} rows before, {len(b)} after; {len(shared)} columns compared;"
          f" columns only before: {only_a}; only after: {only_b}; differences: {bad}")
    sys.exit(1 if bad else 0)

main()
