#!/usr/bin/env python3
"""Issue 41's goals read from one run's folders (default, methods, perf-binned, stacked-scans,
default-webgpu): the tables of RUN.md. Usage: python3 goals.py RUN_DIR
RUN_DIR holds those five folders (or links to them: RUN.md's "before" column is this script on a
folder of links to the earlier runs it names)."""
import csv, sys, statistics, json, os, collections

BEVY = {"bunny": {512: 3.00, 1024: 7.43, 2048: 18.28}, "ogre": {512: 3.32, 1024: 5.73, 2048: 13.68}}

def load(d):
    p = os.path.join(d, "runs.csv")
    return list(csv.DictReader(open(p))) if os.path.exists(p) else []

def f(r, k):
    try: return float(r[k])
    except (KeyError, ValueError): return None

def key(r): return (r["scene_label"] or r["scene"], int(r["width"]))

def groups(rows):
    g = collections.defaultdict(list)
    for r in rows: g[key(r)].append(r)
    return g

def is_default(r):
    # The method's own configuration: capture auto (a missing column is an older build's pixels),
    # small_max 256 where swept, attributes clip, bindings auto.
    return (r.get("capture", "") in ("auto", "")
            and r.get("small_max", "") in ("", "256")
            and r.get("attributes", "") in ("", "clip")
            and r.get("bindings", "") in ("", "auto"))

def goal1(rows, label):
    out = []
    for k, rs in sorted(groups(rows).items()):
        blend = [r for r in rs if r["method"] == "floor_blend_const" and r["status"] == "ok"]
        depth = [r for r in rs if r["method"] == "floor_depth" and r["status"] == "ok"]
        ca = [r for r in rs if r["method"] == "compute_abuffer" and r["status"] == "ok"]
        if not blend or not ca: continue
        fr = f(ca[0], "true_fragments") or 0
        if fr < 1e6: continue
        b = f(blend[0], "gpu_ms_median"); dfl = f(depth[0], "gpu_ms_median") if depth else None
        has_auto = any(r.get("capture") == "auto" for r in ca)
        dflt = [r for r in ca if is_default(r) and (has_auto or r.get("capture") != "auto")]
        if not has_auto:
            dflt = [r for r in ca if r.get("capture", "pixels") in ("pixels", "") and r.get("small_max", "") in ("", "256")
                    and r.get("attributes", "") in ("", "clip") and r.get("bindings", "") in ("", "auto")]
        best = min(ca, key=lambda r: f(r, "gpu_ms_median"))
        d = dflt[0] if dflt else None
        out.append(dict(suite=label, scene=k[0], px=k[1], frags=fr, blend=b, floor=dfl,
                        dflt=f(d, "gpu_ms_median") if d else None,
                        dflt_cfg=(d.get("capture"), d.get("small_max")) if d else None,
                        best=f(best, "gpu_ms_median"),
                        best_cfg=(best.get("capture"), best.get("small_max"))))
    return out

def main():
    run = sys.argv[1]
    print("## goal 1/2 rows:", run)
    for s in ["default", "methods", "perf-binned"]:
        pts = goal1(load(os.path.join(run, s)), s)
        ok = [p for p in pts if p["dflt"] is not None and p["dflt"] <= p["blend"]]
        print(f"\n### {s}: {len(ok)} of {len(pts)} ≥1M-fragment points ≤ 1.0× blend (default config)")
        for p in pts:
            xd = p["dflt"] / p["blend"] if p["dflt"] else float('nan')
            xb = p["best"] / p["blend"]
            xf = p["dflt"] / p["floor"] if p["dflt"] and p["floor"] else float('nan')
            print(f"| {p['scene']} | {p['px']}² | {p['frags']/1e6:.2f}M | {p['blend']:.3f} | {p['dflt'] or float('nan'):.3f} {p['dflt_cfg']} | {xd:.2f} | best {p['best']:.3f} {p['best_cfg']} {xb:.2f} | ×floor {xf:.2f} |")
    print("\n## goal 3: linked list on stacked scans")
    for r in load(os.path.join(run, "stacked-scans")):
        if r["method"] in ("linked_list", "compute_abuffer", "floor_depth", "floor_blend_const"):
            sc = "bunny" if "bunny" in r["scene"] + r["scene_label"] else "ogre"
            w = int(r["width"]); ms = f(r, "gpu_ms_median")
            xb = ms / BEVY[sc][w] if ms else None
            print(f"| {sc} | {w}² | {r['method']} | {r.get('pool','')} | {r['status']} | {ms} | × Bevy {xb:.2f} | {r.get('pass_ms','')[:120]}")
    print("\n## goal 5/6: webgpu")
    web = load(os.path.join(run, "default-webgpu")); nat = {(key(r), r["method"], r.get("layers",""), r.get("heuristics","")): r for r in load(os.path.join(run, "default"))}
    st = collections.Counter((r["method"], r["status"]) for r in web)
    print(dict(st))
    for r in web:
        if r["status"] == "skipped": print("  skipped", r["method"], key(r), r["reason"][:140]); break
    xs = []
    for r in web:
        if r["method"] == "compute_abuffer" and r["status"] == "ok":
            n = nat.get((key(r), r["method"], r.get("layers",""), r.get("heuristics","")))
            if n: xs.append((f(r, "gpu_ms_median") / f(n, "gpu_ms_median"), key(r), r.get("split")))
    for x in sorted(xs): print(f"  ca webgpu/native {x[0]:.3f} {x[1]} split={x[2]}")
    for s in ["default", "methods", "perf-binned", "stacked-scans", "default-webgpu"]:
        rows = load(os.path.join(run, s))
        ll = [r for r in rows if r["method"] == "linked_list"]
        print(s, "linked_list statuses", dict(collections.Counter(r["status"] for r in ll)),
              "l2_resident", dict(collections.Counter(r.get("l2_resident","") for r in rows)))
        p = os.path.join(run, s, "run.json")
        if os.path.exists(p):
            j = json.load(open(p)); ro = j.get("roofs") or {}
            print("  roofs", {k: ro.get(k) for k in ("l2_bytes", "l2_source", "l2_bytes_per_s", "dram_bytes_per_s")}, j.get("git_rev"), j.get("elapsed_s"))

main()
