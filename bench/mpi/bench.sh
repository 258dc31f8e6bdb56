# SPDX-License-Identifier: BSD-3-Clause
# usage: mpi     (sort-last compositing of ray runs over 1/2/4 MPI ranks on holeblock-1m cut into slabs, METIS parts and round-robin cells, unlit, Phong and with the light volume: render and composite ms, bytes and messages per rank, runs per pixel and their peak memory, light solve ms, error against one process)
# Sourced by bench/run.sh, which provides build_targets, log, holeblock_mesh, $root, $build, $data and
# $frames. Environment: PNB_BENCH_MPI_SCENE (holeblock-1m, the default), PNB_BENCH_MPI_RANKS
# (default "1 2 4"), PNB_BENCH_MPI_PARTITIONS (default "slabs metis round-robin"),
# PNB_BENCH_MPI_SIZES (default "512"; 2048 for slabs and metis: PNB_BENCH_MPI_LARGE, default on),
# PNB_BENCH_MPI_LIT (default "none phong light-volume"), PNB_BENCH_MPI_RUNS_MB (the runs' bound
# for round-robin at 2048x2048, default 512). mpirun runs as root with --allow-run-as-root and
# oversubscribes the 2 cores with --oversubscribe.
# After Penumbra's lines for each rank count, ParaView's pvbatch renders the same parts as a peer
# (bench_mpi_pvbatch below; "peer": "pvbatch" lines): PNB_BENCH_MPI_PEER=off skips it,
# PNB_BENCH_MPI_PEER_TIMEOUT bounds each partition's run (seconds, default 600).

bench_mpi() {
  build_targets pnb_bench_mpi
  local scene=${PNB_BENCH_MPI_SCENE:-holeblock-1m} ranks
  [ "$scene" = holeblock-1m ] && holeblock_mesh
  [ "$scene" = holeblock-100k ] && holeblock_mesh holeblock-100k 0.34
  for ranks in ${PNB_BENCH_MPI_RANKS:-1 2 4}; do
    log "mpi/$scene: $ranks rank(s)"
    mpirun -np "$ranks" --allow-run-as-root --oversubscribe "$build/bench/pnb_bench_mpi" --scene "$scene" \
      --data-dir "$data" --frames "$frames" --partitions "${PNB_BENCH_MPI_PARTITIONS:-slabs metis round-robin}" \
      --sizes "${PNB_BENCH_MPI_SIZES:-512}" --lit "${PNB_BENCH_MPI_LIT:-none phong light-volume}"
    if [ "${PNB_BENCH_MPI_LARGE:-on}" = on ]; then
      mpirun -np "$ranks" --allow-run-as-root --oversubscribe "$build/bench/pnb_bench_mpi" --scene "$scene" \
        --data-dir "$data" --frames "$frames" --partitions "slabs metis" --sizes 2048 --lit none
      # Round-robin cells at 2048x2048 under a bound of PNB_BENCH_MPI_RUNS_MB (default 512) per rank:
      # the line shows the runs' peak, or that the bound refused the frame.
      mpirun -np "$ranks" --allow-run-as-root --oversubscribe "$build/bench/pnb_bench_mpi" --scene "$scene" \
        --data-dir "$data" --frames 1 --partitions round-robin --sizes 2048 --lit none \
        --runs-memory-mb "${PNB_BENCH_MPI_RUNS_MB:-512}"
    fi
    bench_mpi_pvbatch "$scene" "$ranks"
  done
}

# bench_mpi_pvbatch SCENE RANKS: pnb_bench_mpi writes each partition's parts on RANKS ranks and the
# one-process picture (--write-parts), then bench/mpi/pvbatch_peer.py renders each partition in its
# own pvbatch run on one shared Xvfb, under a timeout. A run that prints nothing (Xvfb refusing a
# rank's connection, a crash, a hang cut by the timeout) is tried once more. The pieces are
# removed afterwards; ParaView's pictures stay in build-bench/data/mpi-pvbatch/SCENE.
bench_mpi_pvbatch() {
  local scene=$1 ranks=$2 parts=$data/mpi-pvbatch/$1 partition try line start python_path
  [ "${PNB_BENCH_MPI_PEER:-on}" = off ] && { log "mpi/$scene: pvbatch peer off (PNB_BENCH_MPI_PEER=off)"; return 0; }
  python_path=$(paraview_python) || { log "mpi/$scene: no pvbatch peer: Debian's paraview could not be set up"; return 0; }
  local partitions=${PNB_BENCH_MPI_PARTITIONS:-slabs metis round-robin}
  mkdir -p "$parts"
  mpirun -np "$ranks" --allow-run-as-root --oversubscribe "$build/bench/pnb_bench_mpi" --scene "$scene" \
    --data-dir "$data" --partitions "$partitions" --sizes 512 --write-parts "$parts"
  for partition in $partitions; do
    for try in 1 2; do
      start=$SECONDS
      # --symmetric: every rank runs the script, so none waits on remote calls from rank 0 (that
      # wait deadlocked about one run in ten at the first composited frame).
      line=$(timeout -k 30 "${PNB_BENCH_MPI_PEER_TIMEOUT:-600}" xvfb-run -a -s "-screen 0 1024x1024x24" \
        mpirun -np "$ranks" --allow-run-as-root --oversubscribe -x PYTHONPATH="$python_path" /usr/bin/pvbatch --symmetric \
        "$root/bench/mpi/pvbatch_peer.py" --parts "$parts" --partitions "$partition" --frames "$frames") || true
      log "mpi/$scene: pvbatch $partition on $ranks rank(s), try $try: $((SECONDS - start)) s"
      [ -n "$line" ] && break
    done
    if [ -n "$line" ]; then echo "$line"; else log "mpi/$scene: pvbatch $partition on $ranks rank(s) printed nothing twice"; fi
  done
  rm -rf "$parts"/*-"$ranks" "$parts"/*-"$ranks".pvtu
}

# Debian's paraview (pvbatch, built with OpenMPI) installs beside the project's dependencies, but
# its Python modules (python3-paraview) conflict with python3-vtk9, which the VTK adaptor and the
# render peers need: both ship vtkmodules. The package is unpacked into the benchmark build instead
# and given to pvbatch through PYTHONPATH. Prints that path.
paraview_python() {
  local dir=$build/paraview-python site=$build/paraview-python/usr/lib/python3/dist-packages deb
  if [ ! -d "$site/paraview" ]; then
    # shellcheck source=/dev/null
    source "$root/scripts/apt_install.sh"
    apt_install_missing paraview xvfb xauth >&2 || return 1
    rm -rf "$dir.tmp" && mkdir -p "$dir.tmp"
    (cd "$dir.tmp" && apt-get download python3-paraview >&2) || return 1
    deb=$(ls "$dir.tmp"/python3-paraview_*.deb) && dpkg -x "$deb" "$dir.tmp/root" || return 1
    rm -rf "$dir" && mv "$dir.tmp/root" "$dir" && rm -rf "$dir.tmp"
  fi
  echo "$site"
}
