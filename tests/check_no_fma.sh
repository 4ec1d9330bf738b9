#!/usr/bin/env bash
# The generated code of log_array's paths (src/vector_log.cpp): every compiled target's LogArray
# holds no fused multiply-add (vfmadd…, vfmsub…, vfnmadd…, vfnmsub…), so each lane does the same
# IEEE operations on every x86-64 CPU, and the AVX-512 target is there and uses 512-bit registers.
#   check_no_fma.sh LIBRARY   (libpolrig_lib.a)
set -euo pipefail
lib="$1"
command -v objdump >/dev/null || { echo "objdump (binutils) is needed" >&2; exit 1; }
listing=$(objdump -d --no-show-raw-insn -C "$lib")
# Each function's body: from its "<name>:" line to the next blank line.
bodies=$(awk '/^[0-9a-f]+ <.*::N_[A-Z0-9_]+::LogArray\(/ { on = 1; print; next } /^$/ { on = 0 } on' <<<"$listing")
targets=$(grep -o '::N_[A-Z0-9_]*::LogArray(' <<<"$bodies" | sort -u | tr '\n' ' ')
echo "LogArray targets compiled: $targets"
[ -n "$targets" ] || { echo "no LogArray found in $lib" >&2; exit 1; }
if grep -Eq '\bv?fn?m(add|sub)[0-9]{3}' <<<"$bodies"; then
  echo "fused multiply-adds in LogArray:" >&2
  grep -E '^[0-9a-f]+ <|\bv?fn?m(add|sub)[0-9]{3}' <<<"$bodies" | grep -B1 -E 'fn?m(add|sub)' >&2
  exit 1
fi
avx3=$(awk '/::N_AVX3::LogArray\(/ { on = 1; next } /^$/ { on = 0 } on' <<<"$bodies")
[ -n "$avx3" ] || { echo "the AVX3 (AVX-512) target is not compiled" >&2; exit 1; }
grep -q '%zmm' <<<"$avx3" || { echo "N_AVX3::LogArray uses no 512-bit register" >&2; exit 1; }
echo "no fused multiply-add in any LogArray; N_AVX3's uses zmm registers"
