# SPDX-License-Identifier: BSD-3-Clause
# Runs the Fortran mini-app into a fresh directory and checks that it wrote a Cinema database.
file(REMOVE_RECURSE ${OUT})
execute_process(COMMAND ${EXE} ${OUT} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "fortran example failed (${rc}): ${out} ${err}")
endif()
if(NOT out MATCHES "last rendered step: cycle 20, 1 image")
  message(FATAL_ERROR "pnb_last_step through the Fortran module reported: ${out}")
endif()
if(NOT out MATCHES "steps that rendered, as pnb_step_needs said: 5;")
  message(FATAL_ERROR "pnb_step_needs through the Fortran module reported: ${out}")
endif()
file(STRINGS ${OUT}/data.csv rows)
list(LENGTH rows n)
# Steps 0, 5, 10, 15, 20 with one camera and one field, plus the header row.
if(NOT n EQUAL 6)
  message(FATAL_ERROR "expected 6 lines in data.csv, got ${n}: ${rows}")
endif()
