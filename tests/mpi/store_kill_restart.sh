#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# A run over MPI ranks with a store, killed on one rank, restarted from a checkpoint on another
# rank count, then replayed over a third rank count and in one process (ctest Mpi.store.*).
# usage: store_kill_restart.sh TEST_BIN REPLAY REPLAY_MPI MPIEXEC OUT
set -u
bin=$1 replay=$2 replay_mpi=$3 mpiexec=$4 out=$5
run() { "$mpiexec" --allow-run-as-root --oversubscribe "$@"; }
fail() { echo "store_kill_restart: $*" >&2; exit 1; }
ulimit -c 0
rm -rf "$out" && mkdir -p "$out" || fail "cannot make $out"

# 1. Three ranks on slabs, each with a halo of its neighbours' cells marked ghost (stored once,
#    by their own rank: a ghost stored twice would darken the replays), steps 0..15 (store
#    windows of 8 steps); rank 1 is killed once step 13 is rendered, five steps after the first
#    window closed.
run -np 3 "$bin" write "$out" slabs 0 16 kill=1@13 ghosts >"$out/killed.log" 2>&1 && fail "the killed run exited 0"
# What it left replays as it is: the database index is whole and the store's finished windows read.
"$replay" "$("$bin" config "$out/after-kill")" "$out/store" --quiet || fail "the store of the killed run does not replay"

# 2. Restarted from the checkpoint at cycle 8 on four ranks, three with METIS parts and rank 1
#    with no cell (its store part keeps steps only): the database is resumed and the store
#    continues in a new segment.
run -np 4 "$bin" write "$out" metis 8 16 resume empty=1 || fail "the restart failed"
[ -f "$out/store/segment-001/part-00001/steps.csv" ] || fail "the empty part kept no steps"
[ -f "$out/store/segment-001/parts.txt" ] || fail "the restart did not begin segment-001 with its parts"

# 3. The whole store over four ranks and in one process.
run -np 4 "$replay_mpi" "$("$bin" config "$out/replay-mpi")" "$out/store" --quiet || fail "penumbra-replay-mpi failed"
"$replay" "$("$bin" config "$out/replay-serial")" "$out/store" --quiet || fail "penumbra-replay failed"

# 4. Pictures against the whole mesh rendered in one process from the exact fields: the live
#    database (composited runs: 0.1 %, 2 levels), the replays (the store's lossy fields: 0.5 %,
#    8 levels) and the replays against each other (composited runs).
"$bin" reference "$out" 0 16 >/dev/null || fail "the reference run failed"
"$bin" compare "$out/reference" "$out/db" 0.1 2 >"$out/db.txt" || fail "the resumed database differs: $(cat "$out/db.txt")"
"$bin" compare "$out/reference" "$out/replay-mpi" 0.5 8 >"$out/replay-mpi.txt" || fail "the replay over ranks differs: $(cat "$out/replay-mpi.txt")"
"$bin" compare "$out/replay-serial" "$out/replay-mpi" 0.1 2 >"$out/replays.txt" || fail "the replays differ: $(cat "$out/replays.txt")"
cat "$out/replay-mpi.txt"
echo "store_kill_restart: ok"
