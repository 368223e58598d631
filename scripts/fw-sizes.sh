#!/usr/bin/env bash
# Firmware image sizes against the budgets (docs/firmware.md "Image sizes"): flash is
# .vector_table (+ .boot2) + .text + .rodata + .data, static RAM is
# .data + .bss + .uninit, as `llvm-size -A` reports them.
#
#   scripts/fw-sizes.sh NAME=ELF[:ram] ...   # ":ram" also checks static RAM
#
# Prints one line per image and exits 1 if any is over 256 KiB of flash (or,
# where checked, 64 KiB of static RAM): the product's budgets (docs/firmware-budget.md).
# The QEMU image's RAM includes an 8 KiB RAM model of the flash, which
# counts against its RAM budget like any other static.
set -euo pipefail
FLASH_BUDGET=$((256 * 1024))
RAM_BUDGET=$((64 * 1024))
status=0
for arg in "$@"; do
  name=${arg%%=*}
  rest=${arg#*=}
  elf=${rest%%:*}
  check_ram=no
  [[ $rest == *:ram ]] && check_ram=yes
  read -r flash ram < <(llvm-size -A "$elf" | awk '
    /^\.vector_table|^\.boot2|^\.text|^\.rodata|^\.data/ { f += $2 }
    /^\.data|^\.bss|^\.uninit/ { r += $2 }
    END { print f, r }')
  verdict=ok
  if (( flash > FLASH_BUDGET )); then verdict="OVER the flash budget by $((flash - FLASH_BUDGET)) B"; status=1; fi
  if [[ $check_ram == yes ]] && (( ram > RAM_BUDGET )); then verdict="OVER the RAM budget by $((ram - RAM_BUDGET)) B"; status=1; fi
  awk -v n="$name" -v f="$flash" -v r="$ram" -v b="$FLASH_BUDGET" -v v="$verdict" 'BEGIN {
    printf "%-22s flash %6d B (%5.1f KiB, %5d B left)  RAM %6d B (%5.1f KiB)  %s\n", n, f, f / 1024, b - f, r, r / 1024, v }'
done
exit $status
