#!/bin/bash
# SPDX-License-Identifier: BSD-3-Clause
# tests/unit/compression/lane_blocks_isa_check.sh LIBRARY -- the AVX-512 lane-block decoders'
# TwoShifts instances run on CPUs without AVX-512 VBMI2, yet GCC compiles them with VBMI2 allowed
# (a template takes the target of its definition; see lane_blocks_decoder.cpp). No VBMI2
# instruction may appear in them, and the FunnelShift instances must still use one (otherwise this
# check would be looking at the wrong code).
set -euo pipefail
command -v objdump >/dev/null || { echo "objdump not found"; exit 1; }
code=$(objdump -d --no-show-raw-insn -C "$1")
instances() {  # the disassembly of the avx512_window, avx512_blocks and avx512_next instances for
  # policy $1, with their lambdas where the compiler left those out of line (the sanitizer build
  # does); at least one window decoder (the blocks one may have taken both in) and one cursor one
  awk -v policy="$1" '/^[0-9a-f]+ </ {
      p = ($0 ~ ("avx512_(window|blocks|next)<[^>]*" policy "[,>]"))
      if ($0 ~ ("^[0-9a-f]+ <void .*avx512_(window|blocks)<[^>]*" policy "[,>][^(]*\\(")) ++w
      if ($0 ~ ("^[0-9a-f]+ <void .*avx512_next<[^>]*" policy ">\\(")) ++c
    }
    p { print } END { if (w < 1 || c != 1) exit 3 }' <<<"$code"
}
two=$(instances TwoShifts) || { echo "TwoShifts instances not found in $1"; exit 1; }
funnel=$(instances FunnelShift) || { echo "FunnelShift instances not found in $1"; exit 1; }
vbmi2='vpshrd|vpshld|vpcompress[bw]|vpexpand[bw]'
if grep -qE "$vbmi2" <<<"$two"; then
  echo "VBMI2 instructions in the decoders for CPUs without VBMI2:"
  grep -E "$vbmi2" <<<"$two" | head
  exit 1
fi
grep -qE 'vpshrdv' <<<"$funnel" || { echo "the FunnelShift instances use no funnel shift"; exit 1; }
echo "TwoShifts instances: no VBMI2 instruction; FunnelShift instances: $(grep -cE 'vpshrdv' <<<"$funnel") funnel shifts"
