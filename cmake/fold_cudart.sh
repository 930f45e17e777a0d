#!/usr/bin/env bash
# Folds the static CUDA runtime into hmsm's CUDA backend (cmake/HmsmCuda.cmake):
#   fold_cudart.sh LD OBJCOPY NM READELF OUTPUT.o libcudart_static.a OBJECT...
# links the objects and the runtime members they need into one relocatable object (ld -r), then
# renames every symbol the runtime defines to hmsm_cudart_* and makes it local, so that nothing
# of the runtime is visible to (or collides with) the program that links hmsm. The renaming
# matters for the runtime's weak symbols that name COMDAT groups: a linker keeps one group per
# name, and would otherwise drop the group of a second runtime the program links itself.
# Fails if a runtime symbol stays global or keeps its name.
set -euo pipefail
ld="$1"; objcopy="$2"; nm="$3"; readelf="$4"; out="$5"; cudart="$6"
shift 6
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
"$ld" -r -o "$tmp/folded.o" "$@" "$cudart"
"$nm" -g --defined-only "$cudart" 2>/dev/null | awk 'NF == 3 {print $3}' | sort -u >"$tmp/runtime.syms"
# The runtime's COMDAT groups are named by local symbols of its own: rename those too.
"$nm" --defined-only "$cudart" 2>/dev/null | awk 'NF == 3 {print $3}' | sort -u >"$tmp/all.syms"
"$readelf" -gW "$tmp/folded.o" | sed -n "s/^COMDAT group section .*\[\(.*\)\] contains.*/\1/p" | sort -u |
    comm -12 - "$tmp/all.syms" >"$tmp/groups.syms"
sort -u "$tmp/runtime.syms" "$tmp/groups.syms" | awk '{print $1 " hmsm_cudart_" $1}' >"$tmp/renames"
awk '{print "hmsm_cudart_" $1}' "$tmp/runtime.syms" >"$tmp/private.syms"
"$objcopy" --redefine-syms="$tmp/renames" --localize-symbols="$tmp/private.syms" "$tmp/folded.o" "$tmp/localized.o"
left=$("$nm" --defined-only "$tmp/localized.o" | awk 'NF == 3 {print $3}' | grep -Fxf "$tmp/runtime.syms" || true)
global=$("$nm" -g --defined-only "$tmp/localized.o" | awk 'NF == 3 {print $3}' | grep '^hmsm_cudart_' || true)
groups=$("$readelf" -gW "$tmp/localized.o" | sed -n "s/^COMDAT group section .*\[\(.*\)\] contains.*/\1/p" |
    grep -Fxf "$tmp/groups.syms" || true)
if [[ -n "$left$global$groups" ]]; then
    echo "fold_cudart.sh: CUDA runtime symbols left visible:" >&2; echo "$left$global$groups" | head >&2; exit 1
fi
mv "$tmp/localized.o" "$out"
