# SPDX-License-Identifier: BSD-3-Clause
# Runs the Fortran MPI mini-app on 1 rank, on 3 and on 14 (two of which own no layer of the 12
# and publish empty parts) and checks that all wrote the same database:
# the same cycles, every picture within RMS 0.1 % of 255 and 2 levels (the ranks' runs are
# composited in float32), compared by COMPARE (penumbra_mpi_store_test compare).
file(REMOVE_RECURSE ${OUT})
foreach(ranks 1 3 14)
  # As root OpenMPI needs --allow-run-as-root; --oversubscribe runs 3 ranks on fewer cores.
  execute_process(COMMAND ${MPIEXEC} ${NUMPROC_FLAG} ${ranks} --allow-run-as-root --oversubscribe ${EXE} ${OUT}/np${ranks}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "fortran MPI example on ${ranks} rank(s) failed (${rc}): ${out} ${err}")
  endif()
  if(NOT out MATCHES "ranks: ${ranks}; last rendered step: cycle 10, 2 image")
    message(FATAL_ERROR "pnb_last_step through the Fortran module over ${ranks} rank(s) reported: ${out}")
  endif()
  file(STRINGS ${OUT}/np${ranks}/data.csv rows)
  list(LENGTH rows n)
  # Steps 0, 5 and 10 with two cameras and one field, plus the header row.
  if(NOT n EQUAL 7)
    message(FATAL_ERROR "expected 7 lines in data.csv on ${ranks} rank(s), got ${n}: ${rows}")
  endif()
endforeach()
foreach(ranks 3 14)
  execute_process(COMMAND ${COMPARE} compare ${OUT}/np1 ${OUT}/np${ranks} 0.1 2 RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${ranks} ranks: ${out}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "the databases of 1 and ${ranks} ranks differ: ${out} ${err}")
  endif()
endforeach()
