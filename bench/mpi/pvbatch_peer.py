# SPDX-License-Identifier: BSD-3-Clause
# bench/mpi/pvbatch_peer.py -- ParaView's parallel volume rendering of the parts pnb_bench_mpi
# wrote (--write-parts DIR), as the peer of its sort-last compositing of ray runs.
#
# Usage: xvfb-run -a mpirun -np N pvbatch --symmetric bench/mpi/pvbatch_peer.py --parts DIR
#        [--partitions "slabs metis round-robin"] [--frames 5] [--width 512]
#        [--mapper "Projected tetra"] [--redistribute view|filter]
# Every rank runs the script (--symmetric: no rank waits on another's remote calls). Reads
# DIR/PARTITION-N.pvtu (piece R on rank R), DIR/scene.json and DIR/serial-W.png; writes
# DIR/pvbatch-PARTITION-N-W.png. Rank 0 prints one JSON line per partition:
#   render_ms        median of the timed frames on rank 0: Render(), which on every rank
#                    redistributes for ordered compositing, projects the tets and composites
#                    in depth order through IceT; render_ms_min
#   first_frame_ms   the first frame: the representation's set-up, the redistribution of the cells
#   redistribute_ms  the view's redistribution for ordered compositing in the first frame (kd-tree
#                    over the cells, cells split at its planes and sent; slowest rank), from
#                    ParaView's own log (its scope "Using ordered compositing w/ data
#                    redistribution as needed"), and redistribute_ms_timed_frames, the same scope
#                    summed over the timed frames (ParaView 5.11 repeats it once, in the second
#                    frame, then finds nothing to move); null on 1 rank, where no depth order is needed
#   filter_ms, cells_after_filter   with --redistribute filter only: the RedistributeDataSet
#                    filter ("Split cells", one region per rank; slowest rank) run before the view
#   load_ms          reading the pieces (slowest rank)
#   rms_vs_serial_pct, max_level_diff, bad_pixels   against pnb_bench_mpi's one-process picture
#   rss_peak_mb_max  the largest rank's peak resident memory for this partition (Linux VmHWM)
import argparse
import importlib.util
import json
import os
import re
import statistics
import tempfile
import time

# ParaView's data-movement log times the view's redistribution. Its level is read when the first
# view renders, so it is set before that: 5, above stderr's INFO (0), reaches the log file only.
os.environ.setdefault('PARAVIEW_LOG_DATA_MOVEMENT_VERBOSITY', '5')

import numpy
from paraview import servermanager
from paraview.simple import (ColorBy, CreateView, Delete, GetColorTransferFunction,
                             GetOpacityTransferFunction, ProgrammableFilter, RedistributeDataSet,
                             Render, SaveScreenshot, Show, Sphere,
                             XMLPartitionedUnstructuredGridReader)
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkDoubleArray, vtkLogger
from vtkmodules.vtkIOImage import vtkPNGReader
from vtkmodules.vtkParallelCore import vtkCommunicator, vtkMultiProcessController


def over_ranks(values, op):
    """`values` reduced element-wise over the ranks (vtkCommunicator.MAX_OP, SUM_OP)."""
    send, result = vtkDoubleArray(), vtkDoubleArray()
    send.SetNumberOfValues(len(values))
    for i, v in enumerate(values):
        send.SetValue(i, v)
    vtkMultiProcessController.GetGlobalController().AllReduce(send, result, op)
    return [result.GetValue(i) for i in range(len(values))]


def read_rgb(path):
    reader = vtkPNGReader()
    reader.SetFileName(path)
    reader.Update()
    image = reader.GetOutput()
    pixels = vtk_to_numpy(image.GetPointData().GetScalars())
    return image.GetDimensions()[:2], pixels[:, :3].astype(numpy.int32)


def compare(path, reference_path):
    """RMS (% of 255) over pixels and channels, largest 8-bit difference, pixels off by > 10%."""
    size, image = read_rgb(path)
    ref_size, reference = read_rgb(reference_path)
    if size != ref_size:
        raise RuntimeError('%s is %s, the reference %s' % (path, size, ref_size))
    d = numpy.abs(image - reference)
    rms = 100.0 * float(numpy.sqrt((d.astype(numpy.float64) ** 2).mean())) / 255.0
    return round(rms, 4), int(d.max()), int((d.max(axis=1) > 25).sum())


def peak_rss_mb(reset=False):
    """This rank's peak resident set (VmHWM); `reset` restarts it, so each partition has its own."""
    try:
        if reset:
            with open('/proc/self/clear_refs', 'w') as f:
                f.write('5')
            return 0.0
        with open('/proc/self/status') as f:
            for line in f:
                if line.startswith('VmHWM:'):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return -1.0


