# SPDX-License-Identifier: BSD-3-Clause
# bench/mpi/pvbatch_peer.py -- ParaView's parallel volume rendering of the parts pnb_bench_mpi
# wrote (--write-parts DIR), as the peer of its sort-last compositing of ray runs.
#
# Usage: xvfb-run -a mpirun -np N pvbatch bench/mpi/pvbatch_peer.py --parts DIR [--frames 5]
#        [--partitions "slabs metis round-robin"] [--width 512] [--mapper "Projected tetra"]
#        [--redistribute explicit|view]
# Reads DIR/PARTITION-N.pvtu (piece R on rank R), DIR/scene.json and DIR/serial-W.png; writes
# DIR/pvbatch-PARTITION-N-W.png. Prints one JSON line per partition (rank 0 runs the script):
#   render_ms        median of the timed frames (Render() on rank 0: every rank's mapper, the
#                    depth-ordered IceT compositing and the read-back), render_ms_min
#   first_frame_ms   the first frame: the view's own kd-tree and redistribution pass, the
#                    mapper's set-up
#   load_ms          reading the pieces
#   redistribute_ms  the RedistributeDataSet filter ("Split cells", one region per rank, the
#                    boundary mode the view uses), cells_after_redistribute its cells over all
#                    ranks; with --redistribute view there is no filter (null) and the view's own
#                    pass, inside first_frame_ms, does all of it
#   rms_vs_serial_pct, max_level_diff, bad_pixels   against pnb_bench_mpi's one-process picture
#   rss_peak_mb_rank0  rank 0's peak resident memory for this partition (Linux VmHWM)
import argparse
import json
import os
import statistics
import time

from paraview import servermanager
from paraview.simple import (ColorBy, CreateView, Delete, GetColorTransferFunction,
                             GetOpacityTransferFunction, RedistributeDataSet, Render,
                             SaveScreenshot, Show, XMLPartitionedUnstructuredGridReader)
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOImage import vtkPNGReader


def read_rgb(path):
    reader = vtkPNGReader()
    reader.SetFileName(path)
    reader.Update()
    image = reader.GetOutput()
    pixels = vtk_to_numpy(image.GetPointData().GetScalars())
    return image.GetDimensions()[:2], pixels[:, :3].astype('int32')


def compare(path, reference_path):
    """RMS (% of 255) over pixels and channels, largest 8-bit difference, pixels off by > 10%."""
    size, image = read_rgb(path)
    ref_size, reference = read_rgb(reference_path)
    if size != ref_size:
        raise RuntimeError('%s is %s, the reference %s' % (path, size, ref_size))
    d = abs(image - reference)
    rms = 100.0 * float((d.astype('float64') ** 2).mean()) ** 0.5 / 255.0
    return round(rms, 4), int(d.max()), int((d.max(axis=1) > 25).sum())


def peak_rss_mb(reset=False):
    """Rank 0's peak resident set (VmHWM); `reset` restarts it, so each partition has its own."""
    try:
        if reset:
            with open('/proc/self/clear_refs', 'w') as f:
                f.write('5')
            return None
        with open('/proc/self/status') as f:
            for line in f:
                if line.startswith('VmHWM:'):
                    return round(int(line.split()[1]) / 1024.0, 1)
    except OSError:
        return None
    return None


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


def bench_partition(args, scene, ranks, partition):
    line = {'bench': 'mpi', 'peer': 'pvbatch', 'scene': scene['scene'], 'tets': scene['tets'],
            'ranks': ranks, 'partition': partition, 'lit': 'none', 'width': args.width,
            'mapper': args.mapper}
    peak_rss_mb(reset=True)
    t = time.perf_counter()
    reader = XMLPartitionedUnstructuredGridReader(
        FileName=[os.path.join(args.parts, '%s-%d.pvtu' % (partition, ranks))])
    reader.PointArrayStatus = ['s']
    reader.UpdatePipeline()
    line['load_ms'] = round(1000 * (time.perf_counter() - t), 1)
    source = reader
    redistribute = None
    if args.redistribute == 'explicit':
        redistribute = RedistributeDataSet(Input=reader)
        redistribute.BoundaryMode = 'Split cells'
        t = time.perf_counter()
        redistribute.UpdatePipeline()
        line['redistribute_ms'] = round(1000 * (time.perf_counter() - t), 1)
        line['cells_after_redistribute'] = redistribute.GetDataInformation().GetNumberOfCells()
        source = redistribute
    else:
        line['redistribute_ms'] = None
    view = make_view(scene, args.width)
    display = show_volume(source, view, scene, args.mapper)
    t = time.perf_counter()
    Render(view)
    line['first_frame_ms'] = round(1000 * (time.perf_counter() - t), 1)
    times = []
    for _ in range(args.frames):
        t = time.perf_counter()
        Render(view)
        times.append(1000 * (time.perf_counter() - t))
    line['render_ms'] = round(statistics.median(times), 1)
    line['render_ms_min'] = round(min(times), 1)
    image = os.path.join(args.parts, 'pvbatch-%s-%d-%d.png' % (partition, ranks, args.width))
    SaveScreenshot(image, view, ImageResolution=[args.width, args.width], TransparentBackground=0)
    rms, level, bad = compare(image, os.path.join(args.parts, 'serial-%d.png' % args.width))
    line.update(rms_vs_serial_pct=rms, max_level_diff=level, bad_pixels=bad)
    line['image'] = image
    line['rss_peak_mb_rank0'] = peak_rss_mb()
    line['frames'] = args.frames
    line['load_avg'] = round(os.getloadavg()[0], 2)
    Delete(display)
    Delete(view)
    if redistribute is not None:
        Delete(redistribute)
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
    parser.add_argument('--redistribute', default='explicit', choices=['explicit', 'view'])
    args = parser.parse_args()
    with open(os.path.join(args.parts, 'scene.json')) as f:
        scene = json.load(f)
    ranks = servermanager.vtkProcessModule.GetProcessModule().GetNumberOfLocalPartitions()
    for partition in args.partitions.split():
        try:
            line = bench_partition(args, scene, ranks, partition)
        except Exception as e:  # one line that says why, and the next partition still runs
            line = {'bench': 'mpi', 'peer': 'pvbatch', 'ranks': ranks, 'partition': partition,
                    'lit': 'none', 'width': args.width, 'error': '%s: %s' % (type(e).__name__, e)}
        print(json.dumps(line), flush=True)


main()
