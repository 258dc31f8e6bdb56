# SPDX-License-Identifier: BSD-3-Clause
# usage: mpi     (sort-last compositing of ray runs over 1/2/4 MPI ranks on holeblock-1m cut into slabs, METIS parts and round-robin cells, unlit, Phong and with the light volume: render and composite ms, bytes per rank, runs per pixel and their peak memory, light solve ms, error against one process)
# Sourced by bench/run.sh, which provides build_targets, log, holeblock_mesh, $build, $data and
# $frames. Environment: PNB_BENCH_MPI_SCENE (holeblock-1m, the default), PNB_BENCH_MPI_RANKS
# (default "1 2 4"), PNB_BENCH_MPI_PARTITIONS (default "slabs metis round-robin"),
# PNB_BENCH_MPI_SIZES (default "512"; 2048 for slabs and metis: PNB_BENCH_MPI_LARGE, default on),
# PNB_BENCH_MPI_LIT (default "none phong light-volume"), PNB_BENCH_MPI_RUNS_MB (the runs' bound
# for round-robin at 2048x2048, default 512). mpirun runs as root with --allow-run-as-root and
# oversubscribes the 2 cores with --oversubscribe.

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
  done
}
