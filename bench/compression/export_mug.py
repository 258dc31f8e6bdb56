#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Exports the point fields of tests/data/mug.e (MOOSE, 21 time steps) as raw arrays.

usage: export_mug.py MUG_E OUT_DIR
Writes OUT_DIR/mug-FIELD.f32 for each point field: uint64 vertices, uint64 steps,
float64 times[steps], float32 values[steps][vertices] (little-endian). Nodes shared by the
two element blocks are kept once (by global node id).
"""
import struct
import sys

import vtk


def to_list(array):
    return [array.GetTuple1(i) for i in range(array.GetNumberOfTuples())]


def main():
    src, out_dir = sys.argv[1], sys.argv[2]
    reader = vtk.vtkExodusIIReader()
    reader.SetFileName(src)
    reader.UpdateInformation()
    reader.GenerateGlobalNodeIdArrayOn()
    names = [reader.GetPointResultArrayName(i) for i in range(reader.GetNumberOfPointResultArrays())]
    for name in names:
        reader.SetPointResultArrayStatus(name, 1)
    times = list(reader.GetOutputInformation(0).Get(vtk.vtkStreamingDemandDrivenPipeline.TIME_STEPS()))
    series = {name: [] for name in names}
    order = None
    for t in times:
        reader.UpdateTimeStep(t)
        reader.Update()
        blocks = reader.GetOutput().GetBlock(0)
        ids, values = [], {name: [] for name in names}
        for b in range(blocks.GetNumberOfBlocks()):
            grid = blocks.GetBlock(b)
            ids.extend(to_list(grid.GetPointData().GetArray("GlobalNodeId")))
            for name in names:
                values[name].extend(to_list(grid.GetPointData().GetArray(name)))
        if order is None:
            first = {}
            for i, node in enumerate(ids):
                first.setdefault(node, i)
            order = [first[node] for node in sorted(first)]
        for name in names:
            series[name].append([values[name][i] for i in order])
    for name in names:
        path = f"{out_dir}/mug-{name}.f32"
        with open(path, "wb") as f:
            f.write(struct.pack("<QQ", len(order), len(times)))
            f.write(struct.pack(f"<{len(times)}d", *times))
            for step in series[name]:
                f.write(struct.pack(f"<{len(step)}f", *step))
        print(f"{path}: {len(order)} vertices x {len(times)} steps", file=sys.stderr)


if __name__ == "__main__":
    main()
