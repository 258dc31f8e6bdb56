#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Reads the JSON lines of the gpu benchmark (penumbra-gpu, penumbra-cpu, vtk-projected-tetra) on
stdin and prints them again, each Penumbra line annotated with its speed ratios to its peers."""
import json
import sys

lines = [json.loads(l) for l in sys.stdin if l.strip()]
by_name = {l["renderer"]: l for l in lines}


def ratio(slow, fast):
    if slow is None or fast is None or fast["ms_per_frame"] <= 0:
        return None
    return round(slow["ms_per_frame"] / fast["ms_per_frame"], 2)


gpu, cpu, vtk = (by_name.get(n) for n in ("penumbra-gpu", "penumbra-cpu", "vtk-projected-tetra"))
if gpu:
    gpu["speedup_vs_cpu"] = ratio(cpu, gpu)
    gpu["speedup_vs_vtk_projected_tetra"] = ratio(vtk, gpu)
if cpu:
    cpu["speedup_vs_vtk_projected_tetra"] = ratio(vtk, cpu)
for l in lines:
    print(json.dumps(l), flush=True)
