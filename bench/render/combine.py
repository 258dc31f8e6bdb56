#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Reads the JSON lines of one scene (Penumbra first, then the VTK mappers) on stdin and prints
them again, the Penumbra line annotated with its speed-up over the fastest VTK mapper."""
import json
import sys

lines = [json.loads(l) for l in sys.stdin if l.strip()]
pnb = [l for l in lines if l["renderer"].startswith("penumbra")]
vtk = [l for l in lines if l["renderer"].startswith("vtk")]
if pnb and vtk:
    best = min(vtk, key=lambda l: l["ms_per_frame"])
    for l in pnb:
        speedup = best["ms_per_frame"] / l["ms_per_frame"] if l["ms_per_frame"] > 0 else None
        l["best_vtk"] = best["renderer"]
        l["speedup_vs_best_vtk"] = round(speedup, 2) if speedup else None
        l["rms_error_pct_best_vtk"] = best.get("rms_error_pct")
        # The target: at least 10x faster per frame than the faster VTK mapper, at equal or
        # lower error.
        l["meets_target"] = bool(speedup and speedup >= 10 and
                                 l["rms_error_pct"] <= best.get("rms_error_pct", float("inf")))
for l in pnb + vtk:
    print(json.dumps(l), flush=True)