# ParaView 5.11's .pvtu reader leaves an empty polyhedron face-location array on some ranks'
# pieces; vtkExtractCells, inside the view's redistribution (and the RedistributeDataSet filter),
# then reads that array as if it held one entry per cell and crashes (SIGSEGV; METIS parts and
# round-robin cells on 2 ranks). The pieces hold tets only, so the filter passes points, cells and
# point data on without the face arrays (no copy).
DROP_FACE_ARRAYS = """
inp = self.GetUnstructuredGridInput()
out = self.GetUnstructuredGridOutput()
out.SetPoints(inp.GetPoints())
out.SetCells(inp.GetCellTypesArray(), inp.GetCells())
out.GetPointData().PassData(inp.GetPointData())
"""


def without_face_arrays(source):
    f = ProgrammableFilter(Input=source)
    f.OutputDataSetType = 'vtkUnstructuredGrid'
    f.Script = DROP_FACE_ARRAYS
    return f


def make_view(scene, width):
    view = CreateView('RenderView')
    view.ViewSize = [width, width]
    view.OrientationAxesVisibility = 0
    view.UseColorPaletteForBackground = 0
    view.BackgroundColorMode = 'Single Color'
    view.Background = scene['background']
    view.UseFXAA = 0
    view.UseToneMapping = 0
    cam = scene['camera']
    view.CameraPosition = cam['eye']
    view.CameraFocalPoint = cam['target']
    view.CameraViewUp = cam['up']
    view.CameraViewAngle = cam['fov_y_deg']
    view.CameraParallelProjection = 0
    return view


def show_volume(source, view, scene, mapper):
    """The scene's transfer function on ParaView's volume representation. One node list for colour
    and extinction as in the render benchmark; the opacity holds tau / tau_max over a unit distance
    of 1 / tau_max, because the projected-tetrahedra mapper keeps opacity in [0, 1] (8 bits per
    vertex) and every unstructured mapper attenuates by opacity / unit distance."""
    display = Show(source, view)
    display.Representation = 'Volume'
    ColorBy(display, ('POINTS', 's'))
    tau_max = max(n[4] for n in scene['tf']) or 1.0
    lut = GetColorTransferFunction('s')
    lut.AutomaticRescaleRangeMode = 'Never'
    lut.ColorSpace = 'RGB'
    lut.Discretize = 0
    lut.RGBPoints = [v for n in scene['tf'] for v in (n[0], n[1], n[2], n[3])]
    lut.ScalarRangeInitialized = 1
    pwf = GetOpacityTransferFunction('s')
    # x, value, midpoint 0.5 and sharpness 0: linear between nodes.
    pwf.Points = [v for n in scene['tf'] for v in (n[0], n[4] / tau_max, 0.5, 0.0)]
    pwf.ScalarRangeInitialized = 1
    display.LookupTable = lut
    display.ScalarOpacityFunction = pwf
    display.ScalarOpacityUnitDistance = 1.0 / tau_max
    display.SelectMapper = mapper
    display.SetScalarBarVisibility(view, False)
    return display


def warm_up():
    """One render before the measured ones. The first projected-tetrahedra view of a process
    otherwise comes out with seams along the tet faces (holeblock-100k: RMS 1.13 % against 0.75 %
    for every later view, 60 levels at most against 24), whatever the partition; a surface
    rendered once first makes every view alike. It also keeps the OpenGL context's creation out
    of the first partition's first frame."""
    view = CreateView('RenderView')
    view.ViewSize = [64, 64]
    sphere = Sphere()
    display = Show(sphere, view)
    Render(view)
    Delete(display)
    Delete(view)
    Delete(sphere)


REDISTRIBUTION_SCOPE = re.compile(r'\}\s+([0-9.]+) s: Using ordered compositing w/ data redistribution')


def frames_with_log(view, frames, log_path):
    """Renders 1 + `frames` frames; returns their times and each frame's redistribution time
    (ms, from ParaView's log), both for this rank."""
    vtkLogger.LogToFile(log_path, vtkLogger.TRUNCATE, vtkLogger.VERBOSITY_5)
    times = []
    try:
        for _ in range(1 + frames):
            t = time.perf_counter()
            Render(view)
            times.append(1000 * (time.perf_counter() - t))
    finally:
        vtkLogger.EndLogToFile(log_path)
    with open(log_path) as f:
        redistribution = [1000 * float(m.group(1)) for m in map(REDISTRIBUTION_SCOPE.search, f) if m]
    os.remove(log_path)
    return times, redistribution


def bench_partition(args, scene, rank, ranks, partition):
    line = {'bench': 'mpi', 'peer': 'pvbatch', 'scene': scene['scene'], 'tets': scene['tets'],
            'ranks': ranks, 'partition': partition, 'lit': 'none', 'width': args.width,
            'mapper': args.mapper}
    peak_rss_mb(reset=True)
    t = time.perf_counter()
    reader = XMLPartitionedUnstructuredGridReader(
        FileName=[os.path.join(args.parts, '%s-%d.pvtu' % (partition, ranks))])
    reader.PointArrayStatus = ['s']
    tets = without_face_arrays(reader)
    tets.UpdatePipeline()
    load_ms = 1000 * (time.perf_counter() - t)
    source, redistribute, filter_ms, cells = tets, None, 0.0, 0.0
    if args.redistribute == 'filter' and ranks > 1:
        redistribute = RedistributeDataSet(Input=tets)
        redistribute.BoundaryMode = 'Split cells'
        t = time.perf_counter()
        redistribute.UpdatePipeline()
        filter_ms = 1000 * (time.perf_counter() - t)
        cells = redistribute.GetDataInformation().GetNumberOfCells()  # this rank's (symmetric)
        source = redistribute
    view = make_view(scene, args.width)
    display = show_volume(source, view, scene, args.mapper)
    log_path = os.path.join(tempfile.gettempdir(), 'pvbatch-peer-%d-rank%d.log' % (os.getpid(), rank))
    times, redistribution = frames_with_log(view, args.frames, log_path)
    first_redistribution = redistribution[0] if redistribution else -1.0
    later_redistribution = sum(redistribution[1:]) if redistribution else -1.0
    peak = peak_rss_mb()
    load_ms, filter_ms, first_redistribution, later_redistribution, peak = over_ranks(
        [load_ms, filter_ms, first_redistribution, later_redistribution, peak], vtkCommunicator.MAX_OP)
    cells = over_ranks([cells], vtkCommunicator.SUM_OP)[0]
    # The capture composites on every rank; rank 0's picture is the one kept.
    image = os.path.join(args.parts, 'pvbatch-%s-%d-%d.png' % (partition, ranks, args.width))
    capture = image if rank == 0 else os.path.join(tempfile.gettempdir(), 'pvbatch-peer-%d.png' % os.getpid())
    SaveScreenshot(capture, view, ImageResolution=[args.width, args.width], TransparentBackground=0)
    if rank != 0 and os.path.exists(capture):
        os.remove(capture)
    line['render_ms'] = round(statistics.median(times[1:]), 1)
    line['render_ms_min'] = round(min(times[1:]), 1)
    line['first_frame_ms'] = round(times[0], 1)
    line['redistribute_ms'] = round(first_redistribution, 1) if first_redistribution >= 0 else None
    line['redistribute_ms_timed_frames'] = round(later_redistribution, 1) if later_redistribution >= 0 else None
    if redistribute is not None:
        line['filter_ms'] = round(filter_ms, 1)
        line['cells_after_filter'] = int(cells)
    line['load_ms'] = round(load_ms, 1)
    if rank == 0:
        rms, level, bad = compare(image, os.path.join(args.parts, 'serial-%d.png' % args.width))
        line.update(rms_vs_serial_pct=rms, max_level_diff=level, bad_pixels=bad)
    line['image'] = image
    line['rss_peak_mb_max'] = round(peak, 1) if peak >= 0 else None
    line['frames'] = args.frames
    line['load_avg'] = round(os.getloadavg()[0], 2)
    Delete(display)
    Delete(view)
    if redistribute is not None:
        Delete(redistribute)
    Delete(tets)
    Delete(reader)
    return line


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument('--parts', required=True)
    parser.add_argument('--partitions', default='slabs metis round-robin')
    parser.add_argument('--frames', type=int, default=5)
    parser.add_argument('--width', type=int, default=512)
    parser.add_argument('--mapper', default='Projected tetra',
                        choices=['Projected tetra', 'Z sweep', 'Bunyk ray cast'])
    parser.add_argument('--redistribute', default='view', choices=['view', 'filter'])
    args = parser.parse_args()
    with open(os.path.join(args.parts, 'scene.json')) as f:
        scene = json.load(f)
    pm = servermanager.vtkProcessModule.GetProcessModule()
    rank, ranks = pm.GetPartitionId(), pm.GetNumberOfLocalPartitions()
    warm_up()
    for partition in args.partitions.split():
        line = bench_partition(args, scene, rank, ranks, partition)
        if rank == 0:
            print(json.dumps(line), flush=True)


# ParaView's programmable filter runs its set-up in __main__'s namespace, star-importing numpy and
# numpy_interface's algorithms over max, min, abs, sum and numpy itself; the functions above
# therefore run from a module of their own.
if __name__ == '__main__':
    spec = importlib.util.spec_from_file_location('pvbatch_peer', os.path.abspath(__file__))
    peer = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(peer)
    peer.main()
